// Tunables of ICP-bundle (method.md §9), the classical baseline: dense point-to-plane residuals
// between every overlapping pair of frames in a window, all poses solved jointly with Ceres. A
// flat struct with in-class defaults and units; YAML section `icp_bundle:` maps onto it in io/.
// The struct builds without Ceres (the core profile parses and validates the section too).
#pragma once

#include <string>

namespace jpcr {

enum class BundleLoss { huber, cauchy };

struct IcpBundleParams {
  /// Semi-dense samples: every grid_stride-th pixel in u and v of frame i (method.md §9: "for
  /// example every 4th pixel") with a valid vertex and normal.
  int grid_stride = 4;  // px
  /// Normals from central differences at ±normal_offset px at 640x480 (frontend
  /// compute_normal_map), scaled with the image width so that the support in the scene is the
  /// front end's; a difference longer than normal_max_jump · z · offset marks a depth edge.
  int normal_offset = 4;          // px at 640 px width
  float normal_max_jump = 0.08f;  // fraction of z per pixel of offset
  /// Overlap test by projection, at the initial poses: the pair (i, j) takes part when at least
  /// this fraction of i's samples project into image j onto a pixel with depth.
  double min_overlap = 0.3;
  /// Projective association (method.md §5), re-found before every solve: a pair is rejected when
  /// the points are farther apart or the normals disagree more than this (ICP-ftf's gates).
  double max_distance = 0.1;       // m
  double max_normal_angle = 30.0;  // deg
  int min_pair_terms = 100;        // associations a pair (i, j) needs in a solve to take part
  BundleLoss robust_loss = BundleLoss::huber;
  double robust_scale = 0.01;  // m: Huber's δ or Cauchy's a on the point-to-plane residual
  int outer_iterations = 5;    // solves, with the correspondences re-found before each
  int solver_iterations = 10;  // Ceres iterations per solve (max_num_iterations)
  double translation_tolerance = 1e-5;  // m: converged when a whole solve moves every pose less
  double rotation_tolerance = 1e-5;     // rad: ... and turns it less than this
  /// λmin / λmax of the unit-free pose system at the end (RefinementReport::degeneracy) below
  /// which the verdict is kDegenerate: the window does not observe every pose (one plane).
  double degeneracy_threshold = 1e-4;
  int threads = 0;  // Ceres threads; 0: one per core

  void validate() const;  // throws InputError "field: problem"
};

/// "huber", "cauchy"; parse throws InputError listing the choices.
const char* to_string(BundleLoss loss);
BundleLoss parse_bundle_loss(const std::string& name);

}  // namespace jpcr
