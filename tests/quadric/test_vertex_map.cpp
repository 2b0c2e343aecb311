#include <cmath>
#include <limits>

#include <gtest/gtest.h>

#include "jpcr/quadric/vertex_map.hpp"

namespace jpcr {
namespace {

TEST(VertexMap, InvalidDepthGivesNaNNeverZero) {
  CameraIntrinsics c;
  c.width = 4;
  c.height = 3;
  c.cx = 1.5;
  c.cy = 1.0;
  DepthImage depth(4, 3, 1.0f);
  depth(0, 0) = 0.0f;
  depth(1, 0) = std::numeric_limits<float>::quiet_NaN();
  depth(2, 0) = std::numeric_limits<float>::infinity();
  depth(3, 0) = -2.0f;
  depth(0, 1) = std::numeric_limits<float>::max();  // a "no return" marker, not a range
  depth(1, 1) = 1e25f;
  depth(2, 1) = kMaxMeasurableDepth;  // the farthest measurement
  const VertexMap v = compute_vertex_map(depth, c);
  for (int u = 0; u < 4; ++u)
    EXPECT_FALSE(is_valid(v(u, 0))) << u;
  EXPECT_FALSE(is_valid(v(0, 1)));
  EXPECT_FALSE(is_valid(v(1, 1)));
  EXPECT_TRUE(is_valid(v(2, 1)));
  ASSERT_TRUE(is_valid(v(1, 2)));
  EXPECT_FLOAT_EQ(v(1, 2).z(), 1.0f);
  EXPECT_FLOAT_EQ(v(3, 2).x(), static_cast<float>((3 - 1.5) / c.fx));
  EXPECT_NEAR(valid_depth_fraction(depth), 6.0 / 12.0, 1e-12);
}

TEST(VertexMap, DepthRangeIsApplied) {
  CameraIntrinsics c;
  c.width = 2;
  c.height = 1;
  DepthImage depth(2, 1);
  depth(0, 0) = 0.3f;
  depth(1, 0) = 5.0f;
  const VertexMap v = compute_vertex_map(depth, c, 0.4f, 4.0f);
  EXPECT_FALSE(is_valid(v(0, 0)));
  EXPECT_FALSE(is_valid(v(1, 0)));
}

TEST(VertexMap, WrongImageSizeIsAnError) {
  const CameraIntrinsics c;
  EXPECT_THROW(compute_vertex_map(DepthImage(320, 240, 1.0f), c), std::invalid_argument);
}

TEST(Image, BoundsAreTwoDimensional) {
  const Image<int> image(5, 4);
  EXPECT_TRUE(image.in_bounds(4, 3));
  EXPECT_FALSE(image.in_bounds(5, 0));  // would wrap to (0, 1) with a flat index
  EXPECT_FALSE(image.in_bounds(-1, 1));
  EXPECT_FALSE(image.in_bounds(0, 4));
}

// Eigen's default constructor leaves a vector uninitialised, so an image of vectors made without
// a fill would hold whatever the allocator returned; it is all-NaN (invalid) instead.
TEST(Image, MadeWithoutAFillIsInvalidForVectorsAndZeroForNumbers) {
  const VertexMap vertices(3, 2);
  const CurvatureImage curvature(3, 2);
  for (std::size_t i = 0; i < vertices.size(); ++i) {
    EXPECT_TRUE(vertices[i].array().isNaN().all()) << i;
    EXPECT_FALSE(is_valid(vertices[i]));
    EXPECT_TRUE(curvature[i].array().isNaN().all()) << i;
  }
  const DepthImage depth(3, 2);
  for (float z : depth)
    EXPECT_EQ(z, 0.0f);
}

}  // namespace
}  // namespace jpcr
