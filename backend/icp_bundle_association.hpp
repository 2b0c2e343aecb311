// The data side of ICP-bundle (method.md §9), without Ceres: semi-dense samples of frame i,
// projective association into frame j (method.md §5), and the overlap test by projection.
//
//   BundleFrame f = make_bundle_frame(vertices, params);        // + normals
//   PairAssociation a = associate_pair(f_i, f_j, T_ji, camera, params);
//   a.overlap()        // fraction of i's samples that land on a pixel of j with depth
//   a.correspondences  // (X in frame i, q and n in frame j) that passed the rejection tests
#pragma once

#include <vector>

#include <Eigen/Geometry>

#include "jpcr/backend/icp_bundle_params.hpp"
#include "jpcr/quadric/camera.hpp"
#include "jpcr/quadric/vertex_map.hpp"

namespace jpcr {

/// One frame of the window: its vertices and the normals ICP-bundle pairs against (n·X < 0).
struct BundleFrame {
  const VertexMap* vertices = nullptr;
  NormalMap normals;
};

BundleFrame make_bundle_frame(const VertexMap& vertices, const IcpBundleParams& params);

/// A source point X of frame i and the target vertex q and unit normal n of frame j it pairs
/// with; the residual is e = nᵀ (T_j⁻¹ T_i X − q) (point_to_plane_residual.hpp).
struct BundleCorrespondence {
  Eigen::Vector3d X, q, n;
};

struct PairAssociation {
  int samples = 0;    // i's grid samples with a vertex and a normal
  int projected = 0;  // of them, those that project into j onto a pixel with depth
  std::vector<BundleCorrespondence> correspondences;

  double overlap() const { return samples > 0 ? static_cast<double>(projected) / samples : 0.0; }
};

/// Every grid_stride-th pixel of `source` (frame i) with a vertex and a normal is mapped into
/// `target` (frame j) by T_ji = T_j⁻¹ T_i, projected to the nearest pixel, and paired with j's
/// vertex and normal there unless they are farther than max_distance apart or their normals
/// disagree by more than max_normal_angle.
PairAssociation associate_pair(const BundleFrame& source, const BundleFrame& target,
                               const Eigen::Isometry3d& T_ji, const CameraIntrinsics& camera,
                               const IcpBundleParams& params);

}  // namespace jpcr
