// How often a repeated log line may be written: a stream of the same kind of event (bad samples
// from a misconfigured camera at 30 Hz, out-of-order frames) must not flood the log. The first
// `free_lines` lines are written; after them, one per `quiet_seconds`, which says how many were
// left out since the last one written.
//
//   LogBudget lines;
//   std::size_t left_out = 0;
//   if (lines.allow(left_out)) log << "rejected sample: ..." << LogBudget::note(left_out) << '\n';
#pragma once

#include <chrono>
#include <cstddef>
#include <string>
#include <utility>

namespace jpcr {

class LogBudget {
 public:
  explicit LogBudget(std::size_t free_lines = 10, double quiet_seconds = 10.0)
      : free_lines_(free_lines), quiet_seconds_(quiet_seconds) {}

  /// Whether a line may be written now; `left_out` gets the lines held back since the last one.
  bool allow(std::size_t& left_out) {
    const auto now = std::chrono::steady_clock::now();
    if (written_ >= free_lines_ &&
        std::chrono::duration<double>(now - last_).count() < quiet_seconds_) {
      ++held_back_;
      return false;
    }
    left_out = std::exchange(held_back_, 0);
    ++written_;
    last_ = now;
    return true;
  }

  /// " (N such lines left out before)", or nothing when none were.
  static std::string note(std::size_t left_out) {
    return left_out == 0 ? "" : " (" + std::to_string(left_out) + " such lines left out before)";
  }

 private:
  std::size_t free_lines_;
  double quiet_seconds_;
  std::size_t written_ = 0, held_back_ = 0;
  std::chrono::steady_clock::time_point last_{};
};

}  // namespace jpcr
