// ICP-bundle (method.md §9): a frame that overlaps no other, the gauge, the analytic Jacobian of
// the point-to-plane cost against Ceres' numeric one, and bad input. Whole windows and the
// pipeline are in test_icp_bundle_windows.cpp.
#include <algorithm>
#include <array>
#include <cstdio>
#include <random>

#include <ceres/gradient_checker.h>
#include <gtest/gtest.h>

#include "joint_test_windows.hpp"
#include "jpcr/backend/icp_bundle.hpp"
#include "jpcr/backend/icp_bundle_association.hpp"
#include "jpcr/backend/point_to_plane_cost.hpp"
#include "jpcr/quadric/error.hpp"

namespace jpcr {
namespace {

using test::bitwise_equal;
using test::JointTestWindow;
using test::perturbed;
using test::pose_error;
using test::print_report;
using test::render_window;

// Frame 3 looks the other way: it overlaps neither frame 1 nor frame 2. It is reported and its
// pose is returned exactly as given; frame 2 is still refined (from 1 cm / 1° off; measured
// 0.051 mm / 0.0017°, the bound the issue's).
TEST(IcpBundle, ReportsAFrameThatOverlapsNoOtherAndLeavesItsPose) {
  const SyntheticScene scene = load_scene("room_spheres");
  const CameraIntrinsics camera = synthetic_camera(320, 240);
  const JointTestWindow w = render_window(2, 320);
  Eigen::Isometry3d away = Eigen::Isometry3d::Identity();
  away.linear() = Eigen::AngleAxisd(M_PI, Eigen::Vector3d::UnitY()).matrix();
  const Eigen::Isometry3d first = test::look_from(scene.view.eye, scene.view.target);
  std::vector<VertexMap> vertices = w.vertices;
  vertices.push_back(compute_vertex_map(render(scene, camera, first * away).frame.depth, camera));
  const std::vector<Eigen::Isometry3d> start = {w.truth[0], perturbed(w.truth[1], 0.01, 1.0), away};
  const RefinementResult r = IcpBundle().refine(vertices, camera, start);
  print_report(r.report);
  EXPECT_EQ(r.report.verdict, RefinementVerdict::kNoOverlap) << to_string(r.report.verdict);
  EXPECT_EQ(r.report.isolated, std::vector<int>{2});
  EXPECT_EQ(r.report.seen[1], 0);
  EXPECT_TRUE(bitwise_equal(r.poses[2], start[2]));
  EXPECT_TRUE(bitwise_equal(r.poses[0], start[0]));
  const test::PoseError e = pose_error(r.poses[1], w.truth[1]);
  std::printf("frame 2: %.3g mm, %.3g deg\n", e.translation * 1e3, e.rotation);
  EXPECT_LT(e.translation, 0.2e-3);
  EXPECT_LT(e.rotation, 0.01);
}

// A window of three views of one plane: its poses are not observed (moving along the plane or
// turning about its normal changes no residual), so the verdict is degenerate, not converged,
// and the pipeline keeps the front end's poses. On the room the same window is well observed
// (measured: plane 7.5e-13, room 9.1e-3; the threshold is 1e-4).
TEST(IcpBundle, AWindowOnOnePlaneIsDegenerate) {
  const JointTestWindow plane = render_window(3, 160, "none", 7, "single_plane");
  std::vector<Eigen::Isometry3d> start = plane.truth;
  for (int j = 1; j < 3; ++j)
    start[j] = perturbed(plane.truth[j], 0.005, 0.5, j);
  const RefinementResult r = IcpBundle().refine(plane.vertices, plane.camera, start);
  print_report(r.report);
  EXPECT_EQ(r.report.verdict, RefinementVerdict::kDegenerate) << to_string(r.report.verdict);
  EXPECT_LT(r.report.degeneracy, IcpBundleParams{}.degeneracy_threshold);

  const JointTestWindow room = render_window(3, 160);
  const RefinementResult good = IcpBundle().refine(room.vertices, room.camera, room.truth);
  print_report(good.report);
  std::printf("degeneracy: plane %.3g, room %.3g\n", r.report.degeneracy, good.report.degeneracy);
  EXPECT_TRUE(usable(good.report.verdict)) << to_string(good.report.verdict);
  EXPECT_GT(good.report.degeneracy, 10 * IcpBundleParams{}.degeneracy_threshold);
}

// Frames 2 and 3 start 25 cm along the reference camera's axis from where frame 1 sees them, but
// right for each other: their pairs with frame 1 pass the overlap test by projection, yet every
// correspondence is farther apart than max_distance (10 cm). A solve then has only the pair
// (2, 3), which ties nothing to the gauge: both are reported isolated and returned as given,
// not solved against each other alone (held by nothing but the damping).
TEST(IcpBundle, FramesTiedToTheGaugeByNoSolvedPairAreHeld) {
  const JointTestWindow w = render_window(3, 160);
  Eigen::Isometry3d shift = Eigen::Isometry3d::Identity();
  shift.translation() = Eigen::Vector3d(0.0, 0.0, 0.25);
  const std::vector<Eigen::Isometry3d> start = {w.truth[0], shift * w.truth[1], shift * w.truth[2]};
  const RefinementResult r = IcpBundle().refine(w.vertices, w.camera, start);
  print_report(r.report);
  EXPECT_EQ(r.report.verdict, RefinementVerdict::kNoOverlap) << to_string(r.report.verdict);
  EXPECT_EQ(r.report.isolated, (std::vector<int>{1, 2}));
  for (int j = 0; j < 3; ++j)
    EXPECT_TRUE(bitwise_equal(r.poses[j], start[j])) << "pose " << j;
}

// Two frames that see the room through the same 16-px strip of columns, frame 1 started where
// the reference is (3 cm / 1° off): the strips pair pixel for pixel there, and fewer pairs
// survive at the true motion (measured 110 and 110 against 84 and 87). With min_pair_terms
// between the two the first solve has its pairs, but it takes frame 1 where none is left
// (measured 47 mm / 1.0° off, farther than the start): frame 1 is isolated (no_overlap) and
// returned as given, and the window says no term is left.
TEST(IcpBundle, AFrameASolveTakesWhereNothingPairsIsReturnedAsGiven) {
  const JointTestWindow w = render_window(2, 160);
  std::vector<VertexMap> strips = w.vertices;
  for (VertexMap& v : strips)
    for (int y = 0; y < v.height(); ++y)
      for (int x = 0; x < v.width(); ++x)
        if (x < 70 || x >= 86) v(x, y) = invalid_vector();
  IcpBundleParams p;
  const BundleFrame f0 = make_bundle_frame(strips[0], p), f1 = make_bundle_frame(strips[1], p);
  const auto pairs = [&](const Eigen::Isometry3d& T_1) {  // terms of (0, 1) and (1, 0)
    return std::array<std::size_t, 2>{
        associate_pair(f0, f1, T_1.inverse(), w.camera, p).correspondences.size(),
        associate_pair(f1, f0, T_1, w.camera, p).correspondences.size()};
  };
  const auto at_start = pairs(Eigen::Isometry3d::Identity()), at_truth = pairs(w.truth[1]);
  std::printf("pair terms at the start %zu, %zu; at the truth %zu, %zu\n", at_start[0], at_start[1],
              at_truth[0], at_truth[1]);
  p.min_pair_terms = static_cast<int>(std::max(at_truth[0], at_truth[1])) + 1;
  ASSERT_LE(p.min_pair_terms, static_cast<int>(std::min(at_start[0], at_start[1])));
  const std::vector<Eigen::Isometry3d> start(2, Eigen::Isometry3d::Identity());
  const RefinementResult r = IcpBundle(p).refine(strips, w.camera, start);
  print_report(r.report);
  EXPECT_EQ(r.report.verdict, RefinementVerdict::kNoOverlap) << to_string(r.report.verdict);
  EXPECT_EQ(r.report.isolated, std::vector<int>{1});
  EXPECT_EQ(r.report.seen[0], 0);
  EXPECT_EQ(r.report.terms, 0);
  EXPECT_EQ(r.report.cost.size(), 2u);  // one solve
  EXPECT_TRUE(bitwise_equal(r.poses[1], start[1]));
  EXPECT_EQ(r.report.residual_variance, 0.0);
}

// Ceres' GradientChecker differentiates Evaluate numerically and compares both Jacobians in the
// manifold's tangent space, at random poses and correspondences.
TEST(PointToPlaneCost, AnalyticJacobianMatchesNumeric) {
  std::mt19937 rng(3);
  std::uniform_real_distribution<double> u(-1.0, 1.0);
  const auto random_vector = [&] { return Eigen::Vector3d(u(rng), u(rng), u(rng)); };
  PoseManifold manifold;
  const std::vector<const ceres::Manifold*> manifolds = {&manifold, &manifold};
  ceres::NumericDiffOptions numeric;
  for (int trial = 0; trial < 20; ++trial) {
    BundleCorrespondence c{random_vector() + Eigen::Vector3d(0, 0, 2), random_vector(),
                           random_vector().normalized()};
    const PointToPlaneCost cost(c);
    Vector6d xi_i, xi_j;
    xi_i << random_vector(), random_vector();
    xi_j << random_vector(), random_vector();
    double pi[7], pj[7];
    to_pose_block(se3_exp(xi_i), pi);
    to_pose_block(se3_exp(xi_j), pj);
    const double* parameters[] = {pi, pj};
    ceres::GradientChecker checker(&cost, &manifolds, numeric);
    ceres::GradientChecker::ProbeResults results;
    EXPECT_TRUE(checker.Probe(parameters, 1e-7, &results)) << results.error_log;
    // The residual itself: e = nᵀ (T_j⁻¹ T_i X − q).
    const double e = c.n.dot(se3_exp(xi_j).inverse() * se3_exp(xi_i) * c.X - c.q);
    EXPECT_NEAR(results.residuals[0], e, 1e-12);
  }
}

TEST(IcpBundle, RejectsBadInputAndParameters) {
  const JointTestWindow w = render_window(2, 160);
  const JointTestWindow small = render_window(1, 80);
  const IcpBundle bundle;
  EXPECT_THROW(bundle.refine({w.vertices[0]}, w.camera, {w.truth[0]}), std::invalid_argument);
  EXPECT_THROW(bundle.refine({w.vertices[0], small.vertices[0]}, w.camera, w.truth),
               std::invalid_argument);
  EXPECT_THROW(bundle.refine(w.vertices, w.camera, {w.truth[1], w.truth[1]}),
               std::invalid_argument);  // the gauge must be I
  EXPECT_THROW(bundle.refine(w.vertices, w.camera, {w.truth[0]}), std::invalid_argument);
  Eigen::Isometry3d scaled = w.truth[1];
  scaled.linear() *= 2.0;
  EXPECT_THROW(bundle.refine(w.vertices, w.camera, {w.truth[0], scaled}),
               std::invalid_argument);  // not a rigid motion
  IcpBundleParams bad;
  bad.min_overlap = 0.0;
  EXPECT_THROW(IcpBundle{bad}, InputError);
  EXPECT_EQ(make_refiner("icp-bundle")->name(), "icp-bundle");
}

}  // namespace
}  // namespace jpcr
