// Depth noise models: measured statistics against the model over many pixels, quantisation,
// dropouts, and parsing.
#include <cmath>
#include <cstring>

#include <gtest/gtest.h>

#include "jpcr/io/synthetic_ray_caster.hpp"
#include "jpcr/quadric/error.hpp"

namespace jpcr {
namespace {

const CameraIntrinsics kCamera = synthetic_camera(160, 120);

// A wall facing the camera at `distance` (camera at the origin looking along +z).
SyntheticScene wall_at(double distance, const Eigen::Vector3d& normal = -Eigen::Vector3d::UnitZ()) {
  SyntheticScene scene;
  scene.surfaces = {Plane{Eigen::Vector3d(0, 0, distance), normal.normalized()}};
  return scene;
}

struct Moments {
  double mean = 0.0, sigma = 0.0;
  std::size_t count = 0;
};

// Statistics of f(noisy, exact) over the pixels with a measurement, over `frames` frames.
template <typename F>
Moments measure(const SyntheticScene& scene, const NoiseModel& noise, int frames, F f) {
  double sum = 0.0, sum2 = 0.0;
  std::size_t n = 0;
  for (int i = 0; i < frames; ++i) {
    const SyntheticFrame frame =
        render(scene, kCamera, Eigen::Isometry3d::Identity(), noise, /*seed=*/11, i);
    for (std::size_t p = 0; p < frame.exact_depth.size(); ++p) {
      if (!(frame.frame.depth[p] > 0.0f)) continue;
      const double x = f(frame.frame.depth[p], frame.exact_depth[p]);
      sum += x;
      sum2 += x * x;
      ++n;
    }
  }
  Moments m;
  m.count = n;
  m.mean = sum / n;
  m.sigma = std::sqrt(sum2 / n - m.mean * m.mean);
  return m;
}

TEST(SyntheticNoise, RangeNoiseSigmaIsKPercentOfTheRange) {
  // 192 000 samples: the standard error of a measured σ is σ/√(2n) ≈ 0.16 % of σ, far inside
  // the 5 %; the mean must be 0 within 5 standard errors.
  for (const double k : {0.5, 1.0, 3.0}) {
    NoiseModel noise;
    noise.kind = NoiseKind::kRange;
    noise.range_percent = k;
    // Relative error of the range; depth and range scale together along the ray.
    const Moments m = measure(wall_at(2.5, Eigen::Vector3d(0.3, 0.2, -1.0)), noise, 10,
                              [](double noisy, double exact) { return noisy / exact - 1.0; });
    ASSERT_GT(m.count, 190000u);
    EXPECT_NEAR(m.sigma, 0.01 * k, 0.05 * 0.01 * k) << "k = " << k;
    EXPECT_NEAR(m.mean, 0.0, 5.0 * 0.01 * k / std::sqrt(m.count)) << "k = " << k;
  }
}

TEST(SyntheticNoise, KinectAxialSigmaFollowsTheModel) {
  for (const double z : {1.0, 3.0}) {
    NoiseModel noise = parse_noise("kinect");
    noise.kinect.disparity_step = 0.0;  // the Gaussian part alone
    const Moments m =
        measure(wall_at(z), noise, 10, [](double noisy, double exact) { return noisy - exact; });
    const double sigma = 0.0012 + 0.0019 * (z - 0.4) * (z - 0.4);
    ASSERT_GT(m.count, 190000u);
    EXPECT_NEAR(m.sigma, sigma, 0.05 * sigma) << "z = " << z;
  }
}

TEST(SyntheticNoise, KinectDisparityIsQuantised) {
  NoiseModel noise = parse_noise("kinect");
  noise.kinect.sigma_constant = noise.kinect.sigma_quadratic = 0.0;
  const double fb = noise.kinect.disparity_focal * noise.kinect.baseline;
  const SyntheticFrame f = render(wall_at(2.0, Eigen::Vector3d(0.4, 0.1, -1.0)), kCamera,
                                  Eigen::Isometry3d::Identity(), noise, 1, 0);
  int checked = 0;
  for (std::size_t p = 0; p < f.exact_depth.size(); ++p) {
    if (!(f.frame.depth[p] > 0.0f)) continue;
    ++checked;
    const double steps = fb / f.frame.depth[p] / noise.kinect.disparity_step;
    EXPECT_NEAR(steps, std::round(steps), 1e-3);  // float depth: ~1e-5 of ~170 steps
    // Rounding the disparity moves depth by at most half a step: Δz ≤ z²/(f b) · step/2.
    const double z = f.exact_depth[p];
    EXPECT_LE(std::abs(f.frame.depth[p] - z), z * z / fb * noise.kinect.disparity_step / 2 * 1.01);
  }
  EXPECT_GT(checked, 15000);
}

TEST(SyntheticNoise, KinectDropsGrazingPixelsDepthEdgesAndOutOfRange) {
  // Grazing: a floor 3 cm below the camera, in the rows just under the horizon, is 0.75 to
  // 2.75 m away and seen at incidence angles of 87.7–89.4°: every pixel is lost...
  NoiseModel noise = parse_noise("kinect");
  SyntheticScene grazing;
  grazing.surfaces = {Plane{Eigen::Vector3d(0, 0.03, 0), Eigen::Vector3d(0, -1, 0)}};
  const Eigen::Isometry3d level = Eigen::Isometry3d::Identity();
  const SyntheticFrame g = render(grazing, kCamera, level, noise, 3, 0);
  int far_rows_valid = 0, far_rows_surface = 0;
  for (int v = kCamera.height / 2 + 1; v < kCamera.height / 2 + 6; ++v) {
    for (int u = 0; u < kCamera.width; ++u) {
      far_rows_surface += g.exact_depth(u, v) > 0.5f && g.exact_depth(u, v) < 3.0f;
      far_rows_valid += g.frame.depth(u, v) > 0.0f;
    }
  }
  EXPECT_GT(far_rows_surface, 300);
  EXPECT_EQ(far_rows_valid, 0);
  // ... while a wall at 30° keeps them all.
  const SyntheticFrame w =
      render(wall_at(2.0, Eigen::Vector3d(0.5, 0, -0.866)), kCamera, level, noise, 3, 0);
  int valid = 0;
  for (std::size_t p = 0; p < w.frame.depth.size(); ++p)
    valid += w.frame.depth[p] > 0.0f;
  EXPECT_EQ(valid, kCamera.width * kCamera.height);

  // Depth edges: a ball in front of a wall; with edge_dropout = 1 every pixel next to a jump
  // larger than edge_jump · z is lost, and only those (the ball is not grazing there... except
  // at its rim, which the grazing rule may also drop).
  noise.kinect.edge_dropout = 1.0;
  SyntheticScene ball = wall_at(3.0);
  ball.surfaces.push_back(Sphere{Eigen::Vector3d(0, 0, 1.5), 0.3});
  const SyntheticFrame b = render(ball, kCamera, level, noise, 3, 0);
  int edges = 0;
  for (int v = 1; v + 1 < kCamera.height; ++v) {
    for (int u = 1; u + 1 < kCamera.width; ++u) {
      const float z = b.exact_depth(u, v);
      bool edge = false;
      for (const auto& [du, dv] : {std::pair{1, 0}, {-1, 0}, {0, 1}, {0, -1}})
        edge |= std::abs(b.exact_depth(u + du, v + dv) - z) > 0.05f * z;
      if (edge) {
        ++edges;
        EXPECT_EQ(b.frame.depth(u, v), 0.0f) << u << "," << v;
      } else if (b.surface(u, v) == 0) {
        EXPECT_GT(b.frame.depth(u, v), 0.0f) << u << "," << v;
      }
    }
  }
  EXPECT_GT(edges, 100);

  // Out of the working range: nothing beyond max_depth.
  const SyntheticFrame far = render(wall_at(9.0), kCamera, level, noise, 3, 0);
  for (std::size_t p = 0; p < far.frame.depth.size(); ++p)
    ASSERT_EQ(far.frame.depth[p], 0.0f);
}

TEST(SyntheticNoise, ParsingAndDescription) {
  EXPECT_EQ(parse_noise("none").kind, NoiseKind::kNone);
  EXPECT_EQ(parse_noise("kinect").kind, NoiseKind::kKinect);
  const NoiseModel r = parse_noise("range:1.5");
  EXPECT_EQ(r.kind, NoiseKind::kRange);
  EXPECT_EQ(r.range_percent, 1.5);
  EXPECT_EQ(r.describe(), "range:1.5");
  EXPECT_EQ(parse_noise(r.describe()).range_percent, 1.5);
  EXPECT_EQ(parse_noise("range:0").describe(), "range:0");
  EXPECT_EQ(parse_noise("range:100").range_percent, 100.0);
  for (const char* bad : {"range", "range:", "range:-1", "range:abc", "range:1%", "gauss", "",
                          "range:nan", "Kinect", "range:100.5", "range:1e308", "range:inf"}) {
    EXPECT_THROW(parse_noise(bad), InputError) << bad;
  }
  try {
    parse_noise("range:x");
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find("range:x"), std::string::npos);
  }
}

TEST(SyntheticNoise, NoneIsExactAndKinectParametersAreValidated) {
  const SyntheticFrame f =
      render(wall_at(2.0), kCamera, Eigen::Isometry3d::Identity(), NoiseModel{}, 5, 0);
  EXPECT_EQ(0, std::memcmp(f.frame.depth.data(), f.exact_depth.data(),
                           f.exact_depth.size() * sizeof(float)));
  KinectNoiseParams k;
  EXPECT_NO_THROW(k.validate());
  k.grazing_full = 60.0;  // below grazing_start
  EXPECT_THROW(k.validate(), InputError);
  k = KinectNoiseParams{};
  k.baseline = 0.0;
  EXPECT_THROW(k.validate(), InputError);
}

}  // namespace
}  // namespace jpcr
