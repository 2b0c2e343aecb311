// jpcr_eval noise: a Monte-Carlo study of a pair method (J-ftf, Q-full, or the peer ICP-ftf) on
// one step of a synthetic walk. Both frames are rendered once without noise; each draw adds fresh
// sensor noise (jpcr_synth's models), refines from the same start, and records the error e = (t −
// t_true, log(R R_trueᵀ)): the change of the translation vector and the rotation vector of the left
// rotation error, the quantities whose spread the refiner predicts (pose_spread, refiner.hpp).
// Over the draws: the mean of e (the bias) with its standard error, the spread of e about that
// mean, and the predicted spread (report.json's translation_sd_m / rotation_sd_rad). For J-ftf and
// Q-full also the mean angle between the reference frame's quadric normals and the true surface
// normals, before (Quad IT) and after refinement: how well the per-pixel quadrics the pose rests
// on are determined at this noise.
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <iostream>
#include <memory>
#include <string>
#include <vector>

#include "cli/arguments.hpp"
#include "cli/dataset_run_checks.hpp"
#include "cli/device_option.hpp"
#include "jpcr/cuda/refiner_factory.hpp"
#include "jpcr/frontend/frame_pyramid.hpp"
#include "jpcr/frontend/point_to_plane_icp.hpp"
#include "jpcr/io/json_writer.hpp"
#include "jpcr/io/params.hpp"
#include "jpcr/io/synthetic_noise.hpp"
#include "jpcr/io/synthetic_ray_caster.hpp"
#include "jpcr/io/synthetic_sequence.hpp"
#include "jpcr/quadric/error.hpp"
#include "jpcr/quadric/quadric_fit.hpp"
#include "jpcr/quadric/se3.hpp"
#include "jpcr_eval/eval_commands.hpp"

namespace jpcr::eval {

namespace {

struct Draw {
  Vector6d error;       // t − t_true (m), log(R R_trueᵀ) (rad)
  std::string verdict;  // the method's own (RefinementVerdict or IcpVerdict)
  bool usable = true;   // the verdict says the pose can be used; else left out of the statistics
  int iterations = 0, rejected = 0;
  double predicted_t = 0.0, predicted_r = 0.0;  // report translation_sd, rotation_sd
  // Mean angle (rad) of the reference quadrics' normals from the true normals: Quad IT's (the
  // start) and the refined ones; NaN for ICP-ftf, which fits no quadrics.
  double normal_error_initial = NAN, normal_error = NAN;
};

struct Study {
  std::vector<Draw> draws;  // all of them; the statistics are over the usable ones
  std::size_t used = 0;     // usable draws
  Vector6d mean = Vector6d::Zero(), sd = Vector6d::Zero();
  double rms_t = 0.0, rms_r = 0.0;        // RMS of |t error| (m) and of the angle (rad)
  double bias_t = 0.0, bias_r = 0.0;      // |mean v|, |mean ω|
  double spread_t = 0.0, spread_r = 0.0;  // RMS length of e − mean (per part)
  double predicted_t = 0.0, predicted_r = 0.0;
  double bias_t_se = 0.0, bias_r_se = 0.0;                // |mean| in standard errors of the mean
  double normal_error_initial = 0.0, normal_error = 0.0;  // means over the draws (rad), NaN: none
};

Study summarize(std::vector<Draw> draws) {
  Study s;
  s.draws = std::move(draws);
  for (const Draw& d : s.draws)
    s.used += d.usable ? 1 : 0;
  const double n = static_cast<double>(s.used);
  for (const Draw& d : s.draws) {
    if (!d.usable) continue;
    s.mean += d.error / n;
    s.predicted_t += d.predicted_t / n;
    s.predicted_r += d.predicted_r / n;
    s.normal_error_initial += d.normal_error_initial / n;
    s.normal_error += d.normal_error / n;
  }
  for (const Draw& d : s.draws) {
    if (!d.usable) continue;
    const Vector6d c = d.error - s.mean;
    s.sd += c.cwiseProduct(c) / std::max(1.0, n - 1.0);
    s.rms_t += d.error.head<3>().squaredNorm() / n;
    s.rms_r += d.error.tail<3>().squaredNorm() / n;
  }
  s.sd = s.sd.cwiseSqrt();
  s.rms_t = std::sqrt(s.rms_t);
  s.rms_r = std::sqrt(s.rms_r);
  s.bias_t = s.mean.head<3>().norm();
  s.bias_r = s.mean.tail<3>().norm();
  s.spread_t = s.sd.head<3>().norm();
  s.spread_r = s.sd.tail<3>().norm();
  // The standard error of |mean| along its own direction: the spread of the draws projected on
  // it, over √n.
  auto in_standard_errors = [&](int offset) {
    const Eigen::Vector3d m = s.mean.segment<3>(offset);
    if (m.norm() == 0.0 || n < 2) return 0.0;
    const Eigen::Vector3d u = m.normalized();
    double var = 0.0;
    for (const Draw& d : s.draws)
      if (d.usable) var += std::pow(u.dot(d.error.segment<3>(offset) - m), 2) / (n - 1.0);
    return var > 0.0 ? m.norm() / std::sqrt(var / n) : INFINITY;
  };
  s.bias_t_se = in_standard_errors(0);
  s.bias_r_se = in_standard_errors(3);
  return s;
}

// exp(δ) T with δ of `metres` along (1, −2, 2)/3 and `degrees` about (−2, 1, 2)/3.
Eigen::Isometry3d offset_start(const Eigen::Isometry3d& T, double metres, double degrees) {
  Vector6d xi;
  xi << Eigen::Vector3d(1, -2, 2) / 3.0 * metres,
      Eigen::Vector3d(-2, 1, 2) / 3.0 * degrees * M_PI / 180;
  return se3_exp(xi) * T;
}

// (t, log R) of a pose: the step in the coordinates of the errors.
Vector6d pose_vector(const Eigen::Isometry3d& T) {
  Vector6d x;
  x << T.translation(), so3_log(T.linear());
  return x;
}

// Fewer draws leave the standard error itself too uncertain for a 3-standard-error test (with 7
// degrees of freedom the 99.7 % point of Student's t is already 4.8).
constexpr std::size_t kMinDrawsToJudge = 8;

std::string verdict_line(const Study& s) {
  if (s.used < kMinDrawsToJudge)
    return "too few usable draws to judge the bias (use --draws 8 or more)";
  const bool significant = s.bias_t_se > 3.0 || s.bias_r_se > 3.0;
  if (!significant) return "no bias measurable: the mean error is within 3 standard errors of zero";
  if (s.bias_t > s.spread_t || s.bias_r > s.spread_r)
    return "the bias dominates: the mean error exceeds the spread about it";
  return "a bias is measurable (more than 3 standard errors) but smaller than the spread";
}

void write_text(std::ostream& out, const Study& s) {
  char line[256];
  out << "draw   t error (mm)  r error (mrad)  iterations  rejected  verdict\n";
  for (std::size_t i = 0; i < s.draws.size(); ++i) {
    const Draw& d = s.draws[i];
    std::snprintf(line, sizeof(line), "%4zu   %12.3f  %14.3f  %10d  %8d  %s\n", i,
                  1e3 * d.error.head<3>().norm(), 1e3 * d.error.tail<3>().norm(), d.iterations,
                  d.rejected, d.verdict.c_str());
    out << line;
  }
  if (s.used < s.draws.size())
    out << "\n"
        << s.draws.size() - s.used << " of " << s.draws.size()
        << " draws failed (verdict above) and are left out of what follows\n";
  out << "\n              t_x      t_y      t_z  (mm)     w_x      w_y      w_z  (mrad)\n";
  auto row = [&](const char* name, const Vector6d& x) {
    std::snprintf(line, sizeof(line), "%-10s %8.3f %8.3f %8.3f      %8.3f %8.3f %8.3f\n", name,
                  1e3 * x(0), 1e3 * x(1), 1e3 * x(2), 1e3 * x(3), 1e3 * x(4), 1e3 * x(5));
    out << line;
  };
  row("mean", s.mean);
  row("std error", s.sd / std::sqrt(static_cast<double>(s.used)));
  row("sd", s.sd);
  std::snprintf(line, sizeof(line),
                "\nRMS error   t %.3f mm   r %.3f mrad\n"
                "bias        t %.3f mm (%.1f standard errors)   r %.3f mrad (%.1f)\n"
                "spread      t %.3f mm   r %.3f mrad   (predicted by the method: t %.3f mm   r "
                "%.3f mrad)\n",
                1e3 * s.rms_t, 1e3 * s.rms_r, 1e3 * s.bias_t, s.bias_t_se, 1e3 * s.bias_r,
                s.bias_r_se, 1e3 * s.spread_t, 1e3 * s.spread_r, 1e3 * s.predicted_t,
                1e3 * s.predicted_r);
  out << line;
  if (std::isfinite(s.normal_error)) {
    std::snprintf(line, sizeof(line),
                  "normals     %.2f deg from the true ones after refinement (%.2f from Quad IT)\n",
                  s.normal_error * 180 / M_PI, s.normal_error_initial * 180 / M_PI);
    out << line;
  }
  out << verdict_line(s) << '\n';
}

void write_json(std::ostream& out, const Study& s, const Eigen::Isometry3d& step) {
  JsonWriter json(out);
  auto vec = [](const Vector6d& x) { return std::vector<double>(x.data(), x.data() + 6); };
  json.begin_object()
      .field("draws", s.draws.size())
      .field("usable_draws", s.used)  // the statistics below are over these
      .field("step_translation_m", step.translation().norm())
      .field("step_rotation_rad", rotation_angle(step.linear()))
      .field("step", vec(pose_vector(step)))
      .field("rms_translation_m", s.rms_t)
      .field("rms_rotation_rad", s.rms_r)
      .field("bias_translation_m", s.bias_t)
      .field("bias_rotation_rad", s.bias_r)
      .field("bias_translation_standard_errors", s.bias_t_se)
      .field("bias_rotation_standard_errors", s.bias_r_se)
      .field("spread_translation_m", s.spread_t)
      .field("spread_rotation_rad", s.spread_r)
      .field("predicted_translation_sd_m", s.predicted_t)
      .field("predicted_rotation_sd_rad", s.predicted_r);
  if (std::isfinite(s.normal_error))
    json.field("normal_error_rad", s.normal_error)
        .field("normal_error_initial_rad", s.normal_error_initial);
  json.field("mean_error", vec(s.mean))
      .field("sd_error", vec(s.sd))
      .field("verdict", verdict_line(s));
  json.key("errors").begin_array();
  for (const Draw& d : s.draws) {
    json.begin_array();
    for (int i = 0; i < 6; ++i)
      json.value(d.error(i));
    json.end_array();
  }
  json.end_array().key("draw_verdicts").begin_array();
  for (const Draw& d : s.draws)
    json.value(d.verdict);
  json.end_array().end_object();
  out << '\n';
}

// The error of an estimate T of `truth`, in the coordinates of the predicted spread.
Vector6d pose_error(const Eigen::Isometry3d& T, const Eigen::Isometry3d& truth) {
  Vector6d e = pose_vector(T) - pose_vector(truth);
  e.tail<3>() = so3_log(T.linear() * truth.linear().transpose());
  return e;
}

// The mean angle (rad) between the quadrics' normals and the true normals, over the pixels with
// both; NaN where there are none.
double mean_normal_error(const QuadricMap& quadrics, const NormalMap& truth) {
  double sum = 0.0;
  long count = 0;
  for (int v = 0; v < quadrics.height(); ++v)
    for (int u = 0; u < quadrics.width(); ++u) {
      const Eigen::Vector3f& n = truth(u, v);
      if (!quadrics.valid(u, v) || !std::isfinite(n.z())) continue;
      const double c = quadrics.quadrics(u, v).normal().cast<double>().dot(n.cast<double>());
      sum += std::acos(std::clamp(c, -1.0, 1.0));
      ++count;
    }
  return count > 0 ? sum / static_cast<double>(count) : NAN;
}

Draw refine_draw(const Refiner& refiner, const QuadricFit& fit,
                 const std::vector<VertexMap>& vertices, const CameraIntrinsics& camera,
                 const NormalMap& true_normals, const Eigen::Isometry3d& start,
                 const Eigen::Isometry3d& truth) {
  const QuadricMap initial = fit.estimate(vertices[0]);
  const RefinementResult r =
      refiner.refine(vertices, camera, {Eigen::Isometry3d::Identity(), start}, initial);
  Draw d;
  d.normal_error_initial = mean_normal_error(initial, true_normals);
  d.normal_error = mean_normal_error(r.quadrics, true_normals);
  d.error = pose_error(r.poses[1], truth);
  d.verdict = to_string(r.report.verdict);
  d.usable = usable(r.report.verdict);
  d.iterations = r.report.iterations;
  d.rejected = r.report.rejected_steps;
  if (!r.report.translation_sd.empty()) {
    d.predicted_t = r.report.translation_sd[0];
    d.predicted_r = r.report.rotation_sd[0];
  }
  return d;
}

// ICP-ftf aligns frame 2 (source) to frame 1 (target): its pose is T₂ as the refiners'.
Draw icp_draw(const FrontendParams& params, const std::vector<DepthImage>& depth,
              const CameraIntrinsics& camera, const Eigen::Isometry3d& start,
              const Eigen::Isometry3d& truth) {
  const FramePyramid target = preprocess(Frame{0.0, depth[0], camera, {}}, params.preprocess);
  const FramePyramid source = preprocess(Frame{0.0, depth[1], camera, {}}, params.preprocess);
  const IcpResult r = align_point_to_plane(source, target, start, params.icp);
  Draw d;
  d.error = pose_error(r.pose, truth);
  d.verdict = to_string(r.verdict);
  d.usable = r.verdict == IcpVerdict::ok;
  d.iterations = r.iterations;
  const PoseSpread spread = pose_spread(r.covariance, r.pose);
  d.predicted_t = spread.translation_m;
  d.predicted_r = spread.rotation_rad;
  return d;
}

}  // namespace

int run_noise(int argc, char** argv) {
  cli::Arguments args(
      "jpcr_eval noise",
      "Monte-Carlo study of a pair method on one step of a synthetic walk: over\n"
      "fresh sensor-noise draws on the same two rendered frames, the mean pose error\n"
      "(the bias) with its standard error, the spread about it, and the spread the\n"
      "method predicts. Errors: t - t_true in mm, log(R R_true^T) in mrad.");
  args.option("method", "j-ftf | q-full | icp-ftf (the front end, the peer)", "j-ftf")
      .option("scene", "scene name (jpcr_synth --help lists them) or scene .yaml", "room_spheres")
      .option("size", "image size WIDTHxHEIGHT", "320x240")
      .option("noise", "noise model: range:K (K % of the range along the ray) | kinect | none",
              "range:1")
      .option("draws", "noise draws, 2-1000", "8")
      .option("walk-seed", "seed of the walk trajectory", "1")
      .option("step", "which step of the walk (frames step and step + 1)", "0")
      .option("motion", "scale of that step's motion (0: both frames at the same pose)", "1")
      .option("start-offset", "start this far from the true pose: 'MM,DEG' (e.g. 5,0.2)", "0,0")
      .option("seed", "seed of the first noise draw (draw i uses seed + i)", "1000")
      .option("params",
              "parameter YAML (sections quadric, joint, frontend; pipeline.filtered_depth: "
              "J-ftf / Q-full on the bilateral-filtered depth), as jpcr_run --params")
      .flag("noise-matched",
            "the report's rules for range:K: n0 = gate = 3 sigma per metre of range, and "
            "ICP-ftf's bilateral filter at 0.05 K m; overrides the parameter file there")
      .flag("json", "print JSON instead of text")
      .epilog(
          "examples:\n"
          "  jpcr_eval noise --noise range:3 --noise-matched --draws 8\n"
          "  jpcr_eval noise --noise range:3 --noise-matched --motion 0     # no motion\n"
          "  jpcr_eval noise --noise range:3 --noise-matched --start-offset 5,0.2");
  cli::add_device_option(args, "J-ftf (Quad IT, which starts it, and ICP-ftf run on the CPU)");
  return cli::run_program("jpcr_eval noise", [&] {
    if (!args.parse(argc, argv)) return 0;
    const std::string method = args.get("method");
    if (method != "j-ftf" && method != "q-full" && method != "icp-ftf")
      throw cli::UsageError("--method expects j-ftf, q-full or icp-ftf, got '" + method + "'");
    int width = 0, height = 0;
    cli::parse_image_size("size", args.get("size"), width, height);
    const int draws = args.get_int("draws"), step = args.get_int("step");
    if (draws < 2 || draws > 1000) throw cli::UsageError("--draws must be 2-1000");
    if (step < 0 || step > 10000) throw cli::UsageError("--step must be 0-10000");
    if (args.get_int("walk-seed") < 0 || args.get_int("seed") < 0)
      throw cli::UsageError("--walk-seed and --seed must be >= 0");
    const double motion = args.get_double("motion");
    if (!std::isfinite(motion) || std::abs(motion) > 100)
      throw cli::UsageError("--motion must be a finite scale within ±100");
    double offset_mm = 0.0, offset_deg = 0.0;
    int consumed = 0;
    const std::string offset = args.get("start-offset");
    if (std::sscanf(offset.c_str(), "%lf,%lf%n", &offset_mm, &offset_deg, &consumed) != 2 ||
        consumed != static_cast<int>(offset.size()) || !std::isfinite(offset_mm) ||
        !std::isfinite(offset_deg))
      throw cli::UsageError("--start-offset expects MM,DEG (e.g. 5,0.2), got '" + offset + "'");
    if (std::abs(offset_mm) > 1000 || std::abs(offset_deg) > 90)
      throw cli::UsageError("--start-offset must be within 1000 mm and 90 deg, got '" + offset +
                            "'");
    NoiseModel noise;
    try {
      noise = parse_noise(args.get("noise"));
    } catch (const InputError& e) {
      throw cli::UsageError(std::string("--noise: ") + e.what());
    }

    Params params = args.has("params") ? load_params(args.get("params")) : Params{};
    if (args.get_flag("noise-matched")) {
      if (noise.kind != NoiseKind::kRange || !(noise.range_percent > 0.0))
        throw cli::UsageError("--noise-matched needs --noise range:K with K > 0");
      const float per_range = static_cast<float>(3.0 * noise.range_percent / 100.0);
      params.joint.quadric.fit.fair_n0_per_range = per_range;
      params.joint.quadric.fit.gate_per_range = per_range;
      params.frontend.preprocess.bilateral = true;
      params.frontend.preprocess.bilateral_sigma_depth =
          static_cast<float>(0.05 * noise.range_percent);
    }
    params.joint.validate();
    params.frontend.validate();

    SyntheticSequenceOptions o;
    o.scene = args.get("scene");
    o.frames = step + 2;
    o.width = width;
    o.height = height;
    o.seed = static_cast<std::uint64_t>(args.get_int("walk-seed"));
    if (method != "icp-ftf") cli::check_quadric_pattern(args, params.joint.quadric, width);
    const SyntheticSequence sequence = make_synthetic_sequence(o);
    const CameraIntrinsics& camera = sequence.camera();
    const Eigen::Isometry3d first = *sequence.ground_truth(static_cast<std::size_t>(step));
    const Eigen::Isometry3d truth =
        se3_exp(motion * se3_log(first.inverse() *
                                 *sequence.ground_truth(static_cast<std::size_t>(step) + 1)));
    const SyntheticFrame frames[2] = {render(sequence.scene(), camera, first),
                                      render(sequence.scene(), camera, first * truth)};
    const Eigen::Isometry3d start = offset_start(truth, 1e-3 * offset_mm, offset_deg);
    const std::unique_ptr<Refiner> refiner =
        method == "icp-ftf"
            ? nullptr
            : make_refiner(method, params.joint, cli::device_from(args, params), std::cerr);
    const QuadricFit fit(params.joint.quadric);

    std::fprintf(stderr,
                 "jpcr_eval noise: %s on %s %dx%d, %s, walk seed %d step %d x %.3g (%.2f mm, "
                 "%.3f deg apart), start %.3g mm / %.3g deg off, %d draws\n",
                 method.c_str(), o.scene.c_str(), width, height, noise.describe().c_str(),
                 args.get_int("walk-seed"), step, motion, 1e3 * truth.translation().norm(),
                 rotation_angle(truth.linear()) * 180 / M_PI, offset_mm, offset_deg, draws);
    std::vector<Draw> results;
    const std::uint64_t seed = static_cast<std::uint64_t>(args.get_int("seed"));
    for (int i = 0; i < draws; ++i) {
      std::vector<DepthImage> noisy;
      std::vector<VertexMap> vertices;
      for (int f = 0; f < 2; ++f) {
        noisy.push_back(
            add_depth_noise(frames[f].exact_depth, frames[f].normals, camera, noise, seed + i, f));
        // The refiners see the raw depth, or with pipeline.filtered_depth the front end's
        // bilateral filter of it, as in the pipeline (pipeline_back_end.cpp).
        vertices.push_back(
            compute_vertex_map(params.pipeline.filtered_depth
                                   ? bilateral_filter(noisy.back(), params.frontend.preprocess)
                                   : noisy.back(),
                               camera));
      }
      const Draw d =
          refiner ? refine_draw(*refiner, fit, vertices, camera, frames[0].normals, start, truth)
                  : icp_draw(params.frontend, noisy, camera, start, truth);
      results.push_back(d);
      std::fprintf(stderr, "jpcr_eval noise: draw %d/%d  %.3f mm  %.3f mrad  %s\n", i + 1, draws,
                   1e3 * d.error.head<3>().norm(), 1e3 * d.error.tail<3>().norm(),
                   d.verdict.c_str());
    }
    const Study study = summarize(std::move(results));
    // A failed draw's pose is its start, so counting it would report the start's error (zero
    // from the true pose) as the method's.
    if (study.used < 2)
      throw InputError(method + " gave a usable result in " + std::to_string(study.used) + " of " +
                       std::to_string(draws) + " draws (verdict of draw 1: " +
                       study.draws[0].verdict + "): too few for statistics");
    if (args.get_flag("json"))
      write_json(std::cout, study, truth);
    else
      write_text(std::cout, study);
    return 0;
  });
}

}  // namespace jpcr::eval
