// jpcr_eval curvature: RMS principal-curvature error and coverage of estimated maps against the
// ground truth that jpcr_synth writes (DIR/curvature/<stamp>.npy in both directories).
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <iostream>
#include <optional>
#include <set>
#include <string>

#include "cli/arguments.hpp"
#include "jpcr/io/atomic_file.hpp"
#include "jpcr/io/curvature_metrics.hpp"
#include "jpcr/io/curvature_output.hpp"
#include "jpcr/io/json_writer.hpp"
#include "jpcr/io/staged_output.hpp"
#include "jpcr/quadric/error.hpp"
#include "jpcr/quadric/quadric_params.hpp"
#include "jpcr_eval/eval_commands.hpp"

namespace jpcr::eval {

namespace {

namespace fs = std::filesystem;

// The stamps of DIR/curvature/*.npy, sorted.
std::set<std::string> curvature_stamps(const std::string& dir) {
  const fs::path folder = fs::path(dir) / "curvature";
  std::error_code ec;
  if (!fs::is_directory(folder, ec))
    throw InputError(folder.string() + ": no curvature/ directory (expected <stamp>.npy maps)");
  std::set<std::string> stamps;
  for (const fs::directory_entry& e : fs::directory_iterator(folder, ec))
    if (e.path().extension() == ".npy") stamps.insert(e.path().stem().string());
  return stamps;
}

// --support: a radius in pixels, or "pattern": the span of the default fit pattern (method.md
// §2, ±18 px at 640 wide) at the maps' width, so interior pixels are those whose whole pattern
// lies on one smooth surface.
int support_radius(const std::string& text, int width) {
  if (text == "pattern") return PatternParams{}.for_width(width).span();
  std::size_t end = 0;
  int r = -1;
  try {
    r = std::stoi(text, &end);
  } catch (const std::exception&) {
  }
  if (end != text.size() || r < 0 || r > CurvatureErrorAccumulator::kMaxSupportRadius)
    throw cli::UsageError("--support: expected a radius in pixels (0.." +
                          std::to_string(CurvatureErrorAccumulator::kMaxSupportRadius) +
                          ") or 'pattern', got '" + text + "'");
  return r;
}

// `frames` compared, of `estimated` maps and `with_truth` ground-truth maps: coverage counts the
// compared frames only, so a method that returns a map for few frames shows it here.
// `with_sd`: compared maps with an sd map (its fields are written then, even when every sd of
// the compared pixels was withheld).
void write_json(std::ostream& out, const CurvatureErrors& e, std::size_t estimated,
                std::size_t with_truth, std::size_t with_sd) {
  JsonWriter json(out);
  json.begin_object()
      .field("frames", e.frames)
      .field("estimated_frames", estimated)
      .field("gt_frames", with_truth)
      .field("rms_k1", e.rms_k1)
      .field("rms_k2", e.rms_k2)
      .field("rms", e.rms)
      .field("median_abs", e.median_abs)
      .field("coverage", e.coverage)
      .field("compared_pixels", e.compared)
      .field("gt_valid_pixels", e.gt_valid)
      .field("support_radius_px", e.support_radius);
  if (with_sd > 0)  // the estimate has sd maps (jpcr_run, jpcr_curvature with Quad IT)
    json.field("sd_maps", with_sd)
        .field("sd_compared_pixels", e.sd_compared)
        .field("sd_rms", e.sd_rms)
        .field("rms_where_sd", e.rms_where_sd)
        .field("within_2sd", e.within_2sd);
  json.end_object();
  out << '\n';
}

}  // namespace

int run_curvature(int argc, char** argv) {
  cli::Arguments args(
      "jpcr_eval curvature",
      "Principal-curvature error against ground truth: RMS of k1 and k2 (1/m) over\n"
      "pixels valid in both, median absolute error, and coverage (the fraction of\n"
      "ground-truth pixels of the compared frames the estimate covers). Frames are\n"
      "matched by stamp (GT/curvature/<stamp>.npy and EST/curvature/<stamp>.npy).\n"
      "With --support R only interior pixels count: those whose (2R+1)x(2R+1) window\n"
      "has ground truth everywhere, so a patch fit of radius R sees one smooth surface\n"
      "(no crease, rim or silhouette in it). Where EST has sd maps\n"
      "(EST/curvature_sd/<stamp>.npy, jpcr_run and jpcr_curvature write them), it also says\n"
      "how well they describe the error: RMS sd against RMS error over the pixels with an\n"
      "sd, and the fraction of errors within 2 sd (about 98 % when they describe it).");
  args.required("gt", "ground-truth directory (jpcr_synth output)")
      .required("est", "estimate directory (jpcr_curvature or jpcr_run output)")
      .option("support",
              "R in px, or 'pattern' (the fit's span: 18 px at 640 wide); 0 = every pixel", "0")
      .option("out", "also write the JSON report to this file")
      .flag("json", "print JSON instead of text")
      .epilog("example:\n  jpcr_eval curvature --gt seq --est seq_it --json");
  return cli::run_program("jpcr_eval curvature", [&] {
    if (!args.parse(argc, argv)) return 0;
    const std::string support = args.get("support");
    if (support != "pattern") support_radius(support, 0);  // a bad value fails before any read
    if (args.has("out")) {
      for (const char* input : {"gt", "est"})
        require_output_file_apart_from(args.get("out"), args.get(input), std::string("--") + input);
      require_not_dataset_or_results_file(args.get("out"));
    }
    const std::set<std::string> gt = curvature_stamps(args.get("gt"));
    const std::set<std::string> est = curvature_stamps(args.get("est"));
    std::optional<CurvatureErrorAccumulator> acc;
    std::size_t infinite = 0;   // estimate pixels at ±Inf: counted as missing, and said so
    std::size_t unordered = 0;  // κ1 < κ2: another convention (swapped channels, flipped sign)
    std::size_t unmatched = 0;  // estimated maps whose stamp has no ground truth: not compared
    std::size_t with_sd = 0;    // compared maps with an sd map
    std::size_t bad_sd = 0;     // sd pixels at ±Inf or below 0: left out, and said so
    for (const std::string& stamp : est) {
      if (!gt.count(stamp)) {
        ++unmatched;
        continue;
      }
      const std::string name = "curvature/" + stamp + ".npy";
      const std::string gt_file = (fs::path(args.get("gt")) / name).string();
      const CurvatureImage truth = read_curvature_npy(gt_file);
      if (!acc) acc.emplace(support_radius(support, truth.width()));
      const std::string est_file = (fs::path(args.get("est")) / name).string();
      const fs::path sd_file = fs::path(args.get("est")) / "curvature_sd" / (stamp + ".npy");
      std::error_code ec;
      try {
        const CurvatureImage estimate = read_curvature_npy(est_file);
        if (estimate.width() != truth.width() || estimate.height() != truth.height())
          throw InputError(est_file + ": the map is " + std::to_string(estimate.width()) + "x" +
                           std::to_string(estimate.height()) + " but its ground truth " + gt_file +
                           " is " + std::to_string(truth.width()) + "x" +
                           std::to_string(truth.height()));
        for (const Eigen::Vector2f& k : estimate) {
          infinite += k.array().isInf().any() ? 1 : 0;
          unordered += k.x() < k.y() ? 1 : 0;  // false with a NaN
        }
        // An sd map is optional per stamp (maps from Quad LS have none). Its errors name it,
        // not the curvature map (below).
        std::optional<Image<float>> sd;
        if (fs::exists(sd_file, ec)) {
          sd = read_curvature_sd_npy(sd_file.string());
          ++with_sd;
          for (const float s : *sd)
            bad_sd += std::isinf(s) || s < 0.0f ? 1 : 0;  // NaN: withheld, not bad
        }
        acc->add(truth, estimate, sd ? &*sd : nullptr);
      } catch (const InputError& e) {  // name the map, not only the problem (once)
        const std::string what = e.what();
        if (what.rfind(est_file + ": ", 0) == 0 || what.rfind(sd_file.string() + ": ", 0) == 0)
          throw;
        if (what.rfind("the sd map is ", 0) == 0) throw InputError(sd_file.string() + ": " + what);
        throw InputError(est_file + ": " + what);
      }
    }
    if (unmatched > 0)
      std::cerr << "jpcr_eval curvature: warning: " << unmatched << " of " << est.size()
                << " maps of " << args.get("est") << " have no ground truth of their stamp in "
                << args.get("gt") << "; they are not compared\n";
    if (bad_sd > 0)
      std::cerr << "jpcr_eval curvature: warning: " << bad_sd << " sd pixels of " << args.get("est")
                << "/curvature_sd are +-Inf or negative; they are left out (an sd map marks "
                   "pixels without one with NaN)\n";
    if (infinite > 0)
      std::cerr << "jpcr_eval curvature: warning: " << infinite << " pixels of " << args.get("est")
                << " are +-Inf; they count as missing (a map marks invalid pixels with NaN)\n";
    if (unordered > 0)
      std::cerr << "jpcr_eval curvature: warning: " << unordered << " pixels of " << args.get("est")
                << " have k1 < k2: method.md section 1 orders k1 >= k2 (negative where the surface "
                   "bulges toward the camera); swapped channels or another sign convention?\n";
    const CurvatureErrors e = acc ? acc->result() : CurvatureErrors{};
    if (e.frames == 0)
      throw InputError(args.get("est") + ": no curvature map shares a stamp with " +
                       args.get("gt"));
    if (e.compared == 0)  // nothing to average: the RMS would be NaN
      throw InputError(args.get("est") + ": no pixel is valid in both it and " + args.get("gt") +
                       (e.support_radius > 0 ? " with --support " + support : std::string()) +
                       " (" + std::to_string(e.gt_valid) + " valid ground-truth pixels)");
    if (args.has("out")) {
      ensure_parent_directory(args.get("out"));
      write_file_atomically(args.get("out"), [&](std::ostream& out) {
        write_json(out, e, est.size(), gt.size(), with_sd);
      });
    }
    if (args.get_flag("json")) {
      write_json(std::cout, e, est.size(), gt.size(), with_sd);
    } else {
      std::printf("frames: %zu compared (%zu estimated, %zu with ground truth)\n", e.frames,
                  est.size(), gt.size());
      std::printf("rms k1 %.4f 1/m  rms k2 %.4f 1/m  rms %.4f 1/m  median |err| %.4f 1/m\n",
                  e.rms_k1, e.rms_k2, e.rms, e.median_abs);
      std::printf("coverage %.2f %% (%zu of %zu ground-truth pixels of the compared frames%s)\n",
                  100.0 * e.coverage, e.compared, e.gt_valid,
                  e.support_radius > 0 ? ", interior only" : "");
      if (with_sd > 0 && e.sd_compared == 0)
        std::printf("sd (%zu of the frames' maps): none at the compared pixels (withheld)\n",
                    with_sd);
      else if (e.sd_compared > 0) {
        char ratio[32] = "-";  // an sd of 0 everywhere: no ratio
        if (e.sd_rms > 0.0) std::snprintf(ratio, sizeof ratio, "%.3f", e.rms_where_sd / e.sd_rms);
        std::printf(
            "sd (%zu of the frames' maps, %zu pixels): rms sd %.4f 1/m against rms error "
            "%.4f 1/m there (ratio %s), %.1f %% of errors within 2 sd\n",
            with_sd, e.sd_compared, e.sd_rms, e.rms_where_sd, ratio, 100.0 * e.within_2sd);
      }
    }
    return 0;
  });
}

}  // namespace jpcr::eval
