// The README's embedding example ("Using jpcr from CMake"), made whole: the full system on a
// generated sequence, with the parameter file's `device:` honoured, poses taken from the frame
// sink as they become final, and the curvature maps from the curvature sink. Exits non-zero
// when a frame is missing or out of order, there are fewer than two curvature maps, or the
// refined path is further from the ground truth than the front end's.
#include <cmath>
#include <cstdio>
#include <exception>
#include <iostream>

#include <jpcr/backend/keyframe_pipeline.hpp>  // jpcr::backend
#include <jpcr/cuda/refiner_factory.hpp>       // jpcr::device
#include <jpcr/io/params.hpp>                  // jpcr::io
#include <jpcr/io/synthetic_sequence.hpp>      // jpcr::io

int main(int argc, char** argv) try {
  const jpcr::Params params = argc > 1 ? jpcr::load_params(argv[1]) : jpcr::Params{};
  jpcr::SyntheticSequenceOptions options;
  options.frames = 8;
  options.width = 160;
  options.height = 120;
  options.seed = 1;
  const jpcr::SyntheticSequence camera = jpcr::make_synthetic_sequence(options);

  // --- The README's example ---
  jpcr::PipelineParams pipeline_params = params.pipeline;  // the `pipeline:` section
  pipeline_params.keep_history = false;  // forget each frame once final: bounded memory
  int maps = 0;
  const auto on_curvature_map = [&](int, const jpcr::Frame&, const jpcr::QuadricMap& quadrics) {
    maps += quadrics.width() > 0 ? 1 : 0;
  };
  jpcr::KeyframePipeline pipeline(pipeline_params, on_curvature_map,
                                  jpcr::device_refiner_factory(params.device, std::clog));
  int next = 0;
  double refined_m = 0, front_end_m = 0;  // largest position errors
  bool in_order = true;
  pipeline.set_frame_sink([&](const jpcr::PipelineFrame& f, const jpcr::StampedPose& refined,
                              const jpcr::FrameVerdicts&) {
    in_order = in_order && f.index == next++;
    const auto truth = camera.ground_truth(static_cast<std::size_t>(f.index));
    const auto first = camera.ground_truth(0);
    const Eigen::Vector3d expected = (first->inverse() * *truth).translation();
    refined_m = std::fmax(refined_m, (refined.pose.translation() - expected).norm());
    front_end_m = std::fmax(front_end_m, (f.front_end.pose.translation() - expected).norm());
  });
  for (std::size_t i = 0; i < camera.size(); ++i)
    pipeline.add(camera.load(i));
  pipeline.finish();
  // ---

  std::printf(
      "embedded pipeline: %d of %zu frames final, in order %s, %d curvature maps, "
      "largest position error %.2e m (front end %.2e m)\n",
      next, camera.size(), in_order ? "yes" : "no", maps, refined_m, front_end_m);
  // The parameters (run_downstream.sh) make a keyframe every centimetre: at least two keyframes
  // and so one J-ftf pair, whose refinement must bring the path nearer the truth.
  const bool ok =
      next == static_cast<int>(camera.size()) && in_order && maps >= 2 && refined_m < front_end_m;
  return ok ? 0 : 1;
} catch (const std::exception& e) {
  std::fprintf(stderr, "embedded pipeline: %s\n", e.what());
  return 1;
}
