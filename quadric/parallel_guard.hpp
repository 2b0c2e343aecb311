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
// Once one piece has failed, the pieces that start after it return at once (the loop still visits
// its rows, which every thread must, but does no work; pieces already running finish): the
// result is discarded anyway.
#pragma once

#include <atomic>
#include <exception>
#include <utility>

namespace jpcr {

class ParallelGuard {
 public:
  /// Runs f() unless a piece has failed already; records what it throws. Thread-safe.
  template <typename F>
  void run(F&& f) noexcept {
    if (failed()) return;
    try {
      std::forward<F>(f)();
    } catch (...) {
      record_current();
    }
  }

  /// In a catch block: records the exception being handled, unless one was recorded before
  /// (for loops whose body cannot be a lambda: clang rejects a lambda that uses the enclosing
  /// function's variables inside a generic lambda in an OpenMP region, llvm-project#58421).
  void record_current() noexcept {
    if (!failed_.exchange(true, std::memory_order_acq_rel)) error_ = std::current_exception();
  }

  /// Whether a piece has failed: the pieces that start after it return at once.
  bool failed() const noexcept { return failed_.load(std::memory_order_relaxed); }

  /// After the region (whose end is a barrier): rethrows the first exception recorded, if any.
  void rethrow() const {
    if (error_) std::rethrow_exception(error_);
  }

 private:
  std::atomic<bool> failed_{false};
  std::exception_ptr error_;  // written once, by the thread that set failed_
};

}  // namespace jpcr
