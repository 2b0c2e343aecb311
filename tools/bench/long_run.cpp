// jpcr_long_run: the long-run check of issue 11. A long synthetic walk at small resolution goes
// through the whole system (KeyframePipeline, --method pipeline by default) in memory, as
// jpcr_run runs it. Prints a row per tenth of the run: the resident set size (/proc/self/statm,
// after malloc_trim so that it counts what is live rather than what the allocator keeps cached)
// and the heap in use (mallinfo2), the tracking ms per frame and the refinement ms per keyframe
// of that tenth. Then the figures over the first block after the warm-up and over the last block.
// Memory is sampled two ways: every 25 frames (whatever the back end is doing then: a window
// fills and empties, so these swing by a factor of two) and right after each J-full window has
// run (the same point of the cycle every time: the window emptied, its frames forgotten). The
// criterion compares the peaks of the after-window samples, where a leak shows as growth and the
// cycle does not; the every-25-frames peaks are printed beside them. Exit status 1 when the RSS
// peak grew by more than --max-rss-growth %, the heap in use (same peaks) by more than
// --max-heap-growth %, or the tracking time per frame or the refinement time per keyframe by more
// than --max-time-growth % (the time of one add() varies with how many keyframes a block holds;
// rendering is not timed). RSS also moves with the allocator's pages (about 1.5 MiB here), so on
// short, small runs only the heap says whether live memory grew (tests/tools: long_run_short). The
// pipeline runs with keep_history = false, as an unattended robot would: each frame goes to a
// FrameSink once final and is forgotten
// (--keep-history keeps them all, about 0.5 kB per frame, as jpcr_run does for trajectory.txt).
//
//   jpcr_long_run --frames 5000            # tools/bench/long_run.sh runs this
#include <malloc.h>
#include <unistd.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <fstream>
#include <iostream>
#include <numeric>
#include <stdexcept>

#include "cli/arguments.hpp"
#include "cli/pipeline_options.hpp"
#include "jpcr/backend/keyframe_pipeline.hpp"
#include "jpcr/io/synthetic_noise.hpp"
#include "jpcr/io/synthetic_sequence.hpp"
#include "jpcr/quadric/error.hpp"

namespace jpcr {

namespace {

using Clock = std::chrono::steady_clock;

// Resident set size in MiB (the second field of /proc/self/statm, in pages) once the allocator
// has returned its free memory to the system, and the heap in use.
struct Memory {
  double rss_mib = 0.0;
  double heap_mib = 0.0;
};

Memory memory() {
  malloc_trim(0);
  std::ifstream statm("/proc/self/statm");
  long size = 0, resident = 0;
  if (!(statm >> size >> resident)) throw InputError("/proc/self/statm: cannot be read");
  const double mib = 1024.0 * 1024.0;
  return {static_cast<double>(resident) * static_cast<double>(sysconf(_SC_PAGESIZE)) / mib,
          static_cast<double>(mallinfo2().uordblks) / mib};
}

double mean(const std::vector<double>& v, std::size_t first, std::size_t last) {
  return last > first ? std::accumulate(v.begin() + first, v.begin() + last, 0.0) /
                            static_cast<double>(last - first)
                      : 0.0;
}

// The tracking ms of frames [first, last) and the refinement ms of the keyframes among them.
struct BlockTimes {
  double track_ms = 0.0;   // per frame
  double refine_ms = 0.0;  // per keyframe
  std::size_t keyframes = 0;
};

// What the FrameSink saw of each final frame: its tracking time, its keyframe's refinement time
// (for the frame a keyframe was made from; NaN otherwise) and whether it is trusted.
struct FinalFrames {
  std::vector<double> track_ms, refine_ms;
  std::size_t untrusted = 0;
};

BlockTimes block_times(const FinalFrames& f, std::size_t first, std::size_t last) {
  BlockTimes t;
  std::vector<double> refine;
  for (std::size_t i = std::max<std::size_t>(first, 1); i < last; ++i)
    if (!std::isnan(f.refine_ms[i])) refine.push_back(f.refine_ms[i]);
  t.track_ms = mean(f.track_ms, first, last);
  t.refine_ms = mean(refine, 0, refine.size());
  t.keyframes = refine.size();
  return t;
}

double growth(double start, double end) {
  return start > 0.0 ? 100.0 * (end - start) / start : 0.0;
}

int long_run_main(int argc, char** argv) {
  cli::Arguments args(
      "jpcr_long_run",
      "Runs a long synthetic walk (ray-traced in memory) through the keyframe pipeline and\n"
      "checks that it runs in bounded memory and constant time: RSS (after malloc_trim) and\n"
      "heap in use after the warm-up and at the end; tracking ms per frame and refinement ms\n"
      "per keyframe over the first block after the warm-up and over the last block. Exit\n"
      "status 1 when the RSS, the heap or either time grew by its limit or more. Short runs\n"
      "are noisy (a few samples after the warm-up): the test runs 5000 frames.");
  args.option("frames", "frames of the walk", "5000")
      .option("scene", "synthetic scene name or .yaml path", "room_spheres")
      .option("noise", "none | range:K | kinect", "range:1")
      .option("width", "px", "160")
      .option("height", "px", "120")
      .option("seed", "walk and noise seed", "5")
      .option("warmup", "frames before the RSS baseline (default: a tenth of --frames)")
      .option("block", "frames averaged for ms per frame at start and end (default: a tenth)")
      .option("max-rss-growth", "%, allowed RSS growth from the warm-up to the end", "5")
      .option("max-heap-growth", "%, allowed growth of the heap in use, the same way", "5")
      .option("max-time-growth",
              "%, allowed growth of tracking ms per frame and refinement ms per keyframe", "25")
      .option("method", "pipeline | icp-ftf | j-ftf | j-full | q-full (default: params)")
      .option("window", "keyframes per J-full window, 2-16 (default: params)")
      .option("params", "parameter YAML (sections frontend, quadric, joint, pipeline)")
      .flag("keep-history",
            "keep every frame in memory (as jpcr_run) instead of forgetting each "
            "once final");
  args.epilog("example:\n  jpcr_long_run --frames 2000 --max-time-growth 50");
  return cli::run_program("jpcr_long_run", [&] {
    if (!args.parse(argc, argv)) return 0;
    const int frames = args.get_int("frames");
    if (frames < 20) throw cli::UsageError("--frames must be at least 20");
    const int tenth = frames / 10;
    const int warmup = args.has("warmup") ? args.get_int("warmup") : tenth;
    const int block = args.has("block") ? args.get_int("block") : tenth;
    if (warmup < 1 || block < 1 || warmup + block > frames)
      throw cli::UsageError("--warmup and --block must be positive, their sum at most --frames");
    for (const char* bound : {"max-rss-growth", "max-heap-growth", "max-time-growth"}) {
      const double percent = args.get_double(bound);
      if (!(std::isfinite(percent) && percent >= 0.0))
        throw cli::UsageError(std::string("--") + bound + " must be a percentage >= 0");
    }
    SyntheticSequenceOptions o;
    o.scene = args.get("scene");
    o.frames = frames;
    // Command-line mistakes are usage errors (exit 2), named by their option, as in jpcr_synth.
    try {
      o.noise = parse_noise(args.get("noise")).describe();
    } catch (const InputError& e) {
      throw cli::UsageError(std::string("--noise: ") + e.what());
    }
    o.width = args.get_int("width");
    o.height = args.get_int("height");
    if (o.width < 1 || o.width > 16384 || o.height < 1 || o.height > 16384)
      throw cli::UsageError("--width and --height must be in 1..16384 px");
    const int seed = args.get_int("seed");
    if (seed < 0) throw cli::UsageError("--seed must be a non-negative integer");
    o.seed = static_cast<std::uint64_t>(seed);
    const SyntheticSequence seq = make_synthetic_sequence(o);
    PipelineParams params = cli::pipeline_params_from(args);
    params.keep_history = args.get_flag("keep-history");

    std::size_t maps = 0;
    KeyframePipeline pipeline(params, [&](int, const Frame&, const QuadricMap&) { ++maps; });
    FinalFrames final_frames;  // reserved: the tool's own records must not count as growth
    final_frames.track_ms.reserve(static_cast<std::size_t>(frames));
    final_frames.refine_ms.reserve(static_cast<std::size_t>(frames));
    pipeline.set_frame_sink([&](const PipelineFrame& f, const StampedPose&,
                                const FrameVerdicts& v) {
      final_frames.track_ms.push_back(f.track_ms);
      const bool is_keyframe =
          f.keyframe >= 0 &&
          pipeline.keyframe(static_cast<std::size_t>(f.keyframe)).frame == f.index;
      final_frames.refine_ms.push_back(
          is_keyframe ? pipeline.keyframe(static_cast<std::size_t>(f.keyframe)).refine_ms : NAN);
      if (!v.trusted()) ++final_frames.untrusted;
    });
    std::vector<double> ms(static_cast<std::size_t>(frames));
    // Memory is sampled every `kSampleEvery` frames: the peak over the first block after the
    // warm-up against the peak over the last block (what a window holds varies from sample to
    // sample; a leak lifts the peaks).
    constexpr int kSampleEvery = 25;
    Memory start, peak, first_peak, last_peak;
    Memory first_window_peak, last_window_peak;  // right after each window (see the header)
    std::size_t first_windows = 0, last_windows = 0;
    const auto raise = [](const Memory& m, Memory& to) {
      to.rss_mib = std::max(to.rss_mib, m.rss_mib);
      to.heap_mib = std::max(to.heap_mib, m.heap_mib);
    };
    const auto in_first_block = [&](int n) { return n > warmup && n <= warmup + block; };
    const auto in_last_block = [&](int n) { return n > frames - block; };
    std::size_t keyframes_seen = 0;
    std::printf("%8s %9s %9s %10s %11s %9s %10s %9s\n", "frame", "RSS MiB", "heap MiB", "add ms",
                "track ms", "refine ms", "keyframes", "held");
    for (int i = 0; i < frames; ++i) {
      const Frame frame = seq.load(static_cast<std::size_t>(i));
      const Clock::time_point t0 = Clock::now();
      pipeline.add(frame);
      ms[i] = std::chrono::duration<double, std::milli>(Clock::now() - t0).count();
      if (i + 1 == warmup) start = memory();
      // A new keyframe whose window report is set: its J-full window ran in this add().
      if (pipeline.keyframe_count() != keyframes_seen) {
        keyframes_seen = pipeline.keyframe_count();
        if (pipeline.keyframe(keyframes_seen - 1).window) {
          const Memory m = memory();
          if (in_first_block(i + 1)) raise(m, first_window_peak), ++first_windows;
          if (in_last_block(i + 1)) raise(m, last_window_peak), ++last_windows;
        }
      }
      if ((i + 1) % kSampleEvery == 0 || (i + 1) % tenth == 0) {
        const Memory m = memory();
        raise(m, peak);
        if (in_first_block(i + 1)) raise(m, first_peak);
        if (in_last_block(i + 1)) raise(m, last_peak);
        if ((i + 1) % tenth != 0) continue;
        // Times of the last tenth of the frames that are final by now.
        const std::size_t done = final_frames.track_ms.size();
        const BlockTimes t = block_times(
            final_frames, done > static_cast<std::size_t>(tenth) ? done - tenth : 0, done);
        std::printf("%8d %9.2f %9.2f %10.2f %11.2f %9.1f %10zu %9zu\n", i + 1, m.rss_mib,
                    m.heap_mib, mean(ms, i + 1 - tenth, i + 1), t.track_ms, t.refine_ms,
                    pipeline.keyframe_count(), pipeline.frames().size());
        std::fflush(stdout);
      }
    }
    pipeline.finish();
    const Memory end = memory();
    if (final_frames.track_ms.size() != static_cast<std::size_t>(frames))
      throw std::logic_error("the frame sink saw " + std::to_string(final_frames.track_ms.size()) +
                             " of " + std::to_string(frames) + " frames");
    // Methods without windows (icp-ftf, j-ftf) have no cycle: their periodic samples are used.
    const bool by_window = first_windows > 0 && last_windows > 0;
    const Memory& first_memory = by_window ? first_window_peak : first_peak;
    const Memory& last_memory = by_window ? last_window_peak : last_peak;
    const double rss_growth = growth(first_memory.rss_mib, last_memory.rss_mib);
    const double heap_growth = growth(first_memory.heap_mib, last_memory.heap_mib);
    const BlockTimes first_block = block_times(final_frames, warmup, warmup + block);
    const BlockTimes last_block = block_times(final_frames, frames - block, frames);
    const double track_growth = growth(first_block.track_ms, last_block.track_ms);
    const double refine_growth = growth(first_block.refine_ms, last_block.refine_ms);
    std::printf(
        "%s, %d frames %dx%d, noise %s, method %s, window %d, %s: %zu keyframes, %zu maps, "
        "%zu frames not trusted\n",
        o.scene.c_str(), frames, o.width, o.height, o.noise.c_str(), to_string(params.method),
        params.window, params.keep_history ? "every frame kept" : "final frames forgotten",
        pipeline.keyframe_count(), maps, final_frames.untrusted);
    std::printf(
        "RSS after %d warm-up frames: %.2f MiB, at the end: %.2f MiB, peak %.2f\n"
        "every %d frames, peak over frames %d-%d -> %d-%d: RSS %.2f -> %.2f MiB (%+.2f %%), heap "
        "in use %.2f -> %.2f MiB (%+.2f %%)\n"
        "right after each window (%zu and %zu windows): RSS %.2f -> %.2f MiB (%+.2f %%), heap in "
        "use %.2f -> %.2f MiB (%+.2f %%)\n",
        warmup, start.rss_mib, end.rss_mib, peak.rss_mib, kSampleEvery, warmup, warmup + block - 1,
        frames - block, frames - 1, first_peak.rss_mib, last_peak.rss_mib,
        growth(first_peak.rss_mib, last_peak.rss_mib), first_peak.heap_mib, last_peak.heap_mib,
        growth(first_peak.heap_mib, last_peak.heap_mib), first_windows, last_windows,
        first_window_peak.rss_mib, last_window_peak.rss_mib,
        growth(first_window_peak.rss_mib, last_window_peak.rss_mib), first_window_peak.heap_mib,
        last_window_peak.heap_mib, growth(first_window_peak.heap_mib, last_window_peak.heap_mib));
    std::printf(
        "frames %d-%d -> %d-%d: tracking %.2f -> %.2f ms per frame (%+.1f %%), refinement "
        "%.1f -> %.1f ms per keyframe (%zu and %zu keyframes, %+.1f %%), add() %.2f -> %.2f "
        "ms per frame\n",
        warmup, warmup + block - 1, frames - block, frames - 1, first_block.track_ms,
        last_block.track_ms, track_growth, first_block.refine_ms, last_block.refine_ms,
        first_block.keyframes, last_block.keyframes, refine_growth,
        mean(ms, warmup, warmup + block), mean(ms, frames - block, frames));
    const double time_growth = std::max(track_growth, refine_growth);
    const bool rss_ok = rss_growth < args.get_double("max-rss-growth");
    const bool heap_ok = heap_growth < args.get_double("max-heap-growth");
    const bool time_ok = time_growth < args.get_double("max-time-growth");
    std::printf(
        "%s: RSS growth (%s peaks) < %s %%, %s: heap growth < %s %%, %s: tracking and refinement "
        "time growth < %s %%\n",
        rss_ok ? "PASS" : "FAIL", by_window ? "after-window" : "periodic",
        args.get("max-rss-growth").c_str(), heap_ok ? "PASS" : "FAIL",
        args.get("max-heap-growth").c_str(), time_ok ? "PASS" : "FAIL",
        args.get("max-time-growth").c_str());
    return rss_ok && heap_ok && time_ok ? 0 : 1;
  });
}

}  // namespace

}  // namespace jpcr

int main(int argc, char** argv) {
  return jpcr::long_run_main(argc, argv);
}
