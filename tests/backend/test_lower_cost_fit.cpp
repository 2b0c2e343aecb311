// keep_lower_cost_fits (backend/lower_cost_fit.hpp): Quad IT's step test per quadric over the
// window, after the joint loop. It restores exactly the fits its start beats, leaves the poses
// alone, and under range noise lowers J-ftf's curvature error.
#include <cmath>
#include <cstdio>
#include <stdexcept>

#include <gtest/gtest.h>

#include "joint_test_windows.hpp"
#include "jpcr/backend/fixed_quadric_alignment.hpp"
#include "jpcr/backend/joint_frame_to_frame.hpp"
#include "jpcr/backend/joint_window.hpp"
#include "jpcr/backend/lower_cost_fit.hpp"
#include "jpcr/io/synthetic_sequence.hpp"
#include "jpcr/quadric/quadric_fit.hpp"

namespace jpcr {
namespace {

using test::JointTestWindow;
using test::render_window;

// The same status and, where valid, the same fit to the bit (an invalid pixel's curvature is
// NaN).
bool same_fit(const QuadricMap& a, const QuadricMap& b, int u, int v) {
  if (a.status(u, v) != b.status(u, v)) return false;
  if (!a.valid(u, v)) return true;
  const Quadric &p = a.quadrics(u, v), &q = b.quadrics(u, v);
  return p.R == q.R && p.center == q.center && p.t_z == q.t_z && p.a == q.a && p.b == q.b &&
         p.c == q.c && a.curvature(u, v) == b.curvature(u, v) &&
         a.direction(u, v) == b.direction(u, v);
}

// A saddle of ±20 1/m on a quadric fitted to a noise-free surface raises its gated cost in every
// frame: 2.5 cm from p̄ it puts the surface 6 mm off.
void bend(QuadricMap& map, int u, int v) {
  Quadric q = map.quadrics(u, v);
  q.a += 20.0f;
  q.c -= 20.0f;
  map.set(u, v, q);
}

// Noise-free pair at the true poses. Where the refined map holds a bent copy of the start, the
// start comes back bit for bit; where the start is the bent one, the refined fit stays; where
// both are the same, nothing changes and nothing is counted.
TEST(LowerCostFit, RestoresExactlyTheStartsThatFitTheWindowBetter) {
  const JointTestWindow w = render_window(2, 160);
  const JointParams params;
  const QuadricMap fit = QuadricFit(params.quadric).estimate(w.vertices[0]);
  QuadricMap start = fit, refined = fit;
  int bent_refined = 0, bent_start = 0;
  for (int v = 0; v < fit.height(); ++v)
    for (int u = 0; u < fit.width(); ++u) {
      if (!fit.valid(u, v)) continue;
      const int k = v * fit.width() + u;
      if (k % 7 == 0) {
        bend(refined, u, v);
        ++bent_refined;
      } else if (k % 7 == 1) {
        bend(start, u, v);
        ++bent_start;
      }
    }
  ASSERT_GT(bent_refined, 1000);
  const QuadricMap before = refined;
  const int restored = keep_lower_cost_fits(w.vertices, w.camera, w.truth, params, start, refined);
  std::printf("%d of %d bent fits restored (%d bent starts)\n", restored, bent_refined, bent_start);
  EXPECT_EQ(restored, bent_refined);
  for (int v = 0; v < fit.height(); ++v)
    for (int u = 0; u < fit.width(); ++u) {
      const int k = v * fit.width() + u;
      if (fit.valid(u, v) && k % 7 == 0)
        ASSERT_TRUE(same_fit(refined, start, u, v)) << u << "," << v;
      else
        ASSERT_TRUE(same_fit(refined, before, u, v)) << u << "," << v;
    }
}

TEST(LowerCostFit, ChecksTheSizes) {
  const JointTestWindow w = render_window(2, 160);
  const JointParams params;
  const QuadricMap fit = QuadricFit(params.quadric).estimate(w.vertices[0]);
  QuadricMap refined = fit;
  EXPECT_THROW(keep_lower_cost_fits(w.vertices, w.camera, {w.truth[0]}, params, fit, refined),
               std::invalid_argument);
  const QuadricMap small(80, 60);
  EXPECT_THROW(keep_lower_cost_fits(w.vertices, w.camera, w.truth, params, small, refined),
               std::invalid_argument);
  const JointTestWindow other = render_window(2, 80);
  EXPECT_THROW(keep_lower_cost_fits(other.vertices, w.camera, w.truth, params, fit, refined),
               std::invalid_argument);
}

double rms_curvature_error(const QuadricMap& map, const CurvatureImage& truth) {
  double sum = 0.0;
  int n = 0;
  for (int v = 0; v < map.height(); ++v)
    for (int u = 0; u < map.width(); ++u) {
      if (!map.valid(u, v) || !std::isfinite(truth(u, v).x())) continue;
      sum += (map.curvature(u, v) - truth(u, v)).squaredNorm();
      n += 2;
    }
  return n > 0 ? std::sqrt(sum / n) : NAN;
}

// J-ftf's pair 0-1 of the report's torus_saddle walk (jpcr_synth --trajectory walk --seed 1,
// 640x480) under 1 % range noise, n₀ and the gate at 3 σ as the report's pose runs, refined from
// the true poses. Measured RMS curvature error of frame 1 over its valid pixels: Quad IT 4.089,
// J-ftf 4.278, with the test 4.013 1/m (8685 quadrics restored; cylinders_boxes 4.967 → 4.797,
// room_spheres 3.732 → 3.553). The bound asks for 2 % less.
TEST(LowerCostFit, LowersJftfsCurvatureErrorUnderRangeNoise) {
  SyntheticSequenceOptions o;
  o.scene = "torus_saddle";
  o.frames = 2;
  o.noise = "range:1";
  o.seed = 1;
  const SyntheticSequence walk = make_synthetic_sequence(o);
  const SyntheticFrame first = walk.render(0);
  const std::vector<VertexMap> vertices = {compute_vertex_map(first.frame.depth, walk.camera()),
                                           compute_vertex_map(walk.load(1).depth, walk.camera())};
  const std::vector<Eigen::Isometry3d> truth = {
      Eigen::Isometry3d::Identity(), walk.ground_truth(0)->inverse() * *walk.ground_truth(1)};
  JointParams paper;
  paper.quadric.fit.fair_n0_per_range = paper.quadric.fit.gate_per_range = 0.03f;
  paper.keep_lower_cost_fit = false;
  const QuadricMap initial = QuadricFit(paper.quadric).estimate(vertices[0]);
  const RefinementResult r =
      JointFrameToFrame(paper).refine(vertices, walk.camera(), truth, initial);
  EXPECT_EQ(r.report.quad_it_fits_restored, 0);
  QuadricMap kept = r.quadrics;
  const int restored = keep_lower_cost_fits(vertices, walk.camera(), r.poses, paper, initial, kept);
  int differ = 0;
  for (int v = 0; v < initial.height(); ++v)
    for (int u = 0; u < initial.width(); ++u)
      if (!same_fit(kept, r.quadrics, u, v)) {
        ++differ;
        ASSERT_TRUE(same_fit(kept, initial, u, v)) << u << "," << v;
      }
  const double e_start = rms_curvature_error(initial, first.curvature),
               e_paper = rms_curvature_error(r.quadrics, first.curvature),
               e_kept = rms_curvature_error(kept, first.curvature);
  std::printf("curvature RMS: Quad IT %.4f, J-ftf %.4f, with the test %.4f 1/m (%d restored)\n",
              e_start, e_paper, e_kept, restored);
  EXPECT_EQ(differ, restored);
  EXPECT_GT(restored, 0);
  EXPECT_LT(e_kept, 0.98 * e_paper);
}

// The refiners apply it when keep_lower_cost_fit is set (the default), J-ftf and J-full, and
// count what they restored; the poses are those without it (up to the rounding of the parallel
// sums, which differ from run to run). Q-full has no quadric step to test.
TEST(LowerCostFit, TheRefinersApplyItAndLeaveThePoses) {
  const JointTestWindow w = render_window(3, 160, "range:1");
  JointParams params;
  params.quadric.fit.fair_n0_per_range = params.quadric.fit.gate_per_range = 0.03f;
  JointParams paper = params;
  paper.keep_lower_cost_fit = false;
  const QuadricMap initial = QuadricFit(params.quadric).estimate(w.vertices[0]);
  const std::vector<VertexMap> pair = {w.vertices[0], w.vertices[1]};
  const std::vector<Eigen::Isometry3d> start = {w.truth[0], w.truth[1]};
  const RefinementResult on = JointFrameToFrame(params).refine(pair, w.camera, start, initial);
  const RefinementResult off = JointFrameToFrame(paper).refine(pair, w.camera, start, initial);
  std::printf("j-ftf restored %d\n", on.report.quad_it_fits_restored);
  EXPECT_TRUE(on.poses[1].isApprox(off.poses[1], 1e-9));
  QuadricMap kept = off.quadrics;
  const int restored = keep_lower_cost_fits(pair, w.camera, off.poses, params, initial, kept);
  EXPECT_GT(on.report.quad_it_fits_restored, 0);
  EXPECT_NEAR(on.report.quad_it_fits_restored, restored, 0.02 * restored + 2);

  const RefinementResult full = JointWindow(params).refine(w.vertices, w.camera, w.truth, initial);
  std::printf("j-full restored %d\n", full.report.quad_it_fits_restored);
  EXPECT_GT(full.report.quad_it_fits_restored, 0);
  EXPECT_EQ(FixedQuadricAlignment(params)
                .refine(w.vertices, w.camera, w.truth, initial)
                .report.quad_it_fits_restored,
            0);
}

}  // namespace
}  // namespace jpcr
