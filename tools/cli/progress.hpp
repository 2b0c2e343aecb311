// A progress line for long runs: rewritten in place on a terminal, every 10 % otherwise (so logs
// stay short). Prints to stderr: "<program>: frame i/N  t s  r frames/s [extra]".
#pragma once

#include <chrono>
#include <string>

namespace jpcr::cli {

class Progress {
 public:
  using Clock = std::chrono::steady_clock;

  explicit Progress(std::string program, Clock::time_point start = Clock::now());

  /// Reports `done` of `total` items; `extra` is appended (e.g. the last frame's verdict).
  void operator()(std::size_t done, std::size_t total, const std::string& extra = "");

  /// Prints "<program>: <message>" on a line of its own (clearing the progress line on a
  /// terminal; the next report redraws it).
  void note(const std::string& message) const;

  double seconds() const;

 private:
  std::string program_;
  Clock::time_point start_;
  bool terminal_;
};

/// "a:b" (half-open, either side may be empty), "a" (one frame) or "" (all) → [first, last).
/// Throws UsageError naming the text when it is malformed or empty after clamping to `size`;
/// a LAST beyond `size` is clamped with a warning on stderr (a script's "0:300" on a shorter
/// dataset runs what there is, and says so).
struct FrameRange {
  std::size_t first = 0, last = 0;
};
FrameRange parse_frame_range(const std::string& text, std::size_t size);

}  // namespace jpcr::cli
