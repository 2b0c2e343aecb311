// estimate_normals takes a separable shortcut (column sums) for windows that drop no point, and
// plane_normal, the kernel the GPU runs, for the others: the two must give the same normals.
// Fresh random frames each run (the seed is printed; JPCR_TEST_SEED replays it), with holes.
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <limits>
#include <random>

#include <Eigen/Eigenvalues>
#include <Eigen/Geometry>

#include <gtest/gtest.h>

#include "cuda/random_frames.hpp"
#include "jpcr/quadric/plane_normal_kernel.hpp"
#include "jpcr/quadric/surface_normals.hpp"

namespace jpcr {
namespace {

struct Agreement {
  int pixels = 0, valid = 0, validity_differs = 0;
  double worst_angle = 0.0;   // rad
  double worst_excess = 0.0;  // the largest angle / angle_bound (below 1 passes)
  double conditioning_at_worst = 0.0;
};

// The bound on the angle between the two normals at one pixel, from the eigenvalues
// λ_min ≤ λ_mid ≤ λ_max of its window's scatter matrix. Both round the normal to float (6e-8
// each). Their moments differ by rounding (the shortcut's are uncentred), and the smallest
// eigenvector turns by such a difference over the gap λ_mid − λ_min: a window of noise, with
// no plane in it, has λ_min ≈ λ_mid. An empirical form: over 40 random frames (654 pixels above
// 3e-7 rad), angle ≤ 1.32 √ε λ_max / gap (ε |X|² / gap and ε |X|² λ_max / gap² fit far worse),
// so 4 √ε leaves a factor 3. Where the plane is well defined the bound is below 1e-6 rad.
double angle_bound(const Eigen::Vector3d& eigenvalues) {
  const double sqrt_epsilon = 1.49e-8;
  return 2e-7 + 4 * sqrt_epsilon * eigenvalues(2) / (eigenvalues(1) - eigenvalues(0));
}

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
      Eigen::Vector3d sum;
      Eigen::Matrix3d outer;
      int count = 0;
      window_moments(view, u, v, p, sum, outer, count);
      const Eigen::Vector3d mean = sum / count;
      const Eigen::Vector3d ev =
          Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d>(outer / count - mean * mean.transpose())
              .eigenvalues();
      a.worst_angle = std::max(a.worst_angle, angle);
      const double excess = angle / angle_bound(ev);
      if (excess > a.worst_excess) {
        a.worst_excess = excess;
        a.conditioning_at_worst = ev(2) / (ev(1) - ev(0));
      }
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

// Both sum the same window points in double and must give the same normal up to angle_bound,
// which grows where the window's plane is ill-defined (a small gap below λ_mid); validity must
// agree exactly.
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
      std::printf(
          "%dx%d h=%d jump %.2f: %d of %d valid, validity differs at %d, worst %.2e rad, "
          "worst angle / bound %.2f (at λ_max / (λ_mid - λ_min) = %.3g)\n",
          w, h, p.half_window, p.max_depth_jump, a.valid, a.pixels, a.validity_differs,
          a.worst_angle, a.worst_excess, a.conditioning_at_worst);
      EXPECT_GT(a.valid, a.pixels / 2) << "seed " << seed;
      EXPECT_EQ(a.validity_differs, 0) << "seed " << seed;
      EXPECT_LT(a.worst_excess, 1.0) << "seed " << seed;
    }
  }
}

// A caller's vertex with NaN in x alone, or a "no return" 1e25 m, is no point of any window,
// as a vertex without depth: the normals are those with that vertex all NaN, by both paths
// (estimate_normals and plane_normal, which the GPU runs). The windows checked z alone: NaN x
// made the 49 normals around it NaN, 1e25 the moments' sums infinite.
TEST(SurfaceNormals, AVertexThatIsNoSampleIsNoPointOfAnyWindow) {
  const SyntheticFrame f = test::random_frame(11, 80, 60);
  const VertexMap clean = compute_vertex_map(f.frame.depth, f.frame.camera);
  ASSERT_TRUE(clean(40, 30).allFinite());
  VertexMap hole = clean;
  hole(40, 30) = Eigen::Vector3f::Constant(std::numeric_limits<float>::quiet_NaN());
  const NormalEstimationParams p;
  const NormalMap expected = estimate_normals(hole, p);
  for (const Eigen::Vector3f& bad :
       {Eigen::Vector3f(std::numeric_limits<float>::quiet_NaN(), 0.1f, clean(40, 30).z()),
        Eigen::Vector3f(0.1f, 0.2f, 1e25f)}) {
    VertexMap vertices = clean;
    vertices(40, 30) = bad;
    const NormalMap normals = estimate_normals(vertices, p);
    const VertexView view{vertices.data(), vertices.width(), vertices.height()},
        hole_view{hole.data(), hole.width(), hole.height()};
    int compared = 0;
    for (int v = 26; v <= 34; ++v)
      for (int u = 36; u <= 44; ++u) {
        const Eigen::Vector3f n = normals(u, v), e = expected(u, v);
        const Eigen::Vector3f r = plane_normal(view, u, v, p),
                              rh = plane_normal(hole_view, u, v, p);
        ASSERT_EQ(is_valid(n), is_valid(e)) << u << "," << v;
        ASSERT_EQ(is_valid(r), is_valid(rh)) << u << "," << v;
        if (is_valid(e)) {
          EXPECT_EQ(n, e) << u << "," << v;
        }
        if (is_valid(rh)) {
          EXPECT_EQ(r, rh) << u << "," << v;
        }
        compared += is_valid(e) ? 1 : 0;
      }
    EXPECT_EQ(compared, 80);                  // every pixel of the 9x9 block but the centre
    EXPECT_FALSE(is_valid(normals(40, 30)));  // no centre: no normal
  }
}

// Vertex maps of analytic surfaces along the rays of a 160x120 camera (fx = fy = 150): each pixel
// gets the first hit of its ray, z(u) the distance along the optical axis to the surface.
constexpr int kW = 160, kH = 120;
constexpr double kF = 150.0;
Eigen::Vector3d ray(int u, int v) {
  return Eigen::Vector3d((u - 79.5) / kF, (v - 59.5) / kF, 1.0);
}

// The vertex of pixel (u, v) on the plane n·X = d (n toward the camera: d < 0).
Eigen::Vector3f on_plane(int u, int v, const Eigen::Vector3d& n, double d) {
  const Eigen::Vector3d r = ray(u, v);
  return (d / n.dot(r) * r).cast<float>();
}

double angle(const Eigen::Vector3f& a, const Eigen::Vector3d& b) {
  const Eigen::Vector3d x = a.cast<double>().normalized();
  return std::atan2(x.cross(b).norm(), x.dot(b));
}

// Both paths: estimate_normals (with its separable shortcut) and plane_normal (the GPU's).
void expect_normal(const VertexMap& vertices, const NormalMap& normals, int u, int v,
                   const Eigen::Vector3d& truth, double tolerance) {
  const VertexView view{vertices.data(), vertices.width(), vertices.height()};
  ASSERT_TRUE(is_valid(normals(u, v))) << u << "," << v;
  EXPECT_LT(angle(normals(u, v), truth), tolerance) << u << "," << v;
  EXPECT_LT(angle(plane_normal(view, u, v, NormalEstimationParams{}), truth), tolerance)
      << u << "," << v;
}

// A depth step of 8 cm at 2 m (4 %, below the 10 % depth jump, so the window keeps both sides)
// between two parallel slanted planes: every pixel next to it gets its own plane's normal. The
// window's plane tilted by 59–86° there, and Quad IT, which starts from it, did not recover.
TEST(SurfaceNormals, ADepthStepBelowTheJumpLeavesEachSideItsPlanesNormal) {
  const Eigen::Vector3d n = Eigen::Vector3d(0.3, -0.2, -1.0).normalized();
  VertexMap vertices(kW, kH);
  for (int v = 0; v < kH; ++v)
    for (int u = 0; u < kW; ++u)
      vertices(u, v) = on_plane(u, v, n, u + v / 3 < 110 ? -2.0 : -2.08);
  const NormalMap normals = estimate_normals(vertices, NormalEstimationParams{});
  NormalEstimationParams off;
  off.quadrant_ratio = 0.0f;
  const NormalMap window_planes = estimate_normals(vertices, off);
  int checked = 0;
  double worst_window = 0.0;
  for (int v = 4; v < kH - 4; ++v)
    for (int u = 4; u < kW - 4; ++u) {
      const int from_step = u + v / 3 - 110;
      if (from_step < -6 || from_step > 6) continue;
      expect_normal(vertices, normals, u, v, n, 1e-4);
      ++checked;
      worst_window = std::max(worst_window, angle(window_planes(u, v), n));
    }
  EXPECT_GT(checked, 1000);
  std::printf("window planes up to %.2f rad off next to the step\n", worst_window);
  EXPECT_GT(worst_window, 0.5);  // what quadrant_ratio: 0 gives (method.md §3 as written)
}

// A crease: two planes meeting at 127° along a vertical line (z = 2 + 0.5 |x|, seen from the
// front). A pixel beside it gets the normal of its own face (the window's plane averages both),
// and quadrant_tilt says by how much its window's plane was off: above the joint refiners'
// 2° (JointParams::edge_tilt) where the window reaches across the crease, at rounding level
// (a plane's window and quadrant fits agree) where it does not.
TEST(SurfaceNormals, ACreaseLeavesEachFaceItsNormal) {
  VertexMap vertices(kW, kH);
  for (int v = 0; v < kH; ++v)
    for (int u = 0; u < kW; ++u) {
      const Eigen::Vector3d r = ray(u, v);
      const double t = 2.0 / (1.0 - 0.5 * std::abs(r.x()));  // z = t = 2 + 0.5 |t r_x|
      vertices(u, v) = (t * r).cast<float>();
    }
  Image<float> tilt;
  const NormalMap normals = estimate_normals(vertices, NormalEstimationParams{}, &tilt);
  const Eigen::Vector3d left = Eigen::Vector3d(-0.5, 0.0, -1.0).normalized(),
                        right = Eigen::Vector3d(0.5, 0.0, -1.0).normalized();
  const double two_degrees = 2.0 * M_PI / 180.0;
  for (int v = 10; v < kH - 10; v += 7) {
    for (int u = 76; u <= 83; ++u) {
      if (u == 79 || u == 80) continue;  // the crease runs between these columns
      expect_normal(vertices, normals, u, v, u < 80 ? left : right, 1e-4);
      // The window (±3 px) of columns 77–82 holds both faces; that of 76 and 83 one.
      if (u >= 77 && u <= 82)
        EXPECT_GT(tilt(u, v), two_degrees) << u << "," << v;
      else
        EXPECT_LT(tilt(u, v), 1e-3) << u << "," << v;
    }
    for (int u = 4; u < kW - 4; ++u)
      if (u < 76 || u > 83) EXPECT_LT(tilt(u, v), 1e-3) << u << "," << v;  // one face
  }
}

// A smooth surface keeps the window's plane: on a sphere of radius 5 cm at 0.5 m (1.3 mm of
// sagitta over a window's 2.3 cm), every normal whose window lies on the sphere is the window's
// own plane fit, not a quadrant's. The window's residual is 10–20 times the best quadrant's
// inside, up to 46 times near the rim, where the depth over the image is no quadric (measured);
// the threshold is 100. There the quadrant's plane was the worse (0.17 against 0.11 rad from the
// true normal, with a threshold of 25).
TEST(SurfaceNormals, ASmoothSurfaceKeepsTheWindowsPlane) {
  const Eigen::Vector3d centre(0.0, 0.0, 0.55);
  const double radius = 0.05;
  VertexMap vertices(kW, kH);
  for (int v = 0; v < kH; ++v)
    for (int u = 0; u < kW; ++u) {
      const Eigen::Vector3d d = ray(u, v).normalized();
      const double b = d.dot(centre), c = centre.squaredNorm() - radius * radius;
      if (b * b - c < 0.0) continue;  // a miss: no vertex
      vertices(u, v) = ((b - std::sqrt(b * b - c)) * d).cast<float>();
    }
  const NormalEstimationParams p;
  Image<float> tilt;
  const NormalMap normals = estimate_normals(vertices, p, &tilt);
  const VertexView view{vertices.data(), vertices.width(), vertices.height()};
  int checked = 0;
  for (int v = 0; v < kH; ++v)
    for (int u = 0; u < kW; ++u) {
      Eigen::Vector3d sum;
      Eigen::Matrix3d outer;
      int count = 0;
      if (!window_moments(view, u, v, p, sum, outer, count) || count < 49) continue;
      const Eigen::Vector3f window =
          plane_normal_from_moments(sum, outer, count, vertices(u, v), p);
      ASSERT_TRUE(is_valid(window));
      EXPECT_LT(angle(normals(u, v), window.cast<double>()), 1e-5) << u << "," << v;
      EXPECT_LT(angle(plane_normal(view, u, v, p), window.cast<double>()), 1e-5) << u << "," << v;
      EXPECT_EQ(tilt(u, v), 0.0f) << u << "," << v;  // the window's plane itself
      Eigen::Vector3f window_out;
      plane_normal(view, u, v, p, &window_out);
      EXPECT_LT(angle(window_out, window.cast<double>()), 1e-5) << u << "," << v;
      ++checked;
    }
  EXPECT_GT(checked, 250);  // 300 measured
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
