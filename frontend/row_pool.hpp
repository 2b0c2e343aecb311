// A small pool of helper threads for the front end's per-row loops (association and reduction,
// vertex and normal maps). Unlike a fork-join region, the calling thread works too and never
// waits for a helper that has not started: chunks of rows are handed out one at a time, so a
// helper the OS schedules late finds nothing left and the caller only waits for chunks already
// in progress. On a machine shared with other jobs this keeps a frame's time close to the
// single-thread time instead of a scheduler time slice per parallel loop.
//
//   RowPool pool(2);                                  // the caller + 1 helper
//   std::vector<Sum> sums(pool.slots());
//   pool.for_rows(height, 8, [&](int begin, int end, int slot) { ... sums[slot] += ...; });
#pragma once

#include <condition_variable>
#include <cstdint>
#include <functional>
#include <mutex>
#include <thread>
#include <vector>

namespace jpcr {

class RowPool {
 public:
  using Body = std::function<void(int begin, int end, int slot)>;

  /// `threads` counts the caller: 1 runs everything on the calling thread; 0 means one per
  /// hardware thread.
  explicit RowPool(int threads = 0);
  ~RowPool();
  RowPool(const RowPool&) = delete;
  RowPool& operator=(const RowPool&) = delete;

  /// Number of distinct `slot` values body() can see: 0 is the caller, 1.. the helpers.
  int slots() const { return static_cast<int>(helpers_.size()) + 1; }

  /// Calls body(begin, end, slot) on chunks [begin, end) of [0, rows), at most `chunk` rows
  /// each (a pool of one thread makes a single call over all rows), and returns when all are
  /// done. body must not throw. Not reentrant: one call at a time per pool.
  void for_rows(int rows, int chunk, const Body& body);

 private:
  void helper(int slot);

  std::mutex mutex_;
  std::condition_variable wake_, finished_;
  std::vector<std::thread> helpers_;
  bool stop_ = false;
  // The current job, guarded by mutex_.
  const Body* body_ = nullptr;
  int rows_ = 0, chunk_ = 1, next_ = 0, done_ = 0, total_ = 0;
  std::uint64_t job_ = 0;
};

/// Runs body over [0, rows) on `pool`, or on the calling thread (slot 0) when pool is null.
inline void for_rows(RowPool* pool, int rows, int chunk, const RowPool::Body& body) {
  if (pool)
    pool->for_rows(rows, chunk, body);
  else if (rows > 0)
    body(0, rows, 0);
}

}  // namespace jpcr
