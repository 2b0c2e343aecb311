#include "jpcr/quadric/camera.hpp"

#include <cmath>
#include <sstream>
#include <stdexcept>
#include <string>

namespace jpcr {

bool CameraIntrinsics::has_distortion() const {
  for (double k : distortion) {
    if (k != 0.0) return true;
  }
  return false;
}

void CameraIntrinsics::validate() const {
  auto require = [](bool ok, const char* field, const std::string& why) {
    if (!ok) throw std::invalid_argument(std::string(field) + ": " + why);
  };
  require(width > 0 && width <= 16384, "width", "must be in 1..16384");
  require(height > 0 && height <= 16384, "height", "must be in 1..16384");
  // A pinhole's field of view 2 atan(side / 2f) between 0.1° and 175°: f in about
  // [0.044, 573] times the image side. Outside it the values are a unit or typing error, and
  // every vertex would be degenerate.
  const auto field_of_view_ok = [](double f, int side) {
    if (!(std::isfinite(f) && f > 0.0)) return false;
    const double fov_deg = 2.0 * std::atan(side / (2.0 * f)) * 180.0 / 3.14159265358979323846;
    return fov_deg >= 0.1 && fov_deg <= 175.0;
  };
  require(field_of_view_ok(fx, width), "fx",
          "must be a positive number of pixels giving a horizontal field of view of 0.1° to 175°");
  require(field_of_view_ok(fy, height), "fy",
          "must be a positive number of pixels giving a vertical field of view of 0.1° to 175°");
  // The optical axis meets the image plane within one image side of the image.
  require(std::isfinite(cx) && cx >= -width && cx <= 2.0 * width, "cx",
          "must lie in [-width, 2 width] pixels");
  require(std::isfinite(cy) && cy >= -height && cy <= 2.0 * height, "cy",
          "must lie in [-height, 2 height] pixels");
  require(std::isfinite(depth_scale) && depth_scale >= 1e-3 && depth_scale <= 1e7, "depth_scale",
          "must be 1e-3 to 1e7 raw units per metre");
  for (double k : distortion)
    require(std::isfinite(k), "distortion", "must be finite");
}

CameraIntrinsics CameraIntrinsics::pyramid_level(int level) const {
  CameraIntrinsics c = *this;
  for (int i = 0; i < level; ++i) {
    // Pixel centres: u_coarse = (u_fine + 0.5) / 2 − 0.5.
    c.fx *= 0.5;
    c.fy *= 0.5;
    c.cx = (c.cx + 0.5) * 0.5 - 0.5;
    c.cy = (c.cy + 0.5) * 0.5 - 0.5;
    c.width /= 2;
    c.height /= 2;
  }
  return c;
}

CameraIntrinsics CameraIntrinsics::resized(int new_width, int new_height) const {
  CameraIntrinsics c = *this;
  const double sx = static_cast<double>(new_width) / width;
  const double sy = static_cast<double>(new_height) / height;
  c.fx *= sx;
  c.fy *= sy;
  c.cx = (cx + 0.5) * sx - 0.5;
  c.cy = (cy + 0.5) * sy - 0.5;
  c.width = new_width;
  c.height = new_height;
  return c;
}

bool same_pinhole(const CameraIntrinsics& a, const CameraIntrinsics& b) {
  return a.fx == b.fx && a.fy == b.fy && a.cx == b.cx && a.cy == b.cy && a.width == b.width &&
         a.height == b.height;
}

std::string describe(const CameraIntrinsics& camera) {
  std::ostringstream s;
  s << camera.width << 'x' << camera.height << ", fx " << camera.fx << ", fy " << camera.fy
    << ", cx " << camera.cx << ", cy " << camera.cy;
  return s.str();
}

}  // namespace jpcr
