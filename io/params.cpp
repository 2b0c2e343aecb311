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
  read_quadric(yaml.section("quadric"), params.quadric);
  read_dds_config(yaml.section("dds"), params.dds);
  yaml.finish();
  return params;
}

}  // namespace jpcr
