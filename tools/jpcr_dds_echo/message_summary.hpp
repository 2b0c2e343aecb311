// One line of text per received ROS 2 message, for jpcr_dds_echo.
#pragma once

#include <string>

#include "jpcr/io/dds/ros_messages.hpp"

namespace jpcr {

std::string summarize(const RosOdometry& m);
std::string summarize(const RosPoseStamped& m);
std::string summarize(const RosPath& m);
/// Includes whether the image decodes (16UC1, 32FC1, 32FC2, rgb8) or why it does not.
std::string summarize(const RosImage& m);
/// A curvature sd map (32FC1, 1/m, NaN where none): the share of pixels with an sd, their
/// median and largest value, or why it is no sd map.
std::string summarize_curvature_sd(const RosImage& m);
std::string summarize(const RosCameraInfoMsg& m);
std::string summarize(const RosKeyframe& m);

}  // namespace jpcr
