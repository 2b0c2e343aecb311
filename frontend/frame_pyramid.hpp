// Preprocessing for the front end: optional bilateral filter of the depth, a 3-level pyramid
// (2x2 block averages that do not cross depth edges), and a vertex and normal map per level
// (method.md §1: normals point toward the camera).
#pragma once

#include <algorithm>

#include <vector>

#include "jpcr/frontend/frontend_params.hpp"
#include "jpcr/frontend/row_pool.hpp"
#include "jpcr/quadric/frame.hpp"
#include "jpcr/quadric/vertex_map.hpp"

namespace jpcr {

/// One level of the pyramid: the camera at that resolution and its maps (camera frame).
struct PyramidLevel {
  CameraIntrinsics camera;
  DepthImage depth;  // m, 0 where there is no measurement
  VertexMap vertices;
  NormalMap normals;  // unit, n·X < 0; NaN at edges and where the vertex is missing. Empty at
                      // level 0 unless PreprocessParams::full_resolution_normals.
  std::size_t valid_vertices = 0;
};

struct FramePyramid {
  static constexpr int kLevels = 3;
  double timestamp = 0.0;
  std::vector<PyramidLevel> levels;  // levels[0] is full resolution, each next one half the size
  int filter_radius = 0;             // px, the bilateral filter of level 0's depth (0: none)
  float filter_sigma_space = 0.0f;   // px
};

/// How much more the sum of a residual over every `stride`-th pixel (in u and v) of level 0
/// varies than it would over independent samples, when the depth went through the bilateral
/// filter: each raw sample is shared by the filtered pixels around it. For a smooth Jacobian the
/// variance of a least-squares estimate grows by Σ_k ρ(k) over the lattice offsets k ∈ stride·Z²
/// (ρ: the normalised autocorrelation of the filter's spatial kernel), so σ²(JᵀWJ)⁻¹ from the
/// filtered residuals understates it by that factor. The range weights only narrow the kernel:
/// this is an upper bound. 1 without a filter. At pyramid `level` l every pixel is the mean of a
/// 2^l x 2^l block of level 0's, and the lattice is stride · 2^l level-0 pixels.
double filtered_noise_inflation(const FramePyramid& pyramid, int stride, int level = 0);

/// The normal map that serves `level`: its own, or when it has none the next coarser level's,
/// read at (u >> shift, v >> shift). The coarser level has ⌊w/2⌋ x ⌊h/2⌋ pixels, so the last
/// column or row of an odd-sized level reads the coarse map's last one.
struct NormalLookup {
  const NormalMap* normals = nullptr;
  int shift = 0;
  const Eigen::Vector3f& operator()(int u, int v) const {
    return (*normals)(std::min(u >> shift, normals->width() - 1),
                      std::min(v >> shift, normals->height() - 1));
  }
};
NormalLookup normals_for(const FramePyramid& pyramid, int level);

/// Throws InputError when the depth image size differs from the camera's, the camera is
/// invalid, or PreprocessParams::validate refuses `params`. NaN, Inf and negative depths read as
/// "no measurement". `pool` spreads the rows over threads; null runs on the calling thread.
FramePyramid preprocess(const Frame& frame, const PreprocessParams& params = {},
                        RowPool* pool = nullptr);

/// Edge-preserving smoothing of depth (m); pixels without depth stay without depth.
DepthImage bilateral_filter(const DepthImage& depth, const PreprocessParams& params,
                            RowPool* pool = nullptr);

/// Half-size depth: each pixel averages the valid depths of its 2x2 block that lie within
/// max_depth_step of the block's nearest depth.
DepthImage downsample_depth(const DepthImage& depth, float max_depth_step, RowPool* pool = nullptr);

/// Normals from central differences at ±offset pixels; NaN where a neighbour is missing or a
/// difference's depth change exceeds max_jump × z per pixel of its 2·offset span, i.e.
/// max_jump × z × 2·offset (a depth edge).
NormalMap compute_normal_map(const VertexMap& vertices, int offset, float max_jump,
                             RowPool* pool = nullptr);

}  // namespace jpcr
