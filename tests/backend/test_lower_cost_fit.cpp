// keep_lower_cost_fits (backend/lower_cost_fit.hpp): the cost half of Quad IT's step test, per
// quadric over the window, after the joint loop. It restores exactly the fits its start beats, over
// every frame of the window; test_lower_cost_fit_refiners.cpp runs it inside the refiners.
#include <cmath>
#include <cstdio>
#include <random>
#include <stdexcept>

#include <gtest/gtest.h>

#include "joint_test_windows.hpp"
#include "jpcr/backend/lower_cost_fit.hpp"
#include "jpcr/quadric/quadric_fit.hpp"

namespace jpcr {
namespace {

using test::JointTestWindow;
using test::render_window;

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
        ASSERT_TRUE(test::same_fit(refined, start, u, v)) << u << "," << v;
      else
        ASSERT_TRUE(test::same_fit(refined, before, u, v)) << u << "," << v;
    }
}

// The other half of Quad IT's step test: where refined_map marked the refined fit
// kTooFewSamples (its step left fewer than min_samples inliers of frame 1), the start comes back
// and is counted; a fit invalid for another reason, or whose start is invalid, stays as it is.
TEST(LowerCostFit, RestoresTheStartWhereTheRefinedFitKeptTooFewSamples) {
  const JointTestWindow w = render_window(2, 160);
  const JointParams params;
  const QuadricMap start = QuadricFit(params.quadric).estimate(w.vertices[0]);
  QuadricMap refined = start;
  int too_few = 0, singular = 0, no_start = 0;
  for (int v = 0; v < start.height(); ++v)
    for (int u = 0; u < start.width(); ++u) {
      const int k = v * start.width() + u;
      if (!start.valid(u, v)) {
        if (k % 2 == 0) {  // a start without a fit has nothing to give back
          refined.set_invalid(u, v, QuadricStatus::kTooFewSamples);
          ++no_start;
        }
      } else if (k % 5 == 0) {
        refined.set_invalid(u, v, QuadricStatus::kTooFewSamples);
        ++too_few;
      } else if (k % 5 == 1) {
        refined.set_invalid(u, v, QuadricStatus::kSingular);
        ++singular;
      }
    }
  ASSERT_GT(too_few, 1000);
  ASSERT_GT(no_start, 10);
  const QuadricMap before = refined;
  const int restored = keep_lower_cost_fits(w.vertices, w.camera, w.truth, params, start, refined);
  std::printf("%d of %d too-few fits restored (%d singular, %d without a start kept)\n", restored,
              too_few, singular, no_start);
  EXPECT_EQ(restored, too_few);
  for (int v = 0; v < start.height(); ++v)
    for (int u = 0; u < start.width(); ++u) {
      const bool back = start.valid(u, v) && (v * start.width() + u) % 5 == 0;
      ASSERT_TRUE(test::same_fit(refined, back ? start : before, u, v)) << u << "," << v;
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
  EXPECT_THROW(keep_lower_cost_fits(w.vertices, other.camera, w.truth, params, fit, refined),
               std::invalid_argument);
  EXPECT_THROW(keep_lower_cost_fits({}, w.camera, {}, params, fit, refined), std::invalid_argument);
}

// Under 1 % range noise, at the true poses of a 3-frame window, against a map of the starts
// moved by random steps (some better, most worse): each pixel's decision is the one of the
// reference sums (frame_cost sample by sample in double, each other frame associated as the
// joint terms are) over every frame, up to near-ties that the float lanes may turn. A function
// that left out a frame, or mapped it with the wrong pose, would decide otherwise on many pixels.
TEST(LowerCostFit, DecidesAsTheReferenceSumsOverEveryFrame) {
  const JointTestWindow w = render_window(3, 160, "range:1");
  JointParams params;
  params.quadric.fit.fair_n0_per_range = params.quadric.fit.gate_per_range = 0.03f;
  const QuadricMap start = QuadricFit(params.quadric).estimate(w.vertices[0]);
  QuadricMap moved = start;
  std::mt19937 rng(3);
  std::normal_distribution<double> step(0.0, 1.0);
  for (int v = 0; v < start.height(); ++v)
    for (int u = 0; u < start.width(); ++u) {
      if (!start.valid(u, v)) continue;
      Quadricd q = start.quadrics(u, v).cast<double>();
      QuadricVector<double> d;
      d << 0.002 * step(rng), 0.002 * step(rng), 2e-4 * step(rng), 0.2 * step(rng), 0.2 * step(rng),
          0.2 * step(rng);
      apply_quadric_update(q, d);
      moved.set(u, v, q.cast<float>());
    }
  QuadricMap kept = moved;
  const int restored = keep_lower_cost_fits(w.vertices, w.camera, w.truth, params, start, kept);

  const JointTermParams terms = params.terms(true);
  const NeighbourhoodPattern pattern = params.quadric.pattern_for(w.camera.width);
  const PinholeProjection projection{w.camera.fx, w.camera.fy, w.camera.cx, w.camera.cy};
  int decided = 0, agree = 0, near_ties = 0, other_frames = 0, frame_1_differs = 0;
  for (int v = 0; v < start.height(); ++v)
    for (int u = 0; u < start.width(); ++u) {
      if (!start.valid(u, v) || !moved.valid(u, v)) continue;
      const Quadricd a = start.quadrics(u, v).cast<double>(),
                     b = moved.quadrics(u, v).cast<double>();
      const SampleGate<double> limits = SampleGate<double>::at(terms.fit, a.center);
      double cost_a = 0.0, cost_b = 0.0, frame_1_a = 0.0, frame_1_b = 0.0;
      for (std::size_t j = 0; j < w.vertices.size(); ++j) {
        const VertexView view{w.vertices[j].data(), w.vertices[j].width(), w.vertices[j].height()};
        const RigidMotion<double> T = test::motion(w.truth[j]);
        int su = u, sv = v, count = 0;
        if (j > 0) {
          if (!associate(a.center, T, view, projection, terms, su, sv)) continue;
          ++other_frames;
        }
        cost_a += frame_cost(a, a, view, T, T, pattern.offsets.data(),
                             static_cast<int>(pattern.size()), su, sv, limits, count);
        cost_b += frame_cost(b, b, view, T, T, pattern.offsets.data(),
                             static_cast<int>(pattern.size()), su, sv, limits, count);
        if (j == 0) {
          frame_1_a = cost_a;
          frame_1_b = cost_b;
        }
      }
      const bool took_start = test::same_fit(kept, start, u, v);
      ++decided;
      frame_1_differs += (frame_1_a < frame_1_b) != (cost_a < cost_b) ? 1 : 0;
      if (took_start == (cost_a < cost_b))
        ++agree;
      else if (std::abs(cost_a - cost_b) <= 1e-4 * (cost_a + cost_b))
        ++near_ties;
      else
        ADD_FAILURE() << u << "," << v << ": costs " << cost_a << " (start), " << cost_b
                      << " (moved), restored " << took_start;
    }
  std::printf(
      "%d decisions, %d as the reference, %d near-ties; %d restored; %d other-frame views; frame 1 "
      "alone would decide %d otherwise\n",
      decided, agree, near_ties, restored, other_frames, frame_1_differs);
  EXPECT_GT(restored, decided / 10);
  EXPECT_LT(restored, decided - decided / 10);
  EXPECT_GT(other_frames, decided);          // the other frames took part ...
  EXPECT_GT(frame_1_differs, decided / 20);  // ... and turned many decisions
  EXPECT_LT(near_ties, decided / 1000 + 1);
}

}  // namespace
}  // namespace jpcr
