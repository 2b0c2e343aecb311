#include "jpcr/quadric/surface_normals.hpp"

#include "jpcr/quadric/error.hpp"
#include "jpcr/quadric/plane_normal_kernel.hpp"

namespace jpcr {

void NormalEstimationParams::validate() const {
  if (half_window < 1 || half_window > 32) throw InputError("half_window: must be in [1, 32]");
  if (min_points < 3) throw InputError("min_points: must be at least 3");
  if (!(max_depth_jump > 0.0f))
    throw InputError("max_depth_jump: must be positive (fraction of depth)");
}

NormalMap estimate_normals(const VertexMap& vertices, const NormalEstimationParams& params) {
  NormalMap normals(vertices.width(), vertices.height(), invalid_vector());
  const VertexView view{vertices.data(), vertices.width(), vertices.height()};
#pragma omp parallel for schedule(dynamic, 8)
  for (int v = 0; v < vertices.height(); ++v)
    for (int u = 0; u < vertices.width(); ++u)
      normals(u, v) = plane_normal(view, u, v, params);
  return normals;
}

}  // namespace jpcr
