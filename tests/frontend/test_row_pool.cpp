// RowPool: every row is visited exactly once whatever the thread count, slots stay in range, and
// thousands of back-to-back jobs (the ICP's pattern) neither lose nor repeat a chunk.
#include <atomic>
#include <numeric>
#include <vector>

#include <gtest/gtest.h>

#include "jpcr/frontend/row_pool.hpp"

namespace jpcr {
namespace {

TEST(RowPool, VisitsEveryRowOnceWithValidSlots) {
  for (int threads : {1, 2, 4}) {
    RowPool pool(threads);
    EXPECT_EQ(pool.slots(), threads);
    for (int rows : {0, 1, 7, 480}) {
      for (int chunk : {1, 8, 1000}) {
        std::vector<std::atomic<int>> visits(rows);
        std::atomic<bool> bad_slot{false};
        pool.for_rows(rows, chunk, [&](int begin, int end, int slot) {
          if (slot < 0 || slot >= pool.slots()) bad_slot = true;
          if (threads > 1 && end - begin > chunk) bad_slot = true;
          for (int r = begin; r < end; ++r)
            ++visits[r];
        });
        EXPECT_FALSE(bad_slot);
        for (int r = 0; r < rows; ++r)
          ASSERT_EQ(visits[r], 1) << threads << " threads, row " << r << " of " << rows;
      }
    }
  }
}

TEST(RowPool, ManyShortJobsSumExactly) {
  RowPool pool(3);
  std::vector<long> per_slot(pool.slots());
  long expected = 0;
  for (int job = 0; job < 3000; ++job) {
    const int rows = 1 + job % 50;
    expected += static_cast<long>(rows) * (rows - 1) / 2;
    pool.for_rows(rows, 2, [&](int begin, int end, int slot) {
      for (int r = begin; r < end; ++r)
        per_slot[slot] += r;  // each slot is written by one thread at a time
    });
  }
  EXPECT_EQ(std::accumulate(per_slot.begin(), per_slot.end(), 0L), expected);
}

TEST(RowPool, NullPoolRunsOnTheCaller) {
  int calls = 0;
  for_rows(nullptr, 10, 3, [&](int begin, int end, int slot) {
    EXPECT_EQ(begin, 0);
    EXPECT_EQ(end, 10);
    EXPECT_EQ(slot, 0);
    ++calls;
  });
  EXPECT_EQ(calls, 1);
}

}  // namespace
}  // namespace jpcr
