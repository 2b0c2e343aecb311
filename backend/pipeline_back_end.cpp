#include "jpcr/backend/pipeline_back_end.hpp"

#include <algorithm>
#include <chrono>
#include <exception>
#include <new>
#include <stdexcept>
#include <string>

#include "jpcr/frontend/frame_pyramid.hpp"
#include "jpcr/quadric/error.hpp"
#include "jpcr/quadric/quadric_fit.hpp"
#include "jpcr/quadric/se3.hpp"

namespace jpcr {

namespace {

using Clock = std::chrono::steady_clock;

double ms_since(Clock::time_point t0) {
  return std::chrono::duration<double, std::milli>(Clock::now() - t0).count();
}

// A refinement whose poses can be used: converged, or still improving at the iteration cap
// (refine_or_report has checked the poses).
bool usable(const RefinementResult& r) {
  return usable(r.report.verdict);
}

RefinementResult failed(const Refiner& refiner, const std::string& why) {
  RefinementResult r;
  r.report.method = refiner.name();
  r.report.verdict = RefinementVerdict::kError;
  r.report.error = why;
  r.report.device.clear();  // unknown: a GPU refiner's non-device error reaches here too
  return r;
}

// Whether any pose after the gauge may be used (Q-full's poses each have their own verdict). Its
// caller has checked the poses' and the verdicts' counts.
bool any_pose_usable(const RefinementResult& r) {
  for (std::size_t j = 1; j < r.poses.size(); ++j)
    if (r.report.pose_usable(j)) return true;
  return false;
}

// A refiner that throws (out of memory, a device error) gives a failed refinement that says why,
// so that the run goes on with the front end's motion as after any other failed refinement. So
// does a refiner (a library caller's, through RefinerFactory) that says it converged but gives
// another number of poses (or of per-pose verdicts) than frames, or a usable pose that is no
// rigid motion: its report would say "converged" of poses the pipeline cannot use.
RefinementResult refine_or_report(const Refiner& refiner, const std::vector<Frame>& frames,
                                  const std::vector<Eigen::Isometry3d>& initial) {
  RefinementResult r;
  try {
    r = refiner.refine(frames, initial);
  } catch (const std::bad_array_new_length& e) {  // a bad size, not a lack of memory
    return failed(refiner, e.what());
  } catch (const std::bad_alloc&) {  // what() says only "std::bad_alloc"
    const std::string size = frames.empty()
                                 ? std::string()
                                 : " of " + std::to_string(frames.front().depth.width()) + "x" +
                                       std::to_string(frames.front().depth.height());
    return failed(refiner, "out of memory: " + refiner.name() + " of " +
                               std::to_string(frames.size()) + " frames" + size +
                               " needs more memory than is free");
  } catch (const std::exception& e) {
    return failed(refiner, e.what());
  } catch (...) {
    return failed(refiner, "the refiner threw an exception that is no std::exception");
  }
  const std::size_t verdicts = r.report.pose_verdicts.size();
  if (verdicts == 0 && !usable(r)) return r;
  if (r.poses.size() != frames.size())
    return failed(refiner, "the refiner gave " + std::to_string(r.poses.size()) + " poses for " +
                               std::to_string(frames.size()) + " frames");
  if (verdicts != 0 && verdicts + 1 != frames.size())
    return failed(refiner, "the refiner gave " + std::to_string(verdicts) + " pose verdicts for " +
                               std::to_string(frames.size() - 1) + " poses");
  if (!any_pose_usable(r)) return r;
  for (std::size_t j = 0; j < r.poses.size(); ++j)
    if ((j == 0 || r.report.pose_usable(j)) && !is_rigid(r.poses[j]))
      return failed(refiner, "the refiner's pose " + std::to_string(j) + " is no rigid motion");
  return r;
}

}  // namespace

/// The keyframes the back end still works on: the current J-full window (or the last pair), with
/// the best quadrics each has so far.
struct PipelineBackEnd::Window {
  std::vector<Frame> frames;
  std::vector<int> keyframes;        // keyframe indices (PipelineBackEnd::keyframe)
  std::vector<QuadricMap> quadrics;  // per slot; empty map = none yet
  std::vector<std::string> sources;  // per slot: the refiner that gave the quadrics
  void pop_front() {
    frames.erase(frames.begin());
    keyframes.erase(keyframes.begin());
    quadrics.erase(quadrics.begin());
    sources.erase(sources.begin());
  }
};

const char* to_string(PipelineMethod method) {
  switch (method) {
    case PipelineMethod::kIcpFtf:
      return "icp-ftf";
    case PipelineMethod::kJointFtf:
      return "j-ftf";
    case PipelineMethod::kJointFull:
      return "j-full";
    case PipelineMethod::kFixedQuadrics:
      return "q-full";
    case PipelineMethod::kIcpBundle:
      return "icp-bundle";
    case PipelineMethod::kPipeline:
      return "pipeline";
  }
  return "?";
}

PipelineMethod parse_pipeline_method(const std::string& name) {
  for (PipelineMethod m :
       {PipelineMethod::kIcpFtf, PipelineMethod::kJointFtf, PipelineMethod::kJointFull,
        PipelineMethod::kFixedQuadrics, PipelineMethod::kIcpBundle, PipelineMethod::kPipeline})
    if (name == to_string(m)) return m;
  throw InputError("unknown method '" + name +
                   "' (choices: icp-ftf, j-ftf, j-full, q-full, icp-bundle, pipeline)");
}

bool refines_windows(PipelineMethod method) {
  return method != PipelineMethod::kIcpFtf && method != PipelineMethod::kJointFtf;
}

void PipelineParams::validate() const {
  if (window < 2 || window > kMaxWindowFrames)
    throw InputError("window: must be in [2, " + std::to_string(kMaxWindowFrames) + "] keyframes");
  if (!is_rigid(initial_pose))
    throw InputError("initial_pose: must be a rigid motion (finite, R orthonormal, det R = 1)");
  frontend.validate();
  joint.validate();
  icp_bundle.validate();
}

PipelineBackEnd::PipelineBackEnd(const PipelineParams& params, CurvatureSink sink,
                                 const RefinerFactory& refiners)
    : params_(params), sink_(std::move(sink)), window_(std::make_unique<Window>()) {
  params_.validate();
  const auto make = [&](const std::string& name) {
    std::unique_ptr<Refiner> r = refiners ? refiners(name, params_.joint, params_.icp_bundle)
                                          : make_refiner(name, params_.joint, params_.icp_bundle);
    if (!r) throw std::invalid_argument("PipelineBackEnd: the refiner factory gave no " + name);
    return r;
  };
  const PipelineMethod m = params_.method;
  if (m == PipelineMethod::kJointFtf || m == PipelineMethod::kPipeline)
    pair_refiner_ = make("j-ftf");
  if (m == PipelineMethod::kJointFull || m == PipelineMethod::kPipeline)
    window_refiner_ = make("j-full");
  if (m == PipelineMethod::kFixedQuadrics) window_refiner_ = make("q-full");
  if (m == PipelineMethod::kIcpBundle) window_refiner_ = make("icp-bundle");
}

PipelineBackEnd::~PipelineBackEnd() = default;

const PipelineFrame& PipelineBackEnd::add(const PipelineFrame& tracked, const Frame* keyframe) {
  if (finished_) throw std::logic_error("PipelineBackEnd::add after finish()");
  if (tracked.index != static_cast<int>(frame_count()))
    throw InputError("frame " + std::to_string(tracked.index) + " arrived as frame " +
                     std::to_string(frame_count()) + " (frames lost or reordered)");
  // Each keyframe's pose builds on the previous one's: one pose that is not rigid (NaN) would
  // spoil every later keyframe.
  if (!is_rigid(tracked.front_end.pose))
    throw InputError(
        "frame " + std::to_string(tracked.index) +
        ": the front end's pose is no rigid motion (finite, R orthonormal, det R = 1)");
  // Every keyframe must come from the first one's camera, checked before anything changes.
  if (keyframe && keyframe_camera_ && !same_pinhole(keyframe->camera, *keyframe_camera_))
    throw InputError("keyframe of frame " + std::to_string(tracked.index) + ": camera " +
                     describe(keyframe->camera) + " differs from the first keyframe's, " +
                     describe(*keyframe_camera_));
  if (keyframe) on_keyframe(*keyframe, tracked);
  if (keyframe && !keyframe_camera_) keyframe_camera_ = keyframe->camera;
  frames_.push_back(tracked);
  frames_.back().keyframe = static_cast<int>(keyframe_count()) - 1;
  emit_final_frames();
  rethrow_sink_error();
  return frames_.back();
}

void PipelineBackEnd::set_frame_sink(FrameSink sink) {
  frame_sink_ = std::move(sink);
  emit_final_frames();
  rethrow_sink_error();
}

// A sink's exception waits until the back end has finished the call that made it, so that the
// back end's state stays whole; the first one then reaches the caller.
template <typename Call>
void PipelineBackEnd::call_sink(Call&& call) {
  try {
    call();
  } catch (...) {
    if (!sink_error_) sink_error_ = std::current_exception();
  }
}

void PipelineBackEnd::rethrow_sink_error() {
  if (!sink_error_) return;
  std::exception_ptr e = sink_error_;
  sink_error_ = nullptr;
  std::rethrow_exception(e);
}

// Without refiners every correction is the identity: the front end's poses stay as they are.
bool PipelineBackEnd::interpolates() const {
  return params_.interpolate_corrections && (pair_refiner_ || window_refiner_);
}

// A frame's pose depends on its keyframe and, when corrections are interpolated, on the next one.
bool PipelineBackEnd::is_final(const PipelineFrame& f) const {
  if (f.keyframe < 0) return true;  // before the first keyframe: nothing refines it
  const std::size_t k = static_cast<std::size_t>(f.keyframe);
  if (k >= final_keyframes_) return false;
  return finished_ || !interpolates() || k + 1 < final_keyframes_;
}

// Frames hang on keyframes in order, so the final ones are a prefix of those not yet emitted.
// Without a sink they wait for one (set_frame_sink), unless they are to be forgotten.
void PipelineBackEnd::emit_final_frames() {
  if (!frame_sink_ && params_.keep_history) return;
  while (emitted_ < frame_count()) {
    const PipelineFrame& f = frame(emitted_);
    if (!is_final(f)) break;
    if (frame_sink_) call_sink([&] { frame_sink_(f, refined_pose(emitted_), verdicts(emitted_)); });
    ++emitted_;
  }
  if (!params_.keep_history) forget_emitted();
}

// Forgets the emitted frames but the newest (add() returns it) and the keyframes that neither a
// held frame, the window, nor the next keyframe (its motion from the newest) needs. Erasing from
// the front once as many can go as stay keeps it amortised O(1) per frame.
void PipelineBackEnd::forget_emitted() {
  const std::size_t frames_gone = std::min(emitted_, frame_count() - 1) - first_frame_;
  if (frames_gone == 0 || 2 * frames_gone < frames_.size()) return;
  std::size_t keep = keyframe_count() == 0 ? 0 : keyframe_count() - 1;
  if (frames_[frames_gone].keyframe >= 0)
    keep = std::min(keep, static_cast<std::size_t>(frames_[frames_gone].keyframe));
  if (!window_->keyframes.empty())
    keep = std::min(keep, static_cast<std::size_t>(window_->keyframes.front()));
  const std::size_t keyframes_gone = keep - first_keyframe_;
  frames_.erase(frames_.begin(), frames_.begin() + static_cast<std::ptrdiff_t>(frames_gone));
  keyframes_.erase(keyframes_.begin(),
                   keyframes_.begin() + static_cast<std::ptrdiff_t>(keyframes_gone));
  // Give back what a long stretch between keyframes took (128 frames held once kept 94 KB for the
  // rest of the run): the vectors hold at most twice what is held (plus 16), so live memory
  // follows it.
  if (frames_.capacity() > 2 * frames_.size() + 16) frames_.shrink_to_fit();
  if (keyframes_.capacity() > 2 * keyframes_.size() + 16) keyframes_.shrink_to_fit();
  first_frame_ += frames_gone;
  first_keyframe_ += keyframes_gone;
}

void PipelineBackEnd::on_keyframe(const Frame& frame, const PipelineFrame& tracked) {
  // The work that can throw (the copy, the filter) comes before anything changes, so that add()
  // leaves the back end as it was when it does; the refiners and sinks report rather than throw
  // (only an allocation of the bookkeeping below could still fail half-way).
  const bool refines = pair_refiner_ || window_refiner_;
  Frame held;
  if (refines) {
    held = frame;
    if (params_.filtered_depth)
      held.depth = bilateral_filter(frame.depth, params_.frontend.preprocess);
  }
  PipelineKeyframe k;
  k.frame = tracked.index;
  k.front_end = k.refined = tracked.front_end;
  if (!keyframes_.empty()) {
    // Until the back end says otherwise, the keyframe moves by the front end's motion from the
    // previous keyframe, applied to that keyframe's refined pose.
    const PipelineKeyframe& previous = keyframes_.back();
    k.refined.pose = orthonormalized(previous.refined.pose *
                                     (previous.front_end.pose.inverse() * tracked.front_end.pose));
  }
  // ICP-ftf: nothing refines a keyframe; every one but the gauge is the front end's motion.
  k.used_front_end = !refines && !keyframes_.empty();
  keyframes_.push_back(k);
  // Without windows a keyframe's pose is final once its pair ran (below); with windows, once its
  // window did (refine_window). The first keyframe is the gauge.
  if (!window_refiner_ || keyframe_count() == 1) final_keyframes_ = keyframe_count();
  if (!refines) return;  // ICP-ftf: nothing to refine or keep
  window_->frames.push_back(std::move(held));
  window_->keyframes.push_back(static_cast<int>(keyframe_count()) - 1);
  window_->quadrics.emplace_back();
  window_->sources.emplace_back();
  if (pair_refiner_ && window_->frames.size() >= 2) refine_pair();
  if (window_refiner_ && static_cast<int>(window_->frames.size()) == params_.window) {
    refine_window();
  } else if (!window_refiner_ && window_->frames.size() >= 2) {
    emit_curvature(0, window_->quadrics[0]);  // J-ftf only: the older keyframe of the pair is done
    window_->pop_front();
  }
}

// J-ftf between the last two keyframes of the window (method.md §6).
void PipelineBackEnd::refine_pair() {
  const Clock::time_point t0 = Clock::now();
  const std::size_t n = window_->frames.size();
  PipelineKeyframe& a = keyframe_at(window_->keyframes[n - 2]);
  PipelineKeyframe& b = keyframe_at(window_->keyframes[n - 1]);
  const Eigen::Isometry3d initial = a.refined.pose.inverse() * b.refined.pose;
  const RefinementResult r = refine_or_report(
      *pair_refiner_, std::vector<Frame>{window_->frames[n - 2], window_->frames[n - 1]},
      {Eigen::Isometry3d::Identity(), initial});
  b.pair = r.report;
  b.used_front_end = !usable(r);
  if (usable(r)) {
    b.refined.pose = orthonormalized(a.refined.pose * r.poses[1]);
    window_->quadrics[n - 2] = r.quadrics;
    window_->sources[n - 2] = pair_refiner_->name();
  }
  b.refine_ms += ms_since(t0);
}

// J-full (or Q-full, ICP-bundle) over the window; its first keyframe is the gauge (method.md §7,
// §8, §9). ICP-bundle gives no quadrics: the reference keeps none and its curvature is Quad IT's.
void PipelineBackEnd::refine_window() {
  const Clock::time_point t0 = Clock::now();
  const std::size_t n = window_->frames.size();
  const PipelineKeyframe& first = keyframe_at(window_->keyframes[0]);
  std::vector<Eigen::Isometry3d> initial;
  for (int k : window_->keyframes)
    initial.push_back(first.refined.pose.inverse() * keyframe_at(k).refined.pose);
  const RefinementResult r = refine_or_report(*window_refiner_, window_->frames, initial);
  PipelineKeyframe& last = keyframe_at(window_->keyframes[n - 1]);
  last.window = r.report;
  const Eigen::Isometry3d anchor = first.refined.pose;
  for (std::size_t j = 1; j < n; ++j) {
    PipelineKeyframe& k = keyframe_at(window_->keyframes[j]);
    const PipelineKeyframe& previous = keyframe_at(window_->keyframes[j - 1]);
    if (r.report.pose_usable(j)) {  // Q-full: each pose by its own verdict
      // Keyframe poses are chains of compositions, and each window composes its first pose with
      // the poses relative to it: without orthonormalizing, the rotations' error doubled every
      // window (se3.hpp).
      k.refined.pose = orthonormalized(anchor * r.poses[j]);
      k.used_front_end = false;
    } else if (!pair_refiner_) {  // with J-ftf, its pose (or its failure) stands
      // The front end's motion from the previous keyframe, which a Q-full window may have moved
      // (its poses are independent); as on_keyframe chains it, so unchanged where it did not.
      k.refined.pose = orthonormalized(previous.refined.pose *
                                       (previous.front_end.pose.inverse() * k.front_end.pose));
      k.used_front_end = true;
    }
  }
  if (usable(r) && r.quadrics.width() > 0) {  // Q-full's are Quad IT's, and say so
    window_->quadrics[0] = r.quadrics;
    window_->sources[0] = window_refiner_->refines_quadrics() ? window_refiner_->name() : "quad-it";
  }
  last.refine_ms += ms_since(t0);
  final_keyframes_ = keyframe_count();  // the window's last keyframe is the newest
  // Every keyframe's curvature but the last is final now; the last one starts the next window.
  while (window_->frames.size() > 1) {
    emit_curvature(0, window_->quadrics[0]);
    window_->pop_front();
  }
}

void PipelineBackEnd::finish() {
  if (window_refiner_ && window_->frames.size() >= 2) refine_window();
  // What remains has no refined quadrics as a reference frame: Quad IT gives its curvature.
  while (!window_->frames.empty()) {
    emit_curvature(0, window_->quadrics[0]);
    window_->pop_front();
  }
  final_keyframes_ = keyframe_count();
  finished_ = true;
  emit_final_frames();
  rethrow_sink_error();
}

void PipelineBackEnd::emit_curvature(std::size_t slot, const QuadricMap& quadrics) {
  const bool refined = quadrics.width() > 0;
  keyframe_at(window_->keyframes[slot]).curvature = refined ? window_->sources[slot] : "quad-it";
  if (!sink_) return;
  const Frame& frame = window_->frames[slot];
  const int keyframe = window_->keyframes[slot];
  if (refined) {
    call_sink([&] { sink_(keyframe, frame, quadrics); });
    return;
  }
  call_sink([&] {
    const QuadricFit fit(params_.joint.quadric);
    sink_(keyframe, frame, fit.estimate(compute_vertex_map(frame.depth, frame.camera)));
  });
}

const PipelineFrame& PipelineBackEnd::frame(std::size_t index) const {
  if (index < first_frame_ || index >= frame_count())
    throw std::out_of_range("PipelineBackEnd: frame " + std::to_string(index) +
                            " is not held (frames " + std::to_string(first_frame_) + " to " +
                            std::to_string(frame_count()) + ")");
  return frames_[index - first_frame_];
}

const PipelineKeyframe& PipelineBackEnd::keyframe(std::size_t index) const {
  if (index < first_keyframe_ || index >= keyframe_count())
    throw std::out_of_range("PipelineBackEnd: keyframe " + std::to_string(index) +
                            " is not held (keyframes " + std::to_string(first_keyframe_) + " to " +
                            std::to_string(keyframe_count()) + ")");
  return keyframes_[index - first_keyframe_];
}

StampedPose PipelineBackEnd::refined_pose(std::size_t index) const {
  const PipelineFrame& f = frame(index);
  if (f.keyframe < 0) return f.front_end;  // before the first keyframe
  const std::size_t ki = static_cast<std::size_t>(f.keyframe);
  const PipelineKeyframe& k = keyframe(ki);
  StampedPose p = f.front_end;
  if (f.index == k.frame) {  // the keyframe itself, to the bit as keyframes.txt has it
    p.pose = k.refined.pose;
    return p;
  }
  // Re-anchoring (header): C_k, or C_k exp(s log(C_k⁻¹ C_{k+1})) between keyframes.
  Eigen::Isometry3d correction = k.refined.pose * k.front_end.pose.inverse();
  if (interpolates() && ki + 1 < keyframe_count()) {
    const PipelineKeyframe& next = keyframe(ki + 1);
    const double s = static_cast<double>(f.index - k.frame) / (next.frame - k.frame);
    const Eigen::Isometry3d step =
        correction.inverse() * (next.refined.pose * next.front_end.pose.inverse());
    correction = correction * se3_exp(s * se3_log(step));
  }
  p.pose = correction * f.front_end.pose;
  return p;
}

Trajectory PipelineBackEnd::trajectory() const {
  Trajectory out;
  out.reserve(frames_.size());
  for (std::size_t i = first_frame_; i < frame_count(); ++i)
    out.push_back(refined_pose(i));
  return out;
}

bool FrameVerdicts::trusted() const {
  return front_end == IcpVerdict::ok && (!pair || usable(*pair)) && (!window || usable(*window));
}

FrameVerdicts PipelineBackEnd::verdicts(std::size_t index) const {
  const PipelineFrame& f = frame(index);
  FrameVerdicts v;
  v.front_end = f.icp_verdict;
  if (f.keyframe < 0) return v;  // before the first keyframe
  const PipelineKeyframe& k = keyframe(static_cast<std::size_t>(f.keyframe));
  if (k.pair) v.pair = k.pair->verdict;
  // The gauge keyframe is never refined; any other was last refined by the window it ends, or
  // else by the window of the first later keyframe that ends one (windows share end frames).
  if (f.keyframe == 0 || !window_refiner_) return v;
  for (std::size_t j = f.keyframe; j < keyframe_count(); ++j) {
    const std::optional<RefinementReport>& w = keyframe(j).window;
    if (!w) continue;
    v.window = w->verdict;
    // Q-full: the keyframe's own pose verdict; the window's last keyframe is pose T_M, the
    // last one.
    const std::size_t back = j - static_cast<std::size_t>(f.keyframe);
    if (back < w->pose_verdicts.size())
      v.window = w->pose_verdicts[w->pose_verdicts.size() - 1 - back];
    break;
  }
  return v;
}

Trajectory PipelineBackEnd::front_end_trajectory() const {
  Trajectory out;
  for (const PipelineFrame& f : frames_)
    out.push_back(f.front_end);
  return out;
}

}  // namespace jpcr
