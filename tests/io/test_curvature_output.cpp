// Curvature outputs and metrics: .npy round trip, the binary PLY layout, the colour code and its
// key, the RMS/coverage figures against a hand-computed case, and the quadric: YAML section.
#include <algorithm>
#include <cmath>
#include <cstring>
#include <random>

#include <gtest/gtest.h>

#include "input_error.hpp"
#include "jpcr/io/curvature_metrics.hpp"
#include "jpcr/io/curvature_output.hpp"
#include "jpcr/io/npy.hpp"
#include "jpcr/io/params.hpp"
#include "temp_dir.hpp"

namespace jpcr {
namespace {

const float kNaN = std::numeric_limits<float>::quiet_NaN();

CurvatureImage ramp(int w, int h) {
  CurvatureImage k(w, h, Eigen::Vector2f::Zero());
  for (int v = 0; v < h; ++v)
    for (int u = 0; u < w; ++u)
      k(u, v) = Eigen::Vector2f(0.5f * u, -0.25f * v);
  k(1, 1) = Eigen::Vector2f(kNaN, kNaN);
  return k;
}

TEST(CurvatureOutput, NpyRoundTripKeepsValuesAndNaN) {
  test::TempDir dir;
  const CurvatureImage k = ramp(7, 5);
  write_curvature_npy(dir.file("k.npy"), k);
  const NpyArray raw = read_npy(dir.file("k.npy"));
  EXPECT_EQ(raw.dtype, "f4");
  EXPECT_EQ(raw.shape, (std::vector<std::size_t>{5, 7, 2}));  // H x W x 2, as numpy reads it
  const CurvatureImage back = read_curvature_npy(dir.file("k.npy"));
  ASSERT_EQ(back.width(), 7);
  ASSERT_EQ(back.height(), 5);
  for (std::size_t i = 0; i < k.size(); ++i) {
    if (std::isnan(k[i].x())) {
      EXPECT_TRUE(std::isnan(back[i].x()) && std::isnan(back[i].y()));
    } else {
      EXPECT_EQ(back[i], k[i]);
    }
  }
}

TEST(CurvatureOutput, ReadingAMapOfTheWrongShapeNamesTheFile) {
  test::TempDir dir;
  const std::vector<float> three(4 * 3 * 3, 0.0f);
  write_npy<float>(dir.file("normals.npy"), {4, 3, 3}, three.data());
  EXPECT_NE(test::input_error_of([&] {
              read_curvature_npy(dir.file("normals.npy"));
            }).find("normals.npy: expected a curvature map of shape H x W x 2"),
            std::string::npos);
  EXPECT_NE(test::input_error_of([&] {
              read_curvature_npy(dir.file("missing.npy"));
            }).find("missing.npy"),
            std::string::npos);
  const std::vector<std::int32_t> integers(4 * 3 * 2, 7);
  write_npy<std::int32_t>(dir.file("labels.npy"), {4, 3, 2}, integers.data());
  EXPECT_NE(test::input_error_of([&] {
              read_curvature_npy(dir.file("labels.npy"));
            }).find("labels.npy: a curvature map must be float32 or float64, got dtype 'i4'"),
            std::string::npos);
}

TEST(CurvatureOutput, SdMapRoundTripsAndAWrongShapeNamesTheFile) {
  test::TempDir dir;
  Image<float> sd(4, 3, 0.0f);
  for (std::size_t i = 0; i < sd.size(); ++i)
    sd[i] = 0.25f * static_cast<float>(i);
  sd(2, 1) = kNaN;
  write_curvature_sd_npy(dir.file("sd.npy"), sd);
  EXPECT_EQ(read_npy(dir.file("sd.npy")).shape, (std::vector<std::size_t>{3, 4}));
  const Image<float> back = read_curvature_sd_npy(dir.file("sd.npy"));
  ASSERT_EQ(back.width(), 4);
  ASSERT_EQ(back.height(), 3);
  for (std::size_t i = 0; i < sd.size(); ++i)
    EXPECT_TRUE(std::isnan(sd[i]) ? std::isnan(back[i]) : back[i] == sd[i]) << i;
  write_curvature_npy(dir.file("k.npy"), ramp(4, 3));  // a curvature map is no sd map
  EXPECT_NE(test::input_error_of([&] {
              read_curvature_sd_npy(dir.file("k.npy"));
            }).find("k.npy: expected a curvature sd map of shape H x W"),
            std::string::npos);
  const std::vector<std::uint8_t> bytes(12, 1);
  write_npy<std::uint8_t>(dir.file("mask.npy"), {3, 4}, bytes.data());
  EXPECT_NE(test::input_error_of([&] {
              read_curvature_sd_npy(dir.file("mask.npy"));
            }).find("mask.npy: a curvature sd map must be float32 or float64, got dtype 'u1'"),
            std::string::npos);
}

TEST(CurvatureOutput, PlyHasOneBinaryVertexPerValidQuadric) {
  QuadricMap map(4, 3);
  VertexMap vertices(4, 3, invalid_vector());
  Quadric q;
  q.R = local_frame<float>(Eigen::Vector3f(0, 0, -1));
  q.a = q.c = -2.0f;  // a ball of radius 0.5 m seen from outside
  vertices(2, 1) = Eigen::Vector3f(0.1f, 0.2f, 1.5f);
  map.set(2, 1, q);
  vertices(3, 2) = Eigen::Vector3f(0.3f, 0.2f, 1.6f);  // a vertex without quadric: left out
  const std::string ply = format_curvature_ply(vertices, map);
  const std::size_t end = ply.find("end_header\n");
  ASSERT_NE(end, std::string::npos);
  EXPECT_NE(ply.find("format binary_little_endian 1.0"), std::string::npos);
  EXPECT_NE(ply.find("element vertex 1\n"), std::string::npos);
  EXPECT_NE(ply.find("property float k1\nproperty float k2\n"), std::string::npos);
  const std::string body = ply.substr(end + 11);
  ASSERT_EQ(body.size(), 8 * sizeof(float) + 3);
  float values[8];
  std::memcpy(values, body.data(), sizeof values);
  EXPECT_FLOAT_EQ(values[2], 1.5f);                      // z
  EXPECT_FLOAT_EQ(values[5], -1.0f);                     // n_z, toward the camera
  EXPECT_FLOAT_EQ(values[6], -2.0f);                     // κ₁
  EXPECT_FLOAT_EQ(values[7], -2.0f);                     // κ₂
  EXPECT_EQ(static_cast<unsigned char>(body[32]), 255);  // a cap is red
}

TEST(CurvatureColors, ShapesHaveTheirColoursAndInvalidIsBlack) {
  const float s = 10.0f;
  const Rgb8 cap = curvature_color(-20, -20, s), cup = curvature_color(20, 20, s);
  const Rgb8 plane = curvature_color(0, 0, s), none = curvature_color(kNaN, kNaN, s);
  const Rgb8 ridge = curvature_color(0, -20, s), saddle = curvature_color(20, -20, s);
  EXPECT_EQ((std::array<int, 3>{cap.r, cap.g, cap.b}), (std::array<int, 3>{255, 0, 0}));
  EXPECT_EQ((std::array<int, 3>{cup.r, cup.g, cup.b}), (std::array<int, 3>{0, 0, 255}));
  EXPECT_EQ((std::array<int, 3>{plane.r, plane.g, plane.b}), (std::array<int, 3>{255, 255, 255}));
  EXPECT_EQ((std::array<int, 3>{none.r, none.g, none.b}), (std::array<int, 3>{0, 0, 0}));
  EXPECT_EQ((std::array<int, 3>{ridge.r, ridge.g, ridge.b}), (std::array<int, 3>{255, 255, 0}));
  EXPECT_EQ(saddle.r, 0);
  EXPECT_GT(saddle.g, 200);
  // Half the scale of curvedness is half way between white and the hue.
  const Rgb8 soft = curvature_color(-5, -5, s);
  EXPECT_EQ(soft.r, 255);
  EXPECT_NEAR(soft.g, 128, 1);
}

TEST(CurvatureColors, KeyIsDrawnInTheCornerAndShowsTheShapes) {
  const CurvatureImage k(640, 480, Eigen::Vector2f(kNaN, kNaN));
  const ColorImage image = render_curvature(k);
  const KeyPlacement key = key_placement(640, 480, {});
  ASSERT_EQ(key.size, 120);
  EXPECT_EQ(key.x0 + key.size, 640 - 8);
  // Top-left of the key is κ₁ = +s, κ₂ = −s: a saddle (green); bottom-left κ₁ = κ₂ = −s: a cap.
  const Rgb8 saddle = image(key.x0 + 2, key.y0 + 2);
  EXPECT_GT(saddle.g, 200);
  EXPECT_LT(saddle.r, 30);
  const Rgb8 cap = image(key.x0 + 2, key.y0 + key.size - 5);  // just above the diagonal
  EXPECT_GT(cap.r, 200);
  EXPECT_LT(cap.b, 60);
  EXPECT_EQ(image(10, 10).r, 0);  // outside the key the map is invalid: black
  CurvatureColorParams no_key;
  no_key.draw_key = false;
  EXPECT_EQ(render_curvature(k, no_key)(key.x0 + 2, key.y0 + 2).g, 0);
}

TEST(CurvatureMetrics, RmsAndCoverageOfAHandComputedCase) {
  CurvatureImage gt(2, 2, Eigen::Vector2f(kNaN, kNaN)), est(2, 2, Eigen::Vector2f(kNaN, kNaN));
  gt(0, 0) = {1, 0};
  gt(1, 0) = {2, 2};
  gt(0, 1) = {0, 0};  // not estimated: counts against coverage only
  est(0, 0) = {1.3f, -0.4f};
  est(1, 0) = {2, 1};
  est(1, 1) = {5, 5};  // no ground truth: ignored
  CurvatureErrorAccumulator acc;
  acc.add(gt, est);
  const CurvatureErrors e = acc.result();
  EXPECT_EQ(e.compared, 2u);
  EXPECT_EQ(e.gt_valid, 3u);
  EXPECT_NEAR(e.coverage, 2.0 / 3.0, 1e-12);
  EXPECT_NEAR(e.rms_k1, std::sqrt((0.09 + 0.0) / 2), 1e-6);
  EXPECT_NEAR(e.rms_k2, std::sqrt((0.16 + 1.0) / 2), 1e-6);
  EXPECT_NEAR(e.rms, std::sqrt((0.09 + 0.16 + 1.0) / 4), 1e-6);
  EXPECT_THROW(acc.add(gt, CurvatureImage(3, 2, Eigen::Vector2f::Zero())), InputError);
}

// With an sd map: over the compared pixels with a finite, non-negative sd, the RMS sd, the RMS
// error e = √((Δκ₁² + Δκ₂²) / 2) there, and the share of e < 2 sd.
TEST(CurvatureMetrics, SdFiguresOfAHandComputedCase) {
  CurvatureImage gt(3, 2, Eigen::Vector2f(0, 0)), est(3, 2, Eigen::Vector2f(kNaN, kNaN));
  Image<float> sd(3, 2, kNaN);
  est(0, 0) = {3, 4};  // e² = 12.5
  sd(0, 0) = 2.0f;     // e = 3.54 < 4: within 2 sd
  est(1, 0) = {1, 1};  // e² = 1
  sd(1, 0) = 0.4f;     // e = 1 > 0.8
  est(2, 0) = {9, 9};  // compared, but without an sd: not in the sd figures
  est(0, 1) = {1, 0};
  sd(0, 1) = -1.0f;  // a negative sd is none
  sd(1, 1) = 1.0f;   // no estimate there: not compared
  CurvatureErrorAccumulator acc;
  acc.add(gt, est, &sd);
  const CurvatureErrors e = acc.result();
  EXPECT_EQ(e.compared, 4u);
  EXPECT_EQ(e.sd_compared, 2u);
  EXPECT_NEAR(e.sd_rms, std::sqrt((4.0 + 0.16) / 2), 1e-6);
  EXPECT_NEAR(e.rms_where_sd, std::sqrt((12.5 + 1.0) / 2), 1e-6);
  EXPECT_NEAR(e.within_2sd, 0.5, 1e-12);
  const Image<float> other(2, 2, 1.0f);
  EXPECT_NE(test::input_error_of([&] {
              acc.add(gt, est, &other);
            }).find("the sd map is 2x2 but its curvature map is 3x2"),
            std::string::npos);
  CurvatureErrorAccumulator without;
  without.add(gt, est);
  EXPECT_EQ(without.result().sd_compared, 0u);
}

// The median |Δκ| comes from a logarithmic histogram (constant memory): within 1e-4 relative of
// the exact (n/2)-th smallest error, over errors spread across 12 decades, exact zeros included.
TEST(CurvatureMetrics, MedianOfTheHistogramIsTheExactMedianTo1e4) {
  std::mt19937 rng(7);
  std::uniform_real_distribution<double> decade(-8.0, 4.0);
  for (int trial = 0; trial < 20; ++trial) {
    const int w = 31 + trial, h = 17;
    CurvatureImage gt(w, h, Eigen::Vector2f(0, 0)), est(w, h, Eigen::Vector2f(0, 0));
    std::vector<double> errors;
    for (int v = 0; v < h; ++v)
      for (int u = 0; u < w; ++u) {
        const bool zero = (u + v + trial) % 11 == 0;
        est(u, v) = zero ? Eigen::Vector2f(0, 0)
                         : Eigen::Vector2f(static_cast<float>(std::pow(10.0, decade(rng))),
                                           -static_cast<float>(std::pow(10.0, decade(rng))));
        errors.push_back(std::abs(double(est(u, v).x())));
        errors.push_back(std::abs(double(est(u, v).y())));
      }
    CurvatureErrorAccumulator acc;
    acc.add(gt, est);
    std::nth_element(errors.begin(), errors.begin() + errors.size() / 2, errors.end());
    const double exact = errors[errors.size() / 2];
    EXPECT_NEAR(acc.result().median_abs, exact, 1e-4 * exact) << "trial " << trial;
  }
  CurvatureImage gt(4, 1, Eigen::Vector2f(0, 0)), est(4, 1, Eigen::Vector2f(0, 0));
  CurvatureErrorAccumulator zeros;  // every error 0: the median is 0
  zeros.add(gt, est);
  EXPECT_EQ(zeros.result().median_abs, 0.0);
}

// A 20x12 map with ground truth everywhere but column 9 (a crease) and an estimate that is off by
// 1 at every pixel and by 100 within 2 px of the crease: the support radius R keeps exactly the
// pixels whose (2R+1)² window misses the crease and the image border, counted by hand.
TEST(CurvatureMetrics, SupportRadiusKeepsOnlyPixelsAwayFromCreasesAndBorders) {
  const int w = 20, h = 12, crease = 9;
  CurvatureImage gt(w, h, Eigen::Vector2f(0, 0)), est(w, h, Eigen::Vector2f(1, -1));
  for (int v = 0; v < h; ++v) {
    gt(crease, v) = {kNaN, kNaN};
    for (int u = crease - 2; u <= crease + 2; ++u)
      if (u != crease) est(u, v) = {100, 100};
  }
  CurvatureErrorAccumulator all;
  all.add(gt, est);
  EXPECT_EQ(all.result().gt_valid, static_cast<std::size_t>((w - 1) * h));
  // The edge band (4 of 19 columns) swamps the RMS.
  EXPECT_NEAR(all.result().rms, std::sqrt((4 * 1e4 + 15) / 19.0), 1e-9);

  for (int R : {1, 2, 3}) {
    CurvatureErrorAccumulator acc(R);
    acc.add(gt, est);
    const CurvatureErrors e = acc.result();
    // Interior columns: u in [R, w−1−R] with |u − crease| > R; rows v in [R, h−1−R].
    std::size_t columns = 0;
    for (int u = R; u <= w - 1 - R; ++u)
      columns += std::abs(u - crease) > R ? 1 : 0;
    const std::size_t expected = columns * static_cast<std::size_t>(h - 2 * R);
    EXPECT_EQ(e.gt_valid, expected) << "R = " << R;
    EXPECT_EQ(e.compared, expected) << "R = " << R;
    EXPECT_EQ(e.support_radius, R);
    // R = 1 still sees the band at |u − crease| = 2; from R = 2 on only the error of 1 is left.
    if (R >= 2) {
      EXPECT_NEAR(e.rms, 1.0, 1e-9) << "R = " << R;
    }
    // R = 1: 15 interior columns, 2 of them (u = 7, 11) in the band.
    if (R == 1) {
      EXPECT_NEAR(e.rms, std::sqrt((2 * 1e4 + 13) / 15.0), 1e-9);
    }
  }
  EXPECT_THROW(CurvatureErrorAccumulator(-1), InputError);
  EXPECT_THROW(CurvatureErrorAccumulator(CurvatureErrorAccumulator::kMaxSupportRadius + 1),
               InputError);
  CurvatureErrorAccumulator widest(CurvatureErrorAccumulator::kMaxSupportRadius);
  widest.add(gt, est);  // no window fits: nothing is counted
  EXPECT_EQ(widest.result().gt_valid, 0u);
  // A window larger than the image leaves nothing to compare (NaN, not 0).
  CurvatureErrorAccumulator huge(7);
  huge.add(gt, est);
  EXPECT_EQ(huge.result().compared, 0u);
  EXPECT_TRUE(std::isnan(huge.result().rms));
}

TEST(QuadricParamsYaml, DefaultYamlStatesTheBuiltInDefaults) {
  const QuadricParams shipped =
      load_params(std::string(JPCR_SOURCE_DIR) + "/configs/default.yaml").quadric;
  const QuadricParams built_in;
  EXPECT_EQ(shipped.pattern.radius, built_in.pattern.radius);
  EXPECT_EQ(shipped.pattern.stride, built_in.pattern.stride);
  EXPECT_EQ(shipped.pattern.reference_width, built_in.pattern.reference_width);
  EXPECT_EQ(shipped.normals.half_window, built_in.normals.half_window);
  EXPECT_FLOAT_EQ(shipped.normals.max_depth_jump, built_in.normals.max_depth_jump);
  EXPECT_FLOAT_EQ(shipped.normals.quadrant_ratio, built_in.normals.quadrant_ratio);
  EXPECT_EQ(shipped.fit.iterations, built_in.fit.iterations);
  EXPECT_FLOAT_EQ(shipped.fit.fair_n0, built_in.fit.fair_n0);
  EXPECT_FLOAT_EQ(shipped.fit.residual_gate, built_in.fit.residual_gate);
  EXPECT_FLOAT_EQ(shipped.fit.damping, built_in.fit.damping);
  EXPECT_EQ(shipped.fit.min_samples, built_in.fit.min_samples);
}

TEST(QuadricParamsYaml, BadValuesNameTheKey) {
  const Params p =
      parse_params("quadric:\n  fit:\n    iterations: 5\n    fair_n0_per_range: 0.03\n", "p.yaml");
  EXPECT_EQ(p.quadric.fit.iterations, 5);
  EXPECT_FLOAT_EQ(p.quadric.fit.fair_n0_per_range, 0.03f);
  EXPECT_NE(test::input_error_of([] {
              parse_params("quadric:\n  fit:\n    fair_n0: big\n", "p.yaml");
            }).find("fair_n0"),
            std::string::npos);
  EXPECT_NE(test::input_error_of([] {
              parse_params("quadric:\n  fit:\n    iterations: 0\n", "p.yaml");
            }).find("iterations"),
            std::string::npos);
  EXPECT_NE(test::input_error_of([] {
              parse_params("quadric:\n  pattern:\n    radius: 6\n    strid: 3\n", "p.yaml");
            }).find("strid"),
            std::string::npos);
  EXPECT_NE(test::input_error_of([] {
              parse_params("quadric:\n  normals:\n    quadrant_ratio: 0.5\n", "p.yaml");
            }).find("quadrant_ratio"),
            std::string::npos);
  EXPECT_FLOAT_EQ(parse_params("quadric:\n  normals:\n    quadrant_ratio: 0\n", "p.yaml")
                      .quadric.normals.quadrant_ratio,
                  0.0f);
}

}  // namespace
}  // namespace jpcr
