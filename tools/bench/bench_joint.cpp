// Speed of one joint iteration on the CPU (issue 6): linearise the Schur-reduced system, solve
// the poses, back-substitute the quadrics and evaluate the candidate's cost (what one accepted
// Levenberg-Marquardt step of refine_window costs). room_spheres with range:1 noise, the
// reference 129-sample pattern scaled to the width, Quad IT quadrics on the reference frame,
// poses 1 cm / 1° off the truth. Arguments: image width (height 3/4 of it), frames M. The
// buffers of the reduced system and the step are reused from one iteration to the next.
#include <algorithm>
#include <memory>
#include <vector>

#include <benchmark/benchmark.h>

#include "benchmark_main.hpp"
#include "joint_bench_window.hpp"
#include "jpcr/backend/joint_params.hpp"
#include "jpcr/backend/lower_cost_fit.hpp"

namespace {

// One joint problem and the buffers the refinement loop keeps across its iterations
// (run_joint_refinement). The system sees the frames it holds.
struct Problem {
  Problem(std::vector<jpcr::VertexMap> vertices, const jpcr::CameraIntrinsics& camera,
          const jpcr::NeighbourhoodPattern& pattern, const jpcr::JointTermParams& terms,
          jpcr::JointSampling sampling, jpcr::JointState start,
          std::size_t block_memory = jpcr::kDefaultBlockMemory)
      : frames(std::move(vertices)),
        system(frames, camera, pattern, terms, sampling, block_memory),
        state(std::move(start)) {}
  std::vector<jpcr::VertexMap> frames;
  jpcr::JointSystem system;
  jpcr::JointState state;
  jpcr::ReducedSystem lin;
  jpcr::JointStep step;
  std::vector<jpcr::Vector6d> steps;
};

// Times `iteration` (false: the reduced system was singular, which ends the benchmark with that
// error) after one untimed call: the buffers' first use (page faults of the ~200 MB of blocks at
// 640x480) is the loop's start, not its iterations; at 640x480 Google Benchmark times a single
// iteration per repetition, which was that first one.
template <typename Iteration>
void time_iterations(benchmark::State& state, Iteration&& iteration) {
  if (!iteration()) {
    state.SkipWithError("the reduced system is singular");
    return;
  }
  for (auto _ : state) {
    if (!iteration()) {
      state.SkipWithError("the reduced system is singular");
      break;
    }
  }
}

// estimate_quadrics = true: one problem over the window (J-ftf, J-full). false: Q-full, whose
// poses are independent problems (fixed_quadric_alignment.hpp), each the reference frame and
// one other; an iteration is one of each.
void run(benchmark::State& state, bool estimate_quadrics,
         jpcr::JointSampling sampling = jpcr::JointSampling::kGathered,
         std::size_t block_memory = jpcr::kDefaultBlockMemory) {
  const jpcr::bench::JointBenchWindow w = jpcr::bench::make_joint_window(
      static_cast<int>(state.range(0)), static_cast<int>(state.range(1)));
  const jpcr::JointParams params;
  const jpcr::NeighbourhoodPattern pattern = params.quadric.pattern.for_width(w.camera.width);
  const jpcr::JointTermParams terms = params.terms(estimate_quadrics);
  std::vector<std::unique_ptr<Problem>> problems;
  if (estimate_quadrics) {
    problems.push_back(std::make_unique<Problem>(w.vertices, w.camera, pattern, terms, sampling,
                                                 w.state, block_memory));
  } else {
    for (std::size_t j = 1; j < w.vertices.size(); ++j) {
      jpcr::JointState alone = w.state;
      alone.poses = {w.state.poses[0], w.state.poses[j]};
      problems.push_back(
          std::make_unique<Problem>(std::vector<jpcr::VertexMap>{w.vertices[0], w.vertices[j]},
                                    w.camera, pattern, terms, sampling, std::move(alone)));
    }
  }
  int active = 0;
  const auto iteration = [&] {
    for (const std::unique_ptr<Problem>& problem : problems) {
      Problem& p = *problem;
      p.system.linearize(p.state, params.initial_damping, p.lin);
      if (!jpcr::JointSystem::solve_poses(p.lin, params.initial_damping, p.steps)) return false;
      p.system.step(p.state, p.lin, params.initial_damping, p.steps, p.step);
      benchmark::DoNotOptimize(p.step.cost);
      active = std::max(active, p.lin.active);
    }
    return true;
  };
  time_iterations(state, iteration);
  state.counters["active_quadrics"] = active;
  state.counters["samples"] = pattern.size();
}

void BM_JointFrameToFrameIteration(benchmark::State& state) {
  run(state, true);
}
// The same iteration with the per-sample reference sums (what the GPU kernels run): the speed-up
// of the gathered SIMD sums on this CPU.
void BM_JointFrameToFrameIterationReference(benchmark::State& state) {
  run(state, true, jpcr::JointSampling::kReference);
}
void BM_JointWindowIteration(benchmark::State& state) {
  run(state, true);
}
// The same without the kept blocks (joint.block_memory_mb: 0): the step computes each quadric's
// system again, as J-full did before it kept them.
void BM_JointWindowIterationRecomputed(benchmark::State& state) {
  run(state, true, jpcr::JointSampling::kGathered, 0);
}
void BM_FixedQuadricIteration(benchmark::State& state) {
  run(state, false);
}

// A rejected J-ftf or J-full step: solve the poses, back-substitute and cost the candidate, then
// only the damping changes (JointSystem::redamp: the kept blocks eliminated again, no new sums),
// as the loop does after a step the cost refuses. The damping alternates between two values.
void rejected_step(benchmark::State& state) {
  const jpcr::bench::JointBenchWindow w = jpcr::bench::make_joint_window(
      static_cast<int>(state.range(0)), static_cast<int>(state.range(1)));
  const jpcr::JointParams params;
  Problem p(w.vertices, w.camera, params.quadric.pattern.for_width(w.camera.width),
            params.terms(true), jpcr::JointSampling::kGathered, w.state);
  double lambda = params.initial_damping;
  p.system.linearize(p.state, lambda, p.lin);
  const auto rejected_step = [&] {
    if (!jpcr::JointSystem::solve_poses(p.lin, lambda, p.steps)) return false;
    p.system.step(p.state, p.lin, lambda, p.steps, p.step);
    benchmark::DoNotOptimize(p.step.cost);
    lambda =
        lambda == params.initial_damping ? lambda * params.damping_factor : params.initial_damping;
    return p.system.redamp(lambda, p.lin);
  };
  time_iterations(state, rejected_step);
  state.counters["active_quadrics"] = p.lin.active;
}
void BM_JointFrameToFrameRejectedStep(benchmark::State& state) {
  rejected_step(state);
}
void BM_JointWindowRejectedStep(benchmark::State& state) {
  rejected_step(state);
}

// keep_lower_cost_fits (joint.keep_lower_cost_fit), the pass after the loop: the refined map is
// the candidate of one iteration from the start (what a refinement hands it, up to how far the
// quadrics moved), judged against Quad IT's map over every frame. Run once per refinement, so
// its ratio to one iteration says what it adds to a refinement of that many iterations.
void BM_KeepLowerCostFits(benchmark::State& state) {
  const jpcr::bench::JointBenchWindow w = jpcr::bench::make_joint_window(
      static_cast<int>(state.range(0)), static_cast<int>(state.range(1)));
  const jpcr::JointParams params;
  const jpcr::JointSystem system(
      w.vertices, w.camera, params.quadric.pattern.for_width(w.camera.width), params.terms(true));
  jpcr::ReducedSystem lin;
  std::vector<jpcr::Vector6d> steps;
  system.linearize(w.state, params.initial_damping, lin);
  if (!jpcr::JointSystem::solve_poses(lin, params.initial_damping, steps)) {
    state.SkipWithError("the reduced system is singular");
    return;
  }
  const jpcr::JointStep step = system.step(w.state, lin, params.initial_damping, steps);
  jpcr::QuadricMap moved = w.initial;
  for (int v = 0; v < moved.height(); ++v)
    for (int u = 0; u < moved.width(); ++u) {
      const std::size_t i = static_cast<std::size_t>(v) * moved.width() + u;
      if (step.candidate.valid[i]) moved.set(u, v, step.candidate.quadrics[i].cast<float>());
    }
  int restored = 0;
  jpcr::QuadricMap refined;  // assigned untimed, so neither its copy nor its release is timed
  for (auto _ : state) {
    state.PauseTiming();
    refined = moved;
    state.ResumeTiming();
    restored = jpcr::keep_lower_cost_fits(w.vertices, w.camera, step.candidate.poses, params,
                                          w.initial, refined);
    benchmark::DoNotOptimize(refined.quadrics.data());
  }
  state.counters["restored"] = restored;
}

BENCHMARK(BM_KeepLowerCostFits)
    ->Args({320, 2})
    ->Args({640, 2})
    ->Args({320, 5})
    ->Args({640, 5})
    ->Unit(benchmark::kMillisecond)
    ->UseRealTime();
BENCHMARK(BM_JointFrameToFrameIteration)
    ->Args({320, 2})
    ->Args({640, 2})
    ->Unit(benchmark::kMillisecond)
    ->UseRealTime();
BENCHMARK(BM_JointFrameToFrameRejectedStep)
    ->Args({320, 2})
    ->Args({640, 2})
    ->Unit(benchmark::kMillisecond)
    ->UseRealTime();
BENCHMARK(BM_JointFrameToFrameIterationReference)
    ->Args({320, 2})
    ->Args({640, 2})
    ->Unit(benchmark::kMillisecond)
    ->UseRealTime();
BENCHMARK(BM_JointWindowIteration)
    ->Args({320, 5})
    ->Args({640, 5})
    ->Unit(benchmark::kMillisecond)
    ->UseRealTime();
BENCHMARK(BM_JointWindowIterationRecomputed)
    ->Args({320, 5})
    ->Args({640, 5})
    ->Unit(benchmark::kMillisecond)
    ->UseRealTime();
BENCHMARK(BM_JointWindowRejectedStep)
    ->Args({320, 5})
    ->Args({640, 5})
    ->Unit(benchmark::kMillisecond)
    ->UseRealTime();
BENCHMARK(BM_FixedQuadricIteration)
    ->Args({320, 5})
    ->Args({640, 5})
    ->Unit(benchmark::kMillisecond)
    ->UseRealTime();

}  // namespace

int main(int argc, char** argv) {
  return jpcr::bench::benchmark_main(
      argc, argv, "bench_joint",
      "Times one Levenberg-Marquardt iteration of J-ftf (M = 2), J-full and Q-full (M = 5) on\n"
      "the CPU: linearise the Schur-reduced system, solve the poses, back-substitute and cost\n"
      "the candidate. room_spheres with 1 % range noise at 320x240 and 640x480, poses 1 cm / 1°\n"
      "off the truth; J-ftf also with the per-sample reference sums the GPU kernels run; and\n"
      "the pass after the loop that keeps each quadric's lower-cost fit (keep_lower_cost_fit);\n"
      "a rejected J-ftf and J-full step (propose, then only the damping changes: redamp); and\n"
      "the J-full iteration without kept blocks (joint.block_memory_mb: 0).\n"
      "Then the ratios of the same run: gathered / reference sums (J-ftf), Q-full / J-full,\n"
      "that pass / one iteration (J-ftf at M = 2, J-full at M = 5), rejected / accepted step,\n"
      "J-full with / without kept blocks.",
      {{"BM_JointFrameToFrameIteration", "BM_JointFrameToFrameIterationReference"},
       {"BM_JointFrameToFrameRejectedStep", "BM_JointFrameToFrameIteration"},
       {"BM_JointWindowRejectedStep", "BM_JointWindowIteration"},
       {"BM_JointWindowIteration", "BM_JointWindowIterationRecomputed"},
       {"BM_FixedQuadricIteration", "BM_JointWindowIteration"},
       {"BM_KeepLowerCostFits", "BM_JointFrameToFrameIteration"},
       {"BM_KeepLowerCostFits", "BM_JointWindowIteration"}});
}
