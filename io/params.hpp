// Pipeline parameters (--params FILE.yaml, default configs/default.yaml). Each component owns a
// plain config struct with in-class defaults; this file maps the YAML sections onto them.
#pragma once

#include <string>

#include "jpcr/backend/keyframe_pipeline.hpp"
#include "jpcr/cuda/device_selection.hpp"
#include "jpcr/frontend/frontend_params.hpp"
#include "jpcr/io/dds/dds_config.hpp"
#include "jpcr/io/synthetic_noise.hpp"
#include "jpcr/io/synthetic_trajectory.hpp"
#include "jpcr/quadric/quadric_params.hpp"

namespace jpcr {

/// Section `dataset:` of the parameter file.
struct DatasetParams {
  double max_time_difference = 0.02;  // s, association window of depth, colour, ground truth
};

/// Section `synthetic:` (jpcr_synth): trajectory shapes and the Kinect noise model.
struct SyntheticParams {
  TrajectoryParams trajectory;
  KinectNoiseParams kinect;
};

struct Params {
  ComputeDevice device = ComputeDevice::kAuto;  // key `device:` auto | cpu | cuda (issue 7)
  DatasetParams dataset;
  SyntheticParams synthetic;
  FrontendParams frontend;  // section `frontend:` (jpcr_odometry, the tracker)
  QuadricParams quadric;    // section `quadric:` (pattern, normals, Quad IT)
  DdsConfig dds;            // section `dds:` (io/dds/dds_config.hpp)
  JointParams joint;  // section `joint:` (J-ftf, J-full, Q-full); its quadric part is `quadric:`
  IcpBundleParams icp_bundle;  // section `icp_bundle:` (ICP-bundle, method.md §9)
  /// Section `pipeline:`: method and window; its frontend, joint and icp_bundle parts are those
  /// sections.
  PipelineParams pipeline;
};

/// Loads a parameter file; absent keys keep their defaults. Throws InputError naming the file,
/// line and key on an unknown key, a wrong type or a syntax error.
Params load_params(const std::string& path);

/// The same from YAML text; `name` stands for the file in messages.
Params parse_params(const std::string& text, const std::string& name);

}  // namespace jpcr
