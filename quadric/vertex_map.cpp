#include "jpcr/quadric/vertex_map.hpp"

#include <limits>
#include <stdexcept>
#include <string>

namespace jpcr {

VertexMap compute_vertex_map(const DepthImage& depth, const CameraIntrinsics& camera,
                             float min_depth, float max_depth) {
  if (depth.width() != camera.width || depth.height() != camera.height) {
    throw std::invalid_argument("depth image is " + std::to_string(depth.width()) + "x" +
                                std::to_string(depth.height()) + " but the camera is " +
                                std::to_string(camera.width) + "x" + std::to_string(camera.height));
  }
  VertexMap vertices(depth.width(), depth.height(), invalid_vector());
  const float fx = static_cast<float>(camera.fx), fy = static_cast<float>(camera.fy);
  const float cx = static_cast<float>(camera.cx), cy = static_cast<float>(camera.cy);
#pragma omp parallel for schedule(static)
  for (int v = 0; v < depth.height(); ++v) {
    for (int u = 0; u < depth.width(); ++u) {
      const float z = depth(u, v);
      if (!is_valid_depth(z) || z < min_depth || z > max_depth) continue;
      vertices(u, v) =
          backproject<float>(static_cast<float>(u), static_cast<float>(v), z, fx, fy, cx, cy);
    }
  }
  return vertices;
}

double valid_depth_fraction(const DepthImage& depth) {
  if (depth.empty()) return 0.0;
  std::size_t valid = 0;
  for (float z : depth)
    valid += is_valid_depth(z) ? 1 : 0;
  return static_cast<double>(valid) / static_cast<double>(depth.size());
}

}  // namespace jpcr
