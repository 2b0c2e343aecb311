// The host-side measurement behind the GPU Quad IT's choice of double (cuda/NOTES.md): the
// per-pixel reference kernel fit_quadric_pixel run in float and in double on the same fresh
// random frames and normals. Float sums are accurate (1e-5 to 3e-5 1/m RMS where both take the
// same steps), but the step-acceptance test (cost > previous cost) flips at tens to hundreds of
// pixels per frame and moves κ there by up to ~4 1/m: measured RMS 1e-5 to 1.3e-2 1/m, over the
// 1e-4 1/m that the GPU parity test asks. Double with and without FMA contraction (GPU against
// host) differs by 1e-14.
// This test prints the measurement and keeps float a sane fallback (CudaPrecision::kFloat).
#include <cmath>
#include <cstdio>

#include <gtest/gtest.h>

#include "cuda/random_frames.hpp"
#include "jpcr/quadric/quadric_fit.hpp"

namespace jpcr {
namespace {

// A κ difference above this is a flipped step decision, not float rounding (1/m).
constexpr double kFlipped = 1e-3;

struct Agreement {
  double rms = 0.0;           // RMS of κ differences over pixels valid in both (1/m)
  double rms_agreeing = 0.0;  // the same over the pixels that took the same steps (1/m)
  double max_abs = 0.0;       // largest κ difference (1/m)
  int flipped = 0;            // pixels whose κ differs by more than kFlipped
  int status_differ = 0;      // pixels whose status differs
  int valid = 0;              // pixels valid in both
  int pixels = 0;
};

Agreement float_against_double(const SyntheticFrame& f, const QuadricParams& params) {
  const VertexMap vertices = compute_vertex_map(f.frame.depth, f.frame.camera);
  const NormalMap normals = estimate_normals(vertices, params.normals);
  const NeighbourhoodPattern pattern = params.pattern.for_width(vertices.width());
  const VertexView view{vertices.data(), vertices.width(), vertices.height()};
  Agreement a;
  a.pixels = vertices.width() * vertices.height();
  double sum = 0.0, sum_agreeing = 0.0, max_abs = 0.0;
  int status_differ = 0, valid = 0, flipped = 0;
#pragma omp parallel for reduction(+ : sum, sum_agreeing, status_differ, valid, flipped) \
    reduction(max : max_abs) \
    schedule(dynamic, 4)
  for (int v = 0; v < vertices.height(); ++v) {
    for (int u = 0; u < vertices.width(); ++u) {
      Quadric qf;
      Quadricd qd;
      const QuadricStatus sf = fit_quadric_pixel<float>(
          view, pattern.offsets.data(), pattern.size(), u, v, normals(u, v), params.fit, qf);
      const QuadricStatus sd = fit_quadric_pixel<double>(
          view, pattern.offsets.data(), pattern.size(), u, v, normals(u, v), params.fit, qd);
      if (sf != sd) ++status_differ;
      if (sf != QuadricStatus::kValid || sd != QuadricStatus::kValid) continue;
      const Eigen::Vector2d d = principal_curvatures(qf.a, qf.b, qf.c).cast<double>() -
                                principal_curvatures(qd.a, qd.b, qd.c);
      sum += d.squaredNorm();
      const double worst = d.cwiseAbs().maxCoeff();
      max_abs = std::max(max_abs, worst);
      if (worst > kFlipped) {
        ++flipped;
      } else {
        sum_agreeing += d.squaredNorm();
      }
      ++valid;
    }
  }
  a.max_abs = max_abs;
  a.status_differ = status_differ;
  a.valid = valid;
  a.flipped = flipped;
  a.rms = valid > 0 ? std::sqrt(sum / (2.0 * valid)) : NAN;
  a.rms_agreeing = valid > flipped ? std::sqrt(sum_agreeing / (2.0 * (valid - flipped))) : NAN;
  return a;
}

TEST(ReferenceKernelPrecision, FloatAgreesWithDoubleOnRandomFrames) {
  const std::uint64_t seed = test::test_seed();
  std::printf("seed %llu (JPCR_TEST_SEED=%llu replays it)\n", static_cast<unsigned long long>(seed),
              static_cast<unsigned long long>(seed));
  const QuadricParams params;
  for (const auto& [w, h] : {std::pair{320, 240}}) {
    for (std::uint64_t k = 0; k < 3; ++k) {
      const Agreement a = float_against_double(test::random_frame(seed + k, w, h), params);
      std::printf(
          "%dx%d frame %llu: float vs double kappa RMS %.3g 1/m (%.3g where the steps agree), "
          "max %.3g 1/m, %d pixels flipped, status differs at %d of %d pixels, %d valid in "
          "both\n",
          w, h, static_cast<unsigned long long>(seed + k), a.rms, a.rms_agreeing, a.max_abs,
          a.flipped, a.status_differ, a.pixels, a.valid);
      EXPECT_GT(a.valid, a.pixels / 3);
      // The RMS over all pixels is one flipped pixel's κ jump over √valid (measured up to
      // 0.013 1/m, from a 4 1/m jump), so it is not asserted. Over 90 frames: the pixels that
      // took the same steps agree to at most 3.3e-5 1/m RMS, and at most 0.8 % of the pixels
      // moved by more than kFlipped.
      EXPECT_LT(a.rms_agreeing, 1e-4) << "seed " << seed + k;
      EXPECT_LT(a.flipped, a.valid / 50) << "seed " << seed + k;
      EXPECT_LE(a.status_differ, a.pixels / 1000) << "seed " << seed + k;
    }
  }
}

}  // namespace
}  // namespace jpcr
