// Exceptions out of OpenMP parallel regions. An exception may not leave a region (the runtime
// calls std::terminate: an allocation that fails on a worker thread would end the process), and
// every thread of the team must reach each worksharing construct (`omp for`) that any reaches.
// So each piece of a region's work runs under ParallelGuard::run, which records the first
// exception and lets the rest of the work be skipped; the caller rethrows it after the region:
//
//   ParallelGuard guard;
//   #pragma omp parallel
//   {
//     std::optional<Scratch> scratch;
//     guard.run([&] { scratch.emplace(size); });   // per-thread buffers may fail to allocate
//   #pragma omp for
//     for (int v = 0; v < rows; ++v)
//       guard.run([&] { if (scratch) work(*scratch, v); });
//   }
//   guard.rethrow();
//
// Once one piece has failed, the others return at once (the loop still visits its rows, which
// every thread must, but does no work): the result is discarded anyway.
#pragma once

#include <atomic>
#include <exception>
#include <mutex>
#include <utility>

namespace jpcr {

class ParallelGuard {
 public:
  /// Runs f() unless a piece has failed already; records what it throws. Thread-safe.
  template <typename F>
  void run(F&& f) noexcept {
    if (failed_.load(std::memory_order_relaxed)) return;
    try {
      std::forward<F>(f)();
    } catch (...) {
      record(std::current_exception());
    }
  }

  bool failed() const { return failed_.load(std::memory_order_relaxed); }

  /// After the region: rethrows the first exception recorded, if any.
  void rethrow() const {
    if (error_) std::rethrow_exception(error_);
  }

 private:
  void record(std::exception_ptr e) noexcept {
    const std::lock_guard<std::mutex> lock(mutex_);
    if (!error_) error_ = std::move(e);
    failed_.store(true, std::memory_order_relaxed);
  }

  std::atomic<bool> failed_{false};
  std::mutex mutex_;
  std::exception_ptr error_;
};

}  // namespace jpcr
