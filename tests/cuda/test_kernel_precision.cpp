// The host-side measurement behind the GPU Quad IT's choice of double (cuda/NOTES.md): the
// per-pixel reference kernel fit_quadric_pixel run in float and in double on the same fresh
// random frames and normals. Float sums are accurate (about 1e-6 1/m RMS where both take the same
// steps), but the step-acceptance test (cost > previous cost) flips at a few pixels per frame and
// moves κ there by up to ~1 1/m: measured RMS 1e-3 to 3e-3 1/m, over the 1e-4 1/m that the GPU
// parity test asks. Double with and without FMA contraction (GPU against host) differs by 1e-14.
// This test prints the measurement and keeps float a sane fallback (CudaPrecision::kFloat).
#include <cmath>
#include <cstdio>

#include <gtest/gtest.h>

#include "cuda/random_frames.hpp"
#include "jpcr/quadric/quadric_fit.hpp"

namespace jpcr {
namespace {

struct Agreement {
  double rms = 0.0;       // RMS of κ differences over pixels valid in both (1/m)
  double max_abs = 0.0;   // largest κ difference (1/m)
  int status_differ = 0;  // pixels whose status differs
  int valid = 0;          // pixels valid in both
  int pixels = 0;
};

Agreement float_against_double(const SyntheticFrame& f, const QuadricParams& params) {
  const VertexMap vertices = compute_vertex_map(f.frame.depth, f.frame.camera);
  const NormalMap normals = estimate_normals(vertices, params.normals);
  const NeighbourhoodPattern pattern = params.pattern.for_width(vertices.width());
  const VertexView view{vertices.data(), vertices.width(), vertices.height()};
  Agreement a;
  a.pixels = vertices.width() * vertices.height();
  double sum = 0.0, max_abs = 0.0;
  int status_differ = 0, valid = 0;
#pragma omp parallel for reduction(+ : sum, status_differ, valid) reduction(max : max_abs) \
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
      max_abs = std::max(max_abs, d.cwiseAbs().maxCoeff());
      ++valid;
    }
  }
  a.max_abs = max_abs;
  a.status_differ = status_differ;
  a.valid = valid;
  a.rms = valid > 0 ? std::sqrt(sum / (2.0 * valid)) : NAN;
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
          "%dx%d frame %llu: float vs double kappa RMS %.3g 1/m, max %.3g 1/m, status "
          "differs at %d of %d pixels, %d valid in both\n",
          w, h, static_cast<unsigned long long>(seed + k), a.rms, a.max_abs, a.status_differ,
          a.pixels, a.valid);
      EXPECT_GT(a.valid, a.pixels / 3);
      EXPECT_LT(a.rms, 1e-2) << "seed " << seed + k;
      EXPECT_LE(a.status_differ, a.pixels / 1000) << "seed " << seed + k;
    }
  }
}

}  // namespace
}  // namespace jpcr
