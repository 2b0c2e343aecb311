// libFuzzer target: the sensor_msgs decoder (io/dds/ros_image.hpp) never reads out of bounds,
// never allocates from a lying header, and accepts only images whose layout is consistent.
// Input layout: height, width, step (uint32 LE each), is_bigendian (1 byte), encoding length n
// (1 byte), n bytes of encoding, 9 doubles of K for a camera_info, then the image data.
#include <cmath>
#include <cstdint>
#include <cstring>
#include <string>

#include "jpcr/io/dds/ros_image.hpp"
#include "jpcr/quadric/error.hpp"

namespace {

template <typename T>
bool take(const std::uint8_t*& data, std::size_t& size, T& out) {
  if (size < sizeof(T)) return false;
  std::memcpy(&out, data, sizeof(T));
  data += sizeof(T);
  size -= sizeof(T);
  return true;
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  jpcr::RosImageView image;
  std::uint8_t encoding_length = 0;
  if (!take(data, size, image.height) || !take(data, size, image.width) ||
      !take(data, size, image.step) || !take(data, size, image.is_bigendian) ||
      !take(data, size, encoding_length) || size < encoding_length) {
    return 0;
  }
  const std::string encoding(reinterpret_cast<const char*>(data), encoding_length);
  data += encoding_length;
  size -= encoding_length;
  jpcr::RosCameraInfo info;
  for (double& k : info.k)
    if (!take(data, size, k)) return 0;
  info.width = image.width;
  info.height = image.height;
  image.encoding = encoding;
  image.data = data;
  image.size = size;

  jpcr::RosImageLimits limits;
  limits.max_bytes = std::size_t{1} << 20;  // keeps each run fast; the check is what matters
  const std::size_t pixels = std::size_t{image.width} * image.height;
  try {
    const jpcr::DepthImage d = jpcr::decode_depth_image(image, limits);
    if (d.size() != pixels || std::size_t{image.step} * image.height != size) __builtin_trap();
    for (const float z : d)
      if (!(z >= 0.0f)) __builtin_trap();  // invalid depths are 0, never NaN or negative
  } catch (const jpcr::InputError&) {
  }
  try {
    if (jpcr::decode_curvature_image(image, limits).size() != pixels) __builtin_trap();
  } catch (const jpcr::InputError&) {
  }
  try {
    const jpcr::Image<float> sd = jpcr::decode_curvature_sd_image(image, limits);
    if (sd.size() != pixels) __builtin_trap();
    for (const float s : sd)
      if (!(std::isnan(s) || (s >= 0.0f && std::isfinite(s)))) __builtin_trap();  // NaN or an sd
  } catch (const jpcr::InputError&) {
  }
  try {
    if (jpcr::decode_rgb8_image(image, limits).size() != pixels) __builtin_trap();
  } catch (const jpcr::InputError&) {
  }
  try {
    const jpcr::CameraIntrinsics camera = jpcr::decode_camera_info(info, limits);
    if (!(camera.fx > 0.0) || !(camera.fy > 0.0)) __builtin_trap();
    const jpcr::Frame f = jpcr::decode_depth_frame(image, jpcr::RosStamp{1, 2}, camera, limits);
    if (f.depth.width() != camera.width || f.depth.height() != camera.height) __builtin_trap();
  } catch (const jpcr::InputError&) {
  }
  return 0;
}
