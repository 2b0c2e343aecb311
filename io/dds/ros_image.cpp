#include "jpcr/io/dds/ros_image.hpp"

#include <algorithm>
#include <array>
#include <charconv>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <limits>
#include <list>
#include <mutex>
#include <optional>
#include <stdexcept>
#include <string>
#include <string_view>
#include <unordered_map>
#include <utility>

#include "jpcr/io/number_format.hpp"
#include "jpcr/quadric/error.hpp"

namespace jpcr {

namespace {

constexpr double kNanosecondsPerSecond = 1e9;
constexpr float kMetresPerMillimetre = 0.001f;
constexpr double kMillimetresPerMetre = 1000.0;

[[noreturn]] void reject(const std::string& problem) {
  throw InputError(problem);
}

std::string quoted(std::string_view text) {
  constexpr std::size_t kShown = 32;  // characters of a bad encoding shown in messages
  std::string shown;
  for (const char c : text.substr(0, kShown))
    shown += (c >= 32 && c < 127) ? c : '?';
  return "'" + shown + (text.size() > kShown ? "...'" : "'");
}

// Reads the rows of a checked image (`step` bytes apart) as values of type In, copied first so
// that nothing is read unaligned from the sample, and writes convert(value) to `out`, packed.
template <typename In, typename Out, typename Convert>
void read_rows(const RosImageView& image, std::size_t values_per_pixel, Convert convert, Out* out) {
  const std::size_t values_per_row = std::size_t{image.width} * values_per_pixel;
  std::vector<In> row(values_per_row);
  for (std::uint32_t v = 0; v < image.height; ++v) {
    std::memcpy(row.data(), image.data + std::size_t{v} * image.step, values_per_row * sizeof(In));
    for (std::size_t i = 0; i < values_per_row; ++i)
      convert(row[i], out + std::size_t{v} * values_per_row + i);
  }
}

template <typename T>
void append_bytes(std::vector<std::uint8_t>& bytes, const T& value) {
  const auto* p = reinterpret_cast<const std::uint8_t*>(&value);
  bytes.insert(bytes.end(), p, p + sizeof(T));
}

RosImageBuffer empty_buffer(int width, int height, const char* encoding, std::size_t bpp) {
  RosImageBuffer b;
  b.width = static_cast<std::uint32_t>(width);
  b.height = static_cast<std::uint32_t>(height);
  b.encoding = encoding;
  b.step = static_cast<std::uint32_t>(std::size_t(width) * bpp);
  b.data.reserve(std::size_t{b.step} * b.height);
  return b;
}

// The stamps to_seconds converted, keyed by the double it returned; the least recently used is
// forgotten first, so the keyframes that every path message stamps again stay.
class StampMemory {
 public:
  void remember(double seconds, const RosStamp& stamp) {
    const std::lock_guard<std::mutex> lock(mutex_);
    const auto found = index_.find(seconds);
    if (found != index_.end()) {
      found->second->second = stamp;  // the latest of two stamps a double cannot tell apart
      order_.splice(order_.begin(), order_, found->second);
      return;
    }
    order_.emplace_front(seconds, stamp);
    index_.emplace(seconds, order_.begin());
    if (order_.size() > kRememberedStamps) {
      index_.erase(order_.back().first);
      order_.pop_back();
    }
  }

  bool recall(double seconds, RosStamp& stamp) {
    const std::lock_guard<std::mutex> lock(mutex_);
    const auto found = index_.find(seconds);
    if (found == index_.end()) return false;
    order_.splice(order_.begin(), order_, found->second);
    stamp = found->second->second;
    return true;
  }

 private:
  using Entries = std::list<std::pair<double, RosStamp>>;
  std::mutex mutex_;
  Entries order_;  // most recently used first
  std::unordered_map<double, Entries::iterator> index_;
};

StampMemory& stamp_memory() {
  static StampMemory memory;
  return memory;
}

// The shortest decimal that reads back as `seconds` (std::to_chars), rounded to nanoseconds,
// as sec + nanosec; none for a value out of a stamp's range. A dataset's stamp in decimal
// (TUM's microseconds: 1305031102.160407) comes back as written, where the nearest nanosecond
// to the double was 1305031102.160407066.
std::optional<RosStamp> shortest_decimal_stamp(double seconds) {
  constexpr long long kPerSecond = 1000000000;
  if (!(std::abs(seconds) < 2147483647.0)) return std::nullopt;
  char text[64];
  const std::to_chars_result r =
      std::to_chars(text, text + sizeof text, seconds, std::chars_format::fixed);
  if (r.ec != std::errc()) return std::nullopt;
  const std::string_view digits(text, static_cast<std::size_t>(r.ptr - text));
  const bool negative = !digits.empty() && digits[0] == '-';
  long long whole = 0, nanosec = 0;
  std::size_t i = negative ? 1 : 0;
  for (; i < digits.size() && digits[i] != '.'; ++i)
    whole = 10 * whole + (digits[i] - '0');
  int place = 0;
  for (++i; i < digits.size() && place < 9; ++i, ++place)
    nanosec = 10 * nanosec + (digits[i] - '0');
  for (; place < 9; ++place)
    nanosec *= 10;
  if (i < digits.size() && digits[i] >= '5') ++nanosec;  // the tenth digit rounds
  long long total = whole * kPerSecond + nanosec;
  if (negative) total = -total;
  long long sec = total / kPerSecond;
  long long rest = total % kPerSecond;
  if (rest < 0) {
    --sec;
    rest += kPerSecond;
  }
  return RosStamp{static_cast<std::int32_t>(sec), static_cast<std::uint32_t>(rest)};
}

}  // namespace

RosStamp to_ros_stamp(double seconds) {
  RosStamp remembered;
  if (stamp_memory().recall(seconds, remembered)) return remembered;
  if (const std::optional<RosStamp> decimal = shortest_decimal_stamp(seconds)) return *decimal;
  const double whole = std::floor(seconds);
  long long nanosec = std::llround((seconds - whole) * kNanosecondsPerSecond);
  long long sec = static_cast<long long>(whole);
  if (nanosec >= static_cast<long long>(kNanosecondsPerSecond)) {
    ++sec;
    nanosec -= static_cast<long long>(kNanosecondsPerSecond);
  }
  RosStamp s;
  s.sec = static_cast<std::int32_t>(sec);
  s.nanosec = static_cast<std::uint32_t>(nanosec);
  return s;
}

std::string format_ros_stamp(std::int64_t sec, std::uint32_t nanosec) {
  constexpr std::int64_t kPerSecond = 1000000000;
  const std::int64_t total = sec * kPerSecond + nanosec;  // |sec| < 2^33: no overflow
  const std::uint64_t magnitude =
      total < 0 ? static_cast<std::uint64_t>(-total) : static_cast<std::uint64_t>(total);
  char text[40];
  std::snprintf(text, sizeof text, "%s%llu.%09llu", total < 0 ? "-" : "",
                static_cast<unsigned long long>(magnitude / kPerSecond),
                static_cast<unsigned long long>(magnitude % kPerSecond));
  return text;
}

double to_seconds(const RosStamp& stamp) {
  const double seconds =
      static_cast<double>(stamp.sec) + static_cast<double>(stamp.nanosec) / kNanosecondsPerSecond;
  // Remembered normalised (nanosec < 1e9), as to_ros_stamp gives every other value: a malformed
  // {5, 1.5e9} is {6, 5e8}.
  constexpr std::uint32_t kPerSecond = 1000000000u;
  RosStamp normal = stamp;
  normal.sec += static_cast<std::int32_t>(stamp.nanosec / kPerSecond);
  normal.nanosec = stamp.nanosec % kPerSecond;
  stamp_memory().remember(seconds, normal);
  return seconds;
}

RosImageView RosImageBuffer::view() const {
  RosImageView v;
  v.height = height;
  v.width = width;
  v.encoding = encoding;
  v.step = step;
  v.data = data.data();
  v.size = data.size();
  return v;
}

DepthEncoding parse_depth_encoding(std::string_view text) {
  if (text == "16UC1") return DepthEncoding::kMillimetres16;
  if (text == "32FC1") return DepthEncoding::kMetres32;
  reject("unknown depth encoding " + quoted(text) + " (expected 16UC1 or 32FC1)");
}

const char* to_string(DepthEncoding encoding) {
  return encoding == DepthEncoding::kMillimetres16 ? "16UC1" : "32FC1";
}

std::size_t check_image_layout(
    const RosImageView& image,
    const std::vector<std::pair<std::string_view, std::size_t>>& encodings,
    const RosImageLimits& limits) {
  std::size_t bpp = 0;
  std::string known;
  for (const auto& [name, bytes] : encodings) {
    if (image.encoding == name) bpp = bytes;
    known += (known.empty() ? "" : " or ") + std::string(name);
  }
  if (bpp == 0) reject("unknown encoding " + quoted(image.encoding) + " (expected " + known + ")");
  if (image.width == 0 || image.height == 0) {
    reject("zero size " + std::to_string(image.width) + "x" + std::to_string(image.height));
  }
  if (image.width > limits.max_side || image.height > limits.max_side) {
    reject("size " + std::to_string(image.width) + "x" + std::to_string(image.height) +
           " exceeds the limit of " + std::to_string(limits.max_side) + " pixels a side");
  }
  if (image.is_bigendian != 0) reject("big-endian data is not supported");
  // 64-bit products: width, height and step are < 2^32 each, so none of these overflow.
  const std::uint64_t row_bytes = std::uint64_t{image.width} * bpp;
  if (image.step < row_bytes) {
    reject("step " + std::to_string(image.step) + " < width x " + std::to_string(bpp) +
           " bytes = " + std::to_string(row_bytes));
  }
  const std::uint64_t claimed = std::uint64_t{image.step} * image.height;
  if (claimed > limits.max_bytes) {
    reject("claimed size step x height = " + std::to_string(claimed) +
           " bytes exceeds the limit of " + std::to_string(limits.max_bytes));
  }
  if (image.size != claimed || (claimed > 0 && image.data == nullptr)) {
    reject("data is " + std::to_string(image.size) +
           " bytes, step x height = " + std::to_string(claimed));
  }
  return bpp;
}

DepthImage decode_depth_image(const RosImageView& image, const RosImageLimits& limits) {
  const std::size_t bpp = check_image_layout(image, {{"16UC1", 2}, {"32FC1", 4}}, limits);
  DepthImage depth(static_cast<int>(image.width), static_cast<int>(image.height));
  if (bpp == 2) {
    read_rows<std::uint16_t>(
        image, 1,
        [](std::uint16_t mm, float* out) { *out = static_cast<float>(mm) * kMetresPerMillimetre; },
        depth.data());
  } else {
    read_rows<float>(
        image, 1, [](float z, float* out) { *out = (std::isfinite(z) && z > 0.0f) ? z : 0.0f; },
        depth.data());
  }
  return depth;
}

CameraIntrinsics decode_camera_info(const RosCameraInfo& info, const RosImageLimits& limits) {
  if (info.width == 0 || info.height == 0) {
    reject("camera_info has zero size " + std::to_string(info.width) + "x" +
           std::to_string(info.height));
  }
  if (info.width > limits.max_side || info.height > limits.max_side) {
    reject("camera_info size exceeds the limit of " + std::to_string(limits.max_side) + " pixels");
  }
  // The image is used as received, so it is the rectified one, whose camera is P's left 3x3
  // (ROS: K and D describe the raw image, P the rectified one; P's Tx, Ty, the stereo baseline,
  // do not change where a point of this camera's own frame projects). A camera_info without P
  // (all zero) gives K.
  const bool has_p = std::any_of(info.p.begin(), info.p.end(), [](double v) { return v != 0.0; });
  const std::string name = has_p ? "P" : "K";
  const auto& p = info.p;
  const std::array<double, 9> k =
      has_p ? std::array<double, 9>{p[0], p[1], p[2], p[4], p[5], p[6], p[8], p[9], p[10]} : info.k;
  for (const double v :
       has_p ? std::vector<double>(p.begin(), p.end()) : std::vector<double>(k.begin(), k.end())) {
    if (!std::isfinite(v)) reject("camera_info " + name + " is not finite");
  }
  // K and R are not used beside P, but a sample with NaN in them is malformed all the same.
  for (const double v : info.k)
    if (!std::isfinite(v)) reject("camera_info K is not finite");
  for (const double v : info.r)
    if (!std::isfinite(v)) reject("camera_info R is not finite");
  if (!(k[0] > 0.0) || !(k[4] > 0.0)) {
    reject("camera_info " + name + " focal lengths fx = " + std::to_string(k[0]) +
           ", fy = " + std::to_string(k[4]) + " must be positive");
  }
  if (k[1] != 0.0 || k[3] != 0.0 || k[6] != 0.0 || k[7] != 0.0 || k[8] != 1.0) {
    reject("camera_info " + name + " is not a pinhole matrix without skew " +
           (has_p ? "[fx 0 cx Tx; 0 fy cy Ty; 0 0 1 0]" : "[fx 0 cx; 0 fy cy; 0 0 1]"));
  }
  if (has_p && p[11] != 0.0) reject("camera_info P is not a pinhole matrix (P[11] is not 0)");
  if (!(k[2] >= 0.0 && k[2] < info.width && k[5] >= 0.0 && k[5] < info.height)) {
    reject("camera_info principal point (" + std::to_string(k[2]) + ", " + std::to_string(k[5]) +
           ") lies outside the " + std::to_string(info.width) + "x" + std::to_string(info.height) +
           " image");
  }
  if (info.binning_x > 1 || info.binning_y > 1) reject("camera_info binning is not supported");
  CameraIntrinsics camera;
  camera.fx = k[0];
  camera.fy = k[4];
  camera.cx = k[2];
  camera.cy = k[5];
  camera.width = static_cast<int>(info.width);
  camera.height = static_cast<int>(info.height);
  // D describes the raw image and is not applied (the image is the rectified one), so any
  // model is taken: plumb_bob's and rational_polynomial's k1, k2, p1, p2, k3 are kept (OpenCV's
  // order, for the caller's log), and the rest (a fisheye's, rational_polynomial's k4-k6) is
  // not, which lens_distortion() still sees.
  camera.distortion = {};
  const std::string& model = info.distortion_model;
  for (const double d : info.d)
    if (!std::isfinite(d)) reject("camera_info D is not finite");
  if (model == "plumb_bob" || model == "rational_polynomial") {
    for (std::size_t i = 0; i < std::min(info.d.size(), camera.distortion.size()); ++i)
      camera.distortion[i] = info.d[i];
  }
  try {
    camera.validate();  // e.g. a focal length giving a field of view of 180°
  } catch (const std::invalid_argument& e) {
    reject(std::string("camera_info ") + e.what());
  }
  return camera;
}

bool lens_distortion(const RosCameraInfo& info) {
  return std::any_of(info.d.begin(), info.d.end(), [](double d) { return d != 0.0; });
}

Frame decode_depth_frame(const RosImageView& image, const RosStamp& stamp,
                         const CameraIntrinsics& camera, const RosImageLimits& limits) {
  if (stamp.nanosec >= static_cast<std::uint32_t>(kNanosecondsPerSecond)) {
    reject("stamp nanosec " + std::to_string(stamp.nanosec) + " is not below 10^9");
  }
  Frame frame;
  frame.depth = decode_depth_image(image, limits);
  if (frame.depth.width() != camera.width || frame.depth.height() != camera.height) {
    reject("image size " + std::to_string(frame.depth.width()) + "x" +
           std::to_string(frame.depth.height()) + " differs from camera_info size " +
           std::to_string(camera.width) + "x" + std::to_string(camera.height));
  }
  frame.timestamp = to_seconds(stamp);
  frame.camera = camera;
  frame.camera.depth_scale = parse_depth_encoding(image.encoding) == DepthEncoding::kMillimetres16
                                 ? kMillimetresPerMetre
                                 : 1.0;
  return frame;
}

Image<Eigen::Vector2f> decode_curvature_image(const RosImageView& image,
                                              const RosImageLimits& limits) {
  check_image_layout(image, {{"32FC2", 8}}, limits);
  Image<Eigen::Vector2f> out(static_cast<int>(image.width), static_cast<int>(image.height),
                             Eigen::Vector2f::Zero());
  read_rows<float>(
      image, 2, [](float k, float* o) { *o = k; }, out.data()->data());
  return out;
}

Image<float> decode_curvature_sd_image(const RosImageView& image, const RosImageLimits& limits) {
  check_image_layout(image, {{"32FC1", 4}}, limits);
  Image<float> out(static_cast<int>(image.width), static_cast<int>(image.height));
  read_rows<float>(
      image, 1, [](float sd, float* o) { *o = sd; }, out.data());
  for (int v = 0; v < out.height(); ++v)
    for (int u = 0; u < out.width(); ++u) {
      const float sd = out(u, v);
      if (!std::isnan(sd) && !(sd >= 0.0f && std::isfinite(sd)))
        reject("curvature sd at pixel (" + std::to_string(u) + ", " + std::to_string(v) + ") is " +
               format_double(sd) + ": an sd is a finite value >= 0, or NaN for none");
    }
  return out;
}

ColorImage decode_rgb8_image(const RosImageView& image, const RosImageLimits& limits) {
  check_image_layout(image, {{"rgb8", 3}}, limits);
  static_assert(sizeof(Rgb8) == 3, "Rgb8 must be packed");
  ColorImage out(static_cast<int>(image.width), static_cast<int>(image.height));
  read_rows<std::uint8_t>(
      image, 3, [](std::uint8_t c, std::uint8_t* o) { *o = c; },
      reinterpret_cast<std::uint8_t*>(out.data()));
  return out;
}

RosImageBuffer encode_depth_image(const DepthImage& depth, DepthEncoding encoding) {
  if (encoding == DepthEncoding::kMetres32) {
    RosImageBuffer b = empty_buffer(depth.width(), depth.height(), "32FC1", 4);
    constexpr float kNoMeasurement = std::numeric_limits<float>::quiet_NaN();  // REP 118
    for (const float z : depth)
      append_bytes(b.data, (std::isfinite(z) && z > 0.0f) ? z : kNoMeasurement);
    return b;
  }
  RosImageBuffer b = empty_buffer(depth.width(), depth.height(), "16UC1", 2);
  constexpr double kMaxMillimetres = std::numeric_limits<std::uint16_t>::max();
  for (const float z : depth) {
    const double mm = std::round(static_cast<double>(z) * kMillimetresPerMetre);
    const bool fits = std::isfinite(mm) && mm > 0.0 && mm <= kMaxMillimetres;
    append_bytes(b.data, static_cast<std::uint16_t>(fits ? mm : 0.0));
  }
  return b;
}

RosImageBuffer encode_curvature_image(const Image<Eigen::Vector2f>& curvature) {
  RosImageBuffer b = empty_buffer(curvature.width(), curvature.height(), "32FC2", 8);
  for (const Eigen::Vector2f& k : curvature) {
    append_bytes(b.data, k.x());
    append_bytes(b.data, k.y());
  }
  return b;
}

RosImageBuffer encode_rgb8_image(const ColorImage& color) {
  RosImageBuffer b = empty_buffer(color.width(), color.height(), "rgb8", 3);
  for (const Rgb8& c : color) {
    b.data.push_back(c.r);
    b.data.push_back(c.g);
    b.data.push_back(c.b);
  }
  return b;
}

RosImageBuffer encode_curvature_sd_image(const Image<float>& sd) {
  RosImageBuffer b = empty_buffer(sd.width(), sd.height(), "32FC1", 4);
  for (const float s : sd)
    append_bytes(b.data, s);
  return b;
}

RosCameraInfo encode_camera_info(const CameraIntrinsics& camera) {
  RosCameraInfo info;
  info.width = static_cast<std::uint32_t>(camera.width);
  info.height = static_cast<std::uint32_t>(camera.height);
  info.distortion_model = "plumb_bob";
  info.d.assign(camera.distortion.begin(), camera.distortion.end());
  info.k = {camera.fx, 0.0, camera.cx, 0.0, camera.fy, camera.cy, 0.0, 0.0, 1.0};
  info.r = {1.0, 0.0, 0.0, 0.0, 1.0, 0.0, 0.0, 0.0, 1.0};
  info.p = {camera.fx, 0.0, camera.cx, 0.0, 0.0, camera.fy, camera.cy, 0.0, 0.0, 0.0, 1.0, 0.0};
  return info;
}

}  // namespace jpcr
