#include <algorithm>
#include <cmath>
#include <limits>

#include <gtest/gtest.h>

#include "jpcr/io/atomic_file.hpp"
#include "jpcr/io/number_format.hpp"
#include "jpcr/io/timestamp_association.hpp"
#include "jpcr/io/tum_lists.hpp"
#include "jpcr/quadric/error.hpp"
#include "jpcr/quadric/se3.hpp"
#include "temp_dir.hpp"

namespace jpcr {
namespace {

std::string error_of(const std::function<void()>& f) {
  try {
    f();
  } catch (const InputError& e) {
    return e.what();
  }
  return "";
}

TEST(FileList, ParsesCommentsAndEntries) {
  const auto list = parse_file_list(
      "# depth maps\n# x\n1.5 depth/a.png\n\n2.25 depth/b.png extra\n", "depth.txt");
  ASSERT_EQ(list.size(), 2u);
  EXPECT_DOUBLE_EQ(list[0].timestamp, 1.5);
  EXPECT_EQ(list[1].path, "depth/b.png");
  EXPECT_EQ(list[1].line, 5);
}

// Windows editors open a file with a UTF-8 byte-order mark; it is no part of the first line.
TEST(FileList, AByteOrderMarkIsSkipped) {
  const std::string bom = "\xEF\xBB\xBF";
  const auto list = parse_file_list(bom + "# timestamp filename\n1.5 depth/1.5.png\n", "d.txt");
  ASSERT_EQ(list.size(), 1u);
  EXPECT_EQ(list[0].path, "depth/1.5.png");
  const Trajectory t = parse_trajectory(bom + "2.0 1 2 3 0 0 0 1\n", "gt.txt");
  ASSERT_EQ(t.size(), 1u);
  EXPECT_EQ(t[0].timestamp, 2.0);
  EXPECT_EQ(without_utf8_bom("\xEF\xBB"), "\xEF\xBB");  // a part of one is kept
}

TEST(FileList, RejectsUnsortedDuplicateAndMalformedLinesNamingFileAndLine) {
  EXPECT_NE(error_of([] {
              parse_file_list("2 a.png\n1 b.png\n", "depth.txt");
            }).find("depth.txt:2: timestamps are not sorted"),
            std::string::npos);
  EXPECT_NE(error_of([] {
              parse_file_list("1 a.png\n1 b.png\n", "depth.txt");
            }).find("depth.txt:2: duplicate timestamp"),
            std::string::npos);
  EXPECT_NE(error_of([] { parse_file_list("abc a.png\n", "d.txt"); }).find("d.txt:1:"),
            std::string::npos);
  EXPECT_NE(error_of([] { parse_file_list("1.0\n", "d.txt"); }).find("d.txt:1:"),
            std::string::npos);
  EXPECT_NE(error_of([] { parse_file_list("nan a.png\n", "d.txt"); }).find("not finite"),
            std::string::npos);
  // A NUL byte would cut the file name, and every message quoting it, short.
  const std::string nul(
      "0 a.png\n0.1 depth/0.0\0"
      "33.png\n",
      29);
  EXPECT_NE(error_of([&] { parse_file_list(nul, "d.txt"); }).find("d.txt:2: holds a NUL byte"),
            std::string::npos);
  EXPECT_NE(error_of([&] {
              parse_trajectory(std::string("0 0 0 0 0 0 0 1\0\n", 17), "gt.txt");
            }).find("gt.txt:1: holds a NUL byte"),
            std::string::npos);
}

TEST(ParseDouble, TakesDecimalAndScientificTokensWhole) {
  double v = 0.0;
  EXPECT_TRUE(parse_double("1305031102.175304", v));
  EXPECT_DOUBLE_EQ(v, 1305031102.175304);
  EXPECT_TRUE(parse_double("+2.5e-3", v));
  EXPECT_DOUBLE_EQ(v, 2.5e-3);
  EXPECT_TRUE(parse_double("-.5", v));
  EXPECT_DOUBLE_EQ(v, -0.5);
  EXPECT_TRUE(parse_double("nan", v));  // finiteness is the callers' check
  EXPECT_TRUE(std::isnan(v));
  // strtod took a hex float (a timestamp named its map by another value) and leading space.
  for (const char* bad : {"0x1.11p-5", " 1", "1 ", "", "+", "+-1", "1e", "1.5x", "1e400"})
    EXPECT_FALSE(parse_double(bad, v)) << "'" << bad << "'";
  EXPECT_NE(error_of([] {
              parse_file_list("0x1.11p-5 a.png\n", "d.txt");
            }).find("d.txt:1: timestamp '0x1.11p-5' is not a number"),
            std::string::npos);
}

TEST(Trajectory, WriteReadRoundTripIsExact) {
  Trajectory t;
  for (int i = 0; i < 10; ++i) {
    Vector6d xi;
    xi << 0.1 * i, -0.03 * i, 1.0 / 3.0, 0.01 * i, 0.2, -0.05 * i;
    t.push_back({1305031102.160407 + 0.033 * i, se3_exp(xi)});
  }
  test::TempDir dir;
  write_trajectory(dir.file("t.txt"), t, "test trajectory");
  const Trajectory back = read_trajectory(dir.file("t.txt"));
  ASSERT_EQ(back.size(), t.size());
  for (std::size_t i = 0; i < t.size(); ++i) {
    EXPECT_EQ(back[i].timestamp, t[i].timestamp);  // shortest round-trip text is exact
    EXPECT_LT((back[i].pose.matrix() - t[i].pose.matrix()).norm(), 1e-14);
  }
}

// Whole-second stamps (a rawlog's, a simulator's) are written as digits, not "1.7e+09", and
// still read back exactly; so are tiny and fractional ones.
TEST(Trajectory, StampsAreWrittenInFixedNotation) {
  Trajectory t;
  for (const double stamp : {1e-7, 0.5, 1305031102.1753041, 1700000000.0, 1700000000.25})
    t.push_back({stamp, Eigen::Isometry3d::Identity()});
  test::TempDir dir;
  write_trajectory(dir.file("t.txt"), t);
  const std::string text = read_file(dir.file("t.txt"));
  EXPECT_EQ(std::count(text.begin(), text.end(), 'e'), 1) << text;  // the header's "timestamp"
  EXPECT_NE(text.find("\n1700000000 "), std::string::npos) << text;
  EXPECT_NE(text.find("\n0.0000001 "), std::string::npos) << text;
  const Trajectory back = read_trajectory(dir.file("t.txt"));
  ASSERT_EQ(back.size(), t.size());
  for (std::size_t i = 0; i < t.size(); ++i)
    EXPECT_EQ(back[i].timestamp, t[i].timestamp);
}

TEST(Trajectory, RejectsNaNWrongFieldCountBadQuaternionAndUnsortedStamps) {
  EXPECT_NE(error_of([] {
              parse_trajectory("1 0 0 nan 0 0 0 1\n", "est.txt");
            }).find("est.txt:1: field 4 is NaN/Inf"),
            std::string::npos);
  EXPECT_NE(
      error_of([] { parse_trajectory("1 0 0 0 0 0 1\n", "est.txt"); }).find("expected 8 fields"),
      std::string::npos);
  EXPECT_NE(
      error_of([] { parse_trajectory("1 0 0 0 0 0 0 0\n", "est.txt"); }).find("quaternion norm"),
      std::string::npos);
  EXPECT_NE(error_of([] {
              parse_trajectory("2 0 0 0 0 0 0 1\n1 0 0 0 0 0 0 1\n", "e.txt");
            }).find("e.txt:2: timestamps are not sorted"),
            std::string::npos);
}

TEST(Trajectory, WritingNaNPoseFailsAndLeavesNoFile) {
  test::TempDir dir;
  Trajectory t(1);
  t[0].pose.translation().x() = std::numeric_limits<double>::quiet_NaN();
  EXPECT_THROW(write_trajectory(dir.file("t.txt"), t), InputError);
  EXPECT_EQ(test::count_files(dir.path()), 0);
}

TEST(Association, GreedyByTimeDifferenceOneToOne) {
  // Pairs closer than 0.02 s match; 2.0 has no partner within the window (2.5 is too far).
  const std::vector<double> a{0.0, 1.0, 2.0, 3.0};
  const std::vector<double> b{0.015, 1.004, 2.5, 2.99};
  const auto m = associate_timestamps(a, b, 0.02);
  ASSERT_EQ(m.size(), 3u);
  EXPECT_EQ(m[0], std::make_pair(std::size_t{0}, std::size_t{0}));
  EXPECT_EQ(m[1], std::make_pair(std::size_t{1}, std::size_t{1}));
  EXPECT_EQ(m[2], std::make_pair(std::size_t{3}, std::size_t{3}));
}

TEST(Association, EachTimestampUsedOnce) {
  const auto m = associate_timestamps({1.0, 1.01}, {1.004}, 0.02);
  ASSERT_EQ(m.size(), 1u);
  EXPECT_EQ(m[0].first, 0u);  // 0.004 beats 0.006
}

// A NaN stamp made the sort's ordering invalid and lost valid matches (2-2 here); it matches
// nothing.
TEST(Association, StampsThatAreNotFiniteMatchNothing) {
  const double nan = std::numeric_limits<double>::quiet_NaN();
  const auto m = associate_timestamps({1.0, nan, 2.0, 3.0}, {1.0, nan, 2.0, 3.0}, 0.02);
  ASSERT_EQ(m.size(), 3u);
  EXPECT_EQ(m[1], std::make_pair(std::size_t{2}, std::size_t{2}));
  EXPECT_EQ(m[2], std::make_pair(std::size_t{3}, std::size_t{3}));
}

TEST(Association, ClosestIndex) {
  const std::vector<double> s{0.0, 1.0, 2.0};
  EXPECT_EQ(closest_index(s, -5.0), 0u);
  EXPECT_EQ(closest_index(s, 0.4), 0u);
  EXPECT_EQ(closest_index(s, 0.6), 1u);
  EXPECT_EQ(closest_index(s, 9.0), 2u);
}

}  // namespace
}  // namespace jpcr
