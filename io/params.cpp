#include "jpcr/io/params.hpp"

#include "jpcr/io/atomic_file.hpp"
#include "jpcr/io/yaml_reader.hpp"
#include "jpcr/quadric/error.hpp"

namespace jpcr {

namespace {

void read_dataset(YamlSection yaml, DatasetParams& p) {
  yaml.read("max_time_difference", p.max_time_difference);
  if (p.max_time_difference <= 0.0) yaml.fail("max_time_difference", "must be positive (s)");
  yaml.finish();
}

// Runs a config struct's validate(), whose InputError reads "field: problem", and reports the
// problem against the file, line and key.
template <typename Config>
void validate_in(const YamlSection& yaml, const Config& config) {
  try {
    config.validate();
  } catch (const InputError& e) {
    const std::string what = e.what();
    const std::size_t colon = what.find(": ");
    if (colon == std::string::npos) throw;
    yaml.fail(what.substr(0, colon), what.substr(colon + 2));
  }
}

void read_trajectory(YamlSection yaml, TrajectoryParams& p) {
  yaml.read("rate", p.rate);
  yaml.read("start_time", p.start_time);
  yaml.read("rail_step", p.rail_step);
  yaml.read("orbit_step", p.orbit_step);
  yaml.read("walk_max_speed", p.walk_max_speed);
  yaml.read("walk_max_head_rate", p.walk_max_head_rate);
  yaml.read("walk_min_period", p.walk_min_period);
  yaml.read("walk_max_period", p.walk_max_period);
  yaml.finish();
  validate_in(yaml, p);
}

void read_kinect(YamlSection yaml, KinectNoiseParams& p) {
  yaml.read("sigma_constant", p.sigma_constant);
  yaml.read("sigma_quadratic", p.sigma_quadratic);
  yaml.read("sigma_offset", p.sigma_offset);
  yaml.read("baseline", p.baseline);
  yaml.read("disparity_focal", p.disparity_focal);
  yaml.read("disparity_step", p.disparity_step);
  yaml.read("min_depth", p.min_depth);
  yaml.read("max_depth", p.max_depth);
  yaml.read("grazing_start", p.grazing_start);
  yaml.read("grazing_full", p.grazing_full);
  yaml.read("edge_jump", p.edge_jump);
  yaml.read("edge_dropout", p.edge_dropout);
  yaml.finish();
  validate_in(yaml, p);
}

void read_synthetic(YamlSection yaml, SyntheticParams& p) {
  read_trajectory(yaml.section("trajectory"), p.trajectory);
  read_kinect(yaml.section("kinect"), p.kinect);
  yaml.finish();
}

// Section `frontend:` (frontend/frontend_params.hpp).
void read_preprocess(YamlSection yaml, PreprocessParams& p) {
  yaml.read("min_depth", p.min_depth);
  yaml.read("max_depth", p.max_depth);
  yaml.read("bilateral", p.bilateral);
  yaml.read("bilateral_radius", p.bilateral_radius);
  yaml.read("bilateral_sigma_space", p.bilateral_sigma_space);
  yaml.read("bilateral_sigma_depth", p.bilateral_sigma_depth);
  yaml.read("pyramid_max_depth_step", p.pyramid_max_depth_step);
  yaml.read("normal_offset", p.normal_offset);
  yaml.read("normal_max_jump", p.normal_max_jump);
  yaml.read("full_resolution_normals", p.full_resolution_normals);
  yaml.finish();
  validate_in(yaml, p);
}

void read_icp(YamlSection yaml, IcpParams& p) {
  std::vector<double> levels;  // absent: keeps the defaults
  yaml.read("iterations", levels);
  if (yaml.has("iterations")) {
    if (levels.size() != p.iterations.size())
      yaml.fail("iterations", "expected 3 counts, finest level first");
    for (std::size_t i = 0; i < levels.size(); ++i) {
      if (levels[i] != static_cast<int>(levels[i])) yaml.fail("iterations", "expected integers");
      p.iterations[i] = static_cast<int>(levels[i]);
    }
  }
  yaml.read("level0_stride", p.level0_stride);
  yaml.read("max_distance", p.max_distance);
  yaml.read("max_normal_angle", p.max_normal_angle);
  std::string loss = to_string(p.robust_loss);
  yaml.read_choice("robust_loss", loss, {"none", "huber", "tukey"});
  p.robust_loss = parse_robust_loss(loss);
  yaml.read("robust_scale", p.robust_scale);
  yaml.read("depth_weight_exponent", p.depth_weight_exponent);
  yaml.read("min_step_translation", p.min_step_translation);
  yaml.read("min_step_rotation", p.min_step_rotation);
  yaml.read("damping", p.damping);
  yaml.read("min_inliers", p.min_inliers);
  yaml.read("min_inlier_ratio", p.min_inlier_ratio);
  yaml.read("degeneracy_threshold", p.degeneracy_threshold);
  yaml.read("max_translation", p.max_translation);
  yaml.read("max_rotation", p.max_rotation);
  yaml.finish();
  validate_in(yaml, p);
}

void read_tracker(YamlSection yaml, TrackerParams& p) {
  std::string mode = to_string(p.mode), prior = to_string(p.motion_prior);
  yaml.read_choice("mode", mode, {"frame_to_frame", "frame_to_keyframe"});
  yaml.read_choice("motion_prior", prior, {"identity", "constant_velocity"});
  p.mode = parse_tracking_mode(mode);
  p.motion_prior = parse_motion_prior(prior);
  yaml.read("keyframe_translation", p.keyframe_translation);
  yaml.read("keyframe_rotation", p.keyframe_rotation);
  yaml.read("keyframe_overlap", p.keyframe_overlap);
  yaml.read("accept_degenerate", p.accept_degenerate);
  yaml.finish();
  validate_in(yaml, p);
}

void read_frontend(YamlSection yaml, FrontendParams& p) {
  yaml.read("threads", p.threads);
  if (p.threads < 0 || p.threads > 256) yaml.fail("threads", "must be in 0..256 (0: one per core)");
  read_preprocess(yaml.section("preprocess"), p.preprocess);
  read_icp(yaml.section("icp"), p.icp);
  read_tracker(yaml.section("tracker"), p.tracker);
  yaml.finish();
  validate_in(yaml.section("preprocess"), p);  // across sections: min_depth and the z^-k weights
}

void read_quadric(YamlSection yaml, QuadricParams& p) {
  YamlSection pattern = yaml.section("pattern");
  pattern.read("radius", p.pattern.radius);
  pattern.read("stride", p.pattern.stride);
  pattern.read("reference_width", p.pattern.reference_width);
  pattern.finish();
  validate_in(pattern, p.pattern);
  YamlSection normals = yaml.section("normals");
  normals.read("half_window", p.normals.half_window);
  normals.read("min_points", p.normals.min_points);
  normals.read("max_depth_jump", p.normals.max_depth_jump);
  normals.read("quadrant_ratio", p.normals.quadrant_ratio);
  normals.finish();
  validate_in(normals, p.normals);
  YamlSection fit = yaml.section("fit");
  fit.read("iterations", p.fit.iterations);
  fit.read("fair_n0", p.fit.fair_n0);
  fit.read("residual_gate", p.fit.residual_gate);
  fit.read("fair_n0_per_range", p.fit.fair_n0_per_range);
  fit.read("gate_per_range", p.fit.gate_per_range);
  fit.read("damping", p.fit.damping);
  fit.read("min_samples", p.fit.min_samples);
  fit.read("angle_tolerance", p.fit.angle_tolerance);
  fit.read("offset_tolerance", p.fit.offset_tolerance);
  fit.read("curvature_tolerance", p.fit.curvature_tolerance);
  fit.finish();
  validate_in(fit, p.fit);
  validate_in(fit, p);  // min_samples against the pattern's size
  yaml.finish();
}

// Section `joint:` (backend/joint_params.hpp).
void read_joint(YamlSection yaml, JointParams& p) {
  yaml.read("max_iterations", p.max_iterations);
  yaml.read("translation_tolerance", p.translation_tolerance);
  yaml.read("rotation_tolerance", p.rotation_tolerance);
  yaml.read("occlusion_threshold", p.occlusion_threshold);
  yaml.read("occlusion_fraction", p.occlusion_fraction);
  yaml.read("min_frame_terms", p.min_frame_terms);
  yaml.read("min_pivot_ratio", p.min_pivot_ratio);
  yaml.read("ray_min_cosine", p.ray_min_cosine);
  yaml.read("edge_tilt", p.edge_tilt);
  yaml.read("keep_lower_cost_fit", p.keep_lower_cost_fit);
  yaml.read("initial_damping", p.initial_damping);
  yaml.read("damping_factor", p.damping_factor);
  yaml.read("damping_decrease", p.damping_decrease);
  yaml.read("max_damping", p.max_damping);
  yaml.read("min_active_quadrics", p.min_active_quadrics);
  yaml.read("degeneracy_threshold", p.degeneracy_threshold);
  yaml.read("block_memory_mb", p.block_memory_mb);
  yaml.finish();
  validate_in(yaml, p);
}

// Section `icp_bundle:` (backend/icp_bundle_params.hpp).
void read_icp_bundle(YamlSection yaml, IcpBundleParams& p) {
  yaml.read("grid_stride", p.grid_stride);
  yaml.read("normal_offset", p.normal_offset);
  yaml.read("normal_max_jump", p.normal_max_jump);
  yaml.read("min_overlap", p.min_overlap);
  yaml.read("max_distance", p.max_distance);
  yaml.read("max_normal_angle", p.max_normal_angle);
  yaml.read("min_pair_terms", p.min_pair_terms);
  std::string loss = to_string(p.robust_loss);
  yaml.read_choice("robust_loss", loss, {"huber", "cauchy"});
  p.robust_loss = parse_bundle_loss(loss);
  yaml.read("robust_scale", p.robust_scale);
  yaml.read("outer_iterations", p.outer_iterations);
  yaml.read("solver_iterations", p.solver_iterations);
  yaml.read("translation_tolerance", p.translation_tolerance);
  yaml.read("rotation_tolerance", p.rotation_tolerance);
  yaml.read("degeneracy_threshold", p.degeneracy_threshold);
  yaml.read("threads", p.threads);
  yaml.finish();
  validate_in(yaml, p);
}

// Section `pipeline:` (backend/keyframe_pipeline.hpp).
void read_pipeline(YamlSection yaml, PipelineParams& p) {
  std::string method = to_string(p.method);
  yaml.read_choice("method", method,
                   {"icp-ftf", "j-ftf", "j-full", "q-full", "icp-bundle", "pipeline"});
  p.method = parse_pipeline_method(method);
  yaml.read("window", p.window);
  if (p.window < 2 || p.window > kMaxWindowFrames)
    yaml.fail("window", "must be in [2, " + std::to_string(kMaxWindowFrames) + "] keyframes");
  yaml.read("keep_history", p.keep_history);
  yaml.read("interpolate_corrections", p.interpolate_corrections);
  yaml.read("filtered_depth", p.filtered_depth);
  yaml.finish();
}

}  // namespace

Params load_params(const std::string& path) {
  return parse_params(read_file(path), path);
}

Params parse_params(const std::string& text, const std::string& path) {
  YamlSection yaml(parse_yaml(text, path), path);
  Params params;
  std::string device = to_string(params.device);
  yaml.read_choice("device", device, {"auto", "cpu", "cuda"});
  params.device = parse_compute_device(device);
  read_dataset(yaml.section("dataset"), params.dataset);
  read_synthetic(yaml.section("synthetic"), params.synthetic);
  read_frontend(yaml.section("frontend"), params.frontend);
  read_quadric(yaml.section("quadric"), params.quadric);
  read_dds_config(yaml.section("dds"), params.dds);
  read_joint(yaml.section("joint"), params.joint);
  read_icp_bundle(yaml.section("icp_bundle"), params.icp_bundle);
  read_pipeline(yaml.section("pipeline"), params.pipeline);
  yaml.finish();
  params.joint.quadric = params.quadric;
  params.pipeline.frontend = params.frontend;
  params.pipeline.joint = params.joint;
  params.pipeline.icp_bundle = params.icp_bundle;
  return params;
}

}  // namespace jpcr
