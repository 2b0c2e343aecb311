// The sampling pattern of method.md §2 and its scaling with resolution.
#include <set>

#include <gtest/gtest.h>

#include "jpcr/quadric/neighbourhood_pattern.hpp"

namespace jpcr {
namespace {

TEST(NeighbourhoodPattern, ReferencePatternHas129SamplesSpanning18Pixels) {
  const NeighbourhoodPattern p = NeighbourhoodPattern::make(6, 3);
  EXPECT_EQ(p.size(), 129);
  EXPECT_EQ(p.span(), 18);
  std::set<std::pair<int, int>> unique;
  for (const PixelOffset& o : p.offsets) {
    EXPECT_EQ(o.du % 3, 0);
    EXPECT_EQ(o.dv % 3, 0);
    EXPECT_LT((o.du / 3) * (o.du / 3) + (o.dv / 3) * (o.dv / 3), 41);
    unique.insert({o.du, o.dv});
  }
  EXPECT_EQ(unique.size(), 129u);
  EXPECT_EQ(unique.count({0, 0}), 1u);
}

TEST(NeighbourhoodPattern, ScalingKeepsTheImageFractionOfTheSpan) {
  EXPECT_EQ(NeighbourhoodPattern::scaled(6, 3, 640).size(), 129);
  const NeighbourhoodPattern half = NeighbourhoodPattern::scaled(6, 3, 320);
  EXPECT_EQ(half.stride, 2);  // round(1.5)
  EXPECT_NEAR(half.span(), 9, 1);
  const NeighbourhoodPattern quarter = NeighbourhoodPattern::scaled(6, 3, 160);
  EXPECT_EQ(quarter.stride, 1);
  EXPECT_NEAR(quarter.span(), 4.5, 0.5);
  const NeighbourhoodPattern big = NeighbourhoodPattern::scaled(6, 3, 1280);
  EXPECT_EQ(big.stride, 6);
  EXPECT_EQ(big.span(), 36);
}

TEST(NeighbourhoodPattern, RejectsNonPositiveSizes) {
  EXPECT_THROW(NeighbourhoodPattern::make(0, 3), std::invalid_argument);
  EXPECT_THROW(NeighbourhoodPattern::make(6, 0), std::invalid_argument);
  EXPECT_THROW(NeighbourhoodPattern::scaled(6, 3, 0), std::invalid_argument);
}

}  // namespace
}  // namespace jpcr
