// The main() of the Google Benchmark tools: --help says what the tool times and lists the
// library's common options; an unknown argument is a usage error (exit 2, as every jpcr tool);
// the console table is followed by the ratios of RatioReporter (ratio_reporter.hpp).
//
//   int main(int argc, char** argv) {
//     return jpcr::bench::benchmark_main(argc, argv, "bench_curvature", "Quad IT, Quad LS ...",
//                                        {{"BM_QuadLS", "BM_QuadIT"}});
//   }
#pragma once

#include <cstdio>
#include <string>
#include <utility>
#include <vector>

#include <benchmark/benchmark.h>

#include "ratio_reporter.hpp"

namespace jpcr::bench {

inline int benchmark_main(int argc, char** argv, const char* name, const char* description,
                          std::vector<RatioReporter::Ratio> ratios = {}) {
  bool console = true;  // --benchmark_format=json|csv gets the library's own reporter
  for (int i = 1; i < argc; ++i) {
    const std::string a = argv[i];
    if (a == "--help" || a == "-h") {
      std::printf(
          "usage: %s [Google Benchmark options]\n\n%s\n\n"
          "Common options (--benchmark_list_tests=true lists the benchmarks; Google Benchmark's\n"
          "documentation has the rest):\n"
          "  --benchmark_filter=REGEX        run only the benchmarks whose name matches\n"
          "  --benchmark_repetitions=N       repeat each N times; the ratios use the median\n"
          "  --benchmark_min_time=X          run each for at least X seconds (a plain number:\n"
          "                                  Debian 12's library 1.7 takes no unit suffix)\n"
          "  --benchmark_format=console|json|csv  output format (the ratios need console)\n"
          "  --benchmark_out=FILE            also write the results to FILE\n",
          name, description);
      return 0;
    }
    if (a.rfind("--benchmark_format=", 0) == 0) console = a == "--benchmark_format=console";
  }
  benchmark::Initialize(&argc, argv);
  if (argc > 1) {  // Initialize removed every option it knows
    std::fprintf(stderr, "%s: unknown argument '%s'\nTry '%s --help'.\n", name, argv[1], name);
    return 2;
  }
  RatioReporter reporter(std::move(ratios));
  if (console)
    benchmark::RunSpecifiedBenchmarks(&reporter);
  else
    benchmark::RunSpecifiedBenchmarks();
  benchmark::Shutdown();
  return 0;
}

}  // namespace jpcr::bench
