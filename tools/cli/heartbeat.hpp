// A line now and then while one long step runs: the progress line moves once per frame, and one
// frame can take tens of seconds (a J-full window of 640x480 keyframes on the CPU), which a user
// cannot tell from a hang. The step's own thread does the work; a second one only speaks.
#pragma once

#include <chrono>
#include <condition_variable>
#include <functional>
#include <mutex>
#include <string>
#include <thread>

namespace jpcr::cli {

class Heartbeat {
 public:
  using Say = std::function<void(const std::string& message)>;

  /// From construction until destruction, calls `say("<what>: still working (N s)")` every
  /// `interval`, from another thread (`say` must not share unsynchronised state with the step's
  /// thread; the step's own output waits until the step ends, so Progress::note is fine).
  Heartbeat(std::string what, std::chrono::milliseconds interval, Say say);
  /// Stops at once, without waiting out the interval.
  ~Heartbeat();
  Heartbeat(const Heartbeat&) = delete;
  Heartbeat& operator=(const Heartbeat&) = delete;

 private:
  void beat();

  std::string what_;
  std::chrono::milliseconds interval_;
  Say say_;
  std::mutex mutex_;
  std::condition_variable stopped_;
  bool stop_ = false;
  std::thread thread_;  // last: starts once the members above exist
};

}  // namespace jpcr::cli
