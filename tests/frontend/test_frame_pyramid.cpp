// Preprocessing: pyramid sizes and cameras, exact normals of a plane, depth edges kept by the
// downsampling and the bilateral filter, the working range, and bad input.
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <limits>
#include <random>
#include <utility>

#include <gtest/gtest.h>

#include "jpcr/frontend/frame_pyramid.hpp"
#include "jpcr/quadric/error.hpp"
#include "synthetic_views.hpp"

namespace jpcr {
namespace {

// A frontal-ish wall seen obliquely: the plane y = 2 in the world.
SyntheticScene wall() {
  SyntheticScene scene;
  scene.surfaces = {Plane{Eigen::Vector3d(0, 2, 0), Eigen::Vector3d(0, -1, 0)}};
  return scene;
}

TEST(FramePyramid, ThreeLevelsHalvingTheCamera) {
  const Eigen::Isometry3d T_wc = test::look_from({0, 0, 1}, {0.5, 2, 1.2});
  const FramePyramid p = preprocess(test::render_at(wall(), T_wc));
  ASSERT_EQ(p.levels.size(), 3u);
  const int widths[] = {640, 320, 160}, heights[] = {480, 240, 120};
  for (int l = 0; l < 3; ++l) {
    EXPECT_EQ(p.levels[l].vertices.width(), widths[l]);
    EXPECT_EQ(p.levels[l].normals.height(), l == 0 ? 0 : heights[l]);  // level 0 borrows level 1's
    EXPECT_EQ(p.levels[l].camera.width, widths[l]);
    EXPECT_GT(p.levels[l].valid_vertices, static_cast<std::size_t>(0.95 * widths[l] * heights[l]));
  }
  EXPECT_DOUBLE_EQ(p.levels[2].camera.fx, synthetic_camera().fx / 4.0);
  const NormalLookup n0 = normals_for(p, 0), n1 = normals_for(p, 1);
  EXPECT_EQ(n0.normals, &p.levels[1].normals);
  EXPECT_EQ(n0.shift, 1);
  EXPECT_EQ(n1.normals, &p.levels[1].normals);
  EXPECT_EQ(n1.shift, 0);
  EXPECT_EQ(&n0(301, 199), &p.levels[1].normals(150, 99));
}

// Level 1 of a 97x65 frame is 48x32: full-resolution column 96 and row 64 map to coarse
// column 48 and row 32, one past the map. The lookup reads the last column and row instead.
TEST(FramePyramid, OddSizedFramesBorrowNormalsInsideTheCoarseMap) {
  const Eigen::Isometry3d T_wc = test::look_from({0, 0, 1}, {0.5, 2, 1.2});
  const FramePyramid p = preprocess(test::render_at(wall(), T_wc, 97, 65));
  const NormalLookup n0 = normals_for(p, 0);
  ASSERT_EQ(n0.normals->width(), 48);
  ASSERT_EQ(n0.normals->height(), 32);
  const Eigen::Vector3f* first = n0.normals->data();
  const Eigen::Vector3f* end = first + n0.normals->size();
  for (int v = 0; v < 65; ++v) {
    for (int u = 0; u < 97; ++u) {
      const Eigen::Vector3f* n = &n0(u, v);
      ASSERT_TRUE(n >= first && n < end) << "pixel " << u << ", " << v;
    }
  }
  EXPECT_EQ(&n0(96, 64), &(*n0.normals)(47, 31));
}

TEST(FramePyramid, NormalsOfAPlaneAreExactAndFaceTheCamera) {
  const Eigen::Isometry3d T_wc = test::look_from({0, 0, 1}, {0.5, 2, 1.2});
  const Eigen::Vector3f expected =
      (T_wc.linear().transpose() * Eigen::Vector3d(0, -1, 0)).cast<float>();
  PreprocessParams params;
  params.full_resolution_normals = true;
  const FramePyramid p = preprocess(test::render_at(wall(), T_wc), params);
  for (int l = 0; l < 3; ++l) {
    const PyramidLevel& level = p.levels[l];
    const int border = std::max(1, params.normal_offset >> l);
    int checked = 0;
    for (int v = border; v < level.normals.height() - border; ++v) {
      for (int u = border; u < level.normals.width() - border; ++u) {
        const Eigen::Vector3f& n = level.normals(u, v);
        ASSERT_TRUE(is_valid(n)) << "level " << l << " pixel " << u << "," << v;
        // Float vertices of a plane: the cross product is exact to ~1e-4 rad at the coarsest.
        EXPECT_LT((n - expected).norm(), 2e-4f);
        EXPECT_LT(n.dot(level.vertices(u, v)), 0.0f);
        ++checked;
      }
    }
    EXPECT_GT(checked, 1000);
  }
}

TEST(FramePyramid, DownsamplingDoesNotAverageAcrossADepthEdge) {
  DepthImage d(4, 2, 1.0f);
  d(1, 0) = 2.0f;  // block (0, 0): 1, 2, 1, 1 → the near surface only
  d(2, 0) = 0.0f;  // block (1, 0): no depth at one pixel
  d(3, 0) = 1.02f;
  const DepthImage half = downsample_depth(d, 0.05f);
  EXPECT_FLOAT_EQ(half(0, 0), 1.0f);
  EXPECT_FLOAT_EQ(half(1, 0), (1.02f + 1.0f + 1.0f) / 3.0f);
}

TEST(FramePyramid, BilateralFilterKeepsStepsAndHolesAndSmoothsNoise) {
  PreprocessParams p;
  DepthImage d(20, 20, 1.0f);
  for (int v = 0; v < 20; ++v)
    for (int u = 10; u < 20; ++u)
      d(u, v) = 1.5f;  // a 0.5 m step: far beyond 3 σ_depth
  d(5, 5) = 0.0f;
  d(3, 12) = 1.004f;  // a bump of 4 mm on the near side
  const DepthImage f = bilateral_filter(d, p);
  EXPECT_FLOAT_EQ(f(9, 3), 1.0f);
  EXPECT_FLOAT_EQ(f(10, 3), 1.5f);
  EXPECT_EQ(f(5, 5), 0.0f);
  EXPECT_LT(f(3, 12), 1.002f);
  EXPECT_GT(f(3, 12), 1.0f);
}

// bilateral_filter is public: NaN and Inf are "no measurement" there too (a NaN neighbour
// indexed the range table at INT_MIN).
TEST(FramePyramid, BilateralFilterTakesNanAndInfAsNoMeasurement) {
  PreprocessParams p;
  DepthImage d(8, 8, 1.0f);
  d(3, 3) = std::numeric_limits<float>::quiet_NaN();
  d(5, 2) = std::numeric_limits<float>::infinity();
  d(1, 6) = -std::numeric_limits<float>::infinity();
  const DepthImage f = bilateral_filter(d, p);
  for (int v = 0; v < 8; ++v)
    for (int u = 0; u < 8; ++u) {
      const bool measured = std::isfinite(d(u, v)) && d(u, v) > 0.0f;
      EXPECT_EQ(f(u, v), measured ? 1.0f : 0.0f) << u << "," << v;
    }
}

// filtered_noise_inflation against sampling: white depth noise through the filter (range weights
// made flat by a huge σ_depth, so the spatial kernel alone), summed over every `stride`-th pixel;
// the variance of the sum over draws, divided by what independent pixels of the same variance
// would give, is the factor. 1600 draws: the sampled ratio scatters by about 3.5 % (√(2/1600));
// the finite lattice lowers it by a few % (its edge samples lack neighbours).
TEST(FramePyramid, FilteredNoiseInflationMatchesSampledSums) {
  PreprocessParams p;
  p.bilateral = true;
  p.bilateral_sigma_depth = 10.0f;  // m: every |Δz| here is in the range table's first bin
  FramePyramid filtered;
  filtered.filter_radius = p.bilateral_radius;
  filtered.filter_sigma_space = p.bilateral_sigma_space;
  EXPECT_EQ(filtered_noise_inflation(FramePyramid{}, 2), 1.0);
  constexpr int kSide = 40, kDraws = 1600;
  const int r = p.bilateral_radius;
  // Level 1 (the ICP's last level when level 0 has no iterations) block-averages the filtered
  // depth: its factor is not level 0's at stride 1 (measured 5.2 sampled; 5.8 predicted now,
  // 20.0 before, which took level 0's kernel and lattice).
  for (const auto& [stride, level] : {std::pair{1, 0}, {2, 0}, {3, 0}, {1, 1}, {2, 1}}) {
    std::mt19937 rng(20261205 + stride + 10 * level);
    std::normal_distribution<float> noise(0.0f, 1e-3f);
    double sum_s = 0.0, sum_s2 = 0.0, sum_pixel2 = 0.0;
    long samples = 0;
    const int margin = (r + 1) >> level;  // pixels whose kernel lies inside the image
    for (int d = 0; d < kDraws; ++d) {
      DepthImage depth(kSide, kSide, 2.0f);
      for (float& z : depth)
        z += noise(rng);
      DepthImage f = bilateral_filter(depth, p);
      if (level == 1) f = downsample_depth(f, 1.0f);
      double s = 0.0;
      samples = 0;
      for (int v = margin; v < f.height() - margin; v += stride)
        for (int u = margin; u < f.width() - margin; u += stride) {
          const double e = f(u, v) - 2.0;
          s += e;
          sum_pixel2 += e * e;
          ++samples;
        }
      sum_s += s;
      sum_s2 += s * s;
    }
    const double var_sum = sum_s2 / kDraws - (sum_s / kDraws) * (sum_s / kDraws);
    const double var_pixel = sum_pixel2 / (static_cast<double>(samples) * kDraws);
    const double sampled = var_sum / (samples * var_pixel);
    const double predicted = filtered_noise_inflation(filtered, stride, level);
    std::printf("level %d, stride %d: sampled %.2f, predicted %.2f\n", level, stride, sampled,
                predicted);
    EXPECT_NEAR(sampled / predicted, 1.0, 0.15) << "level " << level << ", stride " << stride;
  }
  EXPECT_EQ(filtered_noise_inflation(filtered, 2), filtered_noise_inflation(filtered, 2, 0));
}

TEST(FramePyramid, WorkingRangeAndNonMeasurements) {
  Frame frame;
  frame.camera = synthetic_camera(64, 48);
  frame.depth = DepthImage(64, 48, 1.0f);
  frame.depth(10, 10) = std::numeric_limits<float>::quiet_NaN();
  frame.depth(11, 10) = -1.0f;
  frame.depth(12, 10) = std::numeric_limits<float>::infinity();
  frame.depth(13, 10) = 0.1f;  // nearer than min_depth
  frame.depth(14, 10) = 9.0f;  // farther than max_depth
  const FramePyramid p = preprocess(frame);
  for (int u = 10; u <= 14; ++u)
    EXPECT_FALSE(is_valid(p.levels[0].vertices(u, 10))) << u;
  EXPECT_TRUE(is_valid(p.levels[0].vertices(15, 10)));
  EXPECT_EQ(p.levels[0].valid_vertices, 64u * 48u - 5u);
}

TEST(FramePyramid, WrongImageSizeIsAClearError) {
  Frame frame;
  frame.camera = synthetic_camera(64, 48);
  frame.depth = DepthImage(32, 48, 1.0f);
  try {
    preprocess(frame);
    FAIL() << "no error";
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find("depth image is 32x48 but the camera is 64x48"),
              std::string::npos)
        << e.what();
  }
}

}  // namespace
}  // namespace jpcr
