// GPU J-ftf against the CPU reference (issue 7, label gpu; skipped without a GPU), on fresh random
// pairs (tests/cuda/random_frames.hpp; the seed is printed, JPCR_TEST_SEED replays it):
// The CPU side is JointSampling::kReference: sample by sample in double, the GPU's own math. (The
// default CPU path sums in float SIMD lanes; on the H200, 2026-12-04, its S, s, diag A and cost
// were 1.1e-8 to 1.6e-8 relative from the GPU's on every pair, and one pair's term count differed
// by 1 in 4.6 million: float rounding, not a GPU error.)
//   - one iteration: the reduced system S, s, diag A and the cost equal the CPU JointSystem's to
//     1e-9 relative (double sums of the same per-pixel numbers; only the summation order and FMA
//     contraction differ, about 1e-15 per term), the active set and the term count exactly, the
//     pose step to 1e-6 relative, the candidate's cost to 1e-9 relative and its curvature map to
//     1e-4 1/m RMS; every device output is pre-filled with NaN and none may remain;
//   - a whole refinement ends as the CPU's does: same verdict and step count, the poses to
//     1e-6 m / 1e-6 rad (a tenth of the convergence tolerances), curvature to 1e-4 1/m RMS;
//   - device buffers are reused across pairs, and the factory hands out the GPU refiner.
#include <cmath>
#include <cstdio>
#include <sstream>
#include <thread>
#include <utility>

#include <cuda_runtime_api.h>

#include <gtest/gtest.h>

#include "cuda/random_frames.hpp"
#include "jpcr/backend/joint_frame_to_frame.hpp"
#include "jpcr/backend/joint_problem.hpp"
#include "jpcr/backend/joint_system.hpp"
#include "jpcr/backend/lower_cost_fit.hpp"
#include "jpcr/cuda/cpu_fallback_refiner.hpp"
#include "jpcr/cuda/cuda_joint_ftf.hpp"
#include "jpcr/cuda/refiner_factory.hpp"
#include "jpcr/quadric/quadric_fit.hpp"
#include "jpcr/quadric/se3.hpp"

namespace jpcr {
namespace {

#define SKIP_WITHOUT_GPU()      \
  if (!cuda_device_available()) \
  GTEST_SKIP() << "no CUDA device (" << query_cuda_device().description << ")"

double relative(const Eigen::MatrixXd& a, const Eigen::MatrixXd& reference) {
  return (a - reference).norm() / reference.norm();
}

double relative(double a, double reference) {
  return std::abs(a - reference) / std::abs(reference);
}

// RMS of the principal-curvature difference over the pixels valid in `valid` whose quadrics
// are finite in both.
double curvature_rms(const std::vector<Quadricd>& a, const std::vector<Quadricd>& b,
                     const std::vector<unsigned char>& valid) {
  double sum = 0.0;
  int n = 0;
  for (std::size_t i = 0; i < a.size(); ++i) {
    if (!valid[i]) continue;
    const Eigen::Vector2d ka = principal_curvatures(a[i].a, a[i].b, a[i].c);
    const Eigen::Vector2d kb = principal_curvatures(b[i].a, b[i].b, b[i].c);
    if (!ka.allFinite() || !kb.allFinite()) continue;
    sum += (ka - kb).squaredNorm();
    n += 2;
  }
  return n > 0 ? std::sqrt(sum / n) : NAN;
}

bool finite(const Quadricd& q) {
  return q.R.allFinite() && q.center.allFinite() && std::isfinite(q.t_z) && std::isfinite(q.a) &&
         std::isfinite(q.b) && std::isfinite(q.c);
}

bool same(const Quadricd& a, const Quadricd& b) {
  return a.R == b.R && a.center == b.center && a.t_z == b.t_z && a.a == b.a && a.b == b.b &&
         a.c == b.c;
}

std::uint64_t announce_seed() {
  const std::uint64_t seed = test::test_seed();
  std::printf("seed %llu (JPCR_TEST_SEED replays it); %s\n", static_cast<unsigned long long>(seed),
              query_cuda_device().description.c_str());
  return seed;
}

// A 160x120 random pair with what CudaJointSystem::load takes: default parameters, their
// pattern, Quad IT's map of frame 1 and the start poses {I, T₂}.
struct PairInputs {
  test::RandomPair pair;
  JointParams params;
  NeighbourhoodPattern pattern;
  QuadricMap initial;
  std::vector<Eigen::Isometry3d> poses;
};

PairInputs pair_inputs(std::uint64_t seed) {
  PairInputs in;
  in.pair = test::random_pair(seed, 160, 120);
  in.pattern = in.params.quadric.pattern.for_width(in.pair.camera.width);
  in.initial = QuadricFit(in.params.quadric).estimate(in.pair.vertices[0]);
  in.poses = {Eigen::Isometry3d::Identity(), in.pair.start};
  return in;
}

// One iteration of the CPU reference from a random pair's start: the state, the linearisation,
// the pose steps and the step.
struct CpuIteration {
  NeighbourhoodPattern pattern;
  JointState state;
  ReducedSystem lin;
  std::vector<Vector6d> steps;
  bool solved = false;
  JointStep step;
};

CpuIteration cpu_iteration(const test::RandomPair& pair, const JointParams& params, double lambda) {
  CpuIteration it;
  it.pattern = params.quadric.pattern.for_width(pair.camera.width);
  const QuadricMap initial = QuadricFit(params.quadric).estimate(pair.vertices[0]);
  it.state = initial_joint_state({Eigen::Isometry3d::Identity(), pair.start}, initial);
  const JointSystem cpu(pair.vertices, pair.camera, it.pattern, params.terms(true),
                        JointSampling::kReference);
  it.lin = cpu.linearize(it.state, lambda);
  it.solved = JointSystem::solve_poses(it.lin, lambda, it.steps);
  if (it.solved) it.step = cpu.step(it.state, it.lin, lambda, it.steps);
  return it;
}

// The parity tests' inputs, checked on the CPU (runs without a GPU too): a random pair overlaps
// (measured 34-72 % of the pixels active on 8 seeds; the bound is 12.5 %) and its start pose is
// 1 cm / 1° off the truth.
TEST(CudaJointFrameToFrame, RandomPairsOverlapAndStartOneCentimetreOneDegreeOff) {
  const std::uint64_t seed = test::test_seed();
  const test::RandomPair pair = test::random_pair(seed, 160, 120);
  const Eigen::Isometry3d E = pair.start * pair.truth.inverse();       // exp(δ^) of 1 cm, 1°
  EXPECT_NEAR(E.translation().norm(), 0.01, 1e-4) << "seed " << seed;  // |V t| = |t| (1 + O(θ²))
  EXPECT_NEAR(rotation_angle(E.linear()), M_PI / 180, 1e-9) << "seed " << seed;
  const JointParams params;
  const QuadricMap initial = QuadricFit(params.quadric).estimate(pair.vertices[0]);
  const JointSystem cpu(pair.vertices, pair.camera,
                        params.quadric.pattern.for_width(pair.camera.width), params.terms(true));
  const ReducedSystem lin =
      cpu.linearize(initial_joint_state({Eigen::Isometry3d::Identity(), pair.start}, initial), 0.0);
  std::printf("seed %llu: %d of %d pixels active\n", static_cast<unsigned long long>(seed),
              lin.active, 160 * 120);
  EXPECT_GT(lin.active, 160 * 120 / 8) << "seed " << seed;
}

TEST(CudaJointFrameToFrame, OneIterationEqualsTheCpuReference) {
  SKIP_WITHOUT_GPU();
  const std::uint64_t seed = announce_seed();
  const JointParams params;
  const double lambda = params.initial_damping;
  // 317x239: thread blocks cut by the image's right and bottom edges.
  const std::pair<int, int> sizes[] = {{320, 240}, {320, 240}, {317, 239}};
  for (std::uint64_t k = 0; k < 3; ++k) {
    const auto [width, height] = sizes[k];
    const test::RandomPair pair = test::random_pair(seed + k, width, height);
    const CpuIteration ref = cpu_iteration(pair, params, lambda);
    ASSERT_TRUE(ref.solved) << "seed " << seed + k;
    const NeighbourhoodPattern& pattern = ref.pattern;
    const JointState& state = ref.state;
    const ReducedSystem& cpu_lin = ref.lin;
    const std::vector<Vector6d>& cpu_steps = ref.steps;
    const JointStep& cpu_step = ref.step;

    CudaJointSystem gpu(params.terms(true));
    gpu.set_poison_outputs(true);
    gpu.load(pair.vertices, pair.camera, pattern, state);
    const ReducedSystem gpu_lin = gpu.linearize(lambda);
    std::vector<Vector6d> gpu_steps;
    ASSERT_TRUE(JointSystem::solve_poses(gpu_lin, lambda, gpu_steps)) << "seed " << seed + k;
    const double gpu_cost = gpu.propose(gpu_lin, lambda, gpu_steps);
    const JointState candidate = gpu.candidate();
    const std::vector<PairFactors> factors = gpu.factors();

    const double rel_S = relative(gpu_lin.S, cpu_lin.S), rel_s = relative(gpu_lin.s, cpu_lin.s);
    const double rel_step = relative(gpu_steps[0], cpu_steps[0]);
    const double rms = curvature_rms(candidate.quadrics, cpu_step.candidate.quadrics, state.valid);
    std::printf(
        "seed %llu: %d active quadrics (CPU %d), S %.2g, s %.2g, diag A %.2g, cost %.2g relative; "
        "pose step %.2g relative; candidate cost %.2g relative, kappa RMS %.2g 1/m; "
        "linearize %.3f ms, propose %.3f ms\n",
        static_cast<unsigned long long>(seed + k), gpu_lin.active, cpu_lin.active, rel_S, rel_s,
        relative(gpu_lin.A_diagonal, cpu_lin.A_diagonal), relative(gpu_lin.cost, cpu_lin.cost),
        rel_step, relative(gpu_cost, cpu_step.cost), rms, gpu.last_timing().linearize_ms,
        gpu.last_timing().propose_ms);
    EXPECT_GT(cpu_lin.active, width * height / 8) << "seed " << seed + k;
    EXPECT_EQ(gpu_lin.active, cpu_lin.active) << "seed " << seed + k;
    EXPECT_EQ(gpu_lin.seen, cpu_lin.seen) << "seed " << seed + k;
    EXPECT_EQ(gpu_lin.terms, cpu_lin.terms) << "seed " << seed + k;
    EXPECT_LE(rel_S, 1e-9) << "seed " << seed + k;
    EXPECT_LE(rel_s, 1e-9) << "seed " << seed + k;
    EXPECT_LE(relative(gpu_lin.A_diagonal, cpu_lin.A_diagonal), 1e-9) << "seed " << seed + k;
    EXPECT_LE(relative(gpu_lin.cost, cpu_lin.cost), 1e-9) << "seed " << seed + k;
    EXPECT_LE(rel_step, 1e-6) << "seed " << seed + k;
    EXPECT_LE(relative(gpu_cost, cpu_step.cost), 1e-9) << "seed " << seed + k;
    EXPECT_LE(rms, 1e-4) << "seed " << seed + k;

    // Every output written: the factors of exactly the CPU's active quadrics, all finite; every
    // candidate quadric finite, and the inactive ones unchanged.
    // (The CPU's factors come in the order its threads finished; the GPU's in pixel order.)
    std::vector<unsigned char> active(state.quadrics.size(), 0), cpu_active(active);
    for (const QuadricBlocks& b : cpu_lin.blocks)
      cpu_active[b.pixel] = 1;
    for (const PairFactors& f : factors) {
      ASSERT_TRUE(f.k.allFinite() && f.K.allFinite()) << "pixel " << f.pixel;
      active[f.pixel] = 1;
    }
    ASSERT_EQ(factors.size(), cpu_lin.blocks.size()) << "seed " << seed + k;
    ASSERT_TRUE(active == cpu_active) << "seed " << seed + k;
    for (std::size_t i = 0; i < candidate.quadrics.size(); ++i) {
      if (!finite(state.quadrics[i])) continue;  // only where the CPU state is a number
      ASSERT_TRUE(finite(candidate.quadrics[i])) << "pixel " << i << ", seed " << seed + k;
      if (!active[i]) {
        ASSERT_TRUE(same(candidate.quadrics[i], state.quadrics[i])) << "pixel " << i;
      }
    }
  }
}

// Float (CudaPrecision::kFloat: selectable, not the default) has its own buffer layout (factors
// at half size) and kernel instances. One iteration against the double CPU reference: measured
// on the H200 (cuda/NOTES.md) the pose step was 1e-5 relative and the candidate κ RMS 1.3e-3 1/m
// at 320x240; the bounds leave 100x and 15x, and every factor and candidate quadric must be
// written. A wrong stride or layout fails them.
TEST(CudaJointFrameToFrame, OneFloatIterationIsWithinFloatOfTheCpuReference) {
  SKIP_WITHOUT_GPU();
  const std::uint64_t seed = announce_seed();
  const JointParams params;
  const double lambda = params.initial_damping;
  for (const auto& [width, height] : {std::pair{320, 240}, std::pair{317, 239}}) {
    const test::RandomPair pair = test::random_pair(seed, width, height);
    const CpuIteration ref = cpu_iteration(pair, params, lambda);
    ASSERT_TRUE(ref.solved) << "seed " << seed;
    const NeighbourhoodPattern& pattern = ref.pattern;
    const JointState& state = ref.state;
    const ReducedSystem& cpu_lin = ref.lin;
    const std::vector<Vector6d>& cpu_steps = ref.steps;
    const JointStep& cpu_step = ref.step;

    CudaJointSystem gpu(params.terms(true), CudaPrecision::kFloat);
    gpu.set_poison_outputs(true);
    gpu.load(pair.vertices, pair.camera, pattern, state);
    const ReducedSystem gpu_lin = gpu.linearize(lambda);
    std::vector<Vector6d> gpu_steps;
    ASSERT_TRUE(JointSystem::solve_poses(gpu_lin, lambda, gpu_steps)) << "seed " << seed;
    gpu.propose(gpu_lin, lambda, gpu_steps);
    const JointState candidate = gpu.candidate();
    const std::vector<PairFactors> factors = gpu.factors();
    const double rel_step = relative(gpu_steps[0], cpu_steps[0]);
    const double rms = curvature_rms(candidate.quadrics, cpu_step.candidate.quadrics, state.valid);
    std::printf(
        "%dx%d float: %d active (CPU %d), S %.2g relative, pose step %.2g relative, "
        "candidate kappa RMS %.2g 1/m\n",
        width, height, gpu_lin.active, cpu_lin.active, relative(gpu_lin.S, cpu_lin.S), rel_step,
        rms);
    EXPECT_NEAR(gpu_lin.active, cpu_lin.active, cpu_lin.active / 100) << "seed " << seed;
    EXPECT_LE(relative(gpu_lin.S, cpu_lin.S), 1e-3) << "seed " << seed;
    EXPECT_LE(rel_step, 1e-3) << "seed " << seed;
    EXPECT_LE(rms, 2e-2) << "seed " << seed;
    ASSERT_EQ(static_cast<int>(factors.size()), gpu_lin.active) << "seed " << seed;
    for (const PairFactors& f : factors)
      ASSERT_TRUE(f.k.allFinite() && f.K.allFinite()) << "pixel " << f.pixel;
    for (std::size_t i = 0; i < candidate.quadrics.size(); ++i) {
      if (finite(state.quadrics[i])) {
        ASSERT_TRUE(finite(candidate.quadrics[i])) << "pixel " << i << ", seed " << seed;
      }
    }
  }
}

TEST(CudaJointFrameToFrame, RefinesAPairToConvergenceAsTheCpu) {
  SKIP_WITHOUT_GPU();
  const std::uint64_t seed = announce_seed();
  JointParams params;  // n₀ and the gate grow with the range, as for range noise in Quad IT
  params.quadric.fit.fair_n0_per_range = params.quadric.fit.gate_per_range = 0.03f;
  // The loop's parity first; keep_lower_cost_fit, host code after the loop, is checked below.
  params.keep_lower_cost_fit = false;
  const test::RandomPair pair = test::random_pair(seed, 320, 240);
  const QuadricMap initial = QuadricFit(params.quadric).estimate(pair.vertices[0]);
  const std::vector<Eigen::Isometry3d> start = {Eigen::Isometry3d::Identity(), pair.start};
  const JointSystem reference(pair.vertices, pair.camera,
                              params.quadric.pattern.for_width(pair.camera.width),
                              params.terms(true), JointSampling::kReference);
  JointState state = initial_joint_state(start, initial);
  const int left_out = leave_out(edge_quadrics(pair.vertices[0], params), state);
  CpuJointProblem problem(reference, std::move(state));
  const RefinementResult cpu =
      run_joint_refinement(problem, params, true, "j-ftf", initial, pair.vertices[0]);
  const CudaJointFrameToFrame gpu_refiner(params);
  const RefinementResult gpu = gpu_refiner.refine(pair.vertices, pair.camera, start, initial);
  const Eigen::Isometry3d E = cpu.poses[1].inverse() * gpu.poses[1];
  const double dt = E.translation().norm(), dr = rotation_angle(E.linear());
  double sum = 0.0;
  int n = 0, gpu_valid = 0, cpu_valid = 0;
  for (std::size_t i = 0; i < gpu.quadrics.status.size(); ++i) {
    gpu_valid += gpu.quadrics.status[i] == QuadricStatus::kValid ? 1 : 0;
    cpu_valid += cpu.quadrics.status[i] == QuadricStatus::kValid ? 1 : 0;
    if (gpu.quadrics.status[i] != QuadricStatus::kValid ||
        cpu.quadrics.status[i] != QuadricStatus::kValid)
      continue;
    sum += (gpu.quadrics.curvature[i] - cpu.quadrics.curvature[i]).cast<double>().squaredNorm();
    n += 2;
  }
  const double rms = n > 0 ? std::sqrt(sum / n) : NAN;
  std::printf(
      "CPU %s after %d steps (%d rejected), GPU %s after %d steps (%d rejected); poses differ "
      "by %.2g m, %.2g rad; kappa RMS %.2g 1/m; final cost %.6g vs %.6g\n",
      to_string(cpu.report.verdict), cpu.report.iterations, cpu.report.rejected_steps,
      to_string(gpu.report.verdict), gpu.report.iterations, gpu.report.rejected_steps, dt, dr, rms,
      cpu.report.cost.back(), gpu.report.cost.back());
  EXPECT_NE(cpu.report.verdict, RefinementVerdict::kTooFewQuadrics) << "seed " << seed;
  EXPECT_GT(cpu.report.iterations, 1) << "seed " << seed;
  EXPECT_EQ(gpu.report.verdict, cpu.report.verdict) << "seed " << seed;
  EXPECT_EQ(cpu.report.device, "cpu");
  EXPECT_EQ(gpu.report.device, "cuda");
  EXPECT_EQ(gpu.report.iterations, cpu.report.iterations) << "seed " << seed;
  EXPECT_EQ(gpu.report.active_quadrics, cpu.report.active_quadrics) << "seed " << seed;
  EXPECT_EQ(gpu.report.edge_quadrics, left_out) << "seed " << seed;
  EXPECT_LE(dt, 1e-6) << "seed " << seed;
  EXPECT_LE(dr, 1e-6) << "seed " << seed;
  EXPECT_LE(rms, 1e-4) << "seed " << seed;
  // The curvature RMS above skips the pixels either map marks invalid; refined_map marks a fit
  // whose inliers fall below min_samples, which a sample on the gate can flip: a few pixels, not
  // a GPU state the host cannot read (that would be thousands).
  EXPECT_NEAR(gpu_valid, cpu_valid, 0.001 * cpu_valid + 2) << "seed " << seed;
  EXPECT_LE(relative(gpu.report.cost.back(), cpu.report.cost.back()), 1e-6) << "seed " << seed;
  if (cpu.covariance[1].norm() > 0.0) {  // zero when S is degenerate (finish_report)
    EXPECT_LE(relative(gpu.covariance[1], cpu.covariance[1]), 1e-6) << "seed " << seed;
  } else {
    EXPECT_EQ(gpu.covariance[1].norm(), 0.0) << "seed " << seed;
  }
  // With keep_lower_cost_fit (the default) the GPU refiner restores the Quad IT fits that the
  // host's keep_lower_cost_fits restores on its result (up to near-ties, which the rounding of
  // the device sums may turn).
  JointParams kept = params;
  kept.keep_lower_cost_fit = true;
  const RefinementResult gpu_kept =
      CudaJointFrameToFrame(kept).refine(pair.vertices, pair.camera, start, initial);
  QuadricMap host = gpu.quadrics;
  const int restored =
      keep_lower_cost_fits(pair.vertices, pair.camera, gpu.poses, kept, initial, host);
  // The same pass on the CPU refiner's result: its decisions differ from those on the GPU's
  // only where the two maps' rounding turns a near-tie.
  QuadricMap cpu_host = cpu.quadrics;
  const int cpu_restored =
      keep_lower_cost_fits(pair.vertices, pair.camera, cpu.poses, kept, initial, cpu_host);
  std::printf("restored: GPU refiner %d, host on its result %d, on the CPU's result %d\n",
              gpu_kept.report.quad_it_fits_restored, restored, cpu_restored);
  EXPECT_EQ(gpu.report.quad_it_fits_restored, 0) << "seed " << seed;
  EXPECT_NEAR(gpu_kept.report.quad_it_fits_restored, restored, 0.02 * restored + 2)
      << "seed " << seed;
  EXPECT_NEAR(restored, cpu_restored, 0.02 * cpu_restored + 2) << "seed " << seed;
  if (restored > 10) {
    EXPECT_GT(gpu_kept.report.quad_it_fits_restored, 0) << "seed " << seed;
  }
}

TEST(CudaJointFrameToFrame, ReusesDeviceBuffersAcrossPairs) {
  SKIP_WITHOUT_GPU();
  const std::uint64_t seed = announce_seed();
  JointParams params;
  params.max_iterations = 2;
  const CudaJointFrameToFrame refiner(params);
  auto refine = [&](const test::RandomPair& pair) {
    const QuadricMap initial = QuadricFit(params.quadric).estimate(pair.vertices[0]);
    refiner.refine(pair.vertices, pair.camera, {Eigen::Isometry3d::Identity(), pair.start},
                   initial);
  };
  refine(test::random_pair(seed, 320, 240));
  const std::size_t after_first = refiner.device_allocations();
  EXPECT_GT(after_first, 0u);
  refine(test::random_pair(seed + 1, 320, 240));
  refine(test::random_pair(seed + 2, 160, 120));
  EXPECT_EQ(refiner.device_allocations(), after_first);
}

TEST(CudaJointFrameToFrame, RejectsBadInputLikeTheCpu) {
  SKIP_WITHOUT_GPU();
  const test::RandomPair pair = test::random_pair(test::test_seed(), 160, 120);
  const QuadricMap initial = QuadricFit().estimate(pair.vertices[0]);
  const CudaJointFrameToFrame refiner;
  const std::vector<VertexMap> three = {pair.vertices[0], pair.vertices[1], pair.vertices[1]};
  EXPECT_THROW(refiner.refine(three, pair.camera,
                              {Eigen::Isometry3d::Identity(), pair.start, pair.start}, initial),
               std::invalid_argument);
  EXPECT_THROW(refiner.refine(pair.vertices, pair.camera, {pair.start, pair.start}, initial),
               std::invalid_argument);
  EXPECT_THROW(refiner.refine(pair.vertices, pair.camera,
                              {Eigen::Isometry3d::Identity(), pair.start}, QuadricMap(80, 60)),
               std::invalid_argument);
}

// A pair that load() rejects leaves the loaded one as it was (the checks come before any copy);
// the reduction is deterministic, so the system linearises to the same numbers, bit for bit.
TEST(CudaJointFrameToFrame, ARejectedLoadKeepsTheLoadedPair) {
  SKIP_WITHOUT_GPU();
  const PairInputs in = pair_inputs(announce_seed());
  const auto& [pair, params, pattern, initial, poses] = in;
  CudaJointSystem gpu(params.terms(true));
  gpu.load(pair.vertices, pair.camera, pattern, poses, initial);
  const ReducedSystem before = gpu.linearize(params.initial_damping);
  ASSERT_GT(before.active, 0);
  EXPECT_THROW(gpu.load({pair.vertices[0]}, pair.camera, pattern, poses, initial),
               std::invalid_argument);
  EXPECT_THROW(gpu.load(pair.vertices, pair.camera, pattern, {poses[0]}, initial),
               std::invalid_argument);
  EXPECT_THROW(gpu.load(pair.vertices, pair.camera, pattern, poses, QuadricMap(80, 60)),
               std::invalid_argument);
  EXPECT_THROW(gpu.load(pair.vertices, pair.camera, pattern, poses, initial,
                        std::vector<unsigned char>(7, 1)),  // edge flags of another size
               std::invalid_argument);
  // Frames of as many pixels but another shape (the kernels would read frame 2 wrongly).
  const VertexMap transposed(pair.vertices[1].height(), pair.vertices[1].width(),
                             Eigen::Vector3f::Zero());
  EXPECT_THROW(gpu.load({pair.vertices[0], transposed}, pair.camera, pattern, poses, initial),
               std::invalid_argument);
  const ReducedSystem after = gpu.linearize(params.initial_damping);
  EXPECT_EQ(after.active, before.active);
  EXPECT_EQ(after.cost, before.cost);
  EXPECT_TRUE(after.S == before.S);
  EXPECT_TRUE(gpu.state().poses[1].isApprox(pair.start, 0.0));
}

// Nothing loaded yet: a step is a logic error, not a read past the poses.
TEST(CudaJointFrameToFrame, ProposeBeforeLoadIsALogicError) {
  SKIP_WITHOUT_GPU();
  CudaJointSystem gpu(JointParams{}.terms(true));
  EXPECT_THROW(gpu.propose(ReducedSystem{}, 0.0, {Vector6d::Zero()}), std::logic_error);
}

// The device buffers hold factors only after linearize() and a candidate only after propose():
// out of that order the calls are logic errors, not reads of another pair's leftovers.
TEST(CudaJointFrameToFrame, CallsOutOfTheLinearizeProposeAcceptOrderAreLogicErrors) {
  SKIP_WITHOUT_GPU();
  const PairInputs in = pair_inputs(announce_seed());
  const auto& [pair, params, pattern, initial, poses] = in;
  CudaJointSystem gpu(params.terms(true));
  gpu.load(pair.vertices, pair.camera, pattern, poses, initial);
  EXPECT_THROW(gpu.propose(ReducedSystem{}, 0.0, {Vector6d::Zero()}), std::logic_error);
  EXPECT_THROW(gpu.factors(), std::logic_error);
  EXPECT_THROW(gpu.candidate(), std::logic_error);
  EXPECT_THROW(gpu.accept(), std::logic_error);
  const ReducedSystem lin = gpu.linearize(params.initial_damping);
  EXPECT_FALSE(gpu.factors().empty());
  EXPECT_THROW(gpu.accept(), std::logic_error);
  gpu.propose(lin, params.initial_damping, {Vector6d::Zero()});
  EXPECT_EQ(gpu.candidate().quadrics.size(), pair.vertices[0].size());
  gpu.accept();
  // The factors were the replaced state's.
  EXPECT_THROW(gpu.propose(lin, params.initial_damping, {Vector6d::Zero()}), std::logic_error);
  EXPECT_THROW(gpu.accept(), std::logic_error);
}

// A refiner keeps the device it was built on and leaves the caller's current device as it was.
// With one GPU only the calls' save-and-restore of the current device runs (from another thread
// too); the half that calls with another device current, where a missing scope fails the launch,
// needs two GPUs and skips otherwise.
TEST(CudaJointFrameToFrame, KeepsItsDeviceWhateverDeviceTheCallerHasCurrent) {
  SKIP_WITHOUT_GPU();
  const test::RandomPair pair = test::random_pair(announce_seed(), 160, 120);
  JointParams params;
  params.max_iterations = 3;
  const QuadricMap initial = QuadricFit(params.quadric).estimate(pair.vertices[0]);
  const std::vector<Eigen::Isometry3d> start = {Eigen::Isometry3d::Identity(), pair.start};
  int built_on = -1;
  ASSERT_EQ(cudaGetDevice(&built_on), cudaSuccess);
  const CudaJointFrameToFrame refiner(params);
  const RefinementResult here = refiner.refine(pair.vertices, pair.camera, start, initial);
  RefinementResult there;
  std::string thread_error;
  std::thread([&] {
    try {
      there = refiner.refine(pair.vertices, pair.camera, start, initial);
    } catch (const std::exception& e) {
      thread_error = e.what();
    }
  }).join();
  ASSERT_TRUE(thread_error.empty()) << thread_error;
  EXPECT_TRUE(there.poses[1].isApprox(here.poses[1], 0.0));
  EXPECT_EQ(there.report.iterations, here.report.iterations);
  int count = 0;
  ASSERT_EQ(cudaGetDeviceCount(&count), cudaSuccess);
  if (count < 2) GTEST_SKIP() << "one CUDA device: the other-device half needs two";
  const int other = built_on == 0 ? 1 : 0;
  ASSERT_EQ(cudaSetDevice(other), cudaSuccess);
  const RefinementResult elsewhere = refiner.refine(pair.vertices, pair.camera, start, initial);
  int current = -1;
  ASSERT_EQ(cudaGetDevice(&current), cudaSuccess);
  ASSERT_EQ(cudaSetDevice(built_on), cudaSuccess);
  EXPECT_EQ(current, other);
  EXPECT_TRUE(elsewhere.poses[1].isApprox(here.poses[1], 0.0));
  EXPECT_EQ(elsewhere.report.verdict, here.report.verdict);
}

TEST(CudaJointFrameToFrame, AnEmptyPairHasTooFewQuadricsAsOnTheCpu) {
  SKIP_WITHOUT_GPU();
  const CameraIntrinsics camera = synthetic_camera(160, 120);
  const VertexMap empty = compute_vertex_map(DepthImage(camera.width, camera.height, 0.0f), camera);
  const QuadricMap initial = QuadricFit().estimate(empty);
  const std::vector<Eigen::Isometry3d> start = {Eigen::Isometry3d::Identity(),
                                                Eigen::Isometry3d::Identity()};
  const RefinementResult gpu =
      CudaJointFrameToFrame().refine({empty, empty}, camera, start, initial);
  const RefinementResult cpu = JointFrameToFrame().refine({empty, empty}, camera, start, initial);
  EXPECT_EQ(gpu.report.verdict, RefinementVerdict::kTooFewQuadrics);
  EXPECT_EQ(cpu.report.verdict, RefinementVerdict::kTooFewQuadrics);
  EXPECT_EQ(gpu.report.active_quadrics, 0);
  EXPECT_TRUE(gpu.poses[1].isApprox(start[1]));
}

TEST(CudaJointFrameToFrame, TheFactoryGivesTheGpuRefinerForCuda) {
  SKIP_WITHOUT_GPU();
  std::ostringstream log;
  const auto refiner = make_refiner("j-ftf", JointParams{}, ComputeDevice::kCuda, log);
  // The GPU refiner, with the CPU one behind it for a device failure during the run.
  const auto* wrapped = dynamic_cast<const CpuFallbackRefiner*>(refiner.get());
  ASSERT_NE(wrapped, nullptr);
  EXPECT_FALSE(wrapped->on_cpu());
  EXPECT_EQ(refiner->name(), "j-ftf");
  EXPECT_NE(log.str().find("-> cuda ("), std::string::npos) << log.str();
}

}  // namespace
}  // namespace jpcr
