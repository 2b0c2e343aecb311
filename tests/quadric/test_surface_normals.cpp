// estimate_normals takes a separable shortcut (column sums) for windows that drop no point, and
// plane_normal, the kernel the GPU runs, for the others: the two must give the same normals.
// Fresh random frames each run (the seed is printed; JPCR_TEST_SEED replays it), with holes.
#include <cmath>
#include <cstdio>
#include <random>

#include <gtest/gtest.h>

#include "cuda/random_frames.hpp"
#include "jpcr/quadric/plane_normal_kernel.hpp"
#include "jpcr/quadric/surface_normals.hpp"

namespace jpcr {
namespace {

struct Agreement {
  int pixels = 0, valid = 0, validity_differs = 0;
  double worst_angle = 0.0;  // rad
};

Agreement compare_with_plane_normal(const VertexMap& vertices, const NormalEstimationParams& p) {
  const NormalMap normals = estimate_normals(vertices, p);
  const VertexView view{vertices.data(), vertices.width(), vertices.height()};
  Agreement a;
  for (int v = 0; v < vertices.height(); ++v)
    for (int u = 0; u < vertices.width(); ++u) {
      const Eigen::Vector3f reference = plane_normal(view, u, v, p);
      const Eigen::Vector3f& n = normals(u, v);
      ++a.pixels;
      if (is_valid(reference) != is_valid(n)) ++a.validity_differs;
      if (!is_valid(reference) || !is_valid(n)) continue;
      ++a.valid;
      const double angle = std::atan2(n.cast<double>().cross(reference.cast<double>()).norm(),
                                      n.cast<double>().dot(reference.cast<double>()));
      a.worst_angle = std::max(a.worst_angle, angle);
    }
  return a;
}

// Random holes, as real depth has them: a fraction of the vertices become NaN.
void punch_holes(VertexMap& vertices, double fraction, std::uint64_t seed) {
  std::mt19937_64 rng(seed);
  std::bernoulli_distribution hole(fraction);
  for (int v = 0; v < vertices.height(); ++v)
    for (int u = 0; u < vertices.width(); ++u)
      if (hole(rng)) vertices(u, v) = invalid_vector();
}

// Both sum the same window points in double; the shortcut's moments are uncentred, which costs
// about log10(|X|² / window²) ≈ 5 of double's 16 digits, and both round the normal to float
// (6e-8). 1e-5 rad leaves two orders of magnitude; validity must agree exactly.
TEST(SurfaceNormals, ShortcutAgreesWithPlaneNormal) {
  const std::uint64_t seed = test::test_seed();
  std::printf("seed %llu (JPCR_TEST_SEED replays it)\n", static_cast<unsigned long long>(seed));
  NormalEstimationParams tight;
  tight.max_depth_jump = 0.01f;  // many windows drop points: the fallback
  NormalEstimationParams wide;
  wide.half_window = 5;
  NormalEstimationParams small;
  small.half_window = 1;
  small.min_points = 9;
  for (const auto& [w, h] : {std::pair{160, 120}, std::pair{320, 240}}) {
    const SyntheticFrame f = test::random_frame(seed, w, h);
    VertexMap vertices = compute_vertex_map(f.frame.depth, f.frame.camera);
    punch_holes(vertices, 0.01, seed);
    for (const NormalEstimationParams& p : {NormalEstimationParams{}, tight, wide, small}) {
      const Agreement a = compare_with_plane_normal(vertices, p);
      std::printf("%dx%d h=%d jump %.2f: %d of %d valid, validity differs at %d, worst %.2e rad\n",
                  w, h, p.half_window, p.max_depth_jump, a.valid, a.pixels, a.validity_differs,
                  a.worst_angle);
      EXPECT_GT(a.valid, a.pixels / 2) << "seed " << seed;
      EXPECT_EQ(a.validity_differs, 0) << "seed " << seed;
      EXPECT_LT(a.worst_angle, 1e-5) << "seed " << seed;
    }
  }
}

// More points required than a window holds: no normal anywhere, by either path.
TEST(SurfaceNormals, TooFewPointsForTheWindowGivesNoNormals) {
  const SyntheticFrame f = test::random_frame(7, 80, 60);
  const VertexMap vertices = compute_vertex_map(f.frame.depth, f.frame.camera);
  NormalEstimationParams p;
  p.min_points = 50;  // a 7x7 window has 49
  const NormalMap normals = estimate_normals(vertices, p);
  for (int v = 0; v < normals.height(); ++v)
    for (int u = 0; u < normals.width(); ++u)
      EXPECT_FALSE(is_valid(normals(u, v))) << u << "," << v;
}

}  // namespace
}  // namespace jpcr
