// What the GPU benchmarks (bench_cuda_quadric, bench_cuda_joint) share: the command line
// [--runs N>=20] [--warmup N] [--no-cpu] [--width 320|640], the median and a wall clock in ms.
#pragma once

#include <algorithm>
#include <chrono>
#include <cstdio>
#include <cstdlib>
#include <string>
#include <vector>

namespace jpcr::bench {

struct CudaBenchOptions {
  int runs = 30;   // timed runs per row (at least 20)
  int warmup = 5;  // untimed runs before them
  bool cpu = true;
  std::vector<int> widths{320, 640};  // frame widths (height = 3/4 width); --width picks one
};

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
    } else if (a == "--no-cpu") {
      o.cpu = false;
    } else if (a == "--width" && i + 1 < argc &&
               (std::atoi(argv[i + 1]) == 320 || std::atoi(argv[i + 1]) == 640)) {
      o.widths = {std::atoi(argv[++i])};
    } else {
      const bool help = a == "--help" || a == "-h";
      std::fprintf(help ? stdout : stderr,
                   "usage: %s [--runs N>=20] [--warmup N] [--no-cpu] [--width 320|640]\n  %s\n",
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
