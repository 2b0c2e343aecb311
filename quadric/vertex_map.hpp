// Organised point clouds: one camera-frame vertex per pixel, NaN where there is no measurement.
#pragma once

#include <cmath>
#include <limits>

#include <Eigen/Core>

#include "jpcr/quadric/camera.hpp"
#include "jpcr/quadric/image.hpp"

namespace jpcr {

using VertexMap = Image<Eigen::Vector3f>;
using NormalMap = Image<Eigen::Vector3f>;
/// Principal curvatures κ₁ ≥ κ₂ per pixel (1/m); NaN where there is no value.
using CurvatureImage = Image<Eigen::Vector2f>;

/// A vertex or normal is valid when it is finite (invalid entries are all-NaN).
inline bool is_valid(const Eigen::Vector3f& x) {
  return std::isfinite(x.z());
}

/// The farthest depth taken as a measurement (m). Beyond it a depth value is a sensor's
/// "no return" marker (FLT_MAX, 1e30), never a range: the float sums of the CPU fits would
/// overflow on such a vertex (a sample dropped by a zero weight then adds 0 · inf = NaN). In a
/// vertex map handed to the fits directly, is_sample_point (quadric_fit_kernel.hpp) drops
/// vertices beyond 1e7 m in Quad IT, Quad LS, the normals and the joint terms.
inline constexpr float kMaxMeasurableDepth = 1e4f;

/// A depth value is a measurement when it is finite, positive and at most kMaxMeasurableDepth.
inline bool is_valid_depth(float z) {
  return std::isfinite(z) && z > 0.0f && z <= kMaxMeasurableDepth;
}

inline Eigen::Vector3f invalid_vector() {
  return Eigen::Vector3f::Constant(std::numeric_limits<float>::quiet_NaN());
}

/// Back-projects every pixel; pixels without a measurement (is_valid_depth), or outside
/// [min_depth, max_depth], get NaN.
/// Throws std::invalid_argument when the image size differs from the camera's.
VertexMap compute_vertex_map(const DepthImage& depth, const CameraIntrinsics& camera,
                             float min_depth = 0.0f,
                             float max_depth = std::numeric_limits<float>::infinity());

/// Fraction of pixels that carry a valid depth value.
double valid_depth_fraction(const DepthImage& depth);

}  // namespace jpcr
