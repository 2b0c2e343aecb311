// The full system (architecture.md "Data flow"): the front end tracks every frame with ICP-ftf
// and picks keyframes; at each new keyframe J-ftf refines it against the previous keyframe
// (initialised by ICP-ftf and Quad IT); every `window` keyframes J-full refines the window; the
// other frames are re-anchored to their refined keyframes. The same loop runs the paper's single
// methods for comparisons, with every frame a keyframe:
//
//   icp-ftf   the front end alone (ICP frame to frame)
//   j-ftf     J-ftf on every consecutive pair, chained
//   j-full    J-full on windows of `window` consecutive frames, chained at shared end frames
//   q-full    the same with the quadrics of each window's first frame fixed (Q-full)
//   icp-bundle  the same windows refined by ICP-bundle (method.md §9; builds with Ceres only)
//   pipeline  keyframes from the front end's policy, J-ftf per keyframe pair, J-full per window
//
//   KeyframePipeline pipeline(params);
//   for (...) pipeline.add(frame);
//   pipeline.finish();
//   Trajectory refined = pipeline.trajectory();
//
// It is PipelineFrontEnd feeding PipelineBackEnd (pipeline_back_end.hpp) in one process; the
// split deployment (jpcr_node --role frontend / backend) runs the two halves in two processes.
// Poses are camera-to-world (T_wc, method.md §1); the first frame's pose is the gauge:
// PipelineParams::initial_pose, by default the identity, so that the trajectory is in the first
// camera's axes (x right, y down, z forward). A sensor that starts blank moves the gauge to the
// first frame with the points to be aligned against (KeyframeTracker); the frames before it stay
// at that pose, untrusted (too_few_points).
//
// Threads: an object is used from one thread at a time; distinct objects are independent. add()
// runs the refinements in the calling thread (a J-full window takes seconds on the CPU at
// 640x480; the CPU refiners use OpenMP, OMP_NUM_THREADS bounds them), so a live system that
// must not stall its tracking runs PipelineFrontEnd and PipelineBackEnd on two threads with a
// queue between them, as jpcr_node --role frontend / backend does over DDS.
//
// Errors: InputError for bad input (a frame of another size or camera, bad parameters),
// std::logic_error for a call out of order (add after finish), and whatever a sink throws
// (PipelineBackEnd::add). A refiner's failure (divergence, a device error) is a verdict in
// the report, not an exception.
#pragma once

#include "jpcr/backend/pipeline_back_end.hpp"

namespace jpcr {

/// The front end's half: ICP-ftf tracking (KeyframeTracker) and the choice of the frames the back
/// end refines: the front end's keyframes for `pipeline`, every frame for the single methods.
class PipelineFrontEnd {
 public:
  explicit PipelineFrontEnd(const PipelineParams& params = {});

  /// Tracks the next frame; `*keyframe` says whether the back end refines it. Throws InputError
  /// when the frame's size differs from the first frame's.
  PipelineFrame track(const Frame& frame, bool* keyframe);

 private:
  PipelineMethod method_;
  KeyframeTracker tracker_;
};

class KeyframePipeline : public PipelineBackEnd {
 public:
  explicit KeyframePipeline(const PipelineParams& params = {}, CurvatureSink sink = {},
                            const RefinerFactory& refiners = {});

  /// Tracks the next frame and refines when a keyframe completes a pair or a window. Throws
  /// InputError when the frame's size differs from the first frame's.
  const PipelineFrame& add(const Frame& frame);

 private:
  PipelineFrontEnd front_end_;
};

}  // namespace jpcr
