// Pinhole camera intrinsics (method.md §1): X = ((u − cx)/fx · z, (v − cy)/fy · z, z).
#pragma once

#include <array>
#include <string>

#include <Eigen/Core>

#include "jpcr/quadric/host_device.hpp"

namespace jpcr {

struct CameraIntrinsics {
  double fx = 525.0;  // focal length in pixels
  double fy = 525.0;
  double cx = 319.5;  // principal point in pixels
  double cy = 239.5;
  int width = 640;  // image size in pixels
  int height = 480;
  double depth_scale = 5000.0;         // raw depth units per metre (TUM: 5000, mm sensors: 1000)
  std::array<double, 5> distortion{};  // k1, k2, p1, p2, k3 (OpenCV order); zero = none

  bool has_distortion() const;

  /// Throws std::invalid_argument naming the first bad field: a focal length that is not
  /// positive or gives a field of view outside 0.1°–175°, a principal point more than one image
  /// side off the image, a depth scale outside 1e-3–1e7 units per metre, a non-finite value.
  void validate() const;

  /// Intrinsics of the image downsampled by 2^level (pixel centres kept consistent).
  CameraIntrinsics pyramid_level(int level) const;

  /// The same camera rendered at another resolution (principal point and focal length scaled).
  CameraIntrinsics resized(int new_width, int new_height) const;
};

/// Whether two cameras give the same vertex maps: the same image size and pinhole (fx, fy, cx,
/// cy). Frames of one refinement, and of one tracked stream, must share them.
bool same_pinhole(const CameraIntrinsics& a, const CameraIntrinsics& b);

/// "640x480, fx 525, fy 525, cx 319.5, cy 239.5", for error messages.
std::string describe(const CameraIntrinsics& camera);

/// Back-projects pixel (u, v) with depth z (metres) to a camera-frame point.
template <typename Scalar>
JPCR_HD Eigen::Matrix<Scalar, 3, 1> backproject(Scalar u, Scalar v, Scalar z, Scalar fx, Scalar fy,
                                                Scalar cx, Scalar cy) {
  return Eigen::Matrix<Scalar, 3, 1>((u - cx) / fx * z, (v - cy) / fy * z, z);
}

/// Projects a camera-frame point to continuous pixel coordinates; z must be positive.
template <typename Scalar>
JPCR_HD Eigen::Matrix<Scalar, 2, 1> project(const Eigen::Matrix<Scalar, 3, 1>& X, Scalar fx,
                                            Scalar fy, Scalar cx, Scalar cy) {
  return Eigen::Matrix<Scalar, 2, 1>(fx * X.x() / X.z() + cx, fy * X.y() / X.z() + cy);
}

}  // namespace jpcr
