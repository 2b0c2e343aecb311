#include <gtest/gtest.h>

#include "jpcr/backend/joint_system.hpp"
#include "jpcr/io/camera_yaml.hpp"
#include "jpcr/io/params.hpp"
#include "jpcr/quadric/error.hpp"
#include "temp_dir.hpp"

namespace jpcr {
namespace {

std::string error_of(const std::function<void()>& f) {
  try {
    f();
  } catch (const InputError& e) {
    return e.what();
  }
  return "<no error>";
}

const std::string kConfigs = std::string(JPCR_SOURCE_DIR) + "/configs/";

TEST(CameraYaml, ShippedCameraConfigsLoad) {
  const CameraIntrinsics fr1 = load_camera_yaml(kConfigs + "tum_fr1.yaml");
  EXPECT_DOUBLE_EQ(fr1.fx, 517.3);
  EXPECT_DOUBLE_EQ(fr1.distortion[4], 1.1633);
  EXPECT_TRUE(fr1.has_distortion());
  const CameraIntrinsics ros = load_camera_yaml(kConfigs + "ros_default.yaml");
  EXPECT_DOUBLE_EQ(ros.cx, 319.5);
  EXPECT_FALSE(ros.has_distortion());
  for (const char* name : {"tum_fr2.yaml", "tum_fr3.yaml", "synthetic.yaml"}) {
    EXPECT_NO_THROW(load_camera_yaml(kConfigs + name)) << name;
  }
}

TEST(CameraYaml, FormatLoadRoundTrip) {
  CameraIntrinsics c;
  c.fx = 517.3;
  c.distortion = {0.1, -0.2, 0.0, 0.001, 0.3};
  test::TempDir dir;
  const CameraIntrinsics back = load_camera_yaml(dir.write("c.yaml", format_camera_yaml(c)));
  EXPECT_EQ(back.fx, c.fx);
  EXPECT_EQ(back.distortion, c.distortion);
}

TEST(CameraYaml, ErrorsNameFileLineAndKey) {
  test::TempDir dir;
  const std::string base = "fx: 525\nfy: 525\ncx: 319.5\ncy: 239.5\nwidth: 640\nheight: 480\n";
  const std::string wrong_type = dir.write("t.yaml", base + "depth_scale: lots\n");
  const std::string e1 = error_of([&] { load_camera_yaml(wrong_type); });
  EXPECT_NE(e1.find(wrong_type + ":7: key 'depth_scale'"), std::string::npos) << e1;

  const std::string missing = dir.write("m.yaml", base);
  EXPECT_NE(error_of([&] { load_camera_yaml(missing); }).find("'depth_scale': missing"),
            std::string::npos);

  const std::string unknown = dir.write("u.yaml", base + "depth_scale: 5000\nfocal: 3\n");
  EXPECT_NE(error_of([&] { load_camera_yaml(unknown); }).find("unknown key 'focal'"),
            std::string::npos);

  const std::string width = dir.write("w.yaml",
                                      "fx: 525\nfy: 525\ncx: 1\ncy: 1\nwidth: 6.5\n"
                                      "height: 480\ndepth_scale: 1\n");
  EXPECT_NE(error_of([&] { load_camera_yaml(width); }).find("'width': expected an integer"),
            std::string::npos);

  const std::string negative = dir.write("n.yaml",
                                         "fx: -525\nfy: 525\ncx: 1\ncy: 1\n"
                                         "width: 6\nheight: 4\ndepth_scale: 1\n");
  EXPECT_NE(error_of([&] { load_camera_yaml(negative); }).find("fx"), std::string::npos);

  const std::string syntax = dir.write("s.yaml", "fx: [1, 2\n");
  EXPECT_NE(error_of([&] { load_camera_yaml(syntax); }).find("YAML syntax error"),
            std::string::npos);

  const std::string dist = dir.write("d.yaml", base + "depth_scale: 1\ndistortion: [1, 2]\n");
  EXPECT_NE(error_of([&] { load_camera_yaml(dist); }).find("list of 5 numbers"), std::string::npos);

  EXPECT_NE(error_of([&] { load_camera_yaml(dir.file("absent.yaml")); }).find("does not exist"),
            std::string::npos);
  const std::string scalar = dir.write("x.yaml", "just a string\n");
  EXPECT_NE(error_of([&] { load_camera_yaml(scalar); }).find("must be a map"), std::string::npos);

  // A second document was ignored without a word; a closing '---' is no document.
  const std::string two = dir.write("two.yaml", base + "depth_scale: 5000\n---\nfx: 1\n");
  EXPECT_NE(error_of([&] { load_camera_yaml(two); }).find("holds more than one YAML document"),
            std::string::npos);
  const std::string closed = dir.write("closed.yaml", base + "depth_scale: 5000\n--- # end\n");
  EXPECT_EQ(load_camera_yaml(closed).depth_scale, 5000.0);

  // yaml-cpp's LoadAll never returned on a stray ',' at the top (the parser stands on it), keeping
  // a node per turn until memory ran out (found by fuzz_yaml_config).
  EXPECT_NE(error_of([&] {
              load_camera_yaml(dir.write("stray.yaml", ","));
            }).find("stray.yaml:1: YAML syntax error: cannot read past column 1"),
            std::string::npos);
  EXPECT_NE(error_of([&] {
              load_camera_yaml(dir.write("stray.yaml", base + "depth_scale: 5000\n---\n  ,\n"));
            }).find("stray.yaml:9: YAML syntax error: cannot read past column 3"),
            std::string::npos);
  // Empty documents before the content are no second document, and the content is read.
  for (const std::string head : {"---\n---\n", "...\n", "--- # header\n---\n", "~\n---\n"})
    EXPECT_EQ(
        load_camera_yaml(dir.write("lead.yaml", head + base + "depth_scale: 5000\n")).depth_scale,
        5000.0)
        << head;
}

TEST(CameraYaml, BracketsInCommentsAndQuotesAreNoNesting) {
  test::TempDir dir;
  std::string text = "fx: 525\nfy: 525\ncx: 319.5\ncy: 239.5\nwidth: 640\nheight: 480\n";
  for (int k = 0; k < 70; ++k)
    text += "# valid range [0, 1) note " + std::to_string(k) + "\n";
  text += "depth_scale: 5000  # '[[[{{{\n";
  EXPECT_EQ(load_camera_yaml(dir.write("c.yaml", text)).depth_scale, 5000.0);
  const std::string quoted = "dataset:\n  name: '" + std::string(70, '[') + "'\n";
  EXPECT_NE(error_of([&] { load_params(dir.write("q.yaml", quoted)); }).find("unknown key"),
            std::string::npos);  // parsed: the brackets were text
  // Real nesting is still refused before yaml-cpp recurses, also after an apostrophe in a plain
  // scalar (no quote: taken for one, it switched the count off, and 100 levels reached yaml-cpp).
  for (const std::string& before : {std::string(), std::string("model: don't care\n")}) {
    const std::string deep = dir.write("deep.yaml", before + "fx: " + std::string(100, '[') + "\n");
    EXPECT_NE(error_of([&] { load_camera_yaml(deep); }).find("nested too deeply"),
              std::string::npos)
        << before;
  }
}

TEST(Params, DefaultFileLoadsAndUnknownKeysAreErrors) {
  const Params p = load_params(kConfigs + "default.yaml");
  EXPECT_DOUBLE_EQ(p.dataset.max_time_difference, 0.02);
  test::TempDir dir;
  const std::string bad = dir.write("p.yaml", "dataset:\n  max_time_diference: 0.1\n");
  EXPECT_NE(error_of([&] { load_params(bad); }).find("unknown key 'dataset.max_time_diference'"),
            std::string::npos);
  const std::string top = dir.write("q.yaml", "datset: {}\n");
  EXPECT_NE(error_of([&] { load_params(top); }).find("unknown key 'datset'"), std::string::npos);
  const std::string type = dir.write("r.yaml", "dataset:\n  max_time_difference: [1]\n");
  EXPECT_NE(error_of([&] { load_params(type); }).find("'dataset.max_time_difference'"),
            std::string::npos);
  const std::string empty = dir.write("e.yaml", "");
  EXPECT_DOUBLE_EQ(load_params(empty).dataset.max_time_difference, 0.02);
}

// A repeated key is an error, not a silent first-one-wins (yaml-cpp keeps both entries).
TEST(Params, DuplicateKeysAndSectionsAreErrorsNamingFileLineAndKey) {
  test::TempDir dir;
  const std::string key =
      dir.write("k.yaml", "dataset:\n  max_time_difference: 0.1\n  max_time_difference: 0.2\n");
  const std::string e1 = error_of([&] { load_params(key); });
  EXPECT_NE(e1.find(key + ":3: duplicate key 'dataset.max_time_difference'"), std::string::npos)
      << e1;
  const std::string section = dir.write("s.yaml", "dataset: {}\nfrontend: {}\ndataset: {}\n");
  EXPECT_NE(error_of([&] { load_params(section); }).find("duplicate key 'dataset'"),
            std::string::npos);
  const std::string camera = dir.write("c.yaml",
                                       "fx: 525\nfy: 525\ncx: 1\ncy: 1\nwidth: 640\nheight: 480\n"
                                       "depth_scale: 5000\nfx: 600\n");
  EXPECT_NE(error_of([&] { load_camera_yaml(camera); }).find("duplicate key 'fx'"),
            std::string::npos);
  // A bound checked after reading still names the file and the key.
  const std::string threads = dir.write("t.yaml", "frontend:\n  threads: 100000\n");
  const std::string e2 = error_of([&] { load_params(threads); });
  EXPECT_NE(e2.find(threads), std::string::npos) << e2;
  EXPECT_NE(e2.find("frontend.threads"), std::string::npos) << e2;
  // So does one that depends on two sections: more samples than the pattern has.
  const std::string samples =
      dir.write("m.yaml", "quadric:\n  pattern:\n    radius: 2\n  fit:\n    min_samples: 100000\n");
  const std::string e3 = error_of([&] { load_params(samples); });
  EXPECT_NE(e3.find(samples + ":5: key 'quadric.fit.min_samples': 100000 exceeds the"),
            std::string::npos)
      << e3;
}

// Section icp_bundle: the shipped defaults are the struct's, keys map onto it and reach the
// pipeline, bad values name the key.
TEST(Params, IcpBundleSection) {
  const Params shipped = load_params(kConfigs + "default.yaml");
  const IcpBundleParams defaults;
  EXPECT_EQ(shipped.icp_bundle.grid_stride, defaults.grid_stride);
  EXPECT_DOUBLE_EQ(shipped.icp_bundle.min_overlap, defaults.min_overlap);
  EXPECT_DOUBLE_EQ(shipped.icp_bundle.robust_scale, defaults.robust_scale);
  EXPECT_EQ(shipped.icp_bundle.outer_iterations, defaults.outer_iterations);
  const Params p = parse_params(
      "icp_bundle:\n  grid_stride: 2\n  robust_loss: cauchy\n  min_overlap: 0.5\n"
      "pipeline:\n  method: icp-bundle\n",
      "p.yaml");
  EXPECT_EQ(p.icp_bundle.grid_stride, 2);
  EXPECT_EQ(p.pipeline.icp_bundle.robust_loss, BundleLoss::cauchy);
  EXPECT_DOUBLE_EQ(p.pipeline.icp_bundle.min_overlap, 0.5);
  EXPECT_EQ(p.pipeline.method, PipelineMethod::kIcpBundle);
  EXPECT_NE(error_of([] {
              parse_params("icp_bundle:\n  min_overlap: 0\n", "b.yaml");
            }).find("icp_bundle.min_overlap"),
            std::string::npos);
  EXPECT_NE(error_of([] {
              parse_params("icp_bundle:\n  robust_loss: tukey\n", "c.yaml");
            }).find("icp_bundle.robust_loss"),
            std::string::npos);
  // Pixel distances beyond any image (normal_offset · width would overflow int).
  EXPECT_NE(error_of([] {
              parse_params("icp_bundle:\n  normal_offset: 2000000000\n", "d.yaml");
            }).find("d.yaml:2: key 'icp_bundle.normal_offset': must be in [1, 16384]"),
            std::string::npos);
}

// joint.keep_lower_cost_fit: shipped on, as built in; false is the paper's refiners; anything
// but a boolean names the file, line and key.
TEST(Params, JointKeepLowerCostFit) {
  EXPECT_TRUE(JointParams{}.keep_lower_cost_fit);
  EXPECT_EQ(load_params(kConfigs + "default.yaml").joint.keep_lower_cost_fit,
            JointParams{}.keep_lower_cost_fit);
  EXPECT_FALSE(
      parse_params("joint:\n  keep_lower_cost_fit: false\n", "p.yaml").joint.keep_lower_cost_fit);
  EXPECT_NE(error_of([] { parse_params("joint:\n  keep_lower_cost_fit: maybe\n", "k.yaml"); })
                .find("k.yaml:2: key 'joint.keep_lower_cost_fit': expected true or false, got "
                      "'maybe'"),
            std::string::npos);
}

// joint.edge_tilt: the shipped value is the built-in default, 0 turns it off, and a value
// outside [0.1, 90] degrees names the file, line and key.
TEST(Params, JointEdgeTilt) {
  EXPECT_FLOAT_EQ(load_params(kConfigs + "default.yaml").joint.edge_tilt, JointParams{}.edge_tilt);
  EXPECT_FLOAT_EQ(parse_params("joint:\n  edge_tilt: 0\n", "p.yaml").joint.edge_tilt, 0.0f);
  EXPECT_NE(error_of([] { parse_params("joint:\n  edge_tilt: 120\n", "e.yaml"); })
                .find("e.yaml:2: key 'joint.edge_tilt': must be 0 (every quadric takes part) or in "
                      "[0.1, 90] (deg)"),
            std::string::npos);
  EXPECT_NE(error_of([] {
              parse_params("joint:\n  edge_tilt: 0.01\n", "e.yaml");
            }).find("joint.edge_tilt"),
            std::string::npos);
}

// joint.block_memory_mb: the shipped value is the built-in default (1 GiB), 0 keeps no blocks, and
// a negative or non-finite budget names the file, line and key.
TEST(Params, JointBlockMemory) {
  const JointParams shipped = load_params(kConfigs + "default.yaml").joint;
  EXPECT_DOUBLE_EQ(shipped.block_memory_mb, JointParams{}.block_memory_mb);
  EXPECT_EQ(block_memory_bytes(shipped), kDefaultBlockMemory);
  const JointParams none = parse_params("joint:\n  block_memory_mb: 0\n", "p.yaml").joint;
  EXPECT_EQ(block_memory_bytes(none), 0u);
  EXPECT_EQ(block_memory_bytes(parse_params("joint:\n  block_memory_mb: 0.5\n", "p.yaml").joint),
            std::size_t{1} << 19);
  const auto error = [](const std::string& value) {
    return error_of([&] { parse_params("joint:\n  block_memory_mb: " + value + "\n", "e.yaml"); });
  };
  for (const char* bad : {"-1", "2e9"})
    EXPECT_NE(error(bad).find("e.yaml:2: key 'joint.block_memory_mb': must be in [0, 1e9]"),
              std::string::npos)
        << bad;
  for (const char* bad : {".nan", ".inf"})
    EXPECT_NE(error(bad).find("e.yaml:2: key 'joint.block_memory_mb': expected a finite number"),
              std::string::npos)
        << bad;
}

}  // namespace
}  // namespace jpcr
