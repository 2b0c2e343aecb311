// sensor_msgs/Image and sensor_msgs/CameraInfo as plain C++ values, and the strict decoding of
// received ones into jpcr types. Nothing here depends on DDS: the DDS layer borrows the fields of
// a sample into a RosImageView, so the decoder is unit-tested and fuzzed on its own.
//
// Every check that a received sample must pass lives here; a failure throws InputError whose
// message names the problem ("data is 100 bytes, step x height = 1200").
#pragma once

#include <array>
#include <cstddef>
#include <cstdint>
#include <string>
#include <string_view>
#include <vector>

#include <Eigen/Core>

#include "jpcr/quadric/camera.hpp"
#include "jpcr/quadric/frame.hpp"
#include "jpcr/quadric/image.hpp"

namespace jpcr {

/// builtin_interfaces/Time.
struct RosStamp {
  std::int32_t sec = 0;
  std::uint32_t nanosec = 0;
};

/// Seconds to sec + nanosec. A double holds a stamp of today (about 1.7e9 s) only to about
/// 240 ns, so the stamps that to_seconds converted are remembered (the kRememberedStamps most
/// recently used, process-wide, thread-safe) and come back exactly: what jpcr publishes for a
/// received frame carries that frame's header stamp to the nanosecond, as ROS's exact-time
/// synchronisation and tf lookups need. Any other value gives the shortest decimal that reads
/// back as it, rounded at the nanosecond: a dataset's decimal stamp as written (1305031102.160407
/// is 160407000 ns, where the double's nearest nanosecond is 160407066).
RosStamp to_ros_stamp(double seconds);
/// sec + nanosec in seconds; remembered for to_ros_stamp.
double to_seconds(const RosStamp& stamp);
/// The stamp as exact decimal seconds: "12.000000500", and "-0.466667000" for {-1, 533333000}
/// (sec + nanosec·1e-9; "%d.%09u" would print -1.533333000). nanosec ≥ 1e9 is normalised.
std::string format_ros_stamp(std::int64_t sec, std::uint32_t nanosec);
constexpr std::size_t kRememberedStamps = std::size_t{1} << 16;  // 36 min of frames at 30 Hz

/// The fields of a received sensor_msgs/Image; `data` is borrowed.
struct RosImageView {
  std::uint32_t height = 0;
  std::uint32_t width = 0;
  std::string_view encoding;
  std::uint8_t is_bigendian = 0;
  std::uint32_t step = 0;  // bytes per row
  const std::uint8_t* data = nullptr;
  std::size_t size = 0;  // bytes in data
};

/// An image to send: sensor_msgs/Image fields with owned data.
struct RosImageBuffer {
  std::uint32_t height = 0;
  std::uint32_t width = 0;
  std::string encoding;
  std::uint32_t step = 0;
  std::vector<std::uint8_t> data;

  RosImageView view() const;
};

/// sensor_msgs/CameraInfo fields jpcr reads and writes (the header travels separately).
struct RosCameraInfo {
  std::uint32_t height = 0;
  std::uint32_t width = 0;
  std::string distortion_model;
  std::vector<double> d;
  std::array<double, 9> k{};   // row-major 3x3
  std::array<double, 9> r{};   // row-major 3x3 rectification
  std::array<double, 12> p{};  // row-major 3x4 projection
  std::uint32_t binning_x = 0;
  std::uint32_t binning_y = 0;
};

/// Bounds on what a received image may claim, checked before anything is read or allocated.
struct RosImageLimits {
  std::size_t max_bytes = std::size_t{64} << 20;  // bytes of data (step x height)
  std::uint32_t max_side = 16384;                 // pixels, width and height
};

/// The depth encodings ROS camera drivers publish.
enum class DepthEncoding {
  kMillimetres16,  // "16UC1": uint16 millimetres, 0 = no measurement
  kMetres32,       // "32FC1": float32 metres, 0 or NaN = no measurement
};

/// "16UC1" | "32FC1"; throws InputError naming the text otherwise.
DepthEncoding parse_depth_encoding(std::string_view text);
const char* to_string(DepthEncoding encoding);

/// Checks the layout of a received image of `expected encodings` (bytes per pixel each) and
/// returns the bytes per pixel of its encoding. Throws InputError on a zero or absurd size, an
/// unknown encoding, big-endian data, step < width x bytes per pixel, or data length != step x
/// height.
std::size_t check_image_layout(
    const RosImageView& image,
    const std::vector<std::pair<std::string_view, std::size_t>>& encodings,
    const RosImageLimits& limits);

/// A 16UC1 (mm) or 32FC1 (m) depth image in metres. Values that are not finite and positive
/// become 0 (no measurement).
DepthImage decode_depth_image(const RosImageView& image, const RosImageLimits& limits);

/// Intrinsics of the rectified image from a CameraInfo: fx, fy, cx, cy from P (from K when P is
/// all zero, as an uncalibrated driver sends it). D describes the raw image, and jpcr does not
/// apply it: any model is taken, and `distortion` holds k1, k2, p1, p2, k3 of "plumb_bob" and
/// "rational_polynomial" (zero for other models). Throws InputError on a zero size, non-finite
/// values, non-positive focal lengths, a P or K that is not a pinhole matrix, or binning.
CameraIntrinsics decode_camera_info(const RosCameraInfo& info, const RosImageLimits& limits);

/// Whether D has any non-zero term, whatever its model (the raw image has lens distortion).
bool lens_distortion(const RosCameraInfo& info);

/// A depth frame: the image decoded and checked against the camera's size. `camera.depth_scale`
/// is set to the encoding's raw units per metre (1000 for 16UC1, 1 for 32FC1).
Frame decode_depth_frame(const RosImageView& image, const RosStamp& stamp,
                         const CameraIntrinsics& camera, const RosImageLimits& limits);

/// A 32FC2 image (κ1, κ2 per pixel, NaN invalid) and an rgb8 image, for receivers and tests.
Image<Eigen::Vector2f> decode_curvature_image(const RosImageView& image,
                                              const RosImageLimits& limits);
ColorImage decode_rgb8_image(const RosImageView& image, const RosImageLimits& limits);
/// A 32FC1 curvature sd map (1/m per pixel, NaN where none: curvature_spread.hpp). Throws
/// InputError naming the first pixel whose value is negative or infinite: not an sd.
Image<float> decode_curvature_sd_image(const RosImageView& image, const RosImageLimits& limits);

/// Encoders for sending; little-endian, rows packed (step = width x bytes per pixel). Depth in
/// 16UC1 is rounded to whole millimetres; depths that do not fit (not finite, <= 0, > 65.535 m)
/// are sent as 0. In 32FC1 a pixel without a measurement is NaN (REP 118: depth_image_proc
/// takes 0 m as a measurement there).
RosImageBuffer encode_depth_image(const DepthImage& depth, DepthEncoding encoding);
RosImageBuffer encode_curvature_image(const Image<Eigen::Vector2f>& curvature);
RosImageBuffer encode_rgb8_image(const ColorImage& color);
/// 32FC1 with every value as it is (NaN stays NaN: no sd there).
RosImageBuffer encode_curvature_sd_image(const Image<float>& sd);

/// A CameraInfo for the intrinsics: K and P from fx, fy, cx, cy, R = I, "plumb_bob" D.
RosCameraInfo encode_camera_info(const CameraIntrinsics& camera);

}  // namespace jpcr
