// The values that flow through the pipeline (architecture.md "Data flow").
#pragma once

#include <vector>

#include <Eigen/Geometry>

#include "jpcr/quadric/camera.hpp"
#include "jpcr/quadric/image.hpp"

namespace jpcr {

/// One depth frame: timestamp (s), depth in metres, intrinsics and optional colour.
struct Frame {
  double timestamp = 0.0;
  DepthImage depth;
  CameraIntrinsics camera;
  ColorImage color;  // empty when the source has no colour
};

/// A camera-to-world pose T_wc with its timestamp (TUM convention).
struct StampedPose {
  double timestamp = 0.0;
  Eigen::Isometry3d pose = Eigen::Isometry3d::Identity();
};

using Trajectory = std::vector<StampedPose>;

}  // namespace jpcr
