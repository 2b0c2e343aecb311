// Parameters shared by the per-pixel quadric estimators (Quad IT, Quad LS) and the joint
// refiners: the sampling pattern, the initial normals and the Quad IT solver. YAML section
// `quadric:` (io/params.hpp).
#pragma once

#include "jpcr/quadric/neighbourhood_pattern.hpp"
#include "jpcr/quadric/quadric_fit_kernel.hpp"
#include "jpcr/quadric/surface_normals.hpp"

namespace jpcr {

/// The pattern of method.md §2, given at a reference width and scaled to each image.
struct PatternParams {
  int radius = 6;             // r, pattern cells at the reference width
  int stride = 3;             // s, pixels per cell at the reference width
  int reference_width = 640;  // px: the width r and s are given for

  /// The pattern for images `width` px wide. Throws InputError naming the fields when the scaled
  /// radius or stride leaves [1, 64] (a reference_width far from the images').
  NeighbourhoodPattern for_width(int width) const;
  void validate() const;  // throws InputError "field: problem"
};

struct QuadricParams {
  PatternParams pattern;
  NormalEstimationParams normals;
  QuadricFitParams fit;

  /// pattern.for_width(width), refused (InputError) when it has fewer samples than
  /// fit.min_samples: validate() checks the pattern at reference_width, and a narrower image
  /// scales it down (r = 5, s = 2 at 320 px: 97 of 129), where no pixel could have a quadric.
  NeighbourhoodPattern pattern_for(int width) const;
  void validate() const;
};

}  // namespace jpcr
