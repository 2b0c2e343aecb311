// Section `dds:` of the parameter file: where jpcr talks DDS (domain, Cyclone configuration),
// under which topic names, with which QoS, and how large an input image may claim to be. A plain
// struct so that the core profile (no Cyclone DDS) still parses every parameter file.
#pragma once

#include <cstddef>
#include <string>

namespace jpcr {

class YamlSection;

/// The QoS of one topic, in ROS terms (plain values; io/dds/dds_endpoint.hpp applies them).
struct DdsQos {
  DdsQos(bool is_reliable = true, bool is_transient_local = false, int history = 10)
      : reliable(is_reliable), transient_local(is_transient_local), depth(history) {}

  bool reliable;               // RELIABLE (ROS default) or BEST_EFFORT (ROS sensor data)
  bool transient_local;        // TRANSIENT_LOCAL: late joiners get the last `depth` samples
  int depth;                   // samples, KEEP_LAST history
  bool keep_all = false;       // KEEP_ALL history instead (depth unused): nothing is overwritten
  int max_samples = 0;         // a KEEP_ALL reader's resource limit, samples (0: unlimited)
  int max_blocking_ms = 1000;  // a reliable writer's wait for room before a write times out
  std::string user_data;       // USER_DATA: what the endpoint is, for matched peers to tell
};

struct DdsConfig {
  int domain_id = 0;        // DDS domain (ROS_DOMAIN_ID), 0..232
  std::string cyclone_uri;  // Cyclone config: "file://PATH" or XML; empty: $CYCLONEDDS_URI
  std::string topic_prefix = "rt/jpcr/";  // published topics are PREFIX + odom, path, ...
  std::string depth_topic = "rt/camera/depth/image_raw";          // input sensor_msgs/Image
  std::string camera_info_topic = "rt/camera/depth/camera_info";  // input sensor_msgs/CameraInfo
  std::string world_frame_id = "map";                             // header.frame_id of poses
  std::string camera_frame_id = "camera_depth_optical_frame";     // odom child, image frames
  int history_depth = 10;       // samples, KEEP_LAST depth of the pose topics and camera_info,
                                // and of path when its paths are incremental (keep_history: false)
  int image_history_depth = 2;  // samples, KEEP_LAST depth of image topics (MB each)
  int keyframe_queue = 32;      // keyframes a split back end holds unread (MB each)
  // Publish each keyframe's curvature sd map (topic curvature_sd, 32FC1; computed per keyframe,
  // about one Quad IT fit's time: quadric/curvature_spread.hpp).
  bool curvature_sd = true;
  bool input_reliable = true;  // depth input QoS: reliable (ROS default) or best effort
  // Depth input history KEEP_ALL (input_history: keep_all), lossless: the reader holds at most
  // image_history_depth images and takes the next only when the caller asks for a frame, so a
  // reliable KEEP_ALL camera (jpcr_dds_play with the same setting) waits for a slow node instead
  // of frames being dropped. A KEEP_LAST publisher is not held back: its frames still drop.
  bool input_keep_all = false;
  // MiB, larger claimed images are rejected unread. Cyclone reassembles a sample before jpcr
  // sees it: its MaxSampleSize bounds that memory (65 MiB in configs/cyclonedds_loopback.xml;
  // Cyclone's default is about 2 GiB, so a network configuration should set it too).
  double max_image_megabytes = 64.0;
  int max_image_side = 16384;  // pixels, larger claimed width or height is rejected

  /// Throws InputError "field: problem" on a value out of range.
  void validate() const;

  /// max_image_megabytes in bytes.
  std::size_t max_image_bytes() const;

  /// QoS of the depth input (input_reliable, volatile, input_keep_all) and its camera_info
  /// (input_reliable, volatile, KEEP_LAST history_depth).
  DdsQos depth_qos() const;
  DdsQos camera_info_qos() const { return DdsQos{input_reliable, false, history_depth}; }
};

/// Throws InputError "FIELD: ..." unless `name` is a DDS topic name as ROS 2 maps one ("rt/" +
/// the ROS name without its leading slash: letters, digits, '_' and '/', no leading digit, no
/// "//"); a ROS name such as /camera/depth is named as such.
void check_topic_name(const std::string& field, const std::string& name);

/// Reads a `dds:` section onto `config` (absent keys keep their value) and validates it.
void read_dds_config(YamlSection yaml, DdsConfig& config);

}  // namespace jpcr
