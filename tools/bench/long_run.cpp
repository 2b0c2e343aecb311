// jpcr_long_run: the long-run check of issue 11. A long synthetic walk at small resolution goes
// through the whole system (KeyframePipeline, --method pipeline by default) in memory, as
// jpcr_run runs it, while the resident set size is sampled (/proc/self/statm) and every add() is
// timed (tracking plus the refinements a keyframe triggers; rendering is not timed). Prints a row
// per tenth of the run, then RSS after the warm-up and at the end, its growth, and the mean ms
// per frame over the first block after the warm-up and over the last block. Exit status 1 when
// RSS grew by more than --max-rss-growth % or the ms per frame by more than --max-time-growth %.
//
//   jpcr_long_run --frames 5000            # tools/bench/long_run.sh runs this
#include <unistd.h>

#include <chrono>
#include <cstdio>
#include <fstream>
#include <iostream>
#include <numeric>

#include "cli/arguments.hpp"
#include "cli/pipeline_options.hpp"
#include "jpcr/backend/keyframe_pipeline.hpp"
#include "jpcr/io/synthetic_sequence.hpp"
#include "jpcr/quadric/error.hpp"

namespace jpcr {

namespace {

using Clock = std::chrono::steady_clock;

// Resident set size in MiB: the second field of /proc/self/statm, in pages.
double rss_mib() {
  std::ifstream statm("/proc/self/statm");
  long size = 0, resident = 0;
  if (!(statm >> size >> resident)) throw InputError("/proc/self/statm: cannot be read");
  return static_cast<double>(resident) * static_cast<double>(sysconf(_SC_PAGESIZE)) /
         (1024.0 * 1024.0);
}

double mean(const std::vector<double>& v, std::size_t first, std::size_t last) {
  return std::accumulate(v.begin() + first, v.begin() + last, 0.0) /
         static_cast<double>(last - first);
}

int long_run_main(int argc, char** argv) {
  cli::Arguments args(
      "jpcr_long_run",
      "Runs a long synthetic walk (ray-traced in memory) through the keyframe pipeline and\n"
      "checks that it runs in bounded memory and constant time per frame: RSS sampled from\n"
      "/proc/self/statm after the warm-up and at the end, mean ms per frame (add(): tracking\n"
      "and the refinements a keyframe triggers) over the first block after the warm-up and\n"
      "the last block. Exit status 1 when either grew by more than its limit.");
  args.option("frames", "frames of the walk", "5000")
      .option("scene", "synthetic scene name or .yaml path", "room_spheres")
      .option("noise", "none | range:K | kinect", "range:1")
      .option("width", "px", "160")
      .option("height", "px", "120")
      .option("seed", "walk and noise seed", "5")
      .option("warmup", "frames before the RSS baseline (default: a tenth of --frames)")
      .option("block", "frames averaged for ms per frame at start and end (default: a tenth)")
      .option("max-rss-growth", "%, allowed RSS growth from the warm-up to the end", "5")
      .option("max-time-growth", "%, allowed growth of ms per frame from start to end", "25")
      .option("method", "pipeline | icp-ftf | j-ftf | j-full | q-full (default: params)")
      .option("window", "keyframes per J-full window, 2-16 (default: params)")
      .option("params", "parameter YAML (sections frontend, quadric, joint, pipeline)");
  args.epilog("example:\n  jpcr_long_run --frames 500 --max-time-growth 50");
  return cli::run_program("jpcr_long_run", [&] {
    if (!args.parse(argc, argv)) return 0;
    const int frames = args.get_int("frames");
    if (frames < 20) throw cli::UsageError("--frames must be at least 20");
    const int tenth = frames / 10;
    const int warmup = args.has("warmup") ? args.get_int("warmup") : tenth;
    const int block = args.has("block") ? args.get_int("block") : tenth;
    if (warmup < 1 || block < 1 || warmup + block > frames)
      throw cli::UsageError("--warmup and --block must be positive, their sum at most --frames");
    SyntheticSequenceOptions o;
    o.scene = args.get("scene");
    o.frames = frames;
    o.noise = args.get("noise");
    o.width = args.get_int("width");
    o.height = args.get_int("height");
    o.seed = static_cast<std::uint64_t>(args.get_int("seed"));
    const SyntheticSequence seq = make_synthetic_sequence(o);
    PipelineParams params = cli::pipeline_params_from(args);

    std::size_t maps = 0;
    KeyframePipeline pipeline(params, [&](int, const Frame&, const QuadricMap&) { ++maps; });
    std::vector<double> ms(static_cast<std::size_t>(frames));
    std::size_t untrusted = 0;
    double rss_start = 0.0, rss_peak = 0.0;
    std::printf("%8s %10s %12s %10s %10s\n", "frame", "RSS MiB", "ms/frame", "keyframes",
                "untrusted");
    for (int i = 0; i < frames; ++i) {
      const Frame frame = seq.load(static_cast<std::size_t>(i));
      const Clock::time_point t0 = Clock::now();
      pipeline.add(frame);
      ms[i] = std::chrono::duration<double, std::milli>(Clock::now() - t0).count();
      if (!pipeline.verdicts(static_cast<std::size_t>(i)).trusted()) ++untrusted;
      if (i + 1 == warmup) rss_start = rss_mib();
      if ((i + 1) % tenth == 0) {
        const double rss = rss_mib();
        rss_peak = std::max(rss_peak, rss);
        std::printf("%8d %10.2f %12.2f %10zu %10zu\n", i + 1, rss, mean(ms, i + 1 - tenth, i + 1),
                    pipeline.keyframes().size(), untrusted);
        std::fflush(stdout);
      }
    }
    pipeline.finish();
    const double rss_end = rss_mib();
    rss_peak = std::max(rss_peak, rss_end);
    const double growth = 100.0 * (rss_end - rss_start) / rss_start;
    const double ms_start = mean(ms, warmup, warmup + block);
    const double ms_end = mean(ms, frames - block, frames);
    const double time_growth = 100.0 * (ms_end - ms_start) / ms_start;
    std::printf(
        "%s, %d frames %dx%d, noise %s, method %s, window %d: %zu keyframes, %zu maps, "
        "%zu frames not trusted\n",
        o.scene.c_str(), frames, o.width, o.height, o.noise.c_str(), to_string(params.method),
        params.window, pipeline.keyframes().size(), maps, untrusted);
    std::printf(
        "RSS after %d warm-up frames: %.2f MiB, at the end: %.2f MiB (peak %.2f): "
        "growth %+.2f %%\n",
        warmup, rss_start, rss_end, rss_peak, growth);
    std::printf("ms per frame, frames %d-%d: %.2f, frames %d-%d: %.2f: growth %+.1f %%\n", warmup,
                warmup + block - 1, ms_start, frames - block, frames - 1, ms_end, time_growth);
    const bool rss_ok = growth < args.get_double("max-rss-growth");
    const bool time_ok = time_growth < args.get_double("max-time-growth");
    std::printf("%s: RSS growth < %s %%, %s: ms per frame growth < %s %%\n",
                rss_ok ? "PASS" : "FAIL", args.get("max-rss-growth").c_str(),
                time_ok ? "PASS" : "FAIL", args.get("max-time-growth").c_str());
    return rss_ok && time_ok ? 0 : 1;
  });
}

}  // namespace

}  // namespace jpcr

int main(int argc, char** argv) {
  return jpcr::long_run_main(argc, argv);
}
