// What the GPU benchmarks (bench_cuda_quadric, bench_cuda_joint) share: the command line
// [--runs N>=20] [--warmup N] [--no-cpu] [--width 320|640] [--noise-matched], the quadric
// parameters, the median and a wall clock in ms.
#pragma once

#include <algorithm>
#include <chrono>
#include <cstdio>
#include <cstdlib>
#include <string>
#include <vector>

#include "jpcr/quadric/quadric_params.hpp"

namespace jpcr::bench {

struct CudaBenchOptions {
  int runs = 30;   // timed runs per row (at least 20)
  int warmup = 5;  // untimed runs before them
  bool cpu = true;
  std::vector<int> widths{320, 640};  // frame widths (height = 3/4 width); --width picks one
  bool noise_matched = false;         // the report's rule for the frames' range:1 noise
};

/// The quadric parameters of a bench at `width`: the reference 129-sample pattern at every
/// size, and with --noise-matched the report's rule for range:K noise (jpcr_eval noise
/// --noise-matched): n₀ = gate = 3σ per metre of range, 0.03 for the benches' range:1.
inline void bench_quadric_params(int width, const CudaBenchOptions& o, QuadricParams& params) {
  params.pattern.reference_width = width;
  if (o.noise_matched) params.fit.fair_n0_per_range = params.fit.gate_per_range = 0.03f;
}

/// Parses the command line; returns -1 to go on, else the exit status (0 after --help, 2 for
/// a usage error), with the usage printed.
inline int parse_cuda_bench_options(int argc, char** argv, const char* name, const char* what,
                                    CudaBenchOptions& o) {
  for (int i = 1; i < argc; ++i) {
    const std::string a = argv[i];
    if (a == "--runs" && i + 1 < argc) {
      o.runs = std::max(20, std::atoi(argv[++i]));
    } else if (a == "--warmup" && i + 1 < argc) {
      o.warmup = std::max(1, std::atoi(argv[++i]));
    } else if (a == "--noise-matched") {
      o.noise_matched = true;
    } else if (a == "--no-cpu") {
      o.cpu = false;
    } else if (a == "--width" && i + 1 < argc &&
               (std::atoi(argv[i + 1]) == 320 || std::atoi(argv[i + 1]) == 640)) {
      o.widths = {std::atoi(argv[++i])};
    } else {
      const bool help = a == "--help" || a == "-h";
      std::fprintf(help ? stdout : stderr,
                   "usage: %s [--runs N>=20] [--warmup N] [--no-cpu] [--width 320|640] "
                   "[--noise-matched]\n  %s\n",
                   name, what);
      return help ? 0 : 2;
    }
  }
  return -1;
}

inline double median(std::vector<double> v) {
  std::sort(v.begin(), v.end());
  const std::size_t n = v.size();
  return n % 2 == 1 ? v[n / 2] : 0.5 * (v[n / 2 - 1] + v[n / 2]);
}

inline double ms_since(std::chrono::steady_clock::time_point since) {
  return std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - since)
      .count();
}

}  // namespace jpcr::bench
