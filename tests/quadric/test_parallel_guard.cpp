// ParallelGuard (quadric/parallel_guard.hpp): an exception on a worker thread of an OpenMP region
// reaches the caller after the region, instead of std::terminate ending the process; the other
// threads still reach the region's worksharing constructs, and skip the work left.
#include <gtest/gtest.h>

#include <atomic>
#include <new>
#include <optional>
#include <stdexcept>
#include <vector>

#include "jpcr/quadric/parallel_guard.hpp"

namespace jpcr {
namespace {

constexpr int kRows = 1000;

TEST(ParallelGuard, AnExceptionInTheLoopIsRethrownAfterTheRegionAndTheRestIsSkipped) {
  ParallelGuard guard;
  std::atomic<int> done{0};
#pragma omp parallel
  {
#pragma omp for schedule(static)
    for (int v = 0; v < kRows; ++v)
      guard.run([&] {
        if (v == 0) throw std::bad_alloc();
        ++done;
      });
  }
  EXPECT_TRUE(guard.failed());
  EXPECT_THROW(guard.rethrow(), std::bad_alloc);
  // Row 0's thread skips the rest of its static chunk (rows 1 on, whatever the thread count).
  EXPECT_LT(done.load(), kRows - 1);
}

TEST(ParallelGuard, AFailedPerThreadSetupStillReachesTheLoop) {
  ParallelGuard guard;
  std::atomic<int> visited{0}, done{0};
  std::atomic<bool> thrown{false};
#pragma omp parallel
  {
    std::optional<std::vector<double>> buffers;
    // The first thread to get here fails; one that entered before the failure was recorded
    // succeeds, and the rest skip their setup.
    guard.run([&] {
      if (!thrown.exchange(true)) throw std::runtime_error("no buffers");
      buffers.emplace(8);
    });
#pragma omp barrier
    // Every thread's setup has run or been skipped: from here on no piece of work runs, not
    // even on a thread whose buffers exist.
#pragma omp for schedule(dynamic, 4)
    for (int v = 0; v < kRows; ++v) {
      ++visited;  // the loop is reached and run through (no thread waits at its barrier)
      guard.run([&] {
        if (buffers) ++done;
      });
    }
  }
  EXPECT_EQ(visited.load(), kRows);
  EXPECT_EQ(done.load(), 0);
  try {
    guard.rethrow();
    FAIL() << "nothing rethrown";
  } catch (const std::runtime_error& e) {
    EXPECT_STREQ(e.what(), "no buffers");
  }
}

TEST(ParallelGuard, WithoutAnExceptionEveryPieceRunsAndNothingIsRethrown) {
  ParallelGuard guard;
  std::vector<int> rows(kRows, 0);
#pragma omp parallel for schedule(dynamic, 8)
  for (int v = 0; v < kRows; ++v)
    guard.run([&] { rows[v] = v + 1; });
  EXPECT_FALSE(guard.failed());
  EXPECT_NO_THROW(guard.rethrow());
  for (int v = 0; v < kRows; ++v)
    ASSERT_EQ(rows[v], v + 1);
}

}  // namespace
}  // namespace jpcr
