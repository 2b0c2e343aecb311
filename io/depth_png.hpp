// 16-bit depth PNGs (TUM: value / depth_scale = metres, 0 = no measurement) and colour PNGs.
#pragma once

#include <string>

#include "jpcr/quadric/image.hpp"

namespace jpcr {

/// Loads a single-channel 16-bit PNG as metres. Throws InputError naming the file when it is
/// missing, cannot be decoded, is not 16-bit single-channel, or (when expected_width > 0) has
/// another size than the camera.
DepthImage load_depth_png(const std::string& path, double depth_scale, int expected_width = 0,
                          int expected_height = 0);

/// The same from the bytes of a PNG file; `path` stands for the file in messages.
DepthImage decode_depth_png(const std::string& bytes, const std::string& path, double depth_scale,
                            int expected_width = 0, int expected_height = 0);

/// Writes metres as a 16-bit PNG at depth_scale, atomically. Non-finite, non-positive or
/// out-of-range depths are written as 0 (no measurement).
void save_depth_png(const std::string& path, const DepthImage& depth, double depth_scale);

/// Loads an 8-bit colour PNG/JPEG as RGB; throws InputError naming the file on failure, and on a
/// size other than expected_width x expected_height when those are given (> 0): for a PNG from
/// its header before decoding, for a JPEG after.
ColorImage load_color_image(const std::string& path, int expected_width = 0,
                            int expected_height = 0);

/// Writes RGB as PNG, atomically.
void save_color_png(const std::string& path, const ColorImage& image);

}  // namespace jpcr
