// jpcr_node's order of live frames (tools/jpcr_node/stamp_order.hpp): steps forward are taken at
// once however long, repeated and stale frames are skipped, a new time line is taken once
// confirmed, and a return to the line left needs the same confirmation.
#include <gtest/gtest.h>

#include <vector>

#include "jpcr/quadric/error.hpp"
#include "jpcr_node/stamp_order.hpp"

namespace jpcr::node {
namespace {

// The stamps `order` took, in order.
std::vector<double> taken(StampOrder& order, const std::vector<double>& stamps) {
  std::vector<double> out;
  for (const double s : stamps) {
    try {
      order.take(s);
      out.push_back(s);
    } catch (const InputError&) {
    }
  }
  return out;
}

TEST(StampOrder, StepsForwardAreTakenAtOnceHoweverLong) {
  StampOrder order;  // a 0.5 Hz sensor, with a dropout of 2.5 s
  const std::vector<double> slow = {100.0, 100.5, 103.0, 103.5, 104.0, 106.0, 108.0, 110.0};
  EXPECT_EQ(taken(order, slow), slow);
}

TEST(StampOrder, RepeatedAndStaleFramesAreSkipped) {
  StampOrder order;
  EXPECT_EQ(taken(order, {10.0, 10.1, 10.1, 10.05, 10.2, 9.5, 10.3}),
            (std::vector<double>{10.0, 10.1, 10.2, 10.3}));
}

TEST(StampOrder, ANewTimeLineIsTakenOnceConfirmed) {
  StampOrder order;  // a recording restarted at 0 after 50
  EXPECT_EQ(taken(order, {50.0, 50.1, 0.0, 0.1, 0.2, 0.3}),
            (std::vector<double>{50.0, 50.1, 0.2, 0.3}));
  // On the new line, a gap forward is a dropout, taken at once. One that reaches the old line
  // may be the old clock back, and is confirmed like a jump back; from there on, gaps forward
  // are taken at once again.
  EXPECT_EQ(taken(order, {3.0, 3.1, 60.0, 60.1, 60.2, 62.0, 65.0}),
            (std::vector<double>{3.0, 3.1, 60.2, 62.0, 65.0}));
}

TEST(StampOrder, OfTwoClocksTheNodeFollowsOne) {
  StampOrder order;  // publisher A near 1000 s, B near 0 s, interleaved
  EXPECT_EQ(taken(order, {1000.0, 0.0, 1000.1, 0.1, 1000.2, 0.2, 1000.3}),
            (std::vector<double>{1000.0, 1000.1, 1000.2, 1000.3}));
  // A burst of B is a new time line; A's frames then return to the line left and need the
  // same confirmation, so a single one of them is skipped.
  EXPECT_EQ(taken(order, {0.3, 0.4, 0.5, 1000.4, 0.6}), (std::vector<double>{0.5, 0.6}));
}

}  // namespace
}  // namespace jpcr::node
