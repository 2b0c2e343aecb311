#include "jpcr/io/depth_undistortion.hpp"

#include <cmath>

#include <opencv2/calib3d.hpp>
#include <opencv2/imgproc.hpp>

#include "jpcr/quadric/error.hpp"

namespace jpcr {

namespace {

cv::Matx33d camera_matrix(const CameraIntrinsics& c) {
  return cv::Matx33d(c.fx, 0, c.cx, 0, c.fy, c.cy, 0, 0, 1);
}

cv::Mat coefficients(const CameraIntrinsics& c) {
  return cv::Mat(static_cast<int>(c.distortion.size()), 1, CV_64F,
                 const_cast<double*>(c.distortion.data()));
}

}  // namespace

DepthUndistortion::DepthUndistortion(const CameraIntrinsics& camera, const std::string& source) {
  cv::initUndistortRectifyMap(camera_matrix(camera), coefficients(camera), cv::Mat(),
                              camera_matrix(camera), cv::Size(camera.width, camera.height),
                              CV_32FC1, map_x_, map_y_);
  std::size_t inside = 0;
  for (int v = 0; v < camera.height; ++v)
    for (int u = 0; u < camera.width; ++u) {
      const float x = map_x_.at<float>(v, u), y = map_y_.at<float>(v, u);
      inside +=
          (x >= 0.0f && x <= camera.width - 1.0f && y >= 0.0f && y <= camera.height - 1.0f) ? 1 : 0;
    }
  const double fraction =
      static_cast<double>(inside) / (static_cast<double>(camera.width) * camera.height);
  if (fraction < 0.5)
    throw InputError(source + ": the camera's distortion coefficients take " +
                     std::to_string(static_cast<int>(std::lround(100.0 * (1.0 - fraction)))) +
                     " % of the pixels from outside the image (check them: OpenCV's order k1 "
                     "k2 p1 p2 k3, for the depth camera)");
}

void DepthUndistortion::apply(DepthImage& depth) const {
  cv::Mat raw(depth.height(), depth.width(), CV_32FC1, depth.data());
  cv::Mat rectified;
  cv::remap(raw, rectified, map_x_, map_y_, cv::INTER_NEAREST, cv::BORDER_CONSTANT, cv::Scalar(0));
  rectified.copyTo(raw);
}

std::vector<float> DepthUndistortion::ray_lengths(const CameraIntrinsics& camera) {
  std::vector<cv::Point2f> pixels;
  pixels.reserve(static_cast<std::size_t>(camera.width) * static_cast<std::size_t>(camera.height));
  for (int v = 0; v < camera.height; ++v)
    for (int u = 0; u < camera.width; ++u)
      pixels.emplace_back(static_cast<float>(u), static_cast<float>(v));
  std::vector<cv::Point2f> normalised;  // no P: normalised image coordinates
  cv::undistortPoints(pixels, normalised, camera_matrix(camera), coefficients(camera));
  std::vector<float> lengths(normalised.size());
  for (std::size_t i = 0; i < normalised.size(); ++i)
    lengths[i] =
        std::sqrt(1.0f + normalised[i].x * normalised[i].x + normalised[i].y * normalised[i].y);
  return lengths;
}

}  // namespace jpcr
