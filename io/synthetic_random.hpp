// Counter-based random numbers for the synthetic generator: every draw is a pure function of
// (seed, stream, counter), so the noise of a pixel does not depend on which thread rendered it or
// in what order (deterministic for a seed, whatever the thread count).
#pragma once

#include <cmath>
#include <cstdint>

namespace jpcr {

/// Streams keep unrelated draws of one seed independent.
enum class RandomStream : std::uint64_t {
  kDepthNoise = 1,  // Gaussian range / axial noise, one per pixel
  kDropout = 2,     // Kinect dropouts, one per pixel
  kWalk = 3,        // the random walk's frequencies, phases and amplitudes
};

class CounterRandom {
 public:
  /// `key` distinguishes e.g. frames; `stream` the purpose of the draws.
  CounterRandom(std::uint64_t seed, RandomStream stream, std::uint64_t key)
      : base_(mix(mix(seed ^ 0x6a09e667f3bcc909ULL) ^ static_cast<std::uint64_t>(stream)) ^
              mix(key + 0xbb67ae8584caa73bULL)) {}

  /// 64 uniformly distributed bits for `counter` (e.g. a pixel index).
  std::uint64_t bits(std::uint64_t counter) const { return mix(base_ ^ mix(counter)); }

  /// Uniform in the open interval (0, 1), from the top 53 bits.
  double uniform(std::uint64_t counter) const {
    return (static_cast<double>(bits(counter) >> 11) + 0.5) * 0x1.0p-53;
  }

  /// Standard normal by Box–Muller from the uniforms at 2·counter and 2·counter + 1.
  double gaussian(std::uint64_t counter) const {
    const double u1 = uniform(2 * counter), u2 = uniform(2 * counter + 1);
    return std::sqrt(-2.0 * std::log(u1)) * std::cos(6.283185307179586 * u2);
  }

 private:
  // The splitmix64 finaliser (Steele, Lea & Flood 2014): a bijective 64-bit mixer.
  static std::uint64_t mix(std::uint64_t x) {
    x += 0x9e3779b97f4a7c15ULL;
    x = (x ^ (x >> 30)) * 0xbf58476d1ce4e5b9ULL;
    x = (x ^ (x >> 27)) * 0x94d049bb133111ebULL;
    return x ^ (x >> 31);
  }

  std::uint64_t base_;
};

}  // namespace jpcr
