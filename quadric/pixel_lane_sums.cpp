#include "jpcr/quadric/pixel_lane_sums.hpp"

#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <stdexcept>

#include "jpcr/quadric/simd_clones.hpp"

namespace jpcr {

namespace {

constexpr int kColumns = kQuadricColumns;
constexpr int kProducts = kQuadricProducts;

// One copy of pixel_lane_sums.inc per instruction set, each compiled for its own target (a
// generic vector wider than the target's registers would be split, or worse scalarised, before
// it could be inlined into a target-specific function).
#if JPCR_HAVE_X86_TARGETS
#pragma GCC push_options
#pragma GCC target("arch=x86-64-v4")
namespace avx512 {
constexpr int kLanes = 16;
#include "pixel_lane_sums.inc"
}  // namespace avx512
#pragma GCC pop_options
#pragma GCC push_options
#pragma GCC target("arch=x86-64-v3")
namespace avx2 {
constexpr int kLanes = 8;
#include "pixel_lane_sums.inc"
}  // namespace avx2
#pragma GCC pop_options
#endif
namespace baseline {
constexpr int kLanes = 4;
#include "pixel_lane_sums.inc"
}  // namespace baseline

}  // namespace

SimdLevel cpu_simd_level() {
#if JPCR_HAVE_X86_TARGETS
  static const SimdLevel level = [] {
    SimdLevel best = SimdLevel::kBaseline;
    if (__builtin_cpu_supports("x86-64-v4"))
      best = SimdLevel::kAvx512;
    else if (__builtin_cpu_supports("x86-64-v3"))
      best = SimdLevel::kAvx2;
    const char* cap = std::getenv("JPCR_SIMD");
    if (cap == nullptr || *cap == '\0' || std::strcmp(cap, "avx512") == 0) return best;
    if (std::strcmp(cap, "avx2") == 0) return best > SimdLevel::kAvx2 ? SimdLevel::kAvx2 : best;
    if (std::strcmp(cap, "baseline") == 0) return SimdLevel::kBaseline;
    std::fprintf(stderr, "jpcr: JPCR_SIMD=%s is not avx512, avx2 or baseline; ignored\n", cap);
    return best;
  }();
  return level;
#else
  return SimdLevel::kBaseline;
#endif
}

void pixel_lane_sums(const PixelLaneQuadrics& q, const float* x, const float* y, const float* z,
                     const std::ptrdiff_t* offsets, int n, bool with_products, PixelLaneSums& out,
                     SimdLevel level) {
  if (level > cpu_simd_level())
    throw std::invalid_argument("pixel_lane_sums: this CPU lacks the requested SIMD level");
#if JPCR_HAVE_X86_TARGETS
  if (level == SimdLevel::kAvx512) return avx512::pass(q, x, y, z, offsets, n, with_products, out);
  if (level == SimdLevel::kAvx2) return avx2::pass(q, x, y, z, offsets, n, with_products, out);
#endif
  baseline::pass(q, x, y, z, offsets, n, with_products, out);
}

}  // namespace jpcr
