// The sensor_msgs decoder (io/dds/ros_image.hpp) without DDS: good images decode exactly, every
// malformed case is rejected with a message naming the problem.
#include <gtest/gtest.h>

#include <array>
#include <cmath>
#include <cstring>
#include <limits>
#include <random>
#include <string>
#include <vector>

#include "input_error.hpp"
#include "jpcr/io/dds/ros_image.hpp"
#include "jpcr/io/params.hpp"

namespace jpcr {
namespace {

using test::input_error_of;

DepthImage ramp_depth(int width, int height) {
  DepthImage d(width, height);
  for (int v = 0; v < height; ++v)
    for (int u = 0; u < width; ++u)
      d(u, v) = (u + v) % 7 == 0 ? 0.0f : 0.001f * static_cast<float>(500 + u * 3 + v * 11);
  return d;
}

CameraIntrinsics small_camera(int width, int height) {
  CameraIntrinsics c;
  c.fx = 300.0;
  c.fy = 301.5;
  c.cx = width / 2.0 - 0.5;
  c.cy = height / 2.0 - 0.5;
  c.width = width;
  c.height = height;
  return c;
}

TEST(RosStamp, RoundTripsToTheNanosecond) {
  for (const double t : {0.0, 1.5, 12.000000001, 1305031102.175304, 99.9999999996}) {
    const RosStamp s = to_ros_stamp(t);
    EXPECT_LT(s.nanosec, 1000000000u);
    EXPECT_NEAR(to_seconds(s), t, 1e-6) << t;
  }
  EXPECT_EQ(to_ros_stamp(99.9999999996).sec, 100);
  EXPECT_EQ(to_ros_stamp(1.5).nanosec, 500000000u);
}

// A stamp that came as decimal text (a TUM list's microseconds) is published as written: the
// shortest decimal that reads back as the double, not the nearest nanosecond to the double
// (1305031102.160407066 for 1305031102.160407: exact-time matching against the recording
// missed it).
TEST(RosStamp, ADecimalStampIsPublishedAsWritten) {
  const auto expect = [](double seconds, std::int32_t sec, std::uint32_t nanosec) {
    const RosStamp s = to_ros_stamp(seconds);
    EXPECT_EQ(s.sec, sec) << seconds;
    EXPECT_EQ(s.nanosec, nanosec) << seconds;
  };
  expect(1305031102.160407, 1305031102, 160407000u);
  expect(1305031102.194330, 1305031102, 194330000u);
  expect(1733400000.5, 1733400000, 500000000u);
  expect(-0.466667, -1, 533333000u);
  expect(2.0000000004, 2, 0u);  // rounded at the ninth digit ...
  expect(2.0000000006, 2, 1u);  // ... both ways
  expect(0.9999999996, 1, 0u);  // into the next second
  expect(1e-12, 0, 0u);
}

// sec + nanosec·1e-9 in decimal: a negative sec with nanosec > 0 is above sec.
TEST(RosStamp, IsFormattedAsItsValue) {
  EXPECT_EQ(format_ros_stamp(12, 500), "12.000000500");
  EXPECT_EQ(format_ros_stamp(-1, 533333000), "-0.466667000");
  EXPECT_EQ(format_ros_stamp(-2, 0), "-2.000000000");
  EXPECT_EQ(format_ros_stamp(0, 0), "0.000000000");
  EXPECT_EQ(format_ros_stamp(5, 1500000000u), "6.500000000");
  EXPECT_EQ(format_ros_stamp(1733400000, 999999999), "1733400000.999999999");
}

// A double resolves today's stamps (1.7e9 s) only to 238 ns: a received stamp must still come
// back to the nanosecond, or ROS's exact-time sync and tf lookups miss what jpcr publishes.
TEST(RosStamp, AReceivedStampComesBackExactly) {
  std::mt19937_64 rng(20261205);
  std::uniform_int_distribution<std::uint32_t> nanosec(0, 999999999);
  int lost_by_rounding = 0;
  for (int i = 0; i < 1000; ++i) {
    const RosStamp s{1733400000 + i, nanosec(rng)};
    const double seconds = to_seconds(s);
    const RosStamp back = to_ros_stamp(seconds);
    EXPECT_EQ(back.sec, s.sec);
    EXPECT_EQ(back.nanosec, s.nanosec);
    // What rounding the double alone gives: the nanoseconds are lost almost always.
    const double whole = std::floor(seconds);
    lost_by_rounding += std::llround((seconds - whole) * 1e9) != std::llround(s.nanosec);
  }
  EXPECT_GT(lost_by_rounding, 900);  // the case this guards (measured: 99.6 % of random stamps)
}

// A malformed stamp (nanosec of 1e9 or more) comes back normalised, as any other.
TEST(RosStamp, AnUnnormalisedStampComesBackNormalised) {
  const RosStamp odd{1700000005, 1500000000u};
  const RosStamp back = to_ros_stamp(to_seconds(odd));
  EXPECT_EQ(back.sec, 1700000006);
  EXPECT_EQ(back.nanosec, 500000000u);
}

// The least recently used stamp is forgotten first, and a value never converted is rounded.
TEST(RosStamp, TheMemoryKeepsTheStampsUsedLast) {
  const RosStamp kept{1800000000, 123456789}, dropped{1800000001, 987654321};
  const double kept_seconds = to_seconds(kept), dropped_seconds = to_seconds(dropped);
  for (std::size_t i = 0; i < kRememberedStamps; ++i) {
    to_seconds(RosStamp{static_cast<std::int32_t>(1900000000 + i), 1});
    if (i % 1000 == 0) to_ros_stamp(kept_seconds);  // used again: stays
  }
  EXPECT_EQ(to_ros_stamp(kept_seconds).nanosec, kept.nanosec);
  const RosStamp forgotten = to_ros_stamp(dropped_seconds);
  EXPECT_EQ(forgotten.sec, dropped.sec);
  EXPECT_NE(forgotten.nanosec, dropped.nanosec);  // 987654321 is not the double's nearest ns
  EXPECT_NEAR(double(forgotten.nanosec), double(dropped.nanosec), 240.0);
}

TEST(RosImage, DepthRoundTripsIn16UC1AndIn32FC1) {
  const DepthImage depth = ramp_depth(13, 7);
  for (const DepthEncoding e : {DepthEncoding::kMillimetres16, DepthEncoding::kMetres32}) {
    const RosImageBuffer b = encode_depth_image(depth, e);
    EXPECT_EQ(b.encoding, to_string(e));
    EXPECT_EQ(b.data.size(), std::size_t{b.step} * b.height);
    const DepthImage back = decode_depth_image(b.view(), {});
    ASSERT_EQ(back.width(), 13);
    ASSERT_EQ(back.height(), 7);
    for (std::size_t i = 0; i < depth.size(); ++i)
      ASSERT_EQ(back[i], depth[i]) << to_string(e) << " pixel " << i;
  }
  // No measurement: 0 in 16UC1, NaN in 32FC1 (REP 118).
  ASSERT_EQ(depth(0, 0), 0.0f);
  float first = 1.0f;
  std::memcpy(&first, encode_depth_image(depth, DepthEncoding::kMetres32).data.data(), 4);
  EXPECT_TRUE(std::isnan(first));
  std::uint16_t first_mm = 1;
  std::memcpy(&first_mm, encode_depth_image(depth, DepthEncoding::kMillimetres16).data.data(), 2);
  EXPECT_EQ(first_mm, 0);
}

TEST(RosImage, PaddedRowsAreRead) {
  const DepthImage depth = ramp_depth(5, 3);
  RosImageBuffer b = encode_depth_image(depth, DepthEncoding::kMetres32);
  RosImageBuffer padded = b;
  padded.step = b.step + 3;  // odd padding: rows start unaligned
  padded.data.assign(std::size_t{padded.step} * padded.height, 0xAB);
  for (std::uint32_t v = 0; v < b.height; ++v)
    std::memcpy(&padded.data[v * padded.step], &b.data[v * b.step], b.step);
  const DepthImage back = decode_depth_image(padded.view(), {});
  for (std::size_t i = 0; i < depth.size(); ++i)
    ASSERT_EQ(back[i], depth[i]);
}

TEST(RosImage, InvalidDepthsBecomeZero) {
  DepthImage d(4, 1);
  d[0] = std::numeric_limits<float>::quiet_NaN();
  d[1] = -1.0f;
  d[2] = std::numeric_limits<float>::infinity();
  d[3] = 70.0f;  // beyond 65.535 m: does not fit 16UC1
  for (const DepthEncoding e : {DepthEncoding::kMillimetres16, DepthEncoding::kMetres32}) {
    const DepthImage back = decode_depth_image(encode_depth_image(d, e).view(), {});
    EXPECT_EQ(back[0], 0.0f);
    EXPECT_EQ(back[1], 0.0f);
    EXPECT_EQ(back[2], 0.0f);
    EXPECT_EQ(back[3], e == DepthEncoding::kMetres32 ? 70.0f : 0.0f);
  }
}

TEST(RosImage, CurvatureAndColourRoundTripBitExact) {
  Image<Eigen::Vector2f> k(6, 4, Eigen::Vector2f::Zero());
  for (std::size_t i = 0; i < k.size(); ++i)
    k[i] = Eigen::Vector2f(1.0f / (1.0f + i), -0.25f * i);
  k[3] = Eigen::Vector2f::Constant(std::numeric_limits<float>::quiet_NaN());
  const Image<Eigen::Vector2f> back = decode_curvature_image(encode_curvature_image(k).view(), {});
  ASSERT_EQ(back.size(), k.size());
  EXPECT_EQ(std::memcmp(back.data(), k.data(), k.size() * sizeof(Eigen::Vector2f)), 0);

  ColorImage c(3, 2);
  for (std::size_t i = 0; i < c.size(); ++i)
    c[i] = Rgb8{std::uint8_t(i), std::uint8_t(2 * i), std::uint8_t(255 - i)};
  const ColorImage cb = decode_rgb8_image(encode_rgb8_image(c).view(), {});
  EXPECT_EQ(std::memcmp(cb.data(), c.data(), c.size() * 3), 0);
}

TEST(RosImage, CurvatureSdRoundTripsBitExactAndRefusesWhatIsNoSd) {
  Image<float> sd(5, 3, 0.0f);
  for (std::size_t i = 0; i < sd.size(); ++i)
    sd[i] = 0.125f * static_cast<float>(i) + 1e-7f;
  sd[4] = std::numeric_limits<float>::quiet_NaN();  // withheld
  const RosImageBuffer bytes = encode_curvature_sd_image(sd);
  EXPECT_EQ(bytes.encoding, "32FC1");
  EXPECT_EQ(bytes.step, 5u * 4u);
  const Image<float> back = decode_curvature_sd_image(bytes.view(), {});
  ASSERT_EQ(back.width(), 5);
  ASSERT_EQ(back.height(), 3);
  EXPECT_EQ(std::memcmp(back.data(), sd.data(), sd.size() * sizeof(float)), 0);

  for (const float bad : {-0.5f, std::numeric_limits<float>::infinity()}) {
    Image<float> wrong = sd;
    wrong(3, 2) = bad;
    const RosImageBuffer b = encode_curvature_sd_image(wrong);
    EXPECT_EQ(input_error_of([&] { decode_curvature_sd_image(b.view(), {}); }),
              "curvature sd at pixel (3, 2) is " + std::string(bad < 0 ? "-0.5" : "inf") +
                  ": an sd is a finite value >= 0, or NaN for none");
  }
  // A 32FC2 curvature map is not an sd map.
  const RosImageBuffer k = encode_curvature_image(Image<Eigen::Vector2f>(5, 3));
  EXPECT_NE(input_error_of([&] { decode_curvature_sd_image(k.view(), {}); }).find("32FC2"),
            std::string::npos);
}

TEST(RosImage, MalformedImagesAreRejected) {
  const RosImageBuffer good = encode_depth_image(ramp_depth(8, 4), DepthEncoding::kMillimetres16);
  auto error = [&](auto&& mutate) {
    RosImageBuffer b = good;
    RosImageView v = b.view();
    mutate(b, v);
    return input_error_of([&] { decode_depth_image(v, {}); });
  };
  EXPECT_EQ(error([](RosImageBuffer&, RosImageView&) {}), "<no error>");
  EXPECT_EQ(error([](RosImageBuffer&, RosImageView& v) { v.size -= 1; }),
            "data is 63 bytes, step x height = 64");
  EXPECT_EQ(error([](RosImageBuffer&, RosImageView& v) { v.step = 8; }),
            "step 8 < width x 2 bytes = 16");
  EXPECT_EQ(error([](RosImageBuffer&, RosImageView& v) { v.encoding = "bgr8"; }),
            "unknown encoding 'bgr8' (expected 16UC1 or 32FC1)");
  EXPECT_EQ(
      error([](RosImageBuffer&, RosImageView& v) { v.encoding = std::string_view("\x01z", 2); }),
      "unknown encoding '?z' (expected 16UC1 or 32FC1)");
  EXPECT_EQ(error([](RosImageBuffer&, RosImageView& v) { v.width = 0; }), "zero size 0x4");
  EXPECT_EQ(error([](RosImageBuffer&, RosImageView& v) { v.height = 0; }), "zero size 8x0");
  EXPECT_EQ(error([](RosImageBuffer&, RosImageView& v) { v.is_bigendian = 1; }),
            "big-endian data is not supported");
  EXPECT_EQ(error([](RosImageBuffer&, RosImageView& v) { v.width = 20000; }),
            "size 20000x4 exceeds the limit of 16384 pixels a side");
  // 100 MB claimed with 64 bytes sent: rejected before anything is read or allocated.
  EXPECT_EQ(error([](RosImageBuffer&, RosImageView& v) {
              v.width = 10000;
              v.height = 5000;
              v.step = 20000;
            }),
            "claimed size step x height = 100000000 bytes exceeds the limit of 67108864");
  // The largest values the fields can hold do not overflow the checks.
  EXPECT_NE(error([](RosImageBuffer&, RosImageView& v) {
              v.width = v.height = 16384;
              v.step = 0xFFFFFFFFu;
            }),
            "<no error>");
  EXPECT_EQ(error([](RosImageBuffer&, RosImageView& v) { v.data = nullptr; }),
            "data is 64 bytes, step x height = 64");
}

TEST(RosImage, LimitsComeFromTheConfig) {
  const RosImageBuffer b = encode_depth_image(ramp_depth(8, 4), DepthEncoding::kMetres32);
  RosImageLimits limits;
  limits.max_bytes = 100;
  EXPECT_EQ(input_error_of([&] { decode_depth_image(b.view(), limits); }),
            "claimed size step x height = 128 bytes exceeds the limit of 100");
  limits = {};
  limits.max_side = 7;
  EXPECT_EQ(input_error_of([&] { decode_depth_image(b.view(), limits); }),
            "size 8x4 exceeds the limit of 7 pixels a side");
  DdsConfig config;
  EXPECT_EQ(config.max_image_bytes(), std::size_t{64} << 20);
}

TEST(RosCameraInfo, EncodeDecodeRoundTrip) {
  CameraIntrinsics c = small_camera(80, 60);
  c.distortion = {0.1, -0.2, 0.001, 0.002, 0.03};
  const CameraIntrinsics back = decode_camera_info(encode_camera_info(c), {});
  EXPECT_EQ(back.fx, c.fx);
  EXPECT_EQ(back.fy, c.fy);
  EXPECT_EQ(back.cx, c.cx);
  EXPECT_EQ(back.cy, c.cy);
  EXPECT_EQ(back.width, 80);
  EXPECT_EQ(back.height, 60);
  EXPECT_EQ(back.distortion, c.distortion);
  RosCameraInfo rational = encode_camera_info(c);
  rational.distortion_model = "rational_polynomial";
  rational.d.resize(8, 0.0);
  EXPECT_EQ(decode_camera_info(rational, {}).distortion, c.distortion);
}

// ROS: K and D describe the raw image, P the rectified one, which is what jpcr reads.
TEST(RosCameraInfo, TheIntrinsicsComeFromPAndFromKWithoutP) {
  RosCameraInfo info = encode_camera_info(small_camera(80, 60));
  info.distortion_model = "plumb_bob";
  info.d = {-0.3, 0.1, 0.0, 0.0, 0.0};
  info.p = {280.0, 0.0, 40.25, -28.0, 0.0, 281.0, 30.75, 0.0, 0.0, 0.0, 1.0, 0.0};  // Tx = -f·B
  const CameraIntrinsics rectified = decode_camera_info(info, {});
  EXPECT_EQ(rectified.fx, 280.0);
  EXPECT_EQ(rectified.fy, 281.0);
  EXPECT_EQ(rectified.cx, 40.25);
  EXPECT_EQ(rectified.cy, 30.75);
  info.p = {};  // an uncalibrated driver's
  const CameraIntrinsics raw = decode_camera_info(info, {});
  EXPECT_EQ(raw.fx, 300.0);
  EXPECT_EQ(raw.fy, 301.5);
  EXPECT_EQ(raw.cx, 39.5);
  EXPECT_EQ(raw.cy, 29.5);

  const RosCameraInfo good = encode_camera_info(small_camera(80, 60));
  auto error = [&](auto&& mutate) {
    RosCameraInfo i = good;
    mutate(i);
    return input_error_of([&] { decode_camera_info(i, {}); });
  };
  EXPECT_EQ(error([](RosCameraInfo& i) { i.k[1] = 0.5; }), "<no error>");  // P is read, not K
  // ... but a K or R with NaN is a malformed sample all the same.
  EXPECT_EQ(error([](RosCameraInfo& i) { i.k[0] = std::nan(""); }), "camera_info K is not finite");
  EXPECT_EQ(error([](RosCameraInfo& i) { i.r[4] = INFINITY; }), "camera_info R is not finite");
  EXPECT_EQ(error([](RosCameraInfo& i) { i.p[0] = 0.0; }),
            "camera_info P focal lengths fx = 0.000000, fy = 301.500000 must be positive");
  EXPECT_EQ(error([](RosCameraInfo& i) { i.p[7] = std::nan(""); }), "camera_info P is not finite");
  EXPECT_EQ(error([](RosCameraInfo& i) { i.p[1] = 0.5; }),
            "camera_info P is not a pinhole matrix without skew [fx 0 cx Tx; 0 fy cy Ty; 0 0 1 0]");
  EXPECT_EQ(error([](RosCameraInfo& i) { i.p[11] = 1.0; }),
            "camera_info P is not a pinhole matrix (P[11] is not 0)");
  EXPECT_EQ(error([](RosCameraInfo& i) { i.p[2] = 1e6; }),
            "camera_info principal point (1000000.000000, 29.500000) lies outside the 80x60 "
            "image");
}

TEST(RosCameraInfo, MalformedCameraInfoIsRejected) {
  RosCameraInfo good = encode_camera_info(small_camera(80, 60));
  good.p = {};  // K's checks: without P, K gives the intrinsics
  auto error = [&](auto&& mutate) {
    RosCameraInfo info = good;
    mutate(info);
    return input_error_of([&] { decode_camera_info(info, {}); });
  };
  EXPECT_EQ(error([](RosCameraInfo&) {}), "<no error>");
  EXPECT_EQ(error([](RosCameraInfo& i) { i.k[0] = 0.0; }),
            "camera_info K focal lengths fx = 0.000000, fy = 301.500000 must be positive");
  EXPECT_EQ(error([](RosCameraInfo& i) { i.k[4] = -5.0; }),
            "camera_info K focal lengths fx = 300.000000, fy = -5.000000 must be positive");
  EXPECT_EQ(error([](RosCameraInfo& i) { i.k[2] = std::nan(""); }), "camera_info K is not finite");
  EXPECT_EQ(error([](RosCameraInfo& i) { i.k[8] = 0.0; }),
            "camera_info K is not a pinhole matrix without skew [fx 0 cx; 0 fy cy; 0 0 1]");
  // Skew would be dropped, and a principal point off the image is no real camera's.
  EXPECT_EQ(error([](RosCameraInfo& i) { i.k[1] = 0.5; }),
            "camera_info K is not a pinhole matrix without skew [fx 0 cx; 0 fy cy; 0 0 1]");
  EXPECT_EQ(error([](RosCameraInfo& i) { i.k[2] = 1e6; }),
            "camera_info principal point (1000000.000000, 29.500000) lies outside the 80x60 "
            "image");
  EXPECT_EQ(error([](RosCameraInfo& i) { i.k[5] = -500; }),
            "camera_info principal point (39.500000, -500.000000) lies outside the 80x60 image");
  EXPECT_EQ(error([](RosCameraInfo& i) { i.k[0] = 1e-300; }),
            "camera_info fx: must be a positive number of pixels giving a horizontal field of view "
            "of 0.1° to 175°");
  EXPECT_EQ(error([](RosCameraInfo& i) { i.width = 0; }), "camera_info has zero size 0x60");
  EXPECT_EQ(error([](RosCameraInfo& i) { i.binning_x = 2; }),
            "camera_info binning is not supported");
  EXPECT_EQ(error([](RosCameraInfo& i) {
              i.d = {0.1, std::nan("")};
            }),
            "camera_info D is not finite");
}

// D describes the raw image, which jpcr does not read (the depth is the rectified image, the
// intrinsics P's): every model is taken, as a driver sends it, and the lens distortion is seen
// for the log. A fisheye's or an 8-term rational_polynomial's D was rejected, and such a camera
// could not be used at all (review).
TEST(RosCameraInfo, AnyDistortionModelIsTakenAndNotApplied) {
  const RosCameraInfo good = encode_camera_info(small_camera(80, 60));
  const CameraIntrinsics expected = decode_camera_info(good, {});
  EXPECT_FALSE(lens_distortion(good));
  const auto taken = [&](const std::string& model, const std::vector<double>& d) {
    RosCameraInfo info = good;
    info.distortion_model = model;
    info.d = d;
    const CameraIntrinsics c = decode_camera_info(info, {});
    EXPECT_EQ(c.fx, expected.fx);
    EXPECT_EQ(c.cx, expected.cx);
    EXPECT_TRUE(lens_distortion(info)) << model;
    return c.distortion;
  };
  using D = std::array<double, 5>;
  EXPECT_EQ(taken("equidistant", {0.1, 0.02, 0.003, 0.0004}), (D{}));
  EXPECT_EQ(taken("rational_polynomial", {0.5, -0.1, 0.001, 0.002, 0.03, 0.4, -0.05, 0.01}),
            (D{0.5, -0.1, 0.001, 0.002, 0.03}));
  EXPECT_EQ(taken("", {0.1}), (D{}));
  EXPECT_EQ(taken("plumb_bob", {0.0, 0.0, 0.0, 0.0, 0.0, 0.7}), (D{}));
}

TEST(RosDepthFrame, FrameMatchesTheCameraAndTheStamp) {
  const CameraIntrinsics camera = small_camera(8, 4);
  const RosImageBuffer b = encode_depth_image(ramp_depth(8, 4), DepthEncoding::kMillimetres16);
  const Frame f = decode_depth_frame(b.view(), RosStamp{12, 250000000}, camera, {});
  EXPECT_EQ(f.timestamp, 12.25);
  EXPECT_EQ(f.camera.fx, camera.fx);
  EXPECT_EQ(f.camera.depth_scale, 1000.0);
  EXPECT_EQ(f.depth.width(), 8);
  EXPECT_TRUE(f.color.empty());
  const RosImageBuffer m = encode_depth_image(ramp_depth(8, 4), DepthEncoding::kMetres32);
  EXPECT_EQ(decode_depth_frame(m.view(), RosStamp{}, camera, {}).camera.depth_scale, 1.0);

  EXPECT_EQ(input_error_of([&] { decode_depth_frame(b.view(), {}, small_camera(8, 5), {}); }),
            "image size 8x4 differs from camera_info size 8x5");
  EXPECT_EQ(input_error_of([&] {
              decode_depth_frame(b.view(), RosStamp{1, 1000000000u}, camera, {});
            }),
            "stamp nanosec 1000000000 is not below 10^9");
}

TEST(DepthEncoding, ParsesTheTwoRosDepthEncodings) {
  EXPECT_EQ(parse_depth_encoding("16UC1"), DepthEncoding::kMillimetres16);
  EXPECT_EQ(parse_depth_encoding("32FC1"), DepthEncoding::kMetres32);
  EXPECT_EQ(input_error_of([] { parse_depth_encoding("mono8"); }),
            "unknown depth encoding 'mono8' (expected 16UC1 or 32FC1)");
}

// input_history: keep_all makes the depth input a bounded KEEP_ALL queue (the resource limit is
// what holds a reliable KEEP_ALL camera back); a best-effort camera cannot be held back.
TEST(DdsConfig, KeepAllInputHistoryIsABoundedReliableQueue) {
  const DdsQos last = parse_params("", "e.yaml").dds.depth_qos();
  EXPECT_FALSE(last.keep_all);
  EXPECT_EQ(last.depth, 2);
  const DdsQos all =
      parse_params("dds:\n  input_history: keep_all\n  image_history_depth: 5\n", "p.yaml")
          .dds.depth_qos();
  EXPECT_TRUE(all.keep_all);
  EXPECT_TRUE(all.reliable);
  EXPECT_EQ(all.max_samples, 5);
  EXPECT_EQ(input_error_of([] {
              parse_params("dds:\n  input_reliability: best_effort\n  input_history: keep_all\n",
                           "p.yaml");
            }),
            "p.yaml:3: key 'dds.input_history': keep_all needs input_reliability: reliable (a "
            "best-effort camera cannot be made to wait)");
  EXPECT_NE(input_error_of([] { parse_params("dds:\n  input_history: keep_some\n", "p.yaml"); }),
            "<no error>");
}

TEST(DdsConfig, YamlSectionMapsOntoTheStruct) {
  const Params p = parse_params(
      "dds:\n  domain_id: 7\n  topic_prefix: rt/robot/\n  depth_topic: rt/d\n"
      "  input_reliability: best_effort\n  max_image_megabytes: 8\n",
      "p.yaml");
  EXPECT_EQ(p.dds.domain_id, 7);
  EXPECT_EQ(p.dds.topic_prefix, "rt/robot/");
  EXPECT_EQ(p.dds.depth_topic, "rt/d");
  EXPECT_EQ(p.dds.camera_info_topic, "rt/camera/depth/camera_info");
  EXPECT_FALSE(p.dds.input_reliable);
  EXPECT_FALSE(p.dds.depth_qos().reliable);
  EXPECT_EQ(p.dds.max_image_bytes(), std::size_t{8} << 20);
  EXPECT_EQ(parse_params("", "e.yaml").dds.topic_prefix, "rt/jpcr/");
  EXPECT_EQ(input_error_of([] { parse_params("dds:\n  domain_id: 300\n", "p.yaml"); }),
            "p.yaml:2: key 'dds.domain_id': must be in 0..232");
  EXPECT_EQ(parse_params("dds:\n  keyframe_queue: 3\n", "p.yaml").dds.keyframe_queue, 3);
  EXPECT_TRUE(parse_params("", "e.yaml").dds.curvature_sd);
  EXPECT_FALSE(parse_params("dds:\n  curvature_sd: false\n", "p.yaml").dds.curvature_sd);
  EXPECT_NE(input_error_of([] {
              parse_params("dds:\n  curvature_sd: maybe\n", "p.yaml");
            }).find("dds.curvature_sd"),
            std::string::npos);
  EXPECT_EQ(input_error_of([] { parse_params("dds:\n  keyframe_queue: 0\n", "p.yaml"); }),
            "p.yaml:2: key 'dds.keyframe_queue': must be in 1..1000");
  EXPECT_EQ(input_error_of([] {
              parse_params("dds:\n  domian_id: 3\n", "p.yaml");
            }).find("domian_id") != std::string::npos,
            true);
  EXPECT_NE(input_error_of([] { parse_params("dds:\n  input_reliability: maybe\n", "p.yaml"); }),
            "<no error>");
  // A ROS name would match no DDS topic, silently.
  EXPECT_EQ(input_error_of(
                [] { parse_params("dds:\n  depth_topic: /camera/depth/image_rect\n", "p.yaml"); }),
            "p.yaml:2: key 'dds.depth_topic': '/camera/depth/image_rect' is a ROS name; its DDS "
            "topic is 'rt/camera/depth/image_rect'");
  EXPECT_EQ(
      input_error_of([] { parse_params("dds:\n  topic_prefix: 'rt/my robot/'\n", "p.yaml"); }),
      "p.yaml:2: key 'dds.topic_prefix': 'rt/my robot/' holds a character other than letters, "
      "digits, '_' and '/'");
  EXPECT_EQ(input_error_of([] { parse_params("dds:\n  camera_info_topic: rt/c/\n", "p.yaml"); }),
            "p.yaml:2: key 'dds.camera_info_topic': must not end with '/'");
  // Settings that would silently match nothing, or the node's own output.
  const auto dds_error = [](const std::string& yaml) {
    return input_error_of([&] { parse_params("dds:\n" + yaml, "p.yaml"); });
  };
  EXPECT_EQ(dds_error("  depth_topic: camera/depth/image_rect_raw\n"),
            "p.yaml:2: key 'dds.depth_topic': 'camera/depth/image_rect_raw' does not start with "
            "'rt/', so no ROS 2 node sees it (ROS's /x is rt/x)");
  EXPECT_EQ(dds_error("  topic_prefix: rt/jpcr\n"),
            "p.yaml:2: key 'dds.topic_prefix': 'rt/jpcr' must end with '/' (the topics are "
            "rt/jpcrodom, ...)");
  EXPECT_EQ(dds_error("  depth_topic: rt/camera/depth/camera_info\n"),
            "p.yaml:2: key 'dds.depth_topic': 'rt/camera/depth/camera_info' is also "
            "camera_info_topic");
  EXPECT_EQ(dds_error("  depth_topic: rt/jpcr/curvature\n"),
            "p.yaml:2: key 'dds.depth_topic': 'rt/jpcr/curvature' is one of jpcr's own topics");
  EXPECT_EQ(dds_error("  world_frame_id: /map\n"),
            "p.yaml:2: key 'dds.world_frame_id': '/map' must be a tf2 frame id: not empty, "
            "without a leading '/'");
  EXPECT_EQ(dds_error("  image_history_depth: 2000000000\n"),
            "p.yaml:2: key 'dds.image_history_depth': must be in 1..1000");
  EXPECT_EQ(dds_error("  max_image_megabytes: 1e-9\n"),
            "p.yaml:2: key 'dds.max_image_megabytes': must be in [1/1024, 4096] MiB");
  EXPECT_EQ(dds_error("  max_image_side: 20000\n"),
            "p.yaml:2: key 'dds.max_image_side': must be in 1..16384 (a camera's largest side)");
}

TEST(DdsConfig, DefaultYamlStatesTheBuiltInDefaults) {
  const DdsConfig shipped = load_params(std::string(JPCR_SOURCE_DIR) + "/configs/default.yaml").dds;
  const DdsConfig built_in;
  EXPECT_EQ(shipped.domain_id, built_in.domain_id);
  EXPECT_EQ(shipped.cyclone_uri, built_in.cyclone_uri);
  EXPECT_EQ(shipped.topic_prefix, built_in.topic_prefix);
  EXPECT_EQ(shipped.depth_topic, built_in.depth_topic);
  EXPECT_EQ(shipped.camera_info_topic, built_in.camera_info_topic);
  EXPECT_EQ(shipped.world_frame_id, built_in.world_frame_id);
  EXPECT_EQ(shipped.camera_frame_id, built_in.camera_frame_id);
  EXPECT_EQ(shipped.history_depth, built_in.history_depth);
  EXPECT_EQ(shipped.image_history_depth, built_in.image_history_depth);
  EXPECT_EQ(shipped.keyframe_queue, built_in.keyframe_queue);
  EXPECT_EQ(shipped.input_reliable, built_in.input_reliable);
  EXPECT_EQ(shipped.max_image_megabytes, built_in.max_image_megabytes);
  EXPECT_EQ(shipped.max_image_side, built_in.max_image_side);
}

}  // namespace
}  // namespace jpcr
