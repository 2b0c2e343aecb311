// Camera YAML: top-level keys fx, fy, cx, cy, width, height, depth_scale and optional
// distortion: [k1, k2, p1, p2, k3] (see configs/*.yaml).
#pragma once

#include <string>

#include "jpcr/quadric/camera.hpp"

namespace jpcr {

/// Throws InputError naming the file and key on a missing key, wrong type, unknown key or an
/// invalid value.
CameraIntrinsics load_camera_yaml(const std::string& path);

/// The same from YAML text; `name` stands for the file in messages.
CameraIntrinsics parse_camera_yaml(const std::string& text, const std::string& name);

/// The YAML text of a camera, loadable by load_camera_yaml.
std::string format_camera_yaml(const CameraIntrinsics& camera);

}  // namespace jpcr
