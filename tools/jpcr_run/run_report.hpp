// What jpcr_run writes besides the curvature maps: the JSON report (per-frame front-end
// verdicts, per-keyframe refinement reports, timings), the per-frame verdicts beside the
// trajectory and, with ground truth, the error table.
#pragma once

#include <cstddef>
#include <map>
#include <optional>
#include <ostream>
#include <string>

#include "jpcr/backend/keyframe_pipeline.hpp"
#include "jpcr/io/trajectory_metrics.hpp"

namespace jpcr::run {

/// Errors of one trajectory against ground truth.
struct TrajectoryErrors {
  AteResult ate;
  RpeResult rpe;            // per frame
  RelativeErrors relative;  // the paper's tables
};

std::optional<TrajectoryErrors> evaluate(const Trajectory& ground_truth,
                                         const Trajectory& estimate);

/// What the run was given, for the report: a result says what it came from.
struct RunInputs {
  std::string dataset;
  std::size_t first_frame = 0;  // the dataset's index of the run's frame 0 (--frames FIRST:LAST)
  std::string config, params;   // the files given, empty for none
  std::string device;           // --device or the parameter file's, as requested
};

/// report.json: the inputs, the trust summary (frames trusted, the causes of the others), the
/// errors against ground truth, and per frame and keyframe the verdicts and reports.
void write_report(std::ostream& out, const RunInputs& inputs, const KeyframePipeline& pipeline,
                  const std::optional<TrajectoryErrors>& front_end,
                  const std::optional<TrajectoryErrors>& refined, double seconds);

/// verdicts.txt: a comment header, then one line per frame, "timestamp front_end pair window
/// trusted" (FrameVerdicts; "-" where a refinement did not run, trusted "yes" or "no").
void write_verdicts(std::ostream& out, const KeyframePipeline& pipeline);

/// One warning line when frames are not trusted (verdicts.txt's last column), with the failures
/// by kind, e.g. "7 of 8 frames are not trusted (front end: 7 too_few_points; window: 3
/// degenerate)"; empty when every frame is.
std::string untrusted_warning(const KeyframePipeline& pipeline);

/// The untrusted frames by cause: "front_end: degenerate", "pair: diverged", "window:
/// too_few_quadrics", ... (a frame counts once under each verdict that fails it).
std::map<std::string, std::size_t> untrusted_causes(const KeyframePipeline& pipeline);

/// "method  ATE m  RPE m/frame  RPE deg/frame  rel. transl. m  rel. rot. rad" rows, then
/// "frames trusted: T of N (verdicts.txt)", so that the numbers never stand without it.
void print_error_table(std::ostream& out, const std::string& method,
                       const std::optional<TrajectoryErrors>& front_end,
                       const std::optional<TrajectoryErrors>& refined,
                       const KeyframePipeline& pipeline);

}  // namespace jpcr::run
