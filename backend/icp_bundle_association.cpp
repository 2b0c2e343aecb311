#include "jpcr/backend/icp_bundle_association.hpp"

#include <algorithm>
#include <cmath>

#include "jpcr/frontend/frame_pyramid.hpp"

namespace jpcr {

BundleFrame make_bundle_frame(const VertexMap& vertices, const IcpBundleParams& params) {
  BundleFrame f;
  f.vertices = &vertices;
  // The same support in the scene at every resolution: ±normal_offset px at 640 px width.
  const int offset =
      std::max(1, static_cast<int>(std::lround(params.normal_offset * vertices.width() / 640.0)));
  f.normals = compute_normal_map(vertices, offset, params.normal_max_jump);
  return f;
}

PairAssociation associate_pair(const BundleFrame& source, const BundleFrame& target,
                               const Eigen::Isometry3d& T_ji, const CameraIntrinsics& camera,
                               const IcpBundleParams& params) {
  const VertexMap& sv = *source.vertices;
  const VertexMap& tv = *target.vertices;
  const Eigen::Matrix3d R = T_ji.linear();
  const Eigen::Vector3d t = T_ji.translation();
  const double max_d2 = params.max_distance * params.max_distance;
  const double min_cos = std::cos(params.max_normal_angle * M_PI / 180.0);
  PairAssociation out;
  for (int v = 0; v < sv.height(); v += params.grid_stride)
    for (int u = 0; u < sv.width(); u += params.grid_stride) {
      const Eigen::Vector3f& Xf = sv(u, v);
      const Eigen::Vector3f& nsf = source.normals(u, v);
      if (!is_valid(Xf) || !is_valid(nsf)) continue;
      ++out.samples;
      // Projective association (method.md §5): p = T_ji X, rounded to the nearest pixel of j.
      const Eigen::Vector3d X = Xf.cast<double>();
      const Eigen::Vector3d p = R * X + t;
      if (!(p.z() > 0.0)) continue;
      const Eigen::Vector2d uv = project<double>(p, camera.fx, camera.fy, camera.cx, camera.cy);
      const double uf = uv.x() + 0.5, vf = uv.y() + 0.5;
      if (!(uf >= 0.0 && vf >= 0.0 && uf < tv.width() && vf < tv.height())) continue;  // NaN too
      const int ut = static_cast<int>(uf), vt = static_cast<int>(vf);
      const Eigen::Vector3f& qf = tv(ut, vt);
      if (!is_valid(qf)) continue;
      ++out.projected;  // the overlap test counts this sample
      const Eigen::Vector3f& nf = target.normals(ut, vt);
      if (!is_valid(nf)) continue;
      const Eigen::Vector3d q = qf.cast<double>(), n = nf.cast<double>();
      if ((p - q).squaredNorm() > max_d2) continue;
      if ((R * nsf.cast<double>()).dot(n) < min_cos) continue;
      out.correspondences.push_back({X, q, n});
    }
  return out;
}

}  // namespace jpcr
