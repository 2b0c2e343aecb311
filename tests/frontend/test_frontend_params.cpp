// The `frontend:` section of the parameter file: configs/default.yaml states the built-in
// defaults, and mistakes are errors naming the file, line and key.
#include <gtest/gtest.h>

#include "jpcr/io/params.hpp"
#include "jpcr/quadric/error.hpp"

namespace jpcr {
namespace {

std::string error_of(const std::string& yaml) {
  try {
    parse_params(yaml, "p.yaml");
  } catch (const InputError& e) {
    return e.what();
  }
  return "(no error)";
}

TEST(FrontendParams, DefaultYamlStatesTheBuiltInDefaults) {
  const FrontendParams p =
      load_params(std::string(JPCR_SOURCE_DIR) + "/configs/default.yaml").frontend;
  const FrontendParams d;
  EXPECT_EQ(p.threads, d.threads);
  EXPECT_EQ(p.preprocess.min_depth, d.preprocess.min_depth);
  EXPECT_EQ(p.preprocess.max_depth, d.preprocess.max_depth);
  EXPECT_EQ(p.preprocess.bilateral, d.preprocess.bilateral);
  EXPECT_EQ(p.preprocess.bilateral_radius, d.preprocess.bilateral_radius);
  EXPECT_EQ(p.preprocess.bilateral_sigma_space, d.preprocess.bilateral_sigma_space);
  EXPECT_EQ(p.preprocess.bilateral_sigma_depth, d.preprocess.bilateral_sigma_depth);
  EXPECT_EQ(p.preprocess.pyramid_max_depth_step, d.preprocess.pyramid_max_depth_step);
  EXPECT_EQ(p.preprocess.normal_offset, d.preprocess.normal_offset);
  EXPECT_EQ(p.preprocess.normal_max_jump, d.preprocess.normal_max_jump);
  EXPECT_EQ(p.preprocess.full_resolution_normals, d.preprocess.full_resolution_normals);
  EXPECT_EQ(p.icp.iterations, d.icp.iterations);
  EXPECT_EQ(p.icp.level0_stride, d.icp.level0_stride);
  EXPECT_EQ(p.icp.max_distance, d.icp.max_distance);
  EXPECT_EQ(p.icp.max_normal_angle, d.icp.max_normal_angle);
  EXPECT_EQ(p.icp.robust_loss, d.icp.robust_loss);
  EXPECT_EQ(p.icp.robust_scale, d.icp.robust_scale);
  EXPECT_EQ(p.icp.depth_weight_exponent, d.icp.depth_weight_exponent);
  EXPECT_EQ(p.icp.min_step_translation, d.icp.min_step_translation);
  EXPECT_EQ(p.icp.min_step_rotation, d.icp.min_step_rotation);
  EXPECT_EQ(p.icp.damping, d.icp.damping);
  EXPECT_EQ(p.icp.min_inliers, d.icp.min_inliers);
  EXPECT_EQ(p.icp.min_inlier_ratio, d.icp.min_inlier_ratio);
  EXPECT_EQ(p.icp.degeneracy_threshold, d.icp.degeneracy_threshold);
  EXPECT_EQ(p.icp.max_translation, d.icp.max_translation);
  EXPECT_EQ(p.icp.max_rotation, d.icp.max_rotation);
  EXPECT_EQ(p.tracker.mode, d.tracker.mode);
  EXPECT_EQ(p.tracker.motion_prior, d.tracker.motion_prior);
  EXPECT_EQ(p.tracker.keyframe_translation, d.tracker.keyframe_translation);
  EXPECT_EQ(p.tracker.keyframe_rotation, d.tracker.keyframe_rotation);
  EXPECT_EQ(p.tracker.keyframe_overlap, d.tracker.keyframe_overlap);
  EXPECT_EQ(p.tracker.accept_degenerate, d.tracker.accept_degenerate);
}

TEST(FrontendParams, ValuesAreRead) {
  const Params p = parse_params(
      "frontend:\n  icp: {iterations: [1, 2, 3], robust_loss: tukey}\n"
      "  tracker: {mode: frame_to_keyframe, motion_prior: constant_velocity}\n",
      "p.yaml");
  EXPECT_EQ(p.frontend.icp.iterations, (std::array<int, 3>{1, 2, 3}));
  EXPECT_EQ(p.frontend.icp.robust_loss, RobustLoss::tukey);
  EXPECT_EQ(p.frontend.tracker.mode, TrackingMode::frame_to_keyframe);
  EXPECT_EQ(p.frontend.tracker.motion_prior, MotionPrior::constant_velocity);
}

TEST(FrontendParams, MistakesNameTheFileLineAndKey) {
  EXPECT_NE(error_of("frontend:\n  icp:\n    max_distanc: 0.1\n")
                .find("unknown key 'frontend.icp.max_distanc'"),
            std::string::npos);
  EXPECT_NE(error_of("frontend:\n  icp:\n    iterations: [1, 2]\n").find("p.yaml:3"),
            std::string::npos);
  EXPECT_NE(error_of("frontend:\n  icp:\n    iterations: [1, 2.5, 3]\n").find("integers"),
            std::string::npos);
  EXPECT_NE(error_of("frontend:\n  preprocess:\n    max_depth: -1\n")
                .find("'frontend.preprocess.max_depth': must be larger than min_depth"),
            std::string::npos);
  EXPECT_NE(error_of("frontend:\n  tracker:\n    mode: sideways\n").find("frame_to_keyframe"),
            std::string::npos);
  // z^-k weights need a floor: a patch at 1 mm outweighed a room 1e12 to 1.
  EXPECT_NE(error_of("frontend:\n  preprocess:\n    min_depth: 0.001\n")
                .find("'frontend.preprocess.min_depth': must be at least 0.01 m while "
                      "icp.depth_weight_exponent weighs pairs by z^-k"),
            std::string::npos);
  FrontendParams unweighted;
  unweighted.preprocess.min_depth = 0.0f;
  unweighted.icp.depth_weight_exponent = 0;
  EXPECT_NO_THROW(unweighted.validate());
}

}  // namespace
}  // namespace jpcr
