#include "jpcr_dds_echo/message_summary.hpp"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <vector>

#include "jpcr/io/dds/ros_image.hpp"
#include "jpcr/quadric/error.hpp"

namespace jpcr {

namespace {

std::string text(const char* s) {
  return s ? s : "";
}

template <typename... Values>
std::string format(const char* fmt, Values... values) {
  char buffer[160];
  std::snprintf(buffer, sizeof buffer, fmt, values...);
  return buffer;
}

std::string header(const char* kind, const std_msgs_msg_dds__Header_& h) {
  return format("%s stamp=", kind) + format_ros_stamp(h.stamp.sec, h.stamp.nanosec) +
         " frame=" + text(h.frame_id);
}

std::string pose(const geometry_msgs_msg_dds__Pose_& p) {
  const auto& q = p.orientation;
  return format(" position=[%.4f %.4f %.4f] orientation=[%.4f %.4f %.4f %.4f]", p.position.x,
                p.position.y, p.position.z, q.x, q.y, q.z, q.w);
}

std::string covariance_diagonal(const double* c) {
  return format(" cov_diag=[%.3g %.3g %.3g %.3g %.3g %.3g]", c[0], c[7], c[14], c[21], c[28],
                c[35]);
}

// Valid-pixel statistics of a decodable image, or why it does not decode.
std::string image_content(const RosImageView& v) {
  try {
    if (v.encoding == "16UC1" || v.encoding == "32FC1") {
      const DepthImage d = decode_depth_image(v, {});
      std::size_t valid = 0;
      float lo = INFINITY, hi = 0.0f;
      for (const float z : d) {
        if (z <= 0.0f) continue;
        ++valid;
        lo = std::min(lo, z);
        hi = std::max(hi, z);
      }
      return format(" valid=%.1f%% depth=[%.3f, %.3f] m", 100.0 * valid / d.size(),
                    valid ? lo : 0.0f, hi);
    }
    if (v.encoding == "32FC2") {
      const Image<Eigen::Vector2f> k = decode_curvature_image(v, {});
      std::size_t valid = 0;
      for (const Eigen::Vector2f& x : k)
        valid += x.allFinite() ? 1 : 0;
      return format(" valid=%.1f%%", 100.0 * valid / k.size());
    }
    if (v.encoding == "rgb8") {
      decode_rgb8_image(v, {});
      return " ok";
    }
    return "";
  } catch (const InputError& e) {
    return std::string(" invalid: ") + e.what();
  }
}

}  // namespace

std::string summarize(const RosOdometry& m) {
  return header("odom", m.header) + " child=" + text(m.child_frame_id) + pose(m.pose.pose) +
         covariance_diagonal(m.pose.covariance);
}

std::string summarize(const RosPoseStamped& m) {
  return header("pose", m.header) + pose(m.pose);
}

std::string summarize(const RosPath& m) {
  std::string s = header("path", m.header) + " poses=" + std::to_string(m.poses._length);
  if (m.poses._length > 0) s += " last" + pose(m.poses._buffer[m.poses._length - 1].pose);
  return s;
}

std::string summarize(const RosImage& m) {
  const RosImageView v = image_view_of(m);
  return header("image", m.header) + " " + std::to_string(m.width) + "x" +
         std::to_string(m.height) + " " + text(m.encoding) + " step=" + std::to_string(m.step) +
         " bytes=" + std::to_string(m.data._length) + image_content(v);
}

std::string summarize_curvature_sd(const RosImage& m) {
  const RosImageView v = image_view_of(m);
  std::string s = header("curvature_sd", m.header) + " " + std::to_string(m.width) + "x" +
                  std::to_string(m.height) + " " + text(m.encoding);
  try {
    const Image<float> sd = decode_curvature_sd_image(v, {});
    std::vector<float> values;
    for (const float x : sd)
      if (!std::isnan(x)) values.push_back(x);
    s += format(" with_sd=%.1f%%", sd.empty() ? 0.0 : 100.0 * values.size() / sd.size());
    if (values.empty()) return s;
    const auto middle = values.begin() + values.size() / 2;
    std::nth_element(values.begin(), middle, values.end());
    return s + format(" median=%.4g max=%.4g 1/m", *middle,
                      *std::max_element(values.begin(), values.end()));
  } catch (const InputError& e) {
    return s + " invalid: " + e.what();
  }
}

// The intrinsics jpcr reads (decode_camera_info): P's, the rectified camera's, or K's when P is
// all zero; " (K)" marks the second.
std::string summarize(const RosCameraInfoMsg& m) {
  const bool has_p = std::any_of(m.p, m.p + 12, [](double v) { return v != 0.0; });
  const std::string intrinsics =
      has_p ? format(" fx=%.3f fy=%.3f cx=%.3f cy=%.3f", m.p[0], m.p[5], m.p[2], m.p[6])
            : format(" fx=%.3f fy=%.3f cx=%.3f cy=%.3f (K)", m.k[0], m.k[4], m.k[2], m.k[5]);
  std::string s = header("camera_info", m.header) + " " + std::to_string(m.width) + "x" +
                  std::to_string(m.height) + intrinsics + " model=" + text(m.distortion_model);
  try {
    decode_camera_info(camera_info_of(m), {});
  } catch (const InputError& e) {
    s += std::string(" invalid: ") + e.what();
  }
  return s;
}

std::string summarize(const RosKeyframe& m) {
  const std::string frames = " frame_index=" + std::to_string(m.frame_index) +
                             " tracked=" + std::to_string(m.tracked._length);
  if (m.end_of_stream) return header("keyframe", m.header) + frames + " end_of_stream";
  return header("keyframe", m.header) + frames + " depth " + std::to_string(m.depth.width) + "x" +
         std::to_string(m.depth.height) + " " + text(m.depth.encoding) + pose(m.pose.pose) +
         covariance_diagonal(m.pose.covariance);
}

}  // namespace jpcr
