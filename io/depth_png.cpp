#include "jpcr/io/depth_png.hpp"

#include <cmath>
#include <filesystem>
#include <vector>

#include <opencv2/imgcodecs.hpp>

#include "jpcr/io/atomic_file.hpp"
#include "jpcr/quadric/error.hpp"

namespace jpcr {

namespace {

std::string describe(const cv::Mat& m) {
  const int depth = m.depth();
  const char* bits = depth == CV_8U    ? "8-bit"
                     : depth == CV_16U ? "16-bit"
                     : depth == CV_32F ? "float"
                                       : "other";
  return std::string(bits) + " with " + std::to_string(m.channels()) + " channel(s)";
}

// What the PNG header says the image is (bit depth and colour type, IHDR bytes 24 and 25): more
// exact than the decoded channel count, where OpenCV turns grey + alpha into four channels.
std::string describe_png_header(const std::string& bytes, const cv::Mat& decoded) {
  if (bytes.size() < 26 || bytes.compare(1, 3, "PNG") != 0) return describe(decoded);
  const int bit_depth = static_cast<unsigned char>(bytes[24]);
  const int colour = static_cast<unsigned char>(bytes[25]);
  const char* kind = colour == 0   ? "grey"
                     : colour == 2 ? "RGB"
                     : colour == 3 ? "palette"
                     : colour == 4 ? "grey + alpha"
                     : colour == 6 ? "RGBA"
                                   : "unknown colour type";
  return std::to_string(bit_depth) + "-bit " + kind;
}

bool starts_with(const std::string& bytes, const char* magic, std::size_t length) {
  return bytes.size() >= length && bytes.compare(0, length, magic, length) == 0;
}

// The width and height a PNG's IHDR chunk declares (big-endian, bytes 16–23); false when the
// bytes do not start as a PNG with its IHDR.
bool png_header_size(const std::string& bytes, long long& width, long long& height) {
  if (!starts_with(bytes, "\x89PNG\r\n\x1a\n", 8) || bytes.size() < 24 ||
      bytes.compare(12, 4, "IHDR") != 0)
    return false;
  const auto be32 = [&](std::size_t at) {
    long long v = 0;
    for (std::size_t k = 0; k < 4; ++k)
      v = v << 8 | static_cast<unsigned char>(bytes[at + k]);
    return v;
  };
  width = be32(16);
  height = be32(20);
  return true;
}

// An image's size against the camera's (expected_width 0: any size).
void check_image_size(const std::string& path, long long width, long long height,
                      int expected_width, int expected_height) {
  if (expected_width > 0 && (width != expected_width || height != expected_height)) {
    throw InputError(path + ": image is " + std::to_string(width) + "x" + std::to_string(height) +
                     " but the camera is " + std::to_string(expected_width) + "x" +
                     std::to_string(expected_height));
  }
}

// Only PNG and JPEG reach OpenCV: cv::imdecode otherwise tries every codec it was built with, and
// some (GDCM's DICOM reader) abort the process on malformed input, which fuzzing found.
cv::Mat decode(const std::string& bytes, const std::string& name, int flags) {
  if (bytes.empty()) throw InputError(name + ": empty file, not an image");
  const bool png = starts_with(bytes, "\x89PNG\r\n\x1a\n", 8);
  const bool jpeg = starts_with(bytes, "\xff\xd8\xff", 3);
  if (!png && !jpeg) throw InputError(name + ": not a PNG or JPEG file");
  const cv::Mat buffer(1, static_cast<int>(bytes.size()), CV_8UC1, const_cast<char*>(bytes.data()));
  cv::Mat image;
  try {
    image = cv::imdecode(buffer, flags);
  } catch (const cv::Exception& e) {
    throw InputError(name + ": cannot be decoded as an image (" + e.msg + ")");
  }
  if (image.empty()) {
    throw InputError(name + ": cannot be decoded as an image (corrupt or not a PNG)");
  }
  return image;
}

void write_encoded(const std::string& path, const cv::Mat& image) {
  std::vector<unsigned char> encoded;
  if (!cv::imencode(".png", image, encoded)) throw InputError(path + ": PNG encoding failed");
  write_file_atomically(path, [&](std::ostream& out) {
    out.write(reinterpret_cast<const char*>(encoded.data()),
              static_cast<std::streamsize>(encoded.size()));
  });
}

}  // namespace

DepthImage load_depth_png(const std::string& path, double depth_scale, int expected_width,
                          int expected_height) {
  return decode_depth_png(read_file(path), path, depth_scale, expected_width, expected_height);
}

DepthImage decode_depth_png(const std::string& bytes, const std::string& path, double depth_scale,
                            int expected_width, int expected_height) {
  const auto check_size = [&](long long width, long long height) {
    check_image_size(path, width, height, expected_width, expected_height);
  };
  // The header's size first: a small file can declare 16384x16384 (600 MB decoded).
  long long width = 0, height = 0;
  if (png_header_size(bytes, width, height)) check_size(width, height);
  const cv::Mat raw = decode(bytes, path, cv::IMREAD_UNCHANGED);
  if (raw.type() != CV_16UC1) {
    throw InputError(path + ": expected a 16-bit single-channel depth PNG, got " +
                     describe_png_header(bytes, raw));
  }
  check_size(raw.cols, raw.rows);
  DepthImage depth(raw.cols, raw.rows, 0.0f);
  const float inv_scale = static_cast<float>(1.0 / depth_scale);
  for (int v = 0; v < raw.rows; ++v) {
    const auto* row = raw.ptr<std::uint16_t>(v);
    for (int u = 0; u < raw.cols; ++u)
      depth(u, v) = static_cast<float>(row[u]) * inv_scale;
  }
  return depth;
}

void save_depth_png(const std::string& path, const DepthImage& depth, double depth_scale) {
  cv::Mat raw(depth.height(), depth.width(), CV_16UC1);
  for (int v = 0; v < depth.height(); ++v) {
    auto* row = raw.ptr<std::uint16_t>(v);
    for (int u = 0; u < depth.width(); ++u) {
      const double value = static_cast<double>(depth(u, v)) * depth_scale;
      row[u] = (std::isfinite(value) && value > 0.0 && value < 65535.5)
                   ? static_cast<std::uint16_t>(std::lround(value))
                   : 0;
    }
  }
  write_encoded(path, raw);
}

ColorImage load_color_image(const std::string& path, int expected_width, int expected_height) {
  std::error_code ec;
  if (!std::filesystem::is_regular_file(path, ec)) throw InputError(path + ": file does not exist");
  const std::string bytes = read_file(path);
  long long width = 0, height = 0;  // the PNG header's size before decoding, as for depth
  if (png_header_size(bytes, width, height))
    check_image_size(path, width, height, expected_width, expected_height);
  const cv::Mat bgr = decode(bytes, path, cv::IMREAD_COLOR);
  check_image_size(path, bgr.cols, bgr.rows, expected_width, expected_height);
  ColorImage image(bgr.cols, bgr.rows);
  for (int v = 0; v < bgr.rows; ++v) {
    const auto* row = bgr.ptr<cv::Vec3b>(v);
    for (int u = 0; u < bgr.cols; ++u)
      image(u, v) = Rgb8{row[u][2], row[u][1], row[u][0]};
  }
  return image;
}

void save_color_png(const std::string& path, const ColorImage& image) {
  cv::Mat bgr(image.height(), image.width(), CV_8UC3);
  for (int v = 0; v < image.height(); ++v) {
    auto* row = bgr.ptr<cv::Vec3b>(v);
    for (int u = 0; u < image.width(); ++u) {
      const Rgb8 c = image(u, v);
      row[u] = cv::Vec3b(c.b, c.g, c.r);
    }
  }
  write_encoded(path, bgr);
}

}  // namespace jpcr
