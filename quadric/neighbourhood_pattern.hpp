// The sampling pattern around each pixel (method.md §2): every integer offset (i, j) with
// i² + j² < r² + 5, times a stride s. The reference r = 6, s = 3 at 640x480 gives 129 samples
// spanning ±18 px; at other resolutions the pattern is scaled to cover the same image fraction.
#pragma once

#include <vector>

namespace jpcr {

struct PixelOffset {
  int du = 0;
  int dv = 0;
};

struct NeighbourhoodPattern {
  int radius = 6;                    // r, in pattern cells
  int stride = 3;                    // s, pixels per cell
  std::vector<PixelOffset> offsets;  // centre (0, 0) included, row-major order

  /// The pattern of radius r and stride s; throws std::invalid_argument unless r ≥ 1, s ≥ 1.
  static NeighbourhoodPattern make(int radius, int stride);

  /// The reference pattern (r, s given at `reference_width`, 640 by default) scaled to an image
  /// `width` pixels wide: s' = max(1, round(s·f)), r' = max(1, round(r·s·f / s')) with
  /// f = width / reference_width, so the span r·s stays the same fraction of the image.
  static NeighbourhoodPattern scaled(int radius, int stride, int width, int reference_width = 640);

  int size() const { return static_cast<int>(offsets.size()); }
  /// Largest |du| (= largest |dv|) in pixels.
  int span() const;
};

}  // namespace jpcr
