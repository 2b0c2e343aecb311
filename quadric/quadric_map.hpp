// A dense map of quadrics, one per pixel of a frame: what Quad IT, Quad LS, J-ftf and J-full
// produce, and what the curvature writers (io/curvature_output.hpp) and DDS publish.
#pragma once

#include <cstddef>
#include <cstdint>

#include <Eigen/Core>

#include "jpcr/quadric/image.hpp"
#include "jpcr/quadric/quadric_fit_kernel.hpp"
#include "jpcr/quadric/vertex_map.hpp"

namespace jpcr {

struct QuadricMap {
  Image<Quadric> quadrics;  // (R, p̄, t_z, a, b, c); meaningful where status == kValid
  // κ₁ ≥ κ₂ (1/m); NaN where invalid (never 0 for "unknown"). Signed with the normal toward the
  // camera (quadric_model.hpp): a sphere of radius R seen from outside is −1/R, the inside of a
  // bowl or a room's concave corner +1/R, a plane 0.
  CurvatureImage curvature;
  Image<Eigen::Vector3f> direction;  // first principal direction d₁ (camera frame); NaN invalid
  Image<QuadricStatus> status;       // kValid or why not

  QuadricMap() = default;
  QuadricMap(int width, int height);  // all pixels invalid (kNoCentre)

  int width() const { return status.width(); }
  int height() const { return status.height(); }
  bool valid(int u, int v) const { return status(u, v) == QuadricStatus::kValid; }
  std::size_t valid_count() const;

  /// Stores a fitted quadric and its curvature and direction (method.md §3 "Output").
  void set(int u, int v, const Quadric& q);
  /// Stores a quadric whose curvature was computed elsewhere (Quad LS's shape operator).
  void set(int u, int v, const Quadric& q, const Eigen::Vector2f& kappa, const Eigen::Vector3f& d1);
  void set_invalid(int u, int v, QuadricStatus why);

  /// The refined normals (third row of each R); NaN where invalid.
  NormalMap normals() const;
};

/// Pixels counted by status, for reports and warnings.
struct QuadricMapSummary {
  std::size_t pixels = 0, valid = 0, no_centre = 0, no_normal = 0, too_few_samples = 0,
              singular = 0, no_step = 0;
};
QuadricMapSummary summarize(const QuadricMap& map);

}  // namespace jpcr
