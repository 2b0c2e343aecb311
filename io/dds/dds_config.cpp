#include "jpcr/io/dds/dds_config.hpp"

#include <cmath>
#include <string>
#include <utility>

#include "jpcr/io/yaml_reader.hpp"
#include "jpcr/quadric/error.hpp"

namespace jpcr {

// A DDS topic name as ROS 2 maps one: "rt/" + the ROS name without its leading slash, made of
// letters, digits, '_' and '/' (what Cyclone accepts: it refuses '.', '-' or a leading digit with
// "Bad Parameter"). A ROS name such as /camera/depth would match nothing, silently.
void check_topic_name(const std::string& field, const std::string& name) {
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

void DdsConfig::validate() const {
  if (domain_id < 0 || domain_id > 232) throw InputError("domain_id: must be in 0..232");
  check_topic_name("topic_prefix", topic_prefix);
  check_topic_name("depth_topic", depth_topic);
  check_topic_name("camera_info_topic", camera_info_topic);
  if (depth_topic.back() == '/' || camera_info_topic.back() == '/')
    throw InputError(std::string(depth_topic.back() == '/' ? "depth_topic" : "camera_info_topic") +
                     ": must not end with '/'");
  // ROS 2 sees the DDS topic rt/x as its topic /x: any other name matches no ROS node, silently.
  for (const auto& [field, name] :
       {std::pair<const char*, const std::string&>{"topic_prefix", topic_prefix},
        {"depth_topic", depth_topic},
        {"camera_info_topic", camera_info_topic}})
    if (name.rfind("rt/", 0) != 0)
      throw InputError(std::string(field) + ": '" + name +
                       "' does not start with 'rt/', so no ROS 2 node sees it (ROS's /x is rt/x)");
  if (topic_prefix.back() != '/')
    throw InputError("topic_prefix: '" + topic_prefix + "' must end with '/' (the topics are " +
                     topic_prefix + "odom, ...)");
  if (depth_topic == camera_info_topic)
    throw InputError("depth_topic: '" + depth_topic + "' is also camera_info_topic");
  for (const char* output :
       {"odom", "keyframe_pose", "path", "curvature", "curvature_color", "keyframe"})
    for (const auto& [field, name] :
         {std::pair<const char*, const std::string&>{"depth_topic", depth_topic},
          {"camera_info_topic", camera_info_topic}})
      if (name == topic_prefix + output)
        throw InputError(std::string(field) + ": '" + name + "' is one of jpcr's own topics");
  for (const auto& [field, id] :
       {std::pair<const char*, const std::string&>{"world_frame_id", world_frame_id},
        {"camera_frame_id", camera_frame_id}})
    if (id.empty() || id.front() == '/')
      throw InputError(std::string(field) + ": '" + id +
                       "' must be a tf2 frame id: not empty, without a leading '/'");
  if (history_depth < 1 || history_depth > 100000)
    throw InputError("history_depth: must be in 1..100000");
  // Each kept image may be max_image_megabytes large.
  if (image_history_depth < 1 || image_history_depth > 1000)
    throw InputError("image_history_depth: must be in 1..1000");
  if (input_keep_all && !input_reliable)
    throw InputError(
        "input_history: keep_all needs input_reliability: reliable (a best-effort camera cannot "
        "be made to wait)");
  if (keyframe_queue < 1 || keyframe_queue > 1000)
    throw InputError("keyframe_queue: must be in 1..1000");
  if (!(max_image_megabytes > 0.0) || max_image_megabytes > 4096.0 || max_image_bytes() < 1024) {
    throw InputError("max_image_megabytes: must be in [1/1024, 4096] MiB");
  }
  if (max_image_side < 1 || max_image_side > 16384)
    throw InputError("max_image_side: must be in 1..16384 (a camera's largest side)");
}

DdsQos DdsConfig::depth_qos() const {
  DdsQos qos{input_reliable, false, image_history_depth};
  if (input_keep_all) {  // the resource limit is what makes a reliable KEEP_ALL writer wait
    qos.keep_all = true;
    qos.max_samples = image_history_depth;
  }
  return qos;
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
  yaml.read("curvature_sd", config.curvature_sd);
  std::string reliability = config.input_reliable ? "reliable" : "best_effort";
  yaml.read_choice("input_reliability", reliability, {"reliable", "best_effort"});
  config.input_reliable = reliability == "reliable";
  std::string history = config.input_keep_all ? "keep_all" : "keep_last";
  yaml.read_choice("input_history", history, {"keep_last", "keep_all"});
  config.input_keep_all = history == "keep_all";
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
