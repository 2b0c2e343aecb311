#include "jpcr/io/dds/dds_config.hpp"

#include <cmath>

#include "jpcr/io/yaml_reader.hpp"
#include "jpcr/quadric/error.hpp"

namespace jpcr {

namespace {

// A DDS topic name as ROS 2 maps one: "rt/" + the ROS name without its leading slash, made of
// letters, digits, '_' and '/' (what Cyclone accepts: it refuses '.', '-' or a leading digit with
// "Bad Parameter"). A ROS name such as /camera/depth would match nothing, silently.
void check_topic(const std::string& field, const std::string& name) {
  if (name.empty()) throw InputError(field + ": must not be empty");
  if (name.front() == '/') {
    throw InputError(field + ": '" + name + "' is a ROS name; its DDS topic is 'rt" + name + "'");
  }
  for (const char c : name) {
    const bool allowed = (c >= 'a' && c <= 'z') || (c >= 'A' && c <= 'Z') ||
                         (c >= '0' && c <= '9') || c == '_' || c == '/';
    if (!allowed) {
      throw InputError(field + ": '" + name +
                       "' holds a character other than letters, digits, '_' and '/'");
    }
  }
  if (name.front() >= '0' && name.front() <= '9')
    throw InputError(field + ": '" + name + "' starts with a digit");
  if (name.find("//") != std::string::npos) throw InputError(field + ": '" + name + "' holds '//'");
}

}  // namespace

void DdsConfig::validate() const {
  if (domain_id < 0 || domain_id > 232) throw InputError("domain_id: must be in 0..232");
  check_topic("topic_prefix", topic_prefix);
  check_topic("depth_topic", depth_topic);
  check_topic("camera_info_topic", camera_info_topic);
  if (depth_topic.back() == '/' || camera_info_topic.back() == '/')
    throw InputError(std::string(depth_topic.back() == '/' ? "depth_topic" : "camera_info_topic") +
                     ": must not end with '/'");
  if (history_depth < 1) throw InputError("history_depth: must be at least 1");
  if (image_history_depth < 1) throw InputError("image_history_depth: must be at least 1");
  if (keyframe_queue < 1) throw InputError("keyframe_queue: must be at least 1");
  if (!(max_image_megabytes > 0.0) || max_image_megabytes > 4096.0) {
    throw InputError("max_image_megabytes: must be in (0, 4096] MiB");
  }
  if (max_image_side < 1) throw InputError("max_image_side: must be at least 1");
}

std::size_t DdsConfig::max_image_bytes() const {
  return static_cast<std::size_t>(std::llround(max_image_megabytes * 1024.0 * 1024.0));
}

void read_dds_config(YamlSection yaml, DdsConfig& config) {
  yaml.read("domain_id", config.domain_id);
  yaml.read("cyclone_uri", config.cyclone_uri);
  yaml.read("topic_prefix", config.topic_prefix);
  yaml.read("depth_topic", config.depth_topic);
  yaml.read("camera_info_topic", config.camera_info_topic);
  yaml.read("world_frame_id", config.world_frame_id);
  yaml.read("camera_frame_id", config.camera_frame_id);
  yaml.read("history_depth", config.history_depth);
  yaml.read("image_history_depth", config.image_history_depth);
  yaml.read("keyframe_queue", config.keyframe_queue);
  std::string reliability = config.input_reliable ? "reliable" : "best_effort";
  yaml.read_choice("input_reliability", reliability, {"reliable", "best_effort"});
  config.input_reliable = reliability == "reliable";
  yaml.read("max_image_megabytes", config.max_image_megabytes);
  yaml.read("max_image_side", config.max_image_side);
  yaml.finish();
  try {
    config.validate();
  } catch (const InputError& e) {
    const std::string what = e.what();
    const std::size_t colon = what.find(": ");
    yaml.fail(what.substr(0, colon), what.substr(colon + 2));
  }
}

}  // namespace jpcr
