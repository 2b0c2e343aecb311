// Rectification of depth taken through a lens with distortion (OpenCV's model, k1 k2 p1 p2 k3;
// CameraIntrinsics::distortion). Each pixel of the rectified image (same K, no distortion) takes
// the depth of the raw pixel nearest to where its ray falls: depth is not interpolated across
// edges. Shared by the dataset readers (TUM directories, MRPT rawlogs), which hand out rectified
// depth with the camera's distortion cleared. Needs OpenCV (full profile).
#pragma once

#include <string>
#include <vector>

#include <opencv2/core.hpp>

#include "jpcr/quadric/camera.hpp"
#include "jpcr/quadric/image.hpp"

namespace jpcr {

class DepthUndistortion {
 public:
  /// Throws InputError naming `source` when the coefficients send most pixels' rays outside the
  /// image (a lens keeps nearly all of its own image: it is a typing or unit error).
  DepthUndistortion(const CameraIntrinsics& camera, const std::string& source);

  /// Rectifies `depth` (the camera's size) in place.
  void apply(DepthImage& depth) const;

  /// |(x, y, 1)| for every raw pixel (row-major), with (x, y) its undistorted normalised image
  /// coordinates: a range along the pixel's ray is depth times this.
  static std::vector<float> ray_lengths(const CameraIntrinsics& camera);

 private:
  cv::Mat map_x_, map_y_;
};

}  // namespace jpcr
