// jpcr_eval traj: ATE, RPE, paper-style relative errors and drift of an estimated trajectory.
#include <cmath>
#include <cstdio>
#include <iostream>
#include <optional>
#include <sstream>

#include "cli/arguments.hpp"
#include "jpcr/io/atomic_file.hpp"
#include "jpcr/io/json_writer.hpp"
#include "jpcr/io/staged_output.hpp"
#include "jpcr/io/trajectory_comparison.hpp"
#include "jpcr/io/trajectory_metrics.hpp"
#include "jpcr/io/tum_lists.hpp"
#include "jpcr/quadric/error.hpp"
#include "jpcr_eval/eval_commands.hpp"

namespace jpcr::eval {

namespace {

struct TrajectoryReport {
  std::size_t gt_poses = 0, est_poses = 0;
  AteResult ate;
  RpeResult rpe_frame;
  std::optional<RpeResult> rpe_second;  // absent when no pair 1 s apart could be formed ...
  std::string rpe_second_missing;       // ... and why
  RelativeErrors relative;
  DriftCurve drift;
  std::optional<PairedComparison> baseline;  // --baseline: est against it, per frame pair
};

constexpr const char* kNoRelativePairs =
    "no two consecutive estimated poses both have ground truth within --max-difference";

double associated_fraction(const TrajectoryReport& r) {
  return static_cast<double>(r.ate.translation.count) / static_cast<double>(r.est_poses);
}

void write_statistics(JsonWriter& json, const char* name, const ErrorStatistics& s) {
  json.key(name).begin_object();
  json.field("rmse", s.rmse).field("mean", s.mean).field("median", s.median);
  json.field("max", s.max).field("count", s.count);
  json.end_object();
}

void write_json(std::ostream& out, const TrajectoryReport& r) {
  JsonWriter json(out);
  json.begin_object();
  json.field("gt_poses", r.gt_poses).field("est_poses", r.est_poses);
  // How much of the estimate the errors describe: its poses with ground truth within
  // --max-difference (the ATE's pairs).
  json.field("associated_poses", r.ate.translation.count)
      .field("associated_fraction", associated_fraction(r));
  json.key("ate");
  json.begin_object();
  write_statistics(json, "translation_m", r.ate.translation);
  json.end_object();
  json.key("rpe_per_frame").begin_object();
  write_statistics(json, "translation_m", r.rpe_frame.translation);
  write_statistics(json, "rotation_deg", r.rpe_frame.rotation);
  json.end_object();
  json.key("rpe_per_second");
  if (r.rpe_second) {
    json.begin_object();
    write_statistics(json, "translation_m", r.rpe_second->translation);
    write_statistics(json, "rotation_deg", r.rpe_second->rotation);
    json.end_object();
  } else {
    json.null();
    json.field("rpe_per_second_missing", r.rpe_second_missing);
  }
  json.key("relative");
  if (r.relative.pairs > 0) {
    json.begin_object();
    json.field("translation_rms_m", r.relative.translation_rms);
    json.field("rotation_rms_rad", r.relative.rotation_rms);
    json.field("pairs", r.relative.pairs);
    json.end_object();
  } else {  // 0 is a perfect score, not "not computed"
    json.null();
    json.field("relative_missing", std::string(kNoRelativePairs));
  }
  json.key("drift").begin_object();
  json.field("distance_m", r.drift.distance.empty() ? 0.0 : r.drift.distance.back());
  json.field("final_translation_m", r.drift.translation.empty() ? 0.0 : r.drift.translation.back());
  json.field("final_rotation_deg", r.drift.rotation.empty() ? 0.0 : r.drift.rotation.back());
  json.field("translation_per_metre", r.drift.translation_per_metre);
  json.field("rotation_deg_per_metre", r.drift.rotation_per_metre);
  json.field("curve_distance_m", r.drift.distance);
  json.field("curve_translation_m", r.drift.translation);
  json.field("curve_rotation_deg", r.drift.rotation);
  json.end_object();
  if (r.baseline) {
    json.key("baseline").begin_object();
    json.field("pairs", r.baseline->pairs).field("block", r.baseline->block);
    for (const auto& [name, ratio] : {std::pair{"translation", r.baseline->translation},
                                      std::pair{"rotation", r.baseline->rotation}}) {
      json.key(name).begin_object();
      json.field("ratio", ratio.ratio).field("low", ratio.low).field("high", ratio.high);
      json.field("verdict", std::string(ratio.verdict()));
      json.end_object();
    }
    json.end_object();
  }
  json.end_object();
}

void write_text(std::ostream& out, const TrajectoryReport& r) {
  char line[256];
  std::snprintf(line, sizeof(line),
                "poses: %zu ground truth, %zu estimated, %zu of them with ground truth (%.1f %%)\n",
                r.gt_poses, r.est_poses, r.ate.translation.count, 100.0 * associated_fraction(r));
  out << line;
  const ErrorStatistics& a = r.ate.translation;
  std::snprintf(line, sizeof(line),
                "ATE            rmse %.6f m   mean %.6f  median %.6f  max %.6f  (%zu pairs)\n",
                a.rmse, a.mean, a.median, a.max, a.count);
  out << line;
  std::snprintf(
      line, sizeof(line), "RPE per frame  rmse %.6f m   %.6f deg              (%zu pairs)\n",
      r.rpe_frame.translation.rmse, r.rpe_frame.rotation.rmse, r.rpe_frame.translation.count);
  out << line;
  if (r.rpe_second) {
    std::snprintf(line, sizeof(line),
                  "RPE per second rmse %.6f m/s %.6f deg/s            (%zu pairs)\n",
                  r.rpe_second->translation.rmse, r.rpe_second->rotation.rmse,
                  r.rpe_second->translation.count);
    out << line;
  } else {
    out << "RPE per second n/a (" << r.rpe_second_missing << ")\n";
  }
  if (r.relative.pairs > 0) {
    std::snprintf(
        line, sizeof(line),
        "relative (paper Tables I-III) translation %.3e m  rotation %.3e rad (%zu pairs)\n",
        r.relative.translation_rms, r.relative.rotation_rms, r.relative.pairs);
    out << line;
  } else {
    out << "relative (paper Tables I-III) n/a (" << kNoRelativePairs << ")\n";
  }
  if (!r.drift.distance.empty()) {
    std::snprintf(
        line, sizeof(line),
        "drift          %.6f m and %.4f deg after %.3f m travelled (%.3f %%, %.4f deg/m)\n",
        r.drift.translation.back(), r.drift.rotation.back(), r.drift.distance.back(),
        100.0 * r.drift.translation_per_metre, r.drift.rotation_per_metre);
    out << line;
  }
  if (r.baseline) {
    const PairedComparison& c = *r.baseline;
    std::snprintf(line, sizeof(line),
                  "against the baseline, relative error ratio est / baseline (95 %% interval, "
                  "paired block bootstrap over %zu frame pairs, blocks of %zu):\n",
                  c.pairs, c.block);
    out << line;
    for (const auto& [name, ratio] :
         {std::pair{"translation", c.translation}, std::pair{"rotation", c.rotation}}) {
      std::snprintf(line, sizeof(line), "  %-11s %.4f  [%.4f, %.4f]  %s\n", name, ratio.ratio,
                    ratio.low, ratio.high, ratio.verdict());
      out << line;
    }
  }
}

}  // namespace

int run_trajectory(int argc, char** argv) {
  cli::Arguments args("jpcr_eval traj",
                      "Trajectory error against ground truth, with the TUM RGB-D benchmark "
                      "conventions:\nATE (Horn alignment, no scale), RPE per frame and per second "
                      "(no alignment),\npaper-style RMS relative translation (m) and rotation "
                      "(rad), and drift against\ndistance travelled.");
  args.required("gt", "ground-truth trajectory, TUM format (timestamp tx ty tz qx qy qz qw)")
      .required("est", "estimated trajectory, TUM format")
      .option("baseline",
              "a second estimate of the same frames (TUM format), e.g. ICP-ftf's: est's "
              "relative errors are compared with its on the frame pairs both have, with a 95 % "
              "interval of the ratio (better / worse / indistinguishable)")
      .option("max-difference",
              "timestamp association window in seconds (ATE, relative errors, drift; RPE pairs "
              "with ground truth as TUM's evaluate_rpe.py: within twice its median interval)",
              "0.02")
      .option("out", "also write the JSON report to this file")
      .flag("json", "print JSON instead of text")
      .epilog(
          "examples:\n  jpcr_eval traj --gt data/groundtruth.txt --est out/trajectory.txt --json\n"
          "  jpcr_eval traj --gt data/groundtruth.txt --est out/trajectory.txt \\\n"
          "      --baseline out/front_end.txt     # the pipeline against its ICP-ftf front end\n"
          "\n"
          "Files: one pose per line, fields separated by spaces or tabs, timestamps strictly\n"
          "increasing; '#' starts a comment. RPE per second follows evaluate_rpe.py: each\n"
          "pose is paired with the pose closest to 1 s later, so across a gap in the estimate\n"
          "a pair can span more or less than 1 s, even the pose itself (error 0). A warning\n"
          "says when fewer than 90 % of the estimated poses have ground truth.");
  return cli::run_program("jpcr_eval traj", [&] {
    if (!args.parse(argc, argv)) return 0;
    const double max_difference = args.get_double("max-difference");
    if (!(max_difference > 0.0) || !std::isfinite(max_difference))
      throw cli::UsageError("--max-difference must be a positive number of seconds");
    if (args.has("out")) {
      for (const char* input : {"gt", "est", "baseline"})
        if (args.has(input))
          require_output_file_apart_from(args.get("out"), args.get(input),
                                         std::string("--") + input);
      require_not_dataset_or_results_file(args.get("out"));
    }
    const Trajectory gt = read_trajectory(args.get("gt"));
    const Trajectory est = read_trajectory(args.get("est"));
    if (gt.empty()) throw InputError(args.get("gt") + ": no poses");
    if (est.empty()) throw InputError(args.get("est") + ": no poses");

    TrajectoryReport report;
    report.gt_poses = gt.size();
    report.est_poses = est.size();
    try {
      report.ate = compute_ate(gt, est, max_difference);
    } catch (const InputError& e) {
      throw InputError(args.get("est") + " against " + args.get("gt") + ": " + e.what());
    }
    // Finite poses far beyond any scene (1e308 m) overflow the alignment: say so, not "nan".
    if (!std::isfinite(report.ate.translation.rmse) || !std::isfinite(report.ate.translation.max))
      throw InputError(args.get("est") + ": the errors against " + args.get("gt") +
                       " are not finite (positions too large to align?)");
    try {
      report.rpe_frame = compute_rpe(gt, est, 1.0, DeltaUnit::kFrames);
    } catch (const InputError& e) {
      throw InputError(args.get("est") + " against " + args.get("gt") + ": " + e.what());
    }
    if (est.back().timestamp - est.front().timestamp > 1.0) {
      try {
        report.rpe_second = compute_rpe(gt, est, 1.0, DeltaUnit::kSeconds);
      } catch (const InputError&) {  // the estimate spans more than 1 s: the ground truth lacks
        report.rpe_second_missing = "no pose pair 1 s apart has ground truth at both ends";
      }
    } else {
      report.rpe_second_missing = "the estimate spans 1 s or less";
    }
    report.relative = compute_relative_errors(gt, est, max_difference);
    report.drift = compute_drift(gt, est, max_difference);
    if (args.has("baseline")) {
      const Trajectory base = read_trajectory(args.get("baseline"));
      try {
        report.baseline = compare_relative_errors(
            report.relative, compute_relative_errors(gt, base, max_difference));
      } catch (const InputError& e) {
        throw InputError(args.get("est") + " and the baseline " + args.get("baseline") + ": " +
                         e.what());
      }
    }
    if (associated_fraction(report) < 0.9)
      std::cerr << "jpcr_eval traj: warning: only " << report.ate.translation.count << " of "
                << report.est_poses << " estimated poses have ground truth within "
                << max_difference
                << " s; ATE, the relative errors and the drift describe those alone (RPE pairs "
                   "with ground truth within twice its median interval)\n";
    if (report.relative.pairs == 0)
      std::cerr << "jpcr_eval traj: warning: relative errors n/a: " << kNoRelativePairs << "\n";

    if (args.has("out")) {
      ensure_parent_directory(args.get("out"));
      write_file_atomically(args.get("out"), [&](std::ostream& out) { write_json(out, report); });
    }
    if (args.get_flag("json"))
      write_json(std::cout, report);
    else
      write_text(std::cout, report);
    return 0;
  });
}

}  // namespace jpcr::eval
