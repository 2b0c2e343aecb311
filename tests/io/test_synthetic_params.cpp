// The synthetic: section of the parameter file: configs/default.yaml states the built-in
// defaults, and bad values are errors naming the file, line and key.
#include <gtest/gtest.h>

#include "input_error.hpp"
#include "jpcr/io/params.hpp"
#include "jpcr/quadric/error.hpp"
#include "temp_dir.hpp"

namespace jpcr {
namespace {

using test::input_error_of;

TEST(SyntheticParams, DefaultYamlStatesTheBuiltInDefaults) {
  const Params p = load_params(std::string(JPCR_SOURCE_DIR) + "/configs/default.yaml");
  const TrajectoryParams t;
  EXPECT_EQ(p.synthetic.trajectory.rate, t.rate);
  EXPECT_EQ(p.synthetic.trajectory.start_time, t.start_time);
  EXPECT_EQ(p.synthetic.trajectory.rail_step, t.rail_step);
  EXPECT_EQ(p.synthetic.trajectory.orbit_step, t.orbit_step);
  EXPECT_EQ(p.synthetic.trajectory.walk_max_speed, t.walk_max_speed);
  EXPECT_EQ(p.synthetic.trajectory.walk_max_head_rate, t.walk_max_head_rate);
  EXPECT_EQ(p.synthetic.trajectory.walk_min_period, t.walk_min_period);
  EXPECT_EQ(p.synthetic.trajectory.walk_max_period, t.walk_max_period);
  const KinectNoiseParams k;
  const KinectNoiseParams& y = p.synthetic.kinect;
  EXPECT_EQ(y.sigma_constant, k.sigma_constant);
  EXPECT_EQ(y.sigma_quadratic, k.sigma_quadratic);
  EXPECT_EQ(y.sigma_offset, k.sigma_offset);
  EXPECT_EQ(y.baseline, k.baseline);
  EXPECT_EQ(y.disparity_focal, k.disparity_focal);
  EXPECT_EQ(y.disparity_step, k.disparity_step);
  EXPECT_EQ(y.min_depth, k.min_depth);
  EXPECT_EQ(y.max_depth, k.max_depth);
  EXPECT_EQ(y.grazing_start, k.grazing_start);
  EXPECT_EQ(y.grazing_full, k.grazing_full);
  EXPECT_EQ(y.edge_jump, k.edge_jump);
  EXPECT_EQ(y.edge_dropout, k.edge_dropout);
}

TEST(SyntheticParams, ValuesAreReadAndCheckedAgainstTheFile) {
  test::TempDir dir;
  const std::string good = dir.write(
      "good.yaml", "synthetic:\n  trajectory: {rail_step: 0.005}\n  kinect: {edge_dropout: 1}\n");
  const Params p = load_params(good);
  EXPECT_EQ(p.synthetic.trajectory.rail_step, 0.005);
  EXPECT_EQ(p.synthetic.kinect.edge_dropout, 1.0);

  const std::string negative = dir.write("n.yaml", "synthetic:\n  trajectory:\n    rate: -30\n");
  EXPECT_NE(input_error_of([&] {
              load_params(negative);
            }).find("n.yaml:3: key 'synthetic.trajectory.rate': must be positive (Hz)"),
            std::string::npos)
      << input_error_of([&] { load_params(negative); });
  const std::string order =
      dir.write("o.yaml", "synthetic:\n  kinect:\n    grazing_start: 80\n    grazing_full: 75\n");
  EXPECT_NE(input_error_of([&] { load_params(order); }).find("'synthetic.kinect.grazing_full'"),
            std::string::npos);
  const std::string unknown = dir.write("u.yaml", "synthetic:\n  kinect: {sigma: 1}\n");
  EXPECT_NE(
      input_error_of([&] { load_params(unknown); }).find("unknown key 'synthetic.kinect.sigma'"),
      std::string::npos);
}

}  // namespace
}  // namespace jpcr
