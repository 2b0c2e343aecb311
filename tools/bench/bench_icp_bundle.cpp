// Speed of ICP-bundle (issue 9, method.md §9): one whole window refinement — overlap test,
// outer loop of association and Ceres solves — on room_spheres (walk) with range:1 noise, poses
// T_2 … T_M 1 cm / 1° off the truth, the default icp_bundle parameters (grid stride 4).
// Arguments: image width (height 3/4 of it), frames M, Ceres threads (0: one per core).
#include <benchmark/benchmark.h>

#include "bench_windows.hpp"
#include "benchmark_main.hpp"
#include "jpcr/backend/icp_bundle.hpp"

namespace {

void BM_IcpBundleWindow(benchmark::State& state) {
  const jpcr::bench::BenchWindow w = jpcr::bench::make_bench_window(
      static_cast<int>(state.range(0)), static_cast<int>(state.range(1)));
  jpcr::IcpBundleParams params;
  params.threads = static_cast<int>(state.range(2));
  const jpcr::IcpBundle bundle(params);
  jpcr::RefinementReport report;
  for (auto _ : state) {
    const jpcr::RefinementResult r = bundle.refine(w.vertices, w.camera, w.start);
    benchmark::DoNotOptimize(r.poses.back());
    report = r.report;
  }
  state.counters["terms"] = static_cast<double>(report.terms);
  state.counters["ceres_steps"] = report.iterations + report.rejected_steps;
  state.counters["solves"] = static_cast<double>(report.cost.size()) - 1.0;
  state.counters["converged"] = report.converged() ? 1.0 : 0.0;
}

BENCHMARK(BM_IcpBundleWindow)
    ->Args({320, 5, 0})
    ->Args({640, 5, 0})
    ->Args({640, 5, 1})
    ->Unit(benchmark::kMillisecond)
    ->UseRealTime();

}  // namespace

int main(int argc, char** argv) {
  return jpcr::bench::benchmark_main(
      argc, argv, "bench_icp_bundle",
      "Times one whole ICP-bundle window refinement (overlap test, association and Ceres\n"
      "solves) on room_spheres with 1 % range noise, M = 5, at 320x240 and 640x480.");
}
