// GPU J-ftf speed (issue 7: ≤ 2 ms per 640x480 iteration and ≤ 15 ms per keyframe pair on an
// H100) at 320x240 and 640x480 with the reference 129-sample pattern (r = 6, s = 3 at both
// sizes), on rendered room_spheres pairs with range:1 noise, T₂ 1 cm / 1° off the truth
// (joint_bench_window.hpp). After a warm-up, the median of --runs (≥ 20) runs of
//   iteration  linearize + the host's 6x6 solve + propose (back-substitution and the candidate's
//              cost): wall time, and the CUDA-event times of the two device stages;
//   refine     CudaJointFrameToFrame::refine of the pair to convergence: uploads, every
//              iteration, the final undamped linearisation and the download of the quadrics.
// Rows for double and float; the float rows also print how far float's first pose step and
// candidate curvature are from double's, and the CPU row (JointSystem, median of 3) the same
// iteration on the host. Exits 0 with a message when there is no GPU.
//
//   bench_cuda_joint [--runs N] [--warmup N] [--no-cpu] [--width 320|640]
//                    [--noise-matched]
#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <string>
#include <vector>

#include "cuda_bench_options.hpp"
#include "joint_bench_window.hpp"
#include "jpcr/backend/joint_problem.hpp"
#include "jpcr/backend/joint_system.hpp"
#include "jpcr/backend/lower_cost_fit.hpp"
#include "jpcr/cuda/cuda_joint_ftf.hpp"
#include "jpcr/cuda/device_selection.hpp"

namespace {

using jpcr::bench::median;
using jpcr::bench::ms_since;

jpcr::JointParams params_at(int width, const jpcr::bench::CudaBenchOptions& o) {
  jpcr::JointParams params;
  jpcr::bench::bench_quadric_params(width, o, params.quadric);
  return params;
}

// One iteration's pose step and candidate (for the float-vs-double comparison).
struct Iteration {
  jpcr::Vector6d step = jpcr::Vector6d::Zero();
  std::vector<jpcr::Quadricd> candidate;
};

Iteration iterate(jpcr::CudaJointSystem& system, double lambda) {
  const jpcr::ReducedSystem lin = system.linearize(lambda);
  std::vector<jpcr::Vector6d> steps;
  Iteration it;
  if (!jpcr::JointSystem::solve_poses(lin, lambda, steps)) return it;
  system.propose(lin, lambda, steps);
  it.step = steps[0];
  return it;
}

double kappa_rms(const std::vector<jpcr::Quadricd>& a, const std::vector<jpcr::Quadricd>& b,
                 const std::vector<unsigned char>& valid) {
  double sum = 0.0;
  long n = 0;
  for (std::size_t i = 0; i < a.size(); ++i) {
    if (!valid[i]) continue;
    const Eigen::Vector2d d = jpcr::principal_curvatures(a[i].a, a[i].b, a[i].c) -
                              jpcr::principal_curvatures(b[i].a, b[i].b, b[i].c);
    if (!d.allFinite()) continue;
    sum += d.squaredNorm();
    n += 2;
  }
  return n > 0 ? std::sqrt(sum / n) : NAN;
}

template <typename F>
double median_ms(int runs, F&& f) {
  std::vector<double> ms;
  for (int i = 0; i < runs; ++i) {
    const auto start = std::chrono::steady_clock::now();
    f();
    ms.push_back(ms_since(start));
  }
  return median(ms);
}

// Where refine()'s time goes, stage by stage (each the median of `runs` on its own): the load
// (the float map converted into the kept double state, then the uploads), every linearisation
// (the first, one per step tried, the final undamped one) and proposal at the event times of
// the iteration rows, the download of the refined quadrics, the host's count of the reference
// frame's inliers (refined_map), the host's lower-cost pass after the loop (keep_lower_cost_fits,
// with its copy of the map), and the rest (6x6 solves, covariance, the refined map's copy, the
// host's normals for edge_quadrics).
// Leaves `system` loaded with the window and one step accepted.
std::string refine_breakdown(jpcr::CudaJointSystem& system, const jpcr::bench::JointBenchWindow& w,
                             const jpcr::NeighbourhoodPattern& pattern,
                             const jpcr::JointParams& params, const jpcr::RefinementResult& result,
                             double refine_ms, double lin_ms, double propose_ms, int runs) {
  const jpcr::RefinementReport& report = result.report;
  jpcr::JointState kept;
  const double fill = median_ms(runs, [&] { fill_joint_state(w.state.poses, w.initial, kept); });
  const double fresh = median_ms(runs, [&] { initial_joint_state(w.state.poses, w.initial); });
  const double load = median_ms(
      runs, [&] { system.load(w.vertices, w.camera, pattern, w.state.poses, w.initial); });
  const double download = median_ms(runs, [&] {
    iterate(system, params.initial_damping);
    system.accept();  // the host copy is stale: state() downloads
    system.state();
  });
  const double inliers = median_ms(runs, [&] {
    jpcr::reference_inliers(w.vertices[0], pattern, params.terms(true), system.state());
  });
  const double pass =
      params.keep_lower_cost_fit && report.iterations > 0
          ? median_ms(runs,
                      [&] {
                        jpcr::QuadricMap refined = result.quadrics;
                        jpcr::keep_lower_cost_fits(w.vertices, w.camera, result.poses, params,
                                                   w.initial, refined);
                      })
          : 0.0;
  const int tried = report.iterations + report.rejected_steps;
  const double rest = refine_ms - load - (tried + 2) * lin_ms - tried * propose_ms -
                      (download - lin_ms - propose_ms) - inliers - pass;
  char text[480];
  std::snprintf(text, sizeof text,
                "          refine = load %.2f (of which the state %.2f; %.2f into fresh memory) + "
                "%d linearisations x %.3f + %d proposals x %.3f + download %.2f + reference "
                "inliers (host) %.2f + lower-cost pass (host) %.2f + rest %.2f; %d rejected "
                "steps\n",
                load, fill, fresh, tried + 2, lin_ms, tried, propose_ms,
                download - lin_ms - propose_ms, inliers, pass, rest, report.rejected_steps);
  return text;
}

void gpu_rows(int width, const jpcr::bench::CudaBenchOptions& o) {
  const jpcr::JointParams params = params_at(width, o);
  const jpcr::bench::JointBenchWindow w = jpcr::bench::make_joint_window(width, 2, params.quadric);
  const jpcr::NeighbourhoodPattern pattern = params.quadric.pattern.for_width(width);
  const double lambda = params.initial_damping;
  Iteration reference;  // double's first iteration
  for (jpcr::CudaPrecision precision :
       {jpcr::CudaPrecision::kDouble, jpcr::CudaPrecision::kFloat}) {
    const bool is_double = precision == jpcr::CudaPrecision::kDouble;
    jpcr::CudaJointSystem system(params.terms(true), precision);
    system.load(w.vertices, w.camera, pattern, w.state);
    Iteration first = iterate(system, lambda);
    first.candidate = system.candidate().quadrics;
    for (int i = 0; i < o.warmup; ++i)
      iterate(system, lambda);
    std::vector<double> wall, lin_ms, propose_ms;
    for (int i = 0; i < o.runs; ++i) {
      const auto start = std::chrono::steady_clock::now();
      iterate(system, lambda);  // the same state every run: nothing is accepted
      wall.push_back(ms_since(start));
      lin_ms.push_back(system.last_timing().linearize_ms);
      propose_ms.push_back(system.last_timing().propose_ms);
    }
    const int active = system.linearize(lambda).active;

    const jpcr::CudaJointFrameToFrame refiner(params, precision);
    const std::vector<Eigen::Isometry3d> start = w.state.poses;
    jpcr::RefinementResult r = refiner.refine(w.vertices, w.camera, start, w.initial);
    for (int i = 0; i < o.warmup; ++i)
      refiner.refine(w.vertices, w.camera, start, w.initial);
    std::vector<double> refine_ms;
    for (int i = 0; i < o.runs; ++i) {
      const auto t0 = std::chrono::steady_clock::now();
      r = refiner.refine(w.vertices, w.camera, start, w.initial);
      refine_ms.push_back(ms_since(t0));
    }
    const std::string breakdown = refine_breakdown(system, w, pattern, params, r, median(refine_ms),
                                                   median(lin_ms), median(propose_ms), o.runs);
    std::string accuracy = "-";
    if (is_double) {
      reference = first;
    } else {
      char text[96];
      std::snprintf(text, sizeof text, "step %.1e rel, kappa %.1e 1/m",
                    (first.step - reference.step).norm() / reference.step.norm(),
                    kappa_rms(first.candidate, reference.candidate, w.state.valid));
      accuracy = text;
    }
    std::printf("%4dx%-4d %7d  %-6s  %8d  %9.3f  %9.3f  %9.3f  %9.3f  %5d  %-16s  %s\n", width,
                width * 3 / 4, pattern.size(), is_double ? "double" : "float", active,
                median(lin_ms), median(propose_ms), median(wall), median(refine_ms),
                r.report.iterations, jpcr::to_string(r.report.verdict), accuracy.c_str());
    std::printf("%s", breakdown.c_str());
  }
}

void cpu_row(int width, const jpcr::bench::CudaBenchOptions& o) {
  const jpcr::JointParams params = params_at(width, o);
  const jpcr::bench::JointBenchWindow w = jpcr::bench::make_joint_window(width, 2, params.quadric);
  const jpcr::NeighbourhoodPattern pattern = params.quadric.pattern.for_width(width);
  const jpcr::JointSystem system(w.vertices, w.camera, pattern, params.terms(true));
  const double lambda = params.initial_damping;
  // Timed as bench_joint and the refinement loop run it: the buffers kept across iterations
  // (fresh ones cost about twice the time at 640x480), after the same warm-up as the GPU rows.
  jpcr::ReducedSystem lin;
  jpcr::JointStep step;
  std::vector<jpcr::Vector6d> steps;
  std::vector<double> wall;
  int active = 0;
  for (int i = 0; i < o.warmup + o.runs; ++i) {
    const auto start = std::chrono::steady_clock::now();
    system.linearize(w.state, lambda, lin);
    if (jpcr::JointSystem::solve_poses(lin, lambda, steps))
      system.step(w.state, lin, lambda, steps, step);
    if (i >= o.warmup) wall.push_back(ms_since(start));
    active = lin.active;
  }
  std::printf("%4dx%-4d %7d  %-6s  %8d  %9s  %9s  %9.3f  %9s  %5s  %-16s  %s\n", width,
              width * 3 / 4, pattern.size(), "cpu", active, "-", "-", median(wall), "-", "-", "-",
              "-");
}

}  // namespace

int main(int argc, char** argv) {
  jpcr::bench::CudaBenchOptions o;
  const int status = jpcr::bench::parse_cuda_bench_options(
      argc, argv, "bench_cuda_joint",
      "GPU J-ftf: ms per iteration and per pair refined to convergence", o);
  if (status >= 0) return status;
  const jpcr::CudaDeviceInfo& gpu = jpcr::query_cuda_device();
  if (!gpu.available) {
    std::printf("bench_cuda_joint: no CUDA device (%s); nothing to time\n",
                gpu.description.c_str());
    return 0;
  }
  std::printf("J-ftf on %s: %d warm-up, median of %d runs (ms)%s\n", gpu.description.c_str(),
              o.warmup, o.runs,
              o.noise_matched ? "; n0 = gate = 0.03 m per m of range (--noise-matched)" : "");
  std::printf("%-9s %7s  %-6s  %8s  %9s  %9s  %9s  %9s  %5s  %-16s  %s\n", "size", "samples",
              "type", "active", "linearize", "propose", "iteration", "refine", "steps", "verdict",
              "float vs double");
  for (int width : o.widths) {
    gpu_rows(width, o);
    if (o.cpu) cpu_row(width, o);
  }
  std::printf(
      "linearize, propose = CUDA events (kernels + the reduced sums' download); iteration = "
      "wall time of linearize + 6x6 solve + propose; refine = wall time of refining the pair "
      "to convergence (uploads, iterations, final linearisation, download)\n");
  return 0;
}
