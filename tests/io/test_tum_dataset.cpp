// The TUM directory reader on the real fr1/xyz slice in tests/data, and every kind of bad input
// the foundation issue lists: each is one clear InputError naming the file (and line).
#include <sys/stat.h>

#include <filesystem>
#include <fstream>
#include <sstream>

#include <gtest/gtest.h>
#include <opencv2/imgcodecs.hpp>

#include "jpcr/io/camera_yaml.hpp"
#include "jpcr/io/depth_png.hpp"
#include "jpcr/io/open_dataset.hpp"
#include "jpcr/io/trajectory_metrics.hpp"
#include "jpcr/io/tum_dataset.hpp"
#include "jpcr/quadric/error.hpp"
#include "jpcr/quadric/vertex_map.hpp"
#include "temp_dir.hpp"

namespace fs = std::filesystem;

namespace jpcr {
namespace {

const std::string kFr1 = std::string(JPCR_TEST_DATA_DIR) + "/tum_fr1_xyz_20";

std::string error_of(const std::function<void()>& f) {
  try {
    f();
  } catch (const InputError& e) {
    return e.what();
  }
  return "<no error>";
}

// A tiny valid TUM directory: n frames of 8x6 depth at 1 m.
std::string make_sequence(const test::TempDir& dir, int n) {
  std::string list = "# depth maps\n";
  for (int i = 0; i < n; ++i) {
    const std::string name = "depth/" + std::to_string(i) + ".png";
    fs::create_directories(dir.file("depth"));
    cv::imwrite(dir.file(name), cv::Mat(6, 8, CV_16UC1, cv::Scalar(5000)));
    list += std::to_string(10 + i) + ".0 " + name + "\n";
  }
  dir.write("depth.txt", list);
  return dir.path();
}

CameraIntrinsics tiny_camera() {
  CameraIntrinsics c;
  c.width = 8;
  c.height = 6;
  c.cx = 3.5;
  c.cy = 2.5;
  return c;
}

TEST(TumDataset, LoadsRealFr1FramesWithGroundTruth) {
  const CameraIntrinsics camera =
      load_camera_yaml(std::string(JPCR_SOURCE_DIR) + "/configs/ros_default.yaml");
  const TumDataset dataset(kFr1, camera);
  ASSERT_EQ(dataset.size(), 20u);
  EXPECT_DOUBLE_EQ(dataset.timestamp(0), 1305031102.160407);
  const Frame frame = dataset.load(0);
  EXPECT_EQ(frame.depth.width(), 640);
  const double valid = valid_depth_fraction(frame.depth);
  EXPECT_GT(valid, 0.5);  // a Kinect frame of a desk: most pixels have depth
  float max_depth = 0.0f;
  for (float z : frame.depth)
    max_depth = std::max(max_depth, z);
  EXPECT_GT(max_depth, 0.5f);
  EXPECT_LT(max_depth, 13.2f);  // 65535 / 5000
  for (std::size_t i = 0; i < dataset.size(); ++i)
    EXPECT_TRUE(dataset.ground_truth(i)) << i;
  // The first ground-truth pose associated with 1305031102.160407 is the 1305031102.1558 line (4.6
  // ms away).
  const Eigen::Vector3d t0 = dataset.ground_truth(0)->translation();
  EXPECT_NEAR(t0.x(), 1.3452, 1e-9);
  EXPECT_EQ(dataset.ground_truth_trajectory().size(), 20u);
}

// A gap in the motion capture (no ground truth within 20 ms of frame 10): the recorded ground
// truth keeps it, so RPE skips the two frame pairs that touch frame 10, as TUM's
// evaluate_rpe.py does. The ground truth re-stamped at the frames has no line for frame 10
// either, but RPE's tolerance there (twice the median interval, 67 ms) gives frame 10 frame 9's
// or 11's pose: 18 pairs instead of 16.
TEST(TumDataset, RecordedGroundTruthKeepsItsGapsForTheMetrics) {
  const test::TempDir dir;
  fs::copy(kFr1, dir.path(), fs::copy_options::recursive | fs::copy_options::overwrite_existing);
  const CameraIntrinsics fr1 =
      load_camera_yaml(std::string(JPCR_SOURCE_DIR) + "/configs/tum_fr1.yaml");
  const double t10 = TumDataset(dir.path(), fr1).timestamp(10);
  std::ifstream in(dir.file("groundtruth.txt"));
  std::ostringstream kept;
  int removed = 0;
  for (std::string line; std::getline(in, line);) {
    if (line.empty() || line[0] == '#' || std::abs(std::stod(line) - t10) >= 0.02)
      kept << line << '\n';
    else
      ++removed;
  }
  ASSERT_GT(removed, 2);
  dir.write("groundtruth.txt", kept.str());

  const TumDataset dataset(dir.path(), fr1);
  EXPECT_FALSE(dataset.ground_truth(10));
  const Trajectory recorded = dataset.recorded_ground_truth();
  EXPECT_EQ(recorded.size(), 73u - static_cast<std::size_t>(removed));
  // The range of frames 2..4 takes the recorded poses from 20 ms before frame 2 to 20 ms after 4.
  const Trajectory part = dataset.recorded_ground_truth(2, 5);
  ASSERT_FALSE(part.empty());
  EXPECT_GE(part.front().timestamp, dataset.timestamp(2) - 0.02);
  EXPECT_LE(part.back().timestamp, dataset.timestamp(4) + 0.02);
  EXPECT_LT(part.size(), recorded.size());

  Trajectory estimate;  // any pose at every frame, frame 10 included
  for (std::size_t i = 0; i < dataset.size(); ++i)
    estimate.push_back({dataset.timestamp(i), Eigen::Isometry3d::Identity()});
  EXPECT_EQ(compute_rpe(recorded, estimate, 1.0, DeltaUnit::kFrames).translation.count, 16u);
  EXPECT_EQ(compute_rpe(dataset.ground_truth_trajectory(), estimate, 1.0, DeltaUnit::kFrames)
                .translation.count,
            18u);
  EXPECT_EQ(compute_relative_errors(recorded, estimate).pairs, 17u);
}

TEST(TumDataset, DistortionIsRemovedWithNearestNeighbour) {
  const CameraIntrinsics fr1 =
      load_camera_yaml(std::string(JPCR_SOURCE_DIR) + "/configs/tum_fr1.yaml");
  const TumDataset dataset(kFr1, fr1);
  const Frame frame = dataset.load(0);
  // Nearest-neighbour remapping only moves raw values: every depth is a multiple of 1/5000 m.
  int checked = 0;
  for (float z : frame.depth) {
    if (z <= 0.0f) continue;
    const double raw = static_cast<double>(z) * 5000.0;
    EXPECT_NEAR(raw, std::round(raw), 1e-2);
    if (++checked > 2000) break;
  }
  EXPECT_GT(checked, 1000);
  // The frame's camera describes the depth as delivered, rectified (what jpcr_dds_play
  // publishes in camera_info: a D beside rectified depth would be applied twice downstream).
  ASSERT_TRUE(fr1.has_distortion());
  EXPECT_FALSE(frame.camera.has_distortion());
  EXPECT_EQ(frame.camera.fx, fr1.fx);
}

TEST(TumDataset, DistortionThatLosesTheImageIsRefused) {
  CameraIntrinsics fr1 = load_camera_yaml(std::string(JPCR_SOURCE_DIR) + "/configs/tum_fr1.yaml");
  fr1.distortion = {1e30, 1e30, 0.0, 0.0, 0.0};  // every ray from far outside the sensor
  try {
    const TumDataset dataset(kFr1, fr1);
    FAIL() << "accepted distortion " << fr1.distortion[0];
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find("distortion coefficients take 100 % of the pixels"),
              std::string::npos)
        << e.what();
  }
  // Through open_dataset the message says the camera was the caller's (--config), not the
  // dataset's own.
  const std::string error = [&] {
    try {
      open_dataset(kFr1, fr1);
    } catch (const InputError& e) {
      return std::string(e.what());
    }
    return std::string("<no error>");
  }();
  EXPECT_NE(error.find(" with the camera given (--config): the camera's distortion coefficients"),
            std::string::npos)
      << error;
  fr1.distortion = {-0.5, 0.0, 0.0, 0.0, 0.0};  // strong barrel: the corners, not the image
  EXPECT_NO_THROW(TumDataset(kFr1, fr1));
}

TEST(TumDataset, MissingDirectoryAndList) {
  EXPECT_NE(error_of([] {
              TumDataset("/no/such/dir", CameraIntrinsics());
            }).find("/no/such/dir: dataset directory does not exist"),
            std::string::npos);
  test::TempDir dir;
  EXPECT_NE(error_of([&] { TumDataset(dir.path(), CameraIntrinsics()); }).find("depth.txt"),
            std::string::npos);
}

// The directory's own camera.yaml says the scale its depth PNGs were written at: a --config with
// another scale read every depth wrong without a word; other intrinsics are a calibration.
TEST(TumDataset, AGivenCameraMustKeepTheDirectorysDepthScale) {
  test::TempDir dir;
  make_sequence(dir, 2);
  CameraIntrinsics own = tiny_camera();
  own.depth_scale = 5000.0;
  dir.write("camera.yaml", format_camera_yaml(own));
  CameraIntrinsics given = own;
  given.fx = 2.0;
  EXPECT_EQ(open_dataset(dir.path(), given, DatasetParams{})->size(), 2u);
  given.depth_scale = 1000.0;
  EXPECT_NE(error_of([&] {
              open_dataset(dir.path(), given, DatasetParams{});
            }).find("the camera given has depth_scale 1000"),
            std::string::npos);
}

TEST(TumDataset, EmptySequence) {
  test::TempDir dir;
  dir.write("depth.txt", "# nothing here\n");
  EXPECT_NE(error_of([&] { TumDataset(dir.path(), tiny_camera()); }).find("no depth frames"),
            std::string::npos);
}

TEST(TumDataset, UnsortedAndDuplicateTimestamps) {
  test::TempDir dir;
  make_sequence(dir, 2);
  dir.write("depth.txt", "11.0 depth/1.png\n10.0 depth/0.png\n");
  EXPECT_NE(error_of([&] {
              TumDataset(dir.path(), tiny_camera());
            }).find("depth.txt:2: timestamps are not sorted"),
            std::string::npos);
  dir.write("depth.txt", "10.0 depth/0.png\n10.0 depth/1.png\n");
  EXPECT_NE(error_of([&] { TumDataset(dir.path(), tiny_camera()); }).find("duplicate timestamp"),
            std::string::npos);
}

// Found when the dataset is opened, before any frame is run; a file removed later is still
// named when its frame is loaded.
TEST(TumDataset, ListNamingAMissingPng) {
  test::TempDir dir;
  make_sequence(dir, 2);
  fs::remove(dir.file("depth/1.png"));
  EXPECT_NE(error_of([&] {
              TumDataset(dir.path(), tiny_camera());
            }).find("depth/1.png: file does not exist (frame 1 of the depth.txt list)"),
            std::string::npos);
  make_sequence(dir, 2);
  const TumDataset dataset(dir.path(), tiny_camera());
  fs::remove(dir.file("depth/1.png"));
  EXPECT_NO_THROW(dataset.load(0));
  EXPECT_NE(error_of([&] { dataset.load(1); }).find("depth/1.png: file does not exist"),
            std::string::npos);
  // A pipe where the PNG should be is there, but no file (it said "does not exist").
  fs::remove(dir.file("depth/1.png"));
  ASSERT_EQ(mkfifo(dir.file("depth/1.png").c_str(), 0600), 0);
  EXPECT_NE(
      error_of([&] { TumDataset(dir.path(), tiny_camera()); })
          .find("depth/1.png: not a regular file (a pipe, a device or a directory; frame 1 of "
                "the depth.txt list)"),
      std::string::npos);
}

TEST(TumDataset, CorruptAndEightBitPngsAndWrongSize) {
  test::TempDir dir;
  make_sequence(dir, 3);
  dir.write("depth/0.png", "\x89PNG\r\n\x1a\n this is not really a png");
  cv::imwrite(dir.file("depth/1.png"), cv::Mat(6, 8, CV_8UC3, cv::Scalar(1, 2, 3)));
  cv::imwrite(dir.file("depth/2.png"), cv::Mat(5, 8, CV_16UC1, cv::Scalar(1)));
  const TumDataset dataset(dir.path(), tiny_camera());
  EXPECT_NE(error_of([&] { dataset.load(0); }).find("0.png: cannot be decoded"), std::string::npos);
  // Bytes that are no PNG never reach OpenCV's other codecs (GDCM aborted on such input).
  const std::string regression =
      std::string(JPCR_SOURCE_DIR) + "/tests/fuzz/corpus/fuzz_depth_png/regression_gdcm_assert";
  EXPECT_NE(error_of([&] { load_depth_png(regression, 5000.0); }).find("not a PNG or JPEG file"),
            std::string::npos);
  EXPECT_NE(error_of([&] {
              dataset.load(1);
            }).find("expected a 16-bit single-channel depth PNG, got 8-bit RGB"),
            std::string::npos);
  // The PNG header's words (OpenCV decodes grey + alpha as four channels, so its count misleads).
  cv::imwrite(dir.file("depth/1.png"), cv::Mat(6, 8, CV_16UC4, cv::Scalar(1, 2, 3, 4)));
  const std::string rgba = error_of([&] { dataset.load(1); });
  EXPECT_NE(rgba.find("got 16-bit RGBA"), std::string::npos) << rgba;
  EXPECT_NE(error_of([&] { dataset.load(2); }).find("image is 8x5 but the camera is 8x6"),
            std::string::npos);
  // The header's size is checked before decoding: a few bytes declaring 16384x16384 (16-bit
  // grey) are refused as the wrong size, not decoded into 512 MB first.
  std::string header("\x89PNG\r\n\x1a\n\0\0\0\x0dIHDR\0\0\x40\0\0\0\x40\0\x10\0\0\0\0", 29);
  dir.write("depth/2.png", header + "truncated");
  EXPECT_NE(error_of([&] { dataset.load(2); }).find("image is 16384x16384 but the camera is 8x6"),
            std::string::npos);
}

// Colour frames are held to the camera's size too, the PNG header before decoding.
TEST(TumDataset, ColourOfAnotherSizeIsRefused) {
  test::TempDir dir;
  make_sequence(dir, 3);
  fs::create_directories(dir.file("rgb"));
  cv::imwrite(dir.file("rgb/0.png"), cv::Mat(6, 8, CV_8UC3, cv::Scalar(1, 2, 3)));
  cv::imwrite(dir.file("rgb/1.png"), cv::Mat(5, 8, CV_8UC3, cv::Scalar(1, 2, 3)));
  std::string header("\x89PNG\r\n\x1a\n\0\0\0\x0dIHDR\0\0\x40\0\0\0\x40\0\x08\x02\0\0\0", 29);
  dir.write("rgb/2.png", header + "truncated");
  dir.write("rgb.txt", "10.0 rgb/0.png\n11.0 rgb/1.png\n12.0 rgb/2.png\n");
  TumDatasetOptions options;
  options.load_color = true;
  const TumDataset dataset(dir.path(), tiny_camera(), options);
  const Frame first = dataset.load(0);
  ASSERT_EQ(first.color.width(), 8);
  EXPECT_EQ(first.color(0, 0).r, 3);  // BGR on disk, RGB in memory
  EXPECT_NE(error_of([&] { dataset.load(1); }).find("1.png: image is 8x5 but the camera is 8x6"),
            std::string::npos);
  EXPECT_NE(
      error_of([&] { dataset.load(2); }).find("2.png: image is 16384x16384 but the camera is 8x6"),
      std::string::npos);
}

TEST(TumDataset, GroundTruthWithNaNIsRejectedWithLine) {
  test::TempDir dir;
  make_sequence(dir, 2);
  dir.write("groundtruth.txt", "# gt\n10.0 0 0 0 0 0 0 1\n11.0 0 nan 0 0 0 0 1\n");
  EXPECT_NE(error_of([&] {
              TumDataset(dir.path(), tiny_camera());
            }).find("groundtruth.txt:3: field 3 is NaN/Inf"),
            std::string::npos);
}

TEST(TumDataset, AssociationsFileIsUsedWhenPresent) {
  test::TempDir dir;
  make_sequence(dir, 2);
  dir.write("associations.txt",
            "9.99 rgb/a.png 10.0 depth/0.png\n11.01 rgb/b.png 11.0 depth/1.png\n");
  const TumDataset dataset(dir.path(), tiny_camera());
  EXPECT_EQ(dataset.size(), 2u);
  EXPECT_DOUBLE_EQ(dataset.timestamp(1), 11.0);
}

// Errors give the line of associations.txt itself, comment lines counted.
TEST(TumDataset, AssociationsErrorsNameTheFilesLine) {
  test::TempDir dir;
  make_sequence(dir, 2);
  dir.write("associations.txt",
            "# rgb depth\n\n9.99 rgb/a.png 10.0 depth/0.png\n# gap\n11.01 rgb/b.png nan "
            "depth/1.png\n");
  const std::string error = error_of([&] { TumDataset(dir.path(), tiny_camera()); });
  EXPECT_NE(error.find("associations.txt:5:"), std::string::npos) << error;
  // A NUL byte in the colour file's name (not parsed as a file list) is refused too.
  dir.write("associations.txt", std::string("9.99 rgb/a\0.png 10.0 depth/0.png\n", 33));
  const std::string nul = error_of([&] { TumDataset(dir.path(), tiny_camera()); });
  EXPECT_NE(nul.find("associations.txt:1: holds a NUL byte"), std::string::npos) << nul;
}

TEST(DepthPng, SaveLoadRoundTripQuantisesToTheScale) {
  test::TempDir dir;
  DepthImage depth(4, 2, 1.23456f);
  depth(0, 0) = 0.0f;
  depth(1, 0) = std::numeric_limits<float>::quiet_NaN();
  depth(2, 0) = 100.0f;  // beyond 16 bits at scale 5000: no measurement
  save_depth_png(dir.file("d.png"), depth, 5000.0);
  const DepthImage back = load_depth_png(dir.file("d.png"), 5000.0);
  EXPECT_EQ(back(0, 0), 0.0f);
  EXPECT_EQ(back(1, 0), 0.0f);
  EXPECT_EQ(back(2, 0), 0.0f);
  EXPECT_NEAR(back(3, 1), 1.23456f, 0.5 / 5000.0 + 1e-6);
}

}  // namespace
}  // namespace jpcr
