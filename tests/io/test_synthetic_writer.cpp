// The TUM layout written by the generator reads back through the foundation's TUM reader with
// the exact poses, the depth to PNG quantisation, and the ground-truth maps bit for bit.
#include <cerrno>
#include <cmath>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <iterator>

#include <gtest/gtest.h>

#include "input_error.hpp"
#include "jpcr/io/camera_yaml.hpp"
#include "jpcr/io/curvature_output.hpp"
#include "jpcr/io/depth_png.hpp"
#include "jpcr/io/npy.hpp"
#include "jpcr/io/synthetic_ray_caster.hpp"
#include "jpcr/io/synthetic_writer.hpp"
#include "jpcr/io/tum_dataset.hpp"
#include "jpcr/quadric/curvature_spread.hpp"
#include "jpcr/quadric/error.hpp"
#include "jpcr/quadric/quadric_fit.hpp"
#include "temp_dir.hpp"

namespace jpcr {
namespace {

SyntheticSequence small_sequence(const std::string& noise, TrajectoryKind kind) {
  SyntheticSequenceOptions options;
  options.scene = "torus_saddle";
  options.trajectory = kind;
  options.frames = 6;
  options.noise = noise;
  options.width = 64;
  options.height = 48;
  options.seed = 4;
  return make_synthetic_sequence(options);
}

bool same_bits(const float* a, const float* b, std::size_t n) {
  return std::memcmp(a, b, n * sizeof(float)) == 0;
}

TEST(SyntheticWriter, RoundTripThroughTheTumReader) {
  const SyntheticSequence seq = small_sequence("range:1", TrajectoryKind::kWalk);
  test::TempDir dir;
  const std::string out = dir.file("seq");
  std::size_t progress = 0;
  SyntheticWriterOptions options;
  options.progress = [&](std::size_t done, std::size_t total) {
    EXPECT_EQ(total, 6u);
    EXPECT_EQ(done, progress + 1);
    progress = done;
  };
  write_synthetic_sequence(seq, out, options);
  EXPECT_EQ(progress, 6u);

  const CameraIntrinsics camera = load_camera_yaml(out + "/camera.yaml");
  EXPECT_EQ(camera.fx, seq.camera().fx);
  EXPECT_EQ(camera.width, 64);
  TumDatasetOptions tum;
  tum.load_color = true;
  const TumDataset data(out, camera, tum);
  ASSERT_EQ(data.size(), seq.size());
  const double half_quantum = 0.5 / camera.depth_scale;  // PNG stores depth in 0.2 mm steps
  for (std::size_t i = 0; i < seq.size(); ++i) {
    const SyntheticFrame expected = seq.render(i);
    EXPECT_EQ(data.timestamp(i), seq.timestamp(i));
    // Poses go through text at full precision (shortest round-trip doubles).
    const auto gt = data.ground_truth(i);
    ASSERT_TRUE(gt);
    EXPECT_LT((gt->matrix() - expected.pose_wc.matrix()).cwiseAbs().maxCoeff(), 1e-15);
    const Frame frame = data.load(i);
    for (std::size_t p = 0; p < frame.depth.size(); ++p) {
      const float z = expected.frame.depth[p];
      if (z > 0.0f)
        EXPECT_NEAR(frame.depth[p], z, half_quantum + 1e-6 * z);
      else
        EXPECT_EQ(frame.depth[p], 0.0f);
    }
    for (std::size_t p = 0; p < frame.color.size(); ++p) {
      EXPECT_EQ(frame.color[p].r, expected.frame.color[p].r);
      EXPECT_EQ(frame.color[p].b, expected.frame.color[p].b);
    }
    // Ground-truth maps: float32 H×W×2 and H×W×3, identical bits (NaN included).
    const std::string stamp = format_stamp(seq.timestamp(i));
    const NpyArray k = read_npy(out + "/curvature/" + stamp + ".npy");
    EXPECT_EQ(k.dtype, "f4");
    EXPECT_EQ(k.shape, (std::vector<std::size_t>{48, 64, 2}));
    EXPECT_TRUE(same_bits(k.to_float().data(), expected.curvature.data()->data(), 48 * 64 * 2));
    const NpyArray n = read_npy(out + "/normals/" + stamp + ".npy");
    EXPECT_EQ(n.shape, (std::vector<std::size_t>{48, 64, 3}));
    EXPECT_TRUE(same_bits(n.to_float().data(), expected.normals.data()->data(), 48 * 64 * 3));
  }
  // The SyntheticSequence is itself a FrameSource with the same ground truth.
  const Trajectory a = seq.ground_truth_trajectory(), b = data.ground_truth_trajectory();
  ASSERT_EQ(a.size(), b.size());
  EXPECT_EQ(seq.load(2).depth.size(), 64u * 48u);
}

TEST(SyntheticWriter, RefusesANonEmptyDirectoryUnlessForced) {
  const SyntheticSequence seq = small_sequence("none", TrajectoryKind::kRail);
  test::TempDir dir;
  dir.write("out/notes.txt", "mine");
  try {
    write_synthetic_sequence(seq, dir.file("out"));
    ADD_FAILURE() << "no error";
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find("not empty (use --force"), std::string::npos);
  }
  EXPECT_FALSE(std::filesystem::exists(dir.file("out/depth.txt")));
  SyntheticWriterOptions force;
  force.force = true;
  write_synthetic_sequence(seq, dir.file("out"), force);
  EXPECT_TRUE(std::filesystem::exists(dir.file("out/depth.txt")));
  EXPECT_TRUE(std::filesystem::exists(dir.file("out/notes.txt")));  // left alone
  const std::string file = dir.write("file", "x");
  EXPECT_THROW(write_synthetic_sequence(seq, file), InputError);
}

// --force rewrites a generated sequence, never another program's results or a recording: each
// is refused before anything is written, and its files stay as they were.
TEST(SyntheticWriter, ForceRefusesResultsAndRecordedDatasets) {
  const SyntheticSequence seq = small_sequence("none", TrajectoryKind::kRail);
  SyntheticWriterOptions force;
  force.force = true;
  test::TempDir dir;
  dir.write("run/report.json", "{}");
  dir.write("run/curvature/0.000000.npy", "map");
  dir.write("curv/summary.json", "{}");
  dir.write("recorded/depth.txt", "# depth maps\n0.0 depth/0.0.png\n");
  const std::pair<const char*, const char*> cases[] = {
      {"run", "holds jpcr_run's results (report.json)"},
      {"curv", "holds jpcr_curvature's results (summary.json)"},
      {"recorded", "holds a dataset that jpcr_synth did not write"}};
  for (const auto& c : cases) {  // no structured binding: clang 14 cannot capture one
    const char *out = c.first, *message = c.second;
    const std::string error =
        test::input_error_of([&] { write_synthetic_sequence(seq, dir.file(out), force); });
    EXPECT_NE(error.find(message), std::string::npos) << error;
  }
  const auto text = [](const std::string& path) {
    std::ifstream in(path, std::ios::binary);
    return std::string(std::istreambuf_iterator<char>(in), {});
  };
  EXPECT_EQ(text(dir.file("run/curvature/0.000000.npy")), "map");
  EXPECT_EQ(text(dir.file("recorded/depth.txt")), "# depth maps\n0.0 depth/0.0.png\n");
  // A sequence it wrote is rewritten.
  write_synthetic_sequence(seq, dir.file("seq"));
  write_synthetic_sequence(seq, dir.file("seq"), force);
}

// A full disk (a 64 kB tmpfs, as root) mid-sequence: the error names the output the user gave
// (it named the staging directory, removed by the time they read it) and nothing is left.
TEST(SyntheticWriter, AFailedWriteNamesTheOutputDirectory) {
  test::TempDir dir;
  const std::string mounted = dir.file("small");
  const test::SmallDisk disk(mounted, "64k");
  if (!disk.mounted()) GTEST_SKIP() << "cannot mount a tmpfs here";
  std::string error;
  try {
    write_synthetic_sequence(small_sequence("none", TrajectoryKind::kRail), mounted + "/seq");
  } catch (const InputError& e) {
    error = e.what();
  }
  EXPECT_EQ(error.rfind(mounted + "/seq/", 0), 0u) << error;
  EXPECT_EQ(error.find(".partial-"), std::string::npos) << error;
  EXPECT_NE(error.find(std::strerror(ENOSPC)), std::string::npos) << error;
  EXPECT_TRUE(std::filesystem::is_empty(mounted));
}

TEST(SyntheticWriter, StampsHaveSixDecimals) {
  EXPECT_EQ(format_stamp(0.0), "0.000000");
  EXPECT_EQ(format_stamp(1.0 / 30.0), "0.033333");
  EXPECT_EQ(format_stamp(1305031102.160407), "1305031102.160407");
}

// Frames whose timestamps agree to 1 us get the same name: the second map is refused instead of
// overwriting the first.
TEST(CurvatureWriter, ASecondMapOfTheSameStampIsAnInputError) {
  test::TempDir dir;
  const CurvatureWriter writer(dir.path(), false);
  QuadricMap map(8, 6);
  const VertexMap vertices(8, 6);
  const std::string stamp = format_stamp(1e-7);
  writer.write(stamp, map, vertices);
  try {
    writer.write(format_stamp(2e-7), map, vertices);
    FAIL() << "no error";
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find("two curvature maps are named 0.000000"),
              std::string::npos)
        << e.what();
  }
  EXPECT_EQ(writer.written(), 1u);
  EXPECT_TRUE(std::filesystem::exists(dir.file("curvature/0.000000.npy")));
}

// With the fit's parameters the writer adds curvature_sd/<stamp>.npy, curvature_spread of the
// map on the vertices it was given; without them it writes no curvature_sd/ at all, and counts
// nothing for the warning.
TEST(CurvatureWriter, WritesTheSdMapWhenGivenTheFitsParameters) {
  const CameraIntrinsics camera = synthetic_camera(80, 60);
  SyntheticScene scene;
  scene.surfaces = {Sphere{{0, 0, 2}, 0.8}};
  const SyntheticFrame f =
      render(scene, camera, Eigen::Isometry3d::Identity(), parse_noise("range:0.5"), 3);
  const VertexMap vertices = compute_vertex_map(f.frame.depth, camera);
  QuadricParams params;
  params.fit.fair_n0_per_range = 0.05f;
  params.fit.gate_per_range = 0.015f;
  const QuadricMap map = QuadricFit(params).estimate(vertices);
  ASSERT_GT(map.valid_count(), 1000u);
  test::TempDir dir;
  const CurvatureWriter writer(dir.path(), false, {}, params);
  const Image<float> returned = writer.write("0.000000", map, vertices);  // for --dds
  const Image<float> written = read_curvature_sd_npy(dir.file("curvature_sd/0.000000.npy"));
  ASSERT_EQ(returned.size(), written.size());
  EXPECT_EQ(std::memcmp(returned.data(), written.data(), written.size() * sizeof(float)), 0);
  const Image<float> expected =
      curvature_spread(map, vertices, params.pattern_for(camera.width), params.fit);
  ASSERT_EQ(written.size(), expected.size());
  std::size_t with_sd = 0;
  for (std::size_t i = 0; i < written.size(); ++i) {
    EXPECT_TRUE(std::isnan(expected[i]) ? std::isnan(written[i]) : written[i] == expected[i]) << i;
    with_sd += std::isfinite(expected[i]) ? 1 : 0;
  }
  EXPECT_EQ(writer.sd_valid_pixels(), map.valid_count());
  EXPECT_EQ(writer.sd_withheld_pixels(), map.valid_count() - with_sd);
  EXPECT_EQ(writer.sd_warning(), "");  // the gate is 3 σ: most pixels have an sd

  // The built-in 14 mm gate under 1 % range noise at 2 m (σ = 20 mm): most sd withheld, warned.
  const SyntheticFrame noisy =
      render(scene, camera, Eigen::Isometry3d::Identity(), parse_noise("range:1"), 3);
  const VertexMap noisy_vertices = compute_vertex_map(noisy.frame.depth, camera);
  test::TempDir built_in;
  const CurvatureWriter warned(built_in.path(), false, {}, QuadricParams{});
  warned.write("0.000000", QuadricFit().estimate(noisy_vertices), noisy_vertices);
  EXPECT_GT(2 * warned.sd_withheld_pixels(), warned.sd_valid_pixels());
  EXPECT_NE(warned.sd_warning().find("gate is likely below the depth noise"), std::string::npos)
      << warned.sd_warning();

  test::TempDir plain;
  const CurvatureWriter without(plain.path(), false);
  EXPECT_TRUE(without.write("0.000000", map, vertices).empty());
  EXPECT_FALSE(std::filesystem::exists(plain.file("curvature_sd")));
  EXPECT_EQ(without.sd_valid_pixels(), 0u);
}

}  // namespace
}  // namespace jpcr
