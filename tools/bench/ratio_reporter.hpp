// Google Benchmark's console output, followed by the ratios of named benchmark families run in
// the same process at the same arguments (the project's rule: a speed goal is compared with its
// peer in the same run, as a ratio). Each ratio uses the real time per iteration, the median
// aggregate when --benchmark_repetitions gives one.
//
//   jpcr::bench::RatioReporter reporter({{"BM_QuadIT", "BM_CgalJetPeer"}});
//   benchmark::RunSpecifiedBenchmarks(&reporter);
//   // ... then: BM_QuadIT / BM_CgalJetPeer at /320/real_time: 0.412 (2.43x faster)
#pragma once

#include <unistd.h>

#include <cstdio>
#include <map>
#include <string>
#include <utility>
#include <vector>

#include <benchmark/benchmark.h>

namespace jpcr::bench {

class RatioReporter : public benchmark::ConsoleReporter {
 public:
  struct Ratio {
    std::string numerator, denominator;  // benchmark family names, e.g. "BM_QuadIT"
  };
  explicit RatioReporter(std::vector<Ratio> ratios)
      : ConsoleReporter(isatty(fileno(stdout)) ? OO_Defaults : OO_Tabular),  // no colour in logs
        ratios_(std::move(ratios)) {}

  void ReportRuns(const std::vector<Run>& runs) override {
    for (const Run& run : runs) {
      if (run.error_occurred) continue;
      const bool median = run.run_type == Run::RT_Aggregate && run.aggregate_name == "median";
      if (run.run_type != Run::RT_Iteration && !median) continue;
      // "BM_QuadIT/320/real_time" (or ".../real_time_median"): family and arguments.
      std::string name = run.benchmark_name();
      if (median) name = name.substr(0, name.rfind('_'));
      const std::size_t slash = name.find('/');
      const std::string family = name.substr(0, slash);
      const std::string arguments = slash == std::string::npos ? "" : name.substr(slash);
      Time& t = times_[{family, arguments}];
      if (median || !t.from_median) t = {run.GetAdjustedRealTime(), median};
    }
    ConsoleReporter::ReportRuns(runs);
  }

  void Finalize() override {
    ConsoleReporter::Finalize();
    bool any = false;
    for (const Ratio& r : ratios_)
      for (const auto& [key, numerator] : times_) {
        if (key.first != r.numerator) continue;
        const auto denominator = times_.find({r.denominator, key.second});
        if (denominator == times_.end() || !(denominator->second.value > 0.0)) continue;
        if (!any) std::printf("\nratios in this run (real time per iteration):\n");
        any = true;
        const double ratio = numerator.value / denominator->second.value;
        std::printf("%s / %s at %s: %.3f (%.2fx %s)\n", r.numerator.c_str(), r.denominator.c_str(),
                    key.second.c_str(), ratio, ratio < 1.0 ? 1.0 / ratio : ratio,
                    ratio < 1.0 ? "faster" : "slower");
      }
    std::fflush(stdout);
  }

 private:
  struct Time {
    double value = 0.0;
    bool from_median = false;
  };
  std::vector<Ratio> ratios_;
  std::map<std::pair<std::string, std::string>, Time> times_;
};

}  // namespace jpcr::bench
