// The receive loop the three jpcr_node roles share: take the next input (a depth frame, or a
// keyframe message for the back end), process it, until SIGINT/SIGTERM, --max-frames,
// --idle-timeout or the end of the stream; and the progress line.
#pragma once

#include <unistd.h>

#include <chrono>
#include <cstddef>
#include <cstdio>
#include <functional>
#include <iostream>
#include <string>
#include <utility>

#include "cli/stop_signal.hpp"
#include "jpcr/backend/pipeline_back_end.hpp"
#include "jpcr/io/dds/dds_depth_subscriber.hpp"
#include "jpcr/io/dds/ros_image.hpp"
#include "jpcr/io/log_budget.hpp"
#include "jpcr/quadric/error.hpp"
#include "stamp_order.hpp"

namespace jpcr::node {

using Clock = std::chrono::steady_clock;

inline double seconds_since(Clock::time_point t) {
  return std::chrono::duration<double>(Clock::now() - t).count();
}

struct StopRules {
  int max_items = 0;          // stop after this many processed inputs (0: no limit)
  double idle_timeout = 0.0;  // s without a processed input after the first one (0: never)
  /// Asked whenever no input is waiting: a non-empty answer stops the loop with it as the reason
  /// (the back end's front end went away).
  std::function<std::string()> source_gone;
};

enum class Step { kProcessed, kEndOfStream };

struct Outcome {
  std::size_t processed = 0;
  std::size_t skipped = 0;  // inputs on_input refused with an InputError (logged)
  std::string reason = "signal";
  double seconds = 0.0;  // from the first input's arrival to the end of the last one's processing
};

/// "N inputs in S s (R/s)", the sustained rate of a run.
inline std::string rate_summary(const Outcome& o, const char* inputs) {
  char line[128];
  std::snprintf(line, sizeof line, "%zu %s in %.3f s (%.1f/s)", o.processed, inputs, o.seconds,
                o.seconds > 0.0 ? o.processed / o.seconds : 0.0);
  return line;
}

/// Calls on_input(input) for each `next(slice)` that is not empty, until a stop. An InputError
/// from on_input skips that input with one log line (the first 10, then one per 10 s); a skipped
/// input is no activity for --idle-timeout.
template <typename Next, typename OnInput>
Outcome receive(const StopRules& rules, Next&& next, OnInput&& on_input) {
  constexpr std::chrono::milliseconds kSlice{100};  // signal and idle polling interval
  Outcome out;
  bool received = false;
  Clock::time_point first = Clock::now(), last = first;
  LogBudget skip_lines;
  while (!cli::stop_requested()) {
    if (rules.max_items > 0 && out.processed >= static_cast<std::size_t>(rules.max_items)) {
      out.reason = "--max-frames";
      break;
    }
    if (received && rules.idle_timeout > 0.0 && seconds_since(last) >= rules.idle_timeout) {
      out.reason = "--idle-timeout";
      break;
    }
    auto input = next(kSlice);
    if (!input) {
      if (rules.source_gone) {
        std::string gone = rules.source_gone();
        if (!gone.empty()) {
          out.reason = std::move(gone);
          break;
        }
      }
      continue;
    }
    const Clock::time_point arrived = Clock::now();
    try {
      const Step step = on_input(*input);
      if (!received) first = arrived;
      received = true;
      last = Clock::now();
      if (step == Step::kEndOfStream) {
        out.reason = "end of stream";
        break;
      }
      ++out.processed;
      out.seconds = seconds_since(first);
    } catch (const InputError& e) {  // e.g. a frame of another size than the first
      ++out.skipped;
      std::size_t left_out = 0;
      if (skip_lines.allow(left_out))
        std::cerr << "jpcr_node: skipped an input: " << e.what() << LogBudget::note(left_out)
                  << '\n';
    }
  }
  return out;
}

/// "rejected R samples, dropped D frames" of a depth subscriber, and ", W frames left
/// unprocessed" when a stop left frames received but not taken.
inline std::string input_summary(const DdsDepthSubscriber& subscriber) {
  std::string s = "rejected " + std::to_string(subscriber.samples_rejected()) +
                  " samples, dropped " + std::to_string(subscriber.frames_dropped()) + " frames";
  if (const std::size_t waiting = subscriber.frames_waiting(); waiting > 0)
    s += ", " + std::to_string(waiting) + " frames left unprocessed";
  return s;
}

/// One progress line per input: rewritten in place on a terminal; in a log inputs 1-10, then
/// every 10th.
class Progress {
 public:
  void frame(const PipelineFrame& f, std::size_t keyframes, const DdsDepthSubscriber& input) {
    if (!due()) return;
    std::fprintf(
        stderr,
        "%sjpcr_node: frame %zu  keyframes %zu  icp %s%s  rejected %zu  dropped %zu  %.1f s%s",
        terminal_ ? "\r" : "", count_, keyframes, to_string(f.icp_verdict),
        f.kept_last_motion ? " (kept last motion)" : "", input.samples_rejected(),
        input.frames_dropped(), seconds_since(start_), terminal_ ? "" : "\n");
  }
  void keyframe(std::size_t keyframes, std::size_t frames) {
    if (!due()) return;
    std::fprintf(stderr, "%sjpcr_node: keyframe %zu  frames %zu  %.1f s%s", terminal_ ? "\r" : "",
                 keyframes, frames, seconds_since(start_), terminal_ ? "" : "\n");
  }
  /// Ends the line on a terminal.
  void done() const {
    if (terminal_ && count_ > 0) std::fputc('\n', stderr);
  }

 private:
  bool due() {
    ++count_;
    return terminal_ || count_ <= 10 || count_ % 10 == 0;
  }
  Clock::time_point start_ = Clock::now();
  bool terminal_ = isatty(2) != 0;
  std::size_t count_ = 0;
};

}  // namespace jpcr::node
