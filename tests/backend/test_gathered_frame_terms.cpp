// The CPU's gathered, vectorised per-frame sums (backend/gathered_frame_terms.hpp) against the
// sample-by-sample reference of joint_pixel_kernel.hpp that the GPU runs: in double lanes they
// are the same numbers up to rounding (the P J_loc factorisation is exact), in float lanes up to
// float rounding of centred coordinates (whole steps: test_gathered_step.cpp).
#include <algorithm>
#include <cmath>

#include <gtest/gtest.h>

#include "joint_test_windows.hpp"
#include "jpcr/backend/gathered_frame_terms.hpp"
#include "jpcr/backend/joint_params.hpp"
#include "jpcr/backend/joint_system.hpp"
#include "jpcr/quadric/quadric_fit.hpp"

namespace jpcr {
namespace {

using test::JointTestWindow;
using test::motion;
using test::perturbed;
using test::render_window;

// The worst difference of the blocks, each relative to its Cauchy-Schwarz scale (a sum Σ w x yᵀ
// is bounded by √(Σ w |x|²) √(Σ w |y|²)), so that sums which nearly cancel, such as the gradient
// at a good fit, are judged against the size of their terms rather than their small total.
double relative_difference(const FrameTerms<double>& a, const FrameTerms<double>& b) {
  const double c = b.C.trace(), A = b.A.trace(), r = b.cost;
  auto diff = [](const auto& x, const auto& y) { return (x - y).norm(); };
  const Matrix6d Ca = a.C.selfadjointView<Eigen::Lower>(), Cb = b.C.selfadjointView<Eigen::Lower>();
  const Matrix6d Aa = a.A.selfadjointView<Eigen::Lower>(), Ab = b.A.selfadjointView<Eigen::Lower>();
  return std::max({diff(Ca, Cb) / c, diff(a.g_gamma, b.g_gamma) / std::sqrt(c * r),
                   diff(a.B, b.B) / std::sqrt(A * c), diff(Aa, Ab) / A,
                   diff(a.g_xi, b.g_xi) / std::sqrt(A * r), std::abs(a.cost - b.cost) / r});
}

// Every 17th valid pixel of a noisy pair, frame 2 perturbed 1 cm / 1°: the frame-2 terms of the
// gathered sampler (Lane) against accumulate_frame_terms; returns the worst relative difference.
template <typename Lane>
double worst_frame_terms_difference(int& compared, float ray_min_cosine) {
  const JointTestWindow w = render_window(2, 320, "range:1");
  const QuadricMap map = QuadricFit().estimate(w.vertices[0]);
  const NeighbourhoodPattern pattern = QuadricParams{}.pattern.for_width(w.camera.width);
  JointParams joint;
  joint.ray_min_cosine = ray_min_cosine;
  const JointTermParams params = joint.terms(true);
  const PinholeProjection cam{w.camera.fx, w.camera.fy, w.camera.cx, w.camera.cy};
  const VertexView view2{w.vertices[1].data(), w.vertices[1].width(), w.vertices[1].height()};
  const RigidMotion<double> T = motion(perturbed(w.truth[1], 0.01, 1.0));
  GatheredSampler<Lane> sampler(pattern.size());
  double worst = 0.0;
  compared = 0;
  for (std::size_t i = 0; i < map.status.size(); i += 17) {
    const int u = static_cast<int>(i % w.camera.width), v = static_cast<int>(i / w.camera.width);
    if (!map.valid(u, v)) continue;
    // The factorisation J_ξ = P J_loc holds for an orthonormal R; a float R cast to double is
    // orthonormal only to 1e-7, which would show as a 1e-7 difference.
    Quadricd q = map.quadrics(u, v).template cast<double>();
    q.R = orthonormalize(q.R);
    int su = 0, sv = 0;
    if (!associate(q.center, T, view2, cam, params, su, sv)) continue;
    const SampleGate<double> limits = SampleGate<double>::at(params.fit, q.center);
    FrameTerms<double> reference, gathered;
    const double foot = params.ray_min_cos2<double>();
    accumulate_frame_terms(q, view2, T, true, foot, pattern.offsets.data(), pattern.size(), su, sv,
                           limits, reference);
    if (reference.count < params.min_frame_terms) continue;
    sampler.accumulate(q, view2, T, true, foot, pattern.offsets.data(), pattern.size(), su, sv,
                       limits, gathered);
    int count = 0;
    const double cost = sampler.cost(q, q, view2, T, T, pattern.offsets.data(), pattern.size(), su,
                                     sv, limits, count);
    EXPECT_EQ(gathered.count, reference.count);
    EXPECT_EQ(count, reference.count);
    EXPECT_NEAR(cost, reference.cost, 1e-5 * reference.cost);
    // The step test's cost: residuals at T and q, the weights held at another motion (5 cm
    // away) and another quadric (offset 4 mm, curved), as frame_cost computes them sample by
    // sample.
    RigidMotion<double> moved = T;
    moved.t += Eigen::Vector3d(0.05, -0.03, 0.02);
    Quadricd q_weight = q;
    q_weight.t_z += 0.004;
    q_weight.a += 2.0;
    int held_count = 0, direct_count = 0;
    const double held = sampler.cost(q, q_weight, view2, T, moved, pattern.offsets.data(),
                                     pattern.size(), su, sv, limits, held_count);
    const double direct =
        frame_cost(q, q_weight, view2, T, moved, pattern.offsets.data(),
                   static_cast<int>(pattern.size()), su, sv, limits, direct_count);
    EXPECT_EQ(held_count, direct_count);
    EXPECT_NEAR(held, direct, 1e-5 * direct);
    EXPECT_NE(held, cost);  // the distances and residuals moved, so the weights did
    // Held at q and T themselves, the held cost is the cost.
    EXPECT_NEAR(frame_cost(q, Quadricd(q), view2, T, T, pattern.offsets.data(),
                           static_cast<int>(pattern.size()), su, sv, limits, direct_count),
                reference.cost, 1e-12 * reference.cost);
    worst = std::max(worst, relative_difference(gathered, reference));
    ++compared;
  }
  return worst;
}

// Both ways of taking the lever arms: at the samples (the default) and at the rays' foot points
// (JointParams::ray_min_cosine 0.2).
class GatheredFrameTerms : public ::testing::TestWithParam<float> {};

TEST_P(GatheredFrameTerms, DoubleLanesEqualTheReferenceSums) {
  int compared = 0;
  const double worst = worst_frame_terms_difference<double>(compared, GetParam());
  std::printf("double lanes, %d quadrics: worst relative difference %.2e\n", compared, worst);
  EXPECT_GT(compared, 1000);
  EXPECT_LT(worst, 1e-11);  // the same sums in another order: rounding only (measured 2e-13)
}

TEST_P(GatheredFrameTerms, FloatLanesMatchTheReferenceSumsToFloatRounding) {
  int compared = 0;
  const double worst = worst_frame_terms_difference<float>(compared, GetParam());
  std::printf("float lanes, %d quadrics: worst relative difference %.2e\n", compared, worst);
  EXPECT_GT(compared, 1000);
  // Float rounding (6e-8) of the centred coordinates and of ~100 products per sum (measured
  // 3e-7 against the terms' scale).
  EXPECT_LT(worst, 1e-5);
}

INSTANTIATE_TEST_SUITE_P(LeverArms, GatheredFrameTerms, ::testing::Values(0.0f, 0.2f));

}  // namespace
}  // namespace jpcr
