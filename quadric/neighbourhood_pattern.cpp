#include "jpcr/quadric/neighbourhood_pattern.hpp"

#include <algorithm>
#include <cmath>
#include <stdexcept>
#include <string>

namespace jpcr {

NeighbourhoodPattern NeighbourhoodPattern::make(int radius, int stride) {
  if (radius < 1 || stride < 1 || radius > 64 || stride > 64) {
    throw std::invalid_argument(
        "neighbourhood pattern: radius and stride must be in [1, 64], got r = " +
        std::to_string(radius) + ", s = " + std::to_string(stride));
  }
  NeighbourhoodPattern p;
  p.radius = radius;
  p.stride = stride;
  const int limit = radius * radius + 5;  // method.md §2: i² + j² < r² + 5
  const int reach = radius + 2;           // √(r² + 4) < r + 2 for r ≥ 1
  for (int j = -reach; j <= reach; ++j)
    for (int i = -reach; i <= reach; ++i)
      if (i * i + j * j < limit) p.offsets.push_back({i * stride, j * stride});
  return p;
}

NeighbourhoodPattern NeighbourhoodPattern::scaled(int radius, int stride, int width,
                                                  int reference_width) {
  if (width < 1 || reference_width < 1)
    throw std::invalid_argument("neighbourhood pattern: image width must be positive");
  const double f = static_cast<double>(width) / reference_width;
  const int s = std::max(1, static_cast<int>(std::lround(stride * f)));
  const int r = std::max(1, static_cast<int>(std::lround(radius * stride * f / s)));
  return make(r, s);
}

int NeighbourhoodPattern::span() const {
  int m = 0;
  for (const PixelOffset& o : offsets)
    m = std::max({m, std::abs(o.du), std::abs(o.dv)});
  return m;
}

}  // namespace jpcr
