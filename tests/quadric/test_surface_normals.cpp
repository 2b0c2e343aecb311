// estimate_normals takes a separable shortcut (column sums) for windows that drop no point, and
// plane_normal, the kernel the GPU runs, for the others: the two must give the same normals.
// Fresh random frames each run (the seed is printed; JPCR_TEST_SEED replays it), with holes.
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <random>

#include <Eigen/Geometry>

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

namespace jpcr {
namespace {

// smallest_eigenvector against Eigen's iterative solver on random scatter matrices: planar
// patches (λ_min ≪ λ_mid), noisy ones, near-spherical ones, and the ill-posed cases it must
// hand back or answer with any vector of the degenerate plane (a multiple of I, a double
// smallest eigenvalue).
TEST(SurfaceNormals, SmallestEigenvectorEqualsAnIterativeSolve) {
  std::mt19937 rng(17);
  std::normal_distribution<double> n(0.0, 1.0);
  int solved = 0;
  double worst = 0.0;  // angle / conditioning
  for (int trial = 0; trial < 2000; ++trial) {
    const Eigen::Quaterniond rotation =
        Eigen::Quaterniond(n(rng), n(rng), n(rng), n(rng)).normalized();
    const double spread = std::pow(10.0, -6.0 * (trial % 7) / 6.0);  // λ_min / λ_mid: 1 … 1e-6
    const Eigen::Vector3d lambda(spread * (0.5 + std::abs(n(rng))), 1.0 + std::abs(n(rng)), 4.0);
    const Eigen::Matrix3d S = 1e-4 * rotation.toRotationMatrix() * lambda.asDiagonal() *
                              rotation.toRotationMatrix().transpose();
    Eigen::Vector3d normal, ev;
    if (!smallest_eigenvector(S, normal, ev)) continue;
    ++solved;
    const Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d> reference(S);
    for (int i = 0; i < 3; ++i)
      EXPECT_NEAR(ev(i), reference.eigenvalues()(i), 1e-12 * reference.eigenvalues()(2));
    // The eigenvector's error grows as λ_max / (λ_mid − λ_min) times the rounding, and the
    // closed form's more near a double root (acos near ±1): measured at most 5.1e-15 times that
    // with GCC (FMA) and 1.5e-13 with clang (the sanitizer build); bound 1e-11. At the worst
    // conditioning here (about 5e4) that is 5e-7 rad, the order of the float normal's rounding.
    const Eigen::Vector3d& l = reference.eigenvalues();
    const double conditioning = l(2) / (l(1) - l(0));
    const double angle = normal.cross(reference.eigenvectors().col(0)).norm();
    worst = std::max(worst, angle / conditioning);
    EXPECT_LT(angle, 1e-11 * conditioning) << "trial " << trial;
    EXPECT_NEAR(normal.norm(), 1.0, 1e-14);
  }
  std::printf("worst angle / conditioning %.2g over %d\n", worst, solved);
  EXPECT_GT(solved, 1990);
  Eigen::Vector3d normal, ev;
  EXPECT_FALSE(smallest_eigenvector(Eigen::Matrix3d::Identity() * 1e-4, normal, ev));
  // A double smallest eigenvalue: any unit vector of its plane is an answer (computeDirect's
  // is as arbitrary); what comes back must be one, or false.
  const Eigen::Matrix3d doubled = Eigen::Vector3d(1e-4, 1e-4, 4e-4).asDiagonal();
  if (smallest_eigenvector(doubled, normal, ev)) {
    EXPECT_LT((doubled * normal - 1e-4 * normal).norm(), 1e-12);
    EXPECT_NEAR(ev(0), 1e-4, 1e-11);
  }
}

}  // namespace
}  // namespace jpcr
