#include "jpcr/io/camera_yaml.hpp"

#include <sstream>

#include "jpcr/io/atomic_file.hpp"
#include "jpcr/io/number_format.hpp"
#include "jpcr/io/yaml_reader.hpp"
#include "jpcr/quadric/error.hpp"

namespace jpcr {

CameraIntrinsics load_camera_yaml(const std::string& path) {
  return parse_camera_yaml(read_file(path), path);
}

CameraIntrinsics parse_camera_yaml(const std::string& text, const std::string& path) {
  YamlSection yaml(parse_yaml(text, path), path);
  for (const char* key : {"fx", "fy", "cx", "cy", "width", "height", "depth_scale"}) {
    if (!yaml.has(key))
      yaml.fail(key, "missing (a camera needs fx, fy, cx, cy, width, height, depth_scale)");
  }
  CameraIntrinsics camera;
  yaml.read("fx", camera.fx);
  yaml.read("fy", camera.fy);
  yaml.read("cx", camera.cx);
  yaml.read("cy", camera.cy);
  yaml.read("width", camera.width);
  yaml.read("height", camera.height);
  yaml.read("depth_scale", camera.depth_scale);
  yaml.read("distortion", camera.distortion);
  yaml.finish();
  try {
    camera.validate();
  } catch (const std::invalid_argument& e) {
    throw InputError(path + ": key " + std::string(e.what()));
  }
  return camera;
}

std::string format_camera_yaml(const CameraIntrinsics& camera) {
  std::ostringstream out;
  out << "fx: " << format_double(camera.fx) << "\nfy: " << format_double(camera.fy)
      << "\ncx: " << format_double(camera.cx) << "\ncy: " << format_double(camera.cy)
      << "\nwidth: " << camera.width << "\nheight: " << camera.height
      << "\ndepth_scale: " << format_double(camera.depth_scale) << '\n';
  if (camera.has_distortion()) {
    out << "distortion: [";
    for (std::size_t i = 0; i < camera.distortion.size(); ++i) {
      out << (i ? ", " : "") << format_double(camera.distortion[i]);
    }
    out << "]\n";
  }
  return out.str();
}

}  // namespace jpcr
