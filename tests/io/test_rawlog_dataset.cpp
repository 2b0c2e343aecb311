// MRPT rawlogs as a third dataset kind: the real sample rawlog of mrpt-common, a round trip of
// real TUM frames through a rawlog the test writes, and bad input.
#include <algorithm>
#include <cmath>
#include <cstdint>
#include <cstring>
#include <filesystem>

#include <gtest/gtest.h>
#include <mrpt/img/CImage.h>
#include <mrpt/io/CFileGZInputStream.h>
#include <mrpt/io/CFileGZOutputStream.h>
#include <mrpt/obs/CObservation3DRangeScan.h>
#include <mrpt/serialization/CArchive.h>

#include "jpcr/io/camera_yaml.hpp"
#include "jpcr/io/open_dataset.hpp"
#include "jpcr/io/rawlog_dataset.hpp"
#include "jpcr/io/tum_dataset.hpp"
#include "jpcr/quadric/error.hpp"
#include "jpcr/quadric/vertex_map.hpp"
#include "temp_dir.hpp"

namespace jpcr {
namespace {

const std::string kSample = "/usr/share/mrpt/datasets/tests_rgbd.rawlog";
const std::string kFr1 = std::string(JPCR_TEST_DATA_DIR) + "/tum_fr1_xyz_20";

// The uncompressed bytes of a rawlog, and back.
std::string gunzip(const std::string& path) {
  mrpt::io::CFileGZInputStream in(path);
  std::string bytes;
  char block[4096];
  for (std::size_t n; (n = in.Read(block, sizeof block)) > 0;)
    bytes.append(block, n);
  return bytes;
}

void gzip(const std::string& path, const std::string& bytes) {
  mrpt::io::CFileGZOutputStream out(path);
  out.Write(bytes.data(), bytes.size());
}

// Rewrites the rawlog `in` (of observations, as write_rawlog makes) to `out`, passing each scan
// and its index through `edit`: to relabel it, restamp it or store its range image outside.
void edit_rawlog(const std::string& in, const std::string& out,
                 const std::function<void(mrpt::obs::CObservation3DRangeScan&, int)>& edit) {
  mrpt::io::CFileGZInputStream input(in);
  auto reader = mrpt::serialization::archiveFrom(input);
  mrpt::io::CFileGZOutputStream output(out);
  auto writer = mrpt::serialization::archiveFrom(output);
  for (int i = 0;; ++i) {
    mrpt::serialization::CSerializable::Ptr object;
    try {
      reader >> object;
    } catch (const std::exception&) {
      break;
    }
    auto scan = std::dynamic_pointer_cast<mrpt::obs::CObservation3DRangeScan>(object);
    ASSERT_TRUE(scan);
    edit(*scan, i);
    writer << *scan;
  }
}

std::string error_of(const std::function<void()>& f) {
  try {
    f();
  } catch (const InputError& e) {
    return e.what();
  }
  return "<no error>";
}

TEST(RawlogDataset, ReadsTheMrptSampleRawlog) {
  if (!std::filesystem::exists(kSample)) GTEST_SKIP() << "mrpt-common is not installed";
  const RawlogDataset rawlog(kSample);
  ASSERT_EQ(rawlog.size(), 1u);
  EXPECT_EQ(rawlog.camera().width, 640);
  EXPECT_NEAR(rawlog.camera().fx, 572.883, 1e-3);
  EXPECT_NEAR(rawlog.camera().depth_scale, 1000.0, 1e-3);  // millimetre units
  const Frame frame = rawlog.load(0);
  EXPECT_GT(valid_depth_fraction(frame.depth), 0.3);
  EXPECT_GT(frame.timestamp, 1.4e9);
  EXPECT_FALSE(rawlog.ground_truth(0));
}

TEST(RawlogDataset, RoundTripOfRealFramesIsExact) {
  const CameraIntrinsics camera =
      load_camera_yaml(std::string(JPCR_SOURCE_DIR) + "/configs/ros_default.yaml");
  const TumDataset tum(kFr1, camera);
  std::vector<Frame> frames;
  for (std::size_t i = 0; i < 4; ++i)
    frames.push_back(tum.load(i));
  test::TempDir dir;
  const std::string path = dir.file("fr1.rawlog");
  write_rawlog(path, frames);
  const auto source = open_dataset(path, std::nullopt);
  ASSERT_EQ(source->size(), frames.size());
  EXPECT_DOUBLE_EQ(source->camera().fx, camera.fx);
  EXPECT_DOUBLE_EQ(source->camera().cy, camera.cy);
  for (std::size_t i = 0; i < frames.size(); ++i) {
    const Frame back = source->load(i);
    EXPECT_NEAR(back.timestamp, frames[i].timestamp, 1e-6);  // MRPT stores 100 ns ticks
    int differing = 0;
    for (std::size_t k = 0; k < back.depth.size(); ++k) {
      differing += std::abs(back.depth[k] - frames[i].depth[k]) > 1e-6f ? 1 : 0;
    }
    EXPECT_EQ(differing, 0) << "frame " << i;
  }
}

// A camera file with lens distortion rectifies a rawlog's depth as it does a TUM directory's:
// the same real frames, read both ways with fr1's camera (k1..k3 of the depth camera), are equal
// and carry no distortion (the rawlog's depth was used unrectified beside D: 0.95 mm apart in
// odometry).
TEST(RawlogDataset, ACameraWithDistortionRectifiesTheDepthAsATumDirectoryDoes) {
  const CameraIntrinsics pinhole =
      load_camera_yaml(std::string(JPCR_SOURCE_DIR) + "/configs/ros_default.yaml");
  const CameraIntrinsics fr1 =
      load_camera_yaml(std::string(JPCR_SOURCE_DIR) + "/configs/tum_fr1.yaml");
  ASSERT_TRUE(fr1.has_distortion());
  const TumDataset raw(kFr1, pinhole), rectified(kFr1, fr1);
  std::vector<Frame> frames{raw.load(0), raw.load(1)};
  test::TempDir dir;
  const std::string path = dir.file("fr1.rawlog");
  write_rawlog(path, frames);
  const RawlogDataset rawlog(path, fr1);
  for (std::size_t i = 0; i < frames.size(); ++i) {
    const Frame want = rectified.load(i), got = rawlog.load(i);
    EXPECT_FALSE(got.camera.has_distortion());
    ASSERT_EQ(got.depth.size(), want.depth.size());
    int differing = 0, moved = 0;
    for (std::size_t k = 0; k < got.depth.size(); ++k) {
      differing += std::abs(got.depth[k] - want.depth[k]) > 1e-6f ? 1 : 0;
      moved += std::abs(got.depth[k] - frames[i].depth[k]) > 1e-6f ? 1 : 0;
    }
    EXPECT_EQ(differing, 0) << "frame " << i;
    EXPECT_GT(moved, 1000) << "frame " << i << ": rectification changed nothing";
  }
}

// Scans that store the range along each pixel's ray (range_is_depth = false) give depth: a wall
// at z = 2 m stored as ranges 2 |((u − cx)/fx, (v − cy)/fy, 1)| reads back as 2 m at every pixel
// (to the 1 mm of the units).
TEST(RawlogDataset, RangesAlongTheRayAreTurnedIntoDepth) {
  test::TempDir dir;
  Frame frame;
  frame.camera.width = 16;
  frame.camera.height = 12;
  frame.camera.fx = frame.camera.fy = 8.0;  // a wide view: the ray's length reaches 1.4
  frame.camera.cx = 7.5;
  frame.camera.cy = 5.5;
  frame.depth = DepthImage(16, 12, 2.0f);
  write_rawlog(dir.file("depth.rawlog"), {frame});
  edit_rawlog(dir.file("depth.rawlog"), dir.file("ranges.rawlog"),
              [&](mrpt::obs::CObservation3DRangeScan& scan, int) {
                scan.range_is_depth = false;
                for (int v = 0; v < 12; ++v)
                  for (int u = 0; u < 16; ++u) {
                    const double x = (u - 7.5) / 8.0, y = (v - 5.5) / 8.0;
                    scan.rangeImage(v, u) = static_cast<std::uint16_t>(
                        std::lround(2.0 * std::sqrt(1.0 + x * x + y * y) / scan.rangeUnits));
                  }
              });
  const Frame back = RawlogDataset(dir.file("ranges.rawlog")).load(0);
  float worst = 0.0f;
  for (const float z : back.depth)
    worst = std::max(worst, std::abs(z - 2.0f));
  EXPECT_LT(worst, 1e-3f);
}

// A scan whose range units are not a positive length is refused with the scan named (units of
// 0 gave an all-zero frame, negative ones negative depth).
TEST(RawlogDataset, AScanWithoutPositiveRangeUnitsIsRefused) {
  test::TempDir dir;
  Frame frame;
  frame.camera = CameraIntrinsics{};
  frame.camera.width = 8;
  frame.camera.height = 6;
  frame.camera.fx = frame.camera.fy = 10.0;
  frame.camera.cx = 3.5;
  frame.camera.cy = 2.5;
  frame.depth = DepthImage(8, 6, 1.0f);
  std::vector<Frame> frames(3, frame);
  for (std::size_t i = 0; i < frames.size(); ++i)
    frames[i].timestamp = 10.0 + static_cast<double>(i);
  write_rawlog(dir.file("units.rawlog"), frames);
  for (const float units : {0.0f, -0.001f}) {
    edit_rawlog(dir.file("units.rawlog"), dir.file("bad_units.rawlog"),
                [&](mrpt::obs::CObservation3DRangeScan& scan, int i) {
                  if (i == 2) scan.rangeUnits = units;
                });
    const RawlogDataset rawlog(dir.file("bad_units.rawlog"), frame.camera);
    EXPECT_NO_THROW(rawlog.load(1));
    const std::string what = error_of([&] { rawlog.load(2); });
    EXPECT_NE(what.find("bad_units.rawlog: scan 2: its rangeUnits"), std::string::npos) << what;
    EXPECT_NE(what.find("is not a positive length"), std::string::npos) << what;
  }
}

CameraIntrinsics small_camera() {
  CameraIntrinsics c;
  c.width = 8;
  c.height = 6;
  c.fx = c.fy = 10.0;
  c.cx = 3.5;
  c.cy = 2.5;
  return c;
}

// Three frames of 8x6, 1/30 s apart, as write_rawlog writes them.
std::string small_rawlog(const test::TempDir& dir) {
  std::vector<Frame> frames(3);
  for (std::size_t i = 0; i < frames.size(); ++i) {
    frames[i].timestamp = 10.0 + i / 30.0;
    frames[i].camera = small_camera();
    frames[i].depth = DepthImage(8, 6, 1.0f + 0.1f * i);
  }
  const std::string path = dir.file("small.rawlog");
  write_rawlog(path, frames);
  return path;
}

// Range images stored outside the rawlog (MRPT's external storage) are read from its images
// directory, <name>_Images beside it, whatever the working directory; one that is missing is
// named, without MRPT's call stack.
TEST(RawlogDataset, ExternallyStoredRangeImagesAreReadFromTheImagesDirectory) {
  test::TempDir dir;
  const std::string images = dir.file("ext_Images");
  std::filesystem::create_directories(images);
  edit_rawlog(small_rawlog(dir), dir.file("ext.rawlog"),
              [&](mrpt::obs::CObservation3DRangeScan& scan, int i) {
                scan.rangeImage_convertToExternalStorage("range_" + std::to_string(i) + ".bin",
                                                         images + "/");
              });
  ASSERT_TRUE(std::filesystem::exists(images + "/range_2.bin"));
  const RawlogDataset rawlog(dir.file("ext.rawlog"));
  ASSERT_EQ(rawlog.size(), 3u);
  mrpt::img::CImage::setImagesPathBase("/the/caller's/own");
  const Frame frame = rawlog.load(2);
  EXPECT_NEAR(frame.depth(3, 2), 1.2f, 1e-3f);
  EXPECT_EQ(mrpt::img::CImage::getImagesPathBase(), "/the/caller's/own");  // put back
  std::filesystem::remove(images + "/range_1.bin");
  const std::string missing = error_of([&] { rawlog.load(1); });
  EXPECT_NE(missing.find("ext.rawlog: scan 1: its range image is stored in"), std::string::npos)
      << missing;
  EXPECT_NE(missing.find("range_1.bin"), std::string::npos) << missing;
  EXPECT_EQ(missing.find("Call stack"), std::string::npos) << missing;
  EXPECT_EQ(mrpt::img::CImage::getImagesPathBase(), "/the/caller's/own");  // after an error too
}

// One camera, in time order: two sensors' scans, or scans out of order, are refused.
TEST(RawlogDataset, ScansOfTwoSensorsOrOutOfOrderAreRefused) {
  test::TempDir dir;
  const std::string small = small_rawlog(dir);
  edit_rawlog(small, dir.file("two.rawlog"), [](mrpt::obs::CObservation3DRangeScan& scan, int i) {
    scan.sensorLabel = i % 2 ? "KINECT_B" : "KINECT_A";
  });
  const std::string two = error_of([&] { RawlogDataset r(dir.file("two.rawlog")); });
  EXPECT_NE(two.find("two.rawlog: the rawlog holds range scans of 2 sensors ('KINECT_A', "
                     "'KINECT_B')"),
            std::string::npos)
      << two;
  edit_rawlog(small, dir.file("back.rawlog"), [](mrpt::obs::CObservation3DRangeScan& scan, int i) {
    scan.timestamp = mrpt::Clock::fromDouble(10.0 - i / 30.0);
  });
  const std::string back = error_of([&] { RawlogDataset r(dir.file("back.rawlog")); });
  EXPECT_NE(back.find("back.rawlog: scan 1 (t = "), std::string::npos) << back;
  EXPECT_NE(back.find("must be in time order"), std::string::npos) << back;
  edit_rawlog(small, dir.file("zoom.rawlog"), [](mrpt::obs::CObservation3DRangeScan& scan, int i) {
    if (i == 2) scan.cameraParams.setIntrinsicParamsFromValues(12, 12, 3.5, 2.5);
  });
  const std::string zoom = error_of([&] { RawlogDataset r(dir.file("zoom.rawlog")); });
  EXPECT_NE(zoom.find("zoom.rawlog: scan 2's camera differs from scan 0's"), std::string::npos)
      << zoom;
  EXPECT_EQ(RawlogDataset(dir.file("zoom.rawlog"), small_camera()).size(), 3u);  // one given
}

TEST(RawlogDataset, BadInputNamesTheFile) {
  test::TempDir dir;
  EXPECT_NE(error_of([&] { RawlogDataset(dir.file("none.rawlog")); }).find("does not exist"),
            std::string::npos);
  const std::string garbage = dir.write("garbage.rawlog", std::string(5000, '\x42'));
  EXPECT_NE(error_of([&] { RawlogDataset r(garbage); }).find("garbage.rawlog"), std::string::npos);
  Frame frame;
  frame.camera.width = 8;
  frame.camera.height = 6;
  frame.depth = DepthImage(8, 6, 1.0f);
  write_rawlog(dir.file("two.rawlog"), {frame, frame});
  std::filesystem::resize_file(dir.file("two.rawlog"),
                               std::filesystem::file_size(dir.file("two.rawlog")) / 2);
  EXPECT_NE(error_of([&] { RawlogDataset r(dir.file("two.rawlog")); }).find("not a readable"),
            std::string::npos);
  // A size field MRPT trusts: the range image's rows and columns (uint32, in that order) set to
  // 2³¹ − 1. MRPT's reader then dies of SIGSEGV inside its own code (measured), which only the
  // child-process read turns into an error.
  frame.depth = DepthImage(23, 17, 1.0f);
  frame.camera.width = 23;
  frame.camera.height = 17;
  write_rawlog(dir.file("sizes.rawlog"), {frame});
  std::string bytes = gunzip(dir.file("sizes.rawlog"));
  const std::uint32_t size[2] = {17, 23}, huge[2] = {0x7FFFFFFF, 0x7FFFFFFF};
  const std::string pattern(reinterpret_cast<const char*>(size), sizeof size);
  const std::size_t at = bytes.find(pattern);
  ASSERT_NE(at, std::string::npos) << "no rows, cols pair in the rawlog";
  std::memcpy(&bytes[at], huge, sizeof huge);
  gzip(dir.file("sizes.rawlog"), bytes);
  const std::string crashed = error_of([&] { RawlogDataset r(dir.file("sizes.rawlog")); });
  EXPECT_NE(crashed.find("sizes.rawlog: not a readable MRPT rawlog"), std::string::npos) << crashed;
  write_rawlog(dir.file("empty.rawlog"), {});
  EXPECT_NE(error_of([&] {
              RawlogDataset r(dir.file("empty.rawlog"));
            }).find("no CObservation3DRangeScan"),
            std::string::npos);
  EXPECT_NE(error_of([&] { open_dataset(dir.file("x.txt"), std::nullopt); }).find("does not exist"),
            std::string::npos);
  const std::string text = dir.write("notes.txt", "hello");
  EXPECT_NE(error_of([&] { open_dataset(text, std::nullopt); }).find("not a dataset"),
            std::string::npos);
  EXPECT_NE(error_of([&] { open_dataset(kFr1, std::nullopt); }).find("no camera given"),
            std::string::npos);
  // A directory without the TUM lists is named as such, also with a camera (it was "no camera
  // given", then a missing depth.txt); a rawlog's extension in capitals is still a rawlog.
  std::filesystem::create_directory(dir.file("empty"));
  for (const auto& camera : {std::optional<CameraIntrinsics>{}, std::optional(small_camera())})
    EXPECT_NE(error_of([&] {
                open_dataset(dir.file("empty"), camera);
              }).find("empty: not a TUM RGB-D directory (no depth.txt or associations.txt"),
              std::string::npos);
  std::filesystem::copy_file(dir.file("two.rawlog"), dir.file("TWO.RAWLOG"));
  EXPECT_NE(error_of([&] {
              open_dataset(dir.file("TWO.RAWLOG"), std::nullopt);
            }).find("TWO.RAWLOG: not a readable"),
            std::string::npos);
}

}  // namespace
}  // namespace jpcr
