// Speed of the synthetic generator (issue 3: 100 frames at 640x480 with noise in under 20 s on 2
// cores). BM_Render ray-traces one frame with range:1 noise, ground truth included; BM_WriteFrame
// adds what jpcr_synth does per frame on top: encoding the PNGs and writing the .npy maps.
#include <benchmark/benchmark.h>

#include <filesystem>
#include <string>

#include "benchmark_main.hpp"
#include "jpcr/io/synthetic_sequence.hpp"
#ifdef JPCR_HAVE_FULL
#include "jpcr/io/synthetic_writer.hpp"
#endif

namespace {

const char* const kScenes[] = {"room_spheres", "cylinders_boxes", "torus_saddle", "rail_wall"};

jpcr::SyntheticSequence sequence(int scene, int frames) {
  jpcr::SyntheticSequenceOptions options;
  options.scene = kScenes[scene];
  options.trajectory = scene == 3 ? jpcr::TrajectoryKind::kRail : jpcr::TrajectoryKind::kWalk;
  options.frames = frames;
  options.noise = "range:1";
  return jpcr::make_synthetic_sequence(options);
}

void BM_Render(benchmark::State& state) {
  const jpcr::SyntheticSequence seq = sequence(static_cast<int>(state.range(0)), 30);
  std::size_t i = 0;
  for (auto _ : state) {
    benchmark::DoNotOptimize(seq.render(i++ % seq.size()));
  }
  state.SetLabel(kScenes[state.range(0)]);
  state.SetItemsProcessed(state.iterations());
}
BENCHMARK(BM_Render)->DenseRange(0, 3)->Unit(benchmark::kMillisecond)->UseRealTime();

#ifdef JPCR_HAVE_FULL
void BM_WriteSequence(benchmark::State& state) {
  const jpcr::SyntheticSequence seq = sequence(static_cast<int>(state.range(0)), 10);
  const std::string dir = (std::filesystem::temp_directory_path() / "jpcr_bench_synth").string();
  for (auto _ : state) {
    std::filesystem::remove_all(dir);
    jpcr::write_synthetic_sequence(seq, dir);
  }
  std::filesystem::remove_all(dir);
  state.SetLabel(std::string(kScenes[state.range(0)]) + ", 10 frames");
  state.SetItemsProcessed(state.iterations() * 10);
}
BENCHMARK(BM_WriteSequence)->DenseRange(0, 3)->Unit(benchmark::kMillisecond)->UseRealTime();
#endif

}  // namespace

int main(int argc, char** argv) {
  return jpcr::bench::benchmark_main(
      argc, argv, "bench_synthetic",
      "Times the synthetic generator on four of the built-in scenes (room_spheres,\n"
      "cylinders_boxes, torus_saddle, rail_wall; 640x480): ray-tracing one frame with\n"
      "1 % range noise and ground truth (BM_Render), and writing a 10-frame sequence as\n"
      "jpcr_synth does (BM_WriteSequence, in full builds).");
}
