#include "jpcr_run/run_report.hpp"

#include <cstdio>
#include <map>
#include <sstream>

#include "jpcr/io/json_writer.hpp"
#include "jpcr/io/number_format.hpp"
#include "jpcr/io/synthetic_writer.hpp"
#include "jpcr/quadric/error.hpp"

namespace jpcr::run {

namespace {

void write_refinement(JsonWriter& json, const char* name,
                      const std::optional<RefinementReport>& r) {
  json.key(name);
  if (!r) {
    json.null();
    return;
  }
  json.begin_object().field("method", r->method).key("device");
  if (r->device.empty())
    json.null();  // the refiner threw (verdict "error")
  else
    json.value(r->device);
  json.field("verdict", to_string(r->verdict));
  if (!r->pose_verdicts.empty()) {  // q-full: each pose's own, T_2 … T_M
    json.key("pose_verdicts").begin_array();
    for (RefinementVerdict v : r->pose_verdicts)
      json.value(to_string(v));
    json.end_array();
  }
  json.field("iterations", r->iterations)
      .field("rejected_steps", r->rejected_steps)
      .field("cost", r->cost)
      .field("active_quadrics", r->active_quadrics)
      .field("edge_quadrics", r->edge_quadrics)  // left out, keeping their Quad IT fit
      .field("quad_it_fits_restored", r->quad_it_fits_restored)  // keep_lower_cost_fit
      .field("residual_variance", r->residual_variance)
      .field("sample_reuse", r->sample_reuse)  // the covariance's inflation (refiner.hpp)
      .field("degeneracy", r->degeneracy)
      // per pose after the reference: the predicted RMS error against the reference frame
      // (pose_spread, refiner.hpp), the spread under sensor noise, not the bias
      .field("translation_sd_m", r->translation_sd)
      .field("rotation_sd_rad", r->rotation_sd)
      .field("step_translation_sd_m", r->step_translation_sd)  // successive frames
      .field("step_rotation_sd_rad", r->step_rotation_sd)
      .field("isolated_frames",  // icp-bundle: window frames without terms at the end
             std::vector<double>(r->isolated.begin(), r->isolated.end()));
  if (!r->error.empty()) json.field("error", r->error);  // verdict "error": what was thrown
  json.end_object();
}

void write_errors(JsonWriter& json, const char* name, const std::optional<TrajectoryErrors>& e) {
  json.key(name);
  if (!e) {
    json.null();
    return;
  }
  json.begin_object()
      .field("ate_rmse_m", e->ate.translation.rmse)
      .field("rpe_frame_translation_rmse_m", e->rpe.translation.rmse)
      .field("rpe_frame_rotation_rmse_deg", e->rpe.rotation.rmse);
  if (e->relative.pairs > 0) {
    json.field("relative_translation_rms_m", e->relative.translation_rms)
        .field("relative_rotation_rms_rad", e->relative.rotation_rms);
  } else {  // no two consecutive frames with ground truth: not computed, not a perfect 0
    json.key("relative_translation_rms_m").null();
    json.key("relative_rotation_rms_rad").null();
  }
  json.end_object();
}

}  // namespace

std::optional<TrajectoryErrors> evaluate(const Trajectory& gt, const Trajectory& est) {
  if (gt.size() < 2 || est.size() < 2) return std::nullopt;
  try {
    return TrajectoryErrors{compute_ate(gt, est), compute_rpe(gt, est, 1.0, DeltaUnit::kFrames),
                            compute_relative_errors(gt, est)};
  } catch (const InputError&) {
    return std::nullopt;  // e.g. no timestamps in common
  }
}

namespace {

void optional_string(JsonWriter& json, const char* name, const std::string& value) {
  json.key(name);
  if (value.empty())
    json.null();
  else
    json.value(value);
}

void optional_verdict(JsonWriter& json, const char* name,
                      const std::optional<RefinementVerdict>& v) {
  json.key(name);
  if (v)
    json.value(to_string(*v));
  else
    json.null();
}

std::size_t untrusted_frames(const KeyframePipeline& p) {
  std::size_t untrusted = 0;
  for (std::size_t i = 0; i < p.frames().size(); ++i)
    untrusted += p.verdicts(i).trusted() ? 0 : 1;
  return untrusted;
}

}  // namespace

std::map<std::string, std::size_t> untrusted_causes(const KeyframePipeline& p) {
  std::map<std::string, std::size_t> causes;
  for (std::size_t i = 0; i < p.frames().size(); ++i) {
    const FrameVerdicts v = p.verdicts(i);
    if (v.front_end != IcpVerdict::ok)
      ++causes[std::string("front_end: ") + to_string(v.front_end)];
    if (v.pair && !usable(*v.pair)) ++causes[std::string("pair: ") + to_string(*v.pair)];
    if (v.window && !usable(*v.window)) ++causes[std::string("window: ") + to_string(*v.window)];
  }
  return causes;
}

void write_report(std::ostream& out, const RunInputs& inputs, const KeyframePipeline& p,
                  const std::optional<TrajectoryErrors>& front_end,
                  const std::optional<TrajectoryErrors>& refined, double seconds) {
  JsonWriter json(out);
  json.begin_object().field("dataset", inputs.dataset);
  optional_string(json, "config", inputs.config);
  optional_string(json, "params", inputs.params);
  json.field("device_requested", inputs.device)
      .field("first_frame", inputs.first_frame)
      .field("method", to_string(p.params().method));
  if (!refines_windows(p.params().method))
    json.key("window").null();  // not applicable: the method refines no windows
  else
    json.field("window", p.params().window);
  json.field("frames", p.frames().size())
      .field("keyframes", p.keyframes().size())
      .field("seconds", seconds);
  write_errors(json, "front_end_errors", front_end);
  write_errors(json, "errors", refined);
  // Whether the result can be trusted, in numbers (verdicts.txt has it per frame).
  const std::size_t untrusted = untrusted_frames(p);
  json.field("frames_trusted", p.frames().size() - untrusted)
      .field("frames_untrusted", untrusted)
      .key("untrusted_causes")
      .begin_object();
  for (const auto& [cause, count] : untrusted_causes(p))
    json.field(cause, count);
  json.end_object();
  std::size_t failed_tracking = 0, failed_refinement = 0, on_front_end = 0;
  for (const PipelineFrame& f : p.frames())
    failed_tracking += f.kept_last_motion ? 1 : 0;
  for (const PipelineKeyframe& k : p.keyframes()) {
    // The window's report sits on its last keyframe; every keyframe it covers shares its verdict
    // (Q-full: each has its own pose's).
    const FrameVerdicts v = p.verdicts(static_cast<std::size_t>(k.frame));
    failed_refinement += (v.pair && !usable(*v.pair)) || (v.window && !usable(*v.window)) ? 1 : 0;
    on_front_end += k.used_front_end ? 1 : 0;
  }
  json.field("frames_with_failed_tracking", failed_tracking)
      .field("keyframes_with_failed_refinement", failed_refinement)
      // no refinement that covers them succeeded: their poses are the front end's motion
      .field("keyframes_on_front_end_motion", on_front_end);
  json.key("frame_records").begin_array();
  for (std::size_t i = 0; i < p.frames().size(); ++i) {
    const PipelineFrame& f = p.frames()[i];
    const FrameVerdicts v = p.verdicts(i);
    json.begin_object()
        .field("index", f.index)
        .field("dataset_index", inputs.first_frame + static_cast<std::size_t>(f.index))
        .field("stamp", f.front_end.timestamp)
        .field("keyframe", f.keyframe)
        .field("icp_verdict", to_string(f.icp_verdict))
        .field("kept_last_motion", f.kept_last_motion);
    optional_verdict(json, "pair", v.pair);
    optional_verdict(json, "window", v.window);
    json.field("trusted", v.trusted()).field("track_ms", f.track_ms).end_object();
  }
  json.end_array();
  json.key("keyframe_records").begin_array();
  for (const PipelineKeyframe& k : p.keyframes()) {
    json.begin_object()
        .field("frame", k.frame)
        .field("dataset_index", inputs.first_frame + static_cast<std::size_t>(k.frame))
        .field("stamp", k.refined.timestamp);
    write_refinement(json, "pair", k.pair);
    write_refinement(json, "window", k.window);
    json.field("used_front_end", k.used_front_end).field("refine_ms", k.refine_ms);
    optional_string(json, "curvature", k.curvature);
    // the maps' name (curvature/<map>.npy): the timestamp to the microsecond, as text
    optional_string(json, "map", k.curvature.empty() ? "" : format_stamp(k.refined.timestamp));
    json.end_object();
  }
  json.end_array().end_object();
  out << '\n';
}

void write_verdicts(std::ostream& out, const KeyframePipeline& p) {
  out << "# jpcr_run verdicts, one line per frame of trajectory.txt:\n"
         "# timestamp front_end pair window trusted\n"
         "# front_end: ICP-ftf, ok | degenerate | diverged | too_few_points\n"
         "# pair: J-ftf of the frame's keyframe, window: J-full/Q-full/ICP-bundle that refined\n"
         "#   it last, converged | max_iterations | diverged | too_few_quadrics | no_overlap |\n"
         "#   degenerate | error (the refiner threw; report.json says what) | - (did not run)\n"
         "#   (a frame between two keyframes also moves towards the next one's correction:\n"
         "#   those verdicts are on the next keyframe's line; a failed one moves nothing)\n"
         "# trusted: yes when front_end is ok and every refinement converged or hit "
         "max_iterations\n";
  const auto refinement = [](const std::optional<RefinementVerdict>& v) {
    return v ? to_string(*v) : "-";
  };
  for (std::size_t i = 0; i < p.frames().size(); ++i) {
    const FrameVerdicts v = p.verdicts(i);
    out << format_timestamp(p.frames()[i].front_end.timestamp) << ' ' << to_string(v.front_end)
        << ' ' << refinement(v.pair) << ' ' << refinement(v.window) << ' '
        << (v.trusted() ? "yes" : "no") << '\n';
  }
}

std::string untrusted_warning(const KeyframePipeline& p) {
  const std::size_t untrusted = untrusted_frames(p);
  if (untrusted == 0) return {};
  std::ostringstream line;
  line << untrusted << " of " << p.frames().size() << " frames are not trusted";
  // "front_end: degenerate" → "(front end: 7 degenerate, 1 diverged; window: 3 degenerate)"
  std::string stage;
  for (const auto& [cause, count] : untrusted_causes(p)) {
    const std::size_t colon = cause.find(": ");
    std::string name = cause.substr(0, colon);
    if (name == "front_end") name = "front end";
    line << (stage.empty()   ? " ("
             : name == stage ? ", "
                             : "; ")
         << (name == stage ? "" : name + ": ") << count << ' ' << cause.substr(colon + 2);
    stage = name;
  }
  line << (stage.empty() ? "" : ")") << "; verdicts.txt says which";
  // What the first refiner that threw said (report.json has each one's): "error" alone would
  // send the user there for "out of memory".
  for (std::size_t k = 0; k < p.keyframe_count(); ++k) {
    const PipelineKeyframe& key = p.keyframe(k);
    for (const std::optional<RefinementReport>* r : {&key.pair, &key.window})
      if (*r && (*r)->verdict == RefinementVerdict::kError && !(*r)->error.empty()) {
        line << "; the first error, " << (*r)->method << " at keyframe " << k << ": "
             << (*r)->error;
        return line.str();
      }
  }
  return line.str();
}

void print_error_table(std::ostream& out, const std::string& method,
                       const std::optional<TrajectoryErrors>& front_end,
                       const std::optional<TrajectoryErrors>& refined,
                       const KeyframePipeline& pipeline) {
  char line[256];
  std::snprintf(line, sizeof line, "%-10s %11s %13s %15s %15s %15s\n", "method", "ATE m",
                "RPE m/frame", "RPE deg/frame", "rel. transl. m", "rel. rot. rad");
  out << line;
  auto row = [&](const std::string& name, const TrajectoryErrors& e) {
    if (e.relative.pairs > 0)
      std::snprintf(line, sizeof line, "%-10s %11.6f %13.6f %15.5f %15.3e %15.3e\n", name.c_str(),
                    e.ate.translation.rmse, e.rpe.translation.rmse, e.rpe.rotation.rmse,
                    e.relative.translation_rms, e.relative.rotation_rms);
    else
      std::snprintf(line, sizeof line, "%-10s %11.6f %13.6f %15.5f %15s %15s\n", name.c_str(),
                    e.ate.translation.rmse, e.rpe.translation.rmse, e.rpe.rotation.rmse, "n/a",
                    "n/a");
    out << line;
  };
  if (front_end) row("icp-ftf", *front_end);
  if (refined && method != "icp-ftf") row(method, *refined);
  const std::size_t frames = pipeline.frames().size();
  out << "frames trusted: " << frames - untrusted_frames(pipeline) << " of " << frames
      << " (verdicts.txt)\n";
}

}  // namespace jpcr::run
