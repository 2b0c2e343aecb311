// pixel_lane_sums (Quad IT's SIMD pass, one pixel per lane) against a per-sample double sum of
// linearize_sample and the gated fair weight (method.md §3), at every SIMD level this CPU runs,
// on fresh random planes with holes, a NaN margin and samples outside the gate.
#include <gtest/gtest.h>

#include <cmath>
#include <limits>
#include <random>
#include <vector>

#include "jpcr/quadric/pixel_lane_sums.hpp"
#include "jpcr/quadric/quadric_fit_kernel.hpp"

namespace jpcr {
namespace {

constexpr int kWidth = 64, kHeight = 24, kReach = 4;

// Three planes of a noisy paraboloid about 1.5 m away, 5 % of the vertices missing, NaN beyond
// the image (kReach on each side, kPixelLanes more on the right), as VertexPlanes lays them out.
struct Planes {
  int stride = kWidth + 2 * kReach + kPixelLanes;
  std::vector<float> p[3];

  explicit Planes(std::mt19937& rng) {
    const float nan = std::numeric_limits<float>::quiet_NaN();
    for (std::vector<float>& plane : p)
      plane.assign(static_cast<std::size_t>(stride) * (kHeight + 2 * kReach), nan);
    std::normal_distribution<float> noise(0.0f, 0.004f);
    std::uniform_real_distribution<float> hole(0.0f, 1.0f);
    for (int v = 0; v < kHeight; ++v) {
      for (int u = 0; u < kWidth; ++u) {
        if (hole(rng) < 0.05f) continue;
        const float x = 0.003f * (u - kWidth / 2), y = 0.003f * (v - kHeight / 2);
        const std::size_t i = index(u, v);
        p[0][i] = x;
        p[1][i] = y;
        p[2][i] = 1.5f + 2.0f * x * x - 1.0f * x * y + 3.0f * y * y + noise(rng);
      }
    }
  }
  std::size_t index(int u, int v) const {
    return static_cast<std::size_t>(v + kReach) * stride + (u + kReach);
  }
  float at(int axis, int u, int v) const { return p[axis][index(u, v)]; }
};

// Lane l: pixel (u0 + l, v) with a random quadric about its own vertex (or about 0 where it has
// none), a range-dependent gate and n₀.
PixelLaneQuadrics random_lanes(std::mt19937& rng, const Planes& planes, int u0, int v,
                               Quadricd q[kPixelLanes]) {
  std::uniform_real_distribution<double> u(-1.0, 1.0);
  PixelLaneQuadrics in{};
  for (int l = 0; l < kPixelLanes; ++l) {
    Quadricd& ql = q[l];
    ql.R = local_frame<double>(Eigen::Vector3d(0.3 * u(rng), 0.3 * u(rng), -1.0).normalized());
    ql.t_z = 0.002 * u(rng);
    ql.a = 6.0 * u(rng);
    ql.b = 6.0 * u(rng);
    ql.c = 6.0 * u(rng);
    const int px = std::min(u0 + l, kWidth - 1);
    const float cz = planes.at(2, px, v);
    const bool has = cz - cz == 0.0f;
    for (int axis = 0; axis < 3; ++axis) {
      ql.center(axis) = has ? planes.at(axis, px, v) : 0.0f;
      in.centre[axis][l] = static_cast<float>(ql.center(axis));
    }
    for (int i = 0; i < 9; ++i)
      in.R[i][l] = static_cast<float>(ql.R(i / 3, i % 3));
    in.t_z[l] = static_cast<float>(ql.t_z);
    in.a[l] = static_cast<float>(ql.a);
    in.b[l] = static_cast<float>(ql.b);
    in.c[l] = static_cast<float>(ql.c);
    in.gate[l] = 0.004f + 0.004f * (l % 3);
    in.n0[l] = 0.004f;
  }
  return in;
}

// The same sums, sample by sample in double from the float inputs.
struct Reference {
  double Y[kQuadricColumns][kQuadricColumns] = {};
  double gated = 0, inliers = 0;
  int count = 0;
};

Reference reference(const PixelLaneQuadrics& in, int l, const Planes& planes, int u, int v,
                    const NeighbourhoodPattern& pattern) {
  Quadricd q;
  for (int i = 0; i < 9; ++i)
    q.R(i / 3, i % 3) = in.R[i][l];
  q.t_z = in.t_z[l], q.a = in.a[l], q.b = in.b[l], q.c = in.c[l];
  const QuadricScalars<double> qs = QuadricScalars<double>::from(q);
  const double gate = in.gate[l], n0 = in.n0[l];
  Reference ref;
  for (const PixelOffset& o : pattern.offsets) {
    const std::size_t i = planes.index(u, v) + o.dv * planes.stride + o.du;
    const float X = planes.p[0][i], Y = planes.p[1][i], Z = planes.p[2][i];
    if (!(Z - Z == 0.0f)) continue;
    const float dx = X - in.centre[0][l], dy = Y - in.centre[1][l], dz = Z - in.centre[2][l];
    const SampleLinearization<double> s = linearize_sample<double>(qs, dx, dy, dz);
    const double d2 = double(dx) * dx + double(dy) * dy + double(dz) * dz;
    const bool inside = std::abs(s.r) <= gate;
    const double e = inside ? s.r : gate;
    const double we = fair_weight(e, d2, n0);
    ref.gated += we * e * e;
    if (!inside) continue;
    ref.inliers += we * s.r * s.r;
    ++ref.count;
    const double y[kQuadricColumns] = {1.0, s.J0, s.J1, s.J3, s.J4, s.J5, s.r};
    for (int a = 0; a < kQuadricColumns; ++a)
      for (int b = 0; b < kQuadricColumns; ++b)
        ref.Y[a][b] += we * y[a] * y[b];
  }
  return ref;
}

// Float sums against double, relative to the size of the terms summed (Cauchy-Schwarz:
// |Y_ab| ≤ √(Y_aa Y_bb)); measured worst 3.7e-7 over these 220 pixels at 3 levels, bound 2e-5.
constexpr double kRelative = 2e-5;

TEST(PixelLaneSums, EqualTheDoubleSumsAtEverySimdLevelWithHolesAndBorders) {
  std::mt19937 rng(20261202);
  const Planes planes(rng);
  const NeighbourhoodPattern pattern = NeighbourhoodPattern::make(2, 2);  // reach 4 = kReach
  std::vector<std::ptrdiff_t> offsets;
  for (const PixelOffset& o : pattern.offsets)
    offsets.push_back(o.dv * planes.stride + o.du);
  std::vector<SimdLevel> levels = {SimdLevel::kBaseline};
  if (cpu_simd_level() >= SimdLevel::kAvx2) levels.push_back(SimdLevel::kAvx2);
  if (cpu_simd_level() >= SimdLevel::kAvx512) levels.push_back(SimdLevel::kAvx512);
  int compared = 0, outside = 0, borders = 0;
  for (int v : {0, 1, kHeight / 2, kHeight - 1}) {
    for (int u0 : {0, 16, kWidth - 16, kWidth - 7}) {  // the last group runs past the image
      Quadricd q[kPixelLanes];
      const PixelLaneQuadrics in = random_lanes(rng, planes, u0, v, q);
      for (const SimdLevel level : levels) {
        PixelLaneSums sums, costs_only;
        const std::size_t first = planes.index(u0, v);
        const float *x = planes.p[0].data() + first, *y = planes.p[1].data() + first,
                    *z = planes.p[2].data() + first;
        pixel_lane_sums(in, x, y, z, offsets.data(), static_cast<int>(offsets.size()), true, sums,
                        level);
        pixel_lane_sums(in, x, y, z, offsets.data(), static_cast<int>(offsets.size()), false,
                        costs_only, level);
        for (int l = 0; l < kPixelLanes && u0 + l < kWidth; ++l) {
          const Reference ref = reference(in, l, planes, u0 + l, v, pattern);
          EXPECT_EQ(static_cast<int>(sums.count[l]), ref.count);
          EXPECT_EQ(costs_only.count[l], sums.count[l]);
          EXPECT_EQ(costs_only.inliers[l], sums.inliers[l]);
          EXPECT_EQ(costs_only.gated[l], sums.gated[l]);
          EXPECT_NEAR(sums.gated[l], ref.gated, kRelative * ref.gated);
          EXPECT_NEAR(sums.inliers[l], ref.inliers, kRelative * ref.gated);
          for (int a = 0; a < kQuadricColumns; ++a) {
            for (int b = 0; b <= a; ++b) {
              const double scale = std::sqrt(ref.Y[a][a] * ref.Y[b][b]);
              EXPECT_NEAR(sums.products[a * (a + 1) / 2 + b][l], ref.Y[a][b],
                          kRelative * scale + 1e-30)
                  << "Y(" << a << ", " << b << ") lane " << l << " level "
                  << static_cast<int>(level);
            }
          }
          ++compared;
          outside += static_cast<int>(pattern.offsets.size()) - ref.count;
          borders += (v == 0 || u0 + l == 0) ? 1 : 0;
        }
      }
    }
  }
  EXPECT_GT(compared, 150);
  EXPECT_GT(outside, compared * 5);  // the gate and the holes were exercised
  EXPECT_GT(borders, 0);
}

TEST(PixelLaneSums, RejectsALevelTheCpuLacks) {
  if (cpu_simd_level() == SimdLevel::kAvx512) GTEST_SKIP() << "this CPU runs every level";
  const PixelLaneQuadrics in{};
  PixelLaneSums out;
  const std::vector<float> plane(64, 0.0f);
  const std::ptrdiff_t offset = 0;
  EXPECT_THROW(pixel_lane_sums(in, plane.data(), plane.data(), plane.data(), &offset, 1, true, out,
                               SimdLevel::kAvx512),
               std::invalid_argument);
}

}  // namespace
}  // namespace jpcr
