#include "jpcr/backend/pipeline_back_end.hpp"

#include <chrono>
#include <stdexcept>

#include "jpcr/quadric/error.hpp"
#include "jpcr/quadric/quadric_fit.hpp"

namespace jpcr {

namespace {

using Clock = std::chrono::steady_clock;

double ms_since(Clock::time_point t0) {
  return std::chrono::duration<double, std::milli>(Clock::now() - t0).count();
}

bool usable(RefinementVerdict v) {
  return v == RefinementVerdict::kConverged || v == RefinementVerdict::kMaxIterations;
}

// A refinement whose poses can be used: converged, or still improving at the iteration cap.
bool usable(const RefinementResult& r) {
  if (!usable(r.report.verdict)) return false;
  for (const Eigen::Isometry3d& T : r.poses)
    if (!T.matrix().allFinite()) return false;
  return true;
}

}  // namespace

/// The keyframes the back end still works on: the current J-full window (or the last pair), with
/// the best quadrics each has so far.
struct PipelineBackEnd::Window {
  std::vector<Frame> frames;
  std::vector<int> keyframes;        // indices into keyframes_
  std::vector<QuadricMap> quadrics;  // per slot; empty map = none yet
  void pop_front() {
    frames.erase(frames.begin());
    keyframes.erase(keyframes.begin());
    quadrics.erase(quadrics.begin());
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

void PipelineParams::validate() const {
  if (window < 2 || window > kMaxWindowFrames)
    throw InputError("window: must be in [2, " + std::to_string(kMaxWindowFrames) + "] keyframes");
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
  if (tracked.index != static_cast<int>(frames_.size()))
    throw InputError("frame " + std::to_string(tracked.index) + " arrived as frame " +
                     std::to_string(frames_.size()) + " (frames lost or reordered)");
  if (!keyframe && keyframes_.empty()) throw InputError("the first frame must be a keyframe");
  if (keyframe) on_keyframe(*keyframe, tracked);
  frames_.push_back(tracked);
  frames_.back().keyframe = static_cast<int>(keyframes_.size()) - 1;
  return frames_.back();
}

void PipelineBackEnd::on_keyframe(const Frame& frame, const PipelineFrame& tracked) {
  PipelineKeyframe k;
  k.frame = tracked.index;
  k.front_end = k.refined = tracked.front_end;
  if (!keyframes_.empty()) {
    // Until the back end says otherwise, the keyframe moves by the front end's motion from the
    // previous keyframe, applied to that keyframe's refined pose.
    const PipelineKeyframe& previous = keyframes_.back();
    k.refined.pose =
        previous.refined.pose * (previous.front_end.pose.inverse() * tracked.front_end.pose);
  }
  keyframes_.push_back(k);
  if (!pair_refiner_ && !window_refiner_) return;  // ICP-ftf: nothing to refine or keep
  window_->frames.push_back(frame);
  window_->keyframes.push_back(static_cast<int>(keyframes_.size()) - 1);
  window_->quadrics.emplace_back();
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
  PipelineKeyframe& a = keyframes_[window_->keyframes[n - 2]];
  PipelineKeyframe& b = keyframes_[window_->keyframes[n - 1]];
  const Eigen::Isometry3d initial = a.refined.pose.inverse() * b.refined.pose;
  const RefinementResult r =
      pair_refiner_->refine(std::vector<Frame>{window_->frames[n - 2], window_->frames[n - 1]},
                            {Eigen::Isometry3d::Identity(), initial});
  b.pair = r.report;
  if (usable(r)) {
    b.refined.pose = a.refined.pose * r.poses[1];
    window_->quadrics[n - 2] = r.quadrics;
  } else {
    b.used_front_end = true;
  }
  b.refine_ms += ms_since(t0);
}

// J-full (or Q-full, ICP-bundle) over the window; its first keyframe is the gauge (method.md §7,
// §8, §9). ICP-bundle gives no quadrics: the reference keeps none and its curvature is Quad IT's.
void PipelineBackEnd::refine_window() {
  const Clock::time_point t0 = Clock::now();
  const std::size_t n = window_->frames.size();
  const PipelineKeyframe& first = keyframes_[window_->keyframes[0]];
  std::vector<Eigen::Isometry3d> initial;
  for (int k : window_->keyframes)
    initial.push_back(first.refined.pose.inverse() * keyframes_[k].refined.pose);
  const RefinementResult r = window_refiner_->refine(window_->frames, initial);
  PipelineKeyframe& last = keyframes_[window_->keyframes[n - 1]];
  last.window = r.report;
  if (usable(r)) {
    const Eigen::Isometry3d anchor = first.refined.pose;
    for (std::size_t j = 1; j < n; ++j)
      keyframes_[window_->keyframes[j]].refined.pose = anchor * r.poses[j];
    window_->quadrics[0] = r.quadrics;
  } else {
    last.used_front_end = true;
  }
  last.refine_ms += ms_since(t0);
  // Every keyframe but the last is final now; the last one starts the next window.
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
}

void PipelineBackEnd::emit_curvature(std::size_t slot, const QuadricMap& quadrics) {
  if (!sink_) return;
  const Frame& frame = window_->frames[slot];
  if (quadrics.width() > 0) {
    sink_(window_->keyframes[slot], frame, quadrics);
    return;
  }
  const QuadricFit fit(params_.joint.quadric);
  sink_(window_->keyframes[slot], frame,
        fit.estimate(compute_vertex_map(frame.depth, frame.camera)));
}

StampedPose PipelineBackEnd::refined_pose(std::size_t index) const {
  const PipelineFrame& f = frames_.at(index);
  const PipelineKeyframe& k = keyframes_[f.keyframe];
  // Re-anchoring: the frame keeps its front-end offset from its keyframe.
  StampedPose p = f.front_end;
  p.pose = k.refined.pose * (k.front_end.pose.inverse() * f.front_end.pose);
  return p;
}

Trajectory PipelineBackEnd::trajectory() const {
  Trajectory out;
  out.reserve(frames_.size());
  for (std::size_t i = 0; i < frames_.size(); ++i)
    out.push_back(refined_pose(i));
  return out;
}

bool FrameVerdicts::trusted() const {
  return front_end == IcpVerdict::ok && (!pair || usable(*pair)) && (!window || usable(*window));
}

FrameVerdicts PipelineBackEnd::verdicts(std::size_t index) const {
  const PipelineFrame& f = frames_.at(index);
  FrameVerdicts v;
  v.front_end = f.icp_verdict;
  const PipelineKeyframe& k = keyframes_[f.keyframe];
  if (k.pair) v.pair = k.pair->verdict;
  // The gauge keyframe is never refined; any other was last refined by the window it ends, or
  // else by the window of the first later keyframe that ends one (windows share end frames).
  if (f.keyframe == 0 || !window_refiner_) return v;
  for (std::size_t j = f.keyframe; j < keyframes_.size(); ++j)
    if (keyframes_[j].window) {
      v.window = keyframes_[j].window->verdict;
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
