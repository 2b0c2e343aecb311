#include "cli/heartbeat.hpp"

#include <algorithm>
#include <cstdio>
#include <exception>

namespace jpcr::cli {

Heartbeat::Heartbeat(std::string what, std::chrono::milliseconds interval, Say say)
    : what_(std::move(what)),
      interval_(interval),
      say_(std::move(say)),
      thread_([this] { beat(); }) {}

Heartbeat::~Heartbeat() {
  {
    std::lock_guard<std::mutex> lock(mutex_);
    stop_ = true;
  }
  stopped_.notify_one();
  thread_.join();
}

void Heartbeat::beat() {
  const auto start = std::chrono::steady_clock::now();
  std::unique_lock<std::mutex> lock(mutex_);
  for (auto next = start + interval_; !stopped_.wait_until(lock, next, [this] { return stop_; });) {
    const auto now = std::chrono::steady_clock::now();
    const auto seconds = std::chrono::duration_cast<std::chrono::seconds>(now - start);
    next = std::max(next + interval_, now + interval_);  // no burst after a stall (SIGSTOP)
    lock.unlock();                                       // said outside the lock
    try {
      say_(what_ + ": still working (" + std::to_string(seconds.count()) + " s)");
    } catch (const std::exception& e) {  // a line that cannot be said must not end the program
      std::fprintf(stderr, "heartbeat: %s\n", e.what());
    } catch (...) {
      std::fprintf(stderr, "heartbeat: a line could not be said\n");
    }
    lock.lock();
  }
}

}  // namespace jpcr::cli
