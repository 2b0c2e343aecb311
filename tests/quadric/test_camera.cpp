#include <gtest/gtest.h>

#include "jpcr/quadric/camera.hpp"

namespace jpcr {
namespace {

TEST(Camera, ProjectInvertsBackproject) {
  const CameraIntrinsics c;  // ROS default 525/525/319.5/239.5
  for (double u : {0.0, 100.5, 639.0}) {
    for (double v : {0.0, 240.25, 479.0}) {
      const Eigen::Vector3d X = backproject(u, v, 1.7, c.fx, c.fy, c.cx, c.cy);
      const Eigen::Vector2d p = project(X, c.fx, c.fy, c.cx, c.cy);
      EXPECT_NEAR(p.x(), u, 1e-12);
      EXPECT_NEAR(p.y(), v, 1e-12);
      EXPECT_DOUBLE_EQ(X.z(), 1.7);
    }
  }
}

TEST(Camera, PyramidLevelKeepsPixelCentresConsistent) {
  const CameraIntrinsics c;
  const CameraIntrinsics half = c.pyramid_level(1);
  EXPECT_EQ(half.width, 320);
  EXPECT_EQ(half.height, 240);
  // The ray through fine pixel centres (0,0),(1,1) averages to coarse pixel (0,0).
  const Eigen::Vector3d ray_fine = backproject(0.5, 0.5, 1.0, c.fx, c.fy, c.cx, c.cy);
  const Eigen::Vector3d ray_coarse = backproject(0.0, 0.0, 1.0, half.fx, half.fy, half.cx, half.cy);
  EXPECT_LT((ray_fine - ray_coarse).norm(), 1e-12);
}

TEST(Camera, ValidateNamesTheBadField) {
  CameraIntrinsics c;
  c.fy = -1.0;
  try {
    c.validate();
    FAIL() << "expected an exception";
  } catch (const std::invalid_argument& e) {
    EXPECT_NE(std::string(e.what()).find("fy"), std::string::npos);
  }
  c = CameraIntrinsics();
  c.width = 0;
  EXPECT_THROW(c.validate(), std::invalid_argument);
  EXPECT_NO_THROW(CameraIntrinsics().validate());
}

TEST(Camera, ValidateRefusesAbsurdButFiniteValues) {
  const auto refused_field = [](const CameraIntrinsics& c) -> std::string {
    try {
      c.validate();
    } catch (const std::invalid_argument& e) {
      return std::string(e.what()).substr(0, std::string(e.what()).find(':'));
    }
    return "";
  };
  CameraIntrinsics c;
  c.fx = 1e-300;  // a field of view of 180° to double precision
  EXPECT_EQ(refused_field(c), "fx");
  c = CameraIntrinsics();
  c.fy = 1e300;  // 0°
  EXPECT_EQ(refused_field(c), "fy");
  // The bounds are the field of view's: 175° at 640 px is fx = 320 / tan(87.5°) = 13.97 px.
  c = CameraIntrinsics();
  c.fx = 14.0;
  EXPECT_EQ(refused_field(c), "");
  c.fx = 13.9;
  EXPECT_EQ(refused_field(c), "fx");
  c = CameraIntrinsics();
  c.cx = 1e12;
  EXPECT_EQ(refused_field(c), "cx");
  c = CameraIntrinsics();
  c.cy = -481.0;
  EXPECT_EQ(refused_field(c), "cy");
  c = CameraIntrinsics();
  c.depth_scale = 1e-300;
  EXPECT_EQ(refused_field(c), "depth_scale");
  c.depth_scale = 1.0;  // float depth in metres
  EXPECT_EQ(refused_field(c), "");
}

TEST(Camera, DistortionFlag) {
  CameraIntrinsics c;
  EXPECT_FALSE(c.has_distortion());
  c.distortion[4] = 0.1;
  EXPECT_TRUE(c.has_distortion());
}

TEST(Camera, ResizedScalesFocalLengthAndCentre) {
  CameraIntrinsics c;
  c.fx = c.fy = 550.0;
  const CameraIntrinsics small = c.resized(320, 240);
  EXPECT_DOUBLE_EQ(small.fx, 275.0);
  EXPECT_DOUBLE_EQ(small.cx, 159.5);
  EXPECT_DOUBLE_EQ(small.cy, 119.5);
}

}  // namespace
}  // namespace jpcr
