#include "jpcr/backend/joint_system.hpp"

#include <algorithm>
#include <atomic>
#include <cmath>
#include <iomanip>
#include <limits>
#include <optional>
#include <sstream>
#include <stdexcept>
#include <string>

#include <Eigen/Cholesky>

#include "jpcr/backend/gathered_frame_terms.hpp"
#include "jpcr/backend/joint_params.hpp"
#include "jpcr/quadric/parallel_guard.hpp"

namespace jpcr {

namespace {

std::vector<RigidMotion<double>> motions_of(const std::vector<Eigen::Isometry3d>& poses) {
  std::vector<RigidMotion<double>> m(poses.size());
  for (std::size_t j = 0; j < poses.size(); ++j) {
    m[j].R = poses[j].linear();
    m[j].t = poses[j].translation();
  }
  return m;
}

// One thread's share of the reduced system, merged into the total at the end (double). Its
// blocks, couplings and active pixels are one row's, moved into the output after each row
// (append_rows). A_sum and a_sum: the same sums before elimination (for the kept blocks).
struct ReductionShare {
  explicit ReductionShare(int n, int poses)
      : S(static_cast<std::size_t>(n) * n, 0.0),
        s(n, 0.0),
        A_diagonal(n, 0.0),
        A_sum(S),
        a_sum(s),
        seen(poses, 0) {}
  std::vector<double> S, s, A_diagonal, A_sum, a_sum;
  std::vector<int> seen;
  std::vector<QuadricBlocks> blocks;
  std::vector<Matrix6d> couplings;
  std::vector<FixedPixel> fixed_active;
  double cost = 0.0;
  long terms = 0;
  int active = 0;
};

// S (n x n, its lower triangle in the row-major `lower`) as a full symmetric matrix: as a
// column-major map, `lower` is the upper triangle of S.
Eigen::MatrixXd symmetric_of(const std::vector<double>& lower, int n) {
  return Eigen::Map<const Eigen::MatrixXd>(lower.data(), n, n).selfadjointView<Eigen::Upper>();
}

// Moves a thread's row of entries to the next free place of `all` (sized for every valid pixel
// beforehand) and empties it: no thread's buffer grows past a row, and `all` keeps its capacity
// from one iteration to the next.
// Returns where the row went.
template <typename T>
std::size_t append_rows(std::vector<T>& row, std::vector<T>& all, std::atomic<std::size_t>& end) {
  if (row.empty()) return end.load();
  const std::size_t at = end.fetch_add(row.size());
  std::copy(row.begin(), row.end(), all.begin() + static_cast<std::ptrdiff_t>(at));
  row.clear();
  return at;
}

// The row's kept blocks, and their couplings (`poses` per block) at the same place.
void append_blocks(ReductionShare& row, ReducedSystem& out, int poses,
                   std::atomic<std::size_t>& end) {
  if (row.blocks.empty()) return;
  const std::size_t at = append_rows(row.blocks, out.blocks, end);
  std::copy(row.couplings.begin(), row.couplings.end(),
            out.couplings.begin() + static_cast<std::ptrdiff_t>(at * poses));
  row.couplings.clear();
}

// The pixels are processed row by row; rows are handed out in small dynamic chunks because the
// number of valid quadrics per row varies.
constexpr int kRowChunk = 4;

// The lower triangle of a 6x6 matrix, column by column, and back (the upper triangle zero:
// cholesky_factor and cholesky_solve read only the lower one).
void pack_lower(const Matrix6d& m, std::array<double, 21>& out) {
  int k = 0;
  for (int c = 0; c < 6; ++c)
    for (int r = c; r < 6; ++r)
      out[static_cast<std::size_t>(k++)] = m(r, c);
}
Matrix6d unpack_lower(const std::array<double, 21>& packed) {
  Matrix6d m = Matrix6d::Zero();
  int k = 0;
  for (int c = 0; c < 6; ++c)
    for (int r = c; r < 6; ++r)
      m(r, c) = packed[static_cast<std::size_t>(k++)];
  return m;
}

// Keeps an active quadric's blocks: its undamped C_p, the damped factor sys.L, −b, and each
// B_jp (zero where frame j does not see it).
template <int MaxFrames>
void keep_blocks_of(std::size_t pixel, const Matrix6d& C,
                    const JointPixelSystem<double, MaxFrames>& sys, int frames,
                    ReductionShare& share) {
  QuadricBlocks& b = share.blocks.emplace_back();
  b.pixel = pixel;
  b.seen = seen_bits(sys, frames);
  pack_lower(C, b.C);
  pack_lower(sys.L, b.L);
  b.g_gamma = sys.g_gamma;
  for (int j = 0; j + 1 < frames; ++j)
    share.couplings.push_back(sys.seen[j] ? sys.B[j] : Matrix6d::Zero());
}

// A kept quadric's B_jp and seen flags back into `sys` (its factors are then recomputed).
template <int MaxFrames>
void restore_couplings(const QuadricBlocks& b, const Matrix6d* couplings, int frames,
                       JointPixelSystem<double, MaxFrames>& sys) {
  for (int j = 0; j + 1 < frames; ++j) {
    sys.seen[j] = ((b.seen >> j) & 1u) != 0u;
    if (sys.seen[j]) sys.B[j] = couplings[j];
  }
  sys.g_gamma = b.g_gamma;
}

// Row v of the reference frame: each active quadric's share of the reduced system; with
// keep_blocks also its blocks and its pose terms on their own.
template <int MaxFrames, typename Sampler>
void linearize_row(const JointState& state, const JointWindowView<double>& window,
                   const JointTermParams& p, double lambda, int v, int width, bool keep_blocks,
                   Sampler& sampler, ReductionShare& share) {
  JointPixelSystem<double, MaxFrames> sys;
  Matrix6d C;
  const int M = window.frames;
  for (int u = 0; u < width; ++u) {
    const std::size_t i = static_cast<std::size_t>(v) * width + u;
    if (!state.valid[i]) continue;
    linearize_joint_pixel(state.quadrics[i], window, u, v, p, lambda, sampler, sys,
                          keep_blocks ? &C : nullptr);
    if (!sys.active) continue;
    add_schur_terms(sys, M, p.estimate_quadrics, share.S.data(), share.s.data(),
                    share.A_diagonal.data());
    share.cost += sys.cost;
    share.terms += sys.count;
    ++share.active;
    for (int j = 0; j + 1 < M; ++j)
      share.seen[j] += sys.seen[j] ? 1 : 0;
    if (keep_blocks) {
      add_pose_terms(sys, M, share.A_sum.data(), share.a_sum.data(), static_cast<double*>(nullptr));
      keep_blocks_of(i, C, sys, M, share);
    }
    if (!p.estimate_quadrics) share.fixed_active.push_back(FixedPixel{i, seen_bits(sys, M)});
  }
}

// Row v, recomputing each active quadric's system: its back-substitution and its cost at the
// candidate (where the blocks were not kept).
template <int MaxFrames, typename Sampler>
double step_row(const JointState& state, const JointWindowView<double>& window,
                const JointWindowView<double>& next, const JointTermParams& p, double lambda,
                const Vector6d* pose_steps, int v, int width, Sampler& sampler, JointStep& out) {
  JointPixelSystem<double, MaxFrames> sys;
  double cost = 0.0;
  for (int u = 0; u < width; ++u) {
    const std::size_t i = static_cast<std::size_t>(v) * width + u;
    if (!state.valid[i]) continue;
    linearize_joint_pixel(state.quadrics[i], window, u, v, p, lambda, sampler, sys);
    if (!sys.active) continue;
    Quadricd& q = out.candidate.quadrics[i];
    if (p.estimate_quadrics) {
      out.quadric_steps[i] = back_substitute(sys, window.frames, pose_steps);
      apply_quadric_update(q, out.quadric_steps[i]);
    }
    cost += linearized_pixel_cost(q, state.quadrics[i], window, next, u, v,
                                  seen_bits(sys, window.frames), p, sampler);
  }
  return cost;
}

// The step of a kept quadric, Δγ_p = (C_p + λ diag C_p)⁻¹ (b_p − Σ_j B_jpᵀ Δξ_j) with its
// factor (method.md §6–§7: k − Σ_j K_j Δξ_j, one right-hand side instead of K_j's six each),
// then the candidate's cost over the frames that saw it.
template <typename Sampler>
double step_blocks(const QuadricBlocks& b, const Matrix6d* couplings, const JointState& state,
                   const JointWindowView<double>& window, const JointWindowView<double>& next,
                   const JointTermParams& p, const Vector6d* pose_steps, int width,
                   Sampler& sampler, JointStep& out) {
  QuadricVector<double> delta = -b.g_gamma;
  for (int j = 0; j + 1 < window.frames; ++j)
    if ((b.seen >> j) & 1u) delta -= couplings[j].transpose() * pose_steps[j];
  cholesky_solve<double, 6>(unpack_lower(b.L), delta);
  Quadricd& q = out.candidate.quadrics[b.pixel];
  out.quadric_steps[b.pixel] = delta;
  apply_quadric_update(q, out.quadric_steps[b.pixel]);
  const int u = static_cast<int>(b.pixel % width), v = static_cast<int>(b.pixel / width);
  return linearized_pixel_cost(q, state.quadrics[b.pixel], window, next, u, v, b.seen, p, sampler);
}

// Eliminates blocks[begin, end) again at the damping λ into S and s (lower triangle, row-major)
// and keeps their new factors.
template <int MaxFrames>
void redamp_blocks(ReducedSystem& system, int frames, double lambda, long begin, long end,
                   double* S, double* s) {
  JointPixelSystem<double, MaxFrames> sys;
  const int poses = frames - 1;
  for (long k = begin; k < end; ++k) {
    QuadricBlocks& b = system.blocks[static_cast<std::size_t>(k)];
    restore_couplings(b, system.couplings.data() + k * poses, frames, sys);
    // Not after linearize: its undamped C_p passed the pivot test there.
    if (!factor_damped_quadric(unpack_lower(b.C), lambda, frames, sys))
      throw std::logic_error("JointSystem: a kept quadric's damped C_p is not positive definite");
    eliminate_quadric(sys, frames, S, s);
    pack_lower(sys.L, b.L);
  }
}

// The sums per frame: gathered and vectorised across samples (the default), or sample by sample
// as the GPU runs them (the reference, for tests). Each thread of a parallel region owns one
// sampler, built under `guard` (its buffers may fail to allocate): then `body` gets a null one,
// and must still reach its `omp for`, as every thread of the team must.
template <typename Sampler>
Sampler* guarded_sampler(std::optional<Sampler>& sampler, int pattern_size, ParallelGuard& guard) {
  guard.run([&] { sampler.emplace(pattern_size); });
  return sampler ? &*sampler : nullptr;
}

template <typename Body>
void with_sampler(JointSampling sampling, int pattern_size, ParallelGuard& guard, Body&& body) {
  if (sampling == JointSampling::kReference) {
    DirectSampler<double> sampler;  // holds no buffers
    body(&sampler);
  } else if (sampling == JointSampling::kGatheredDouble) {
    std::optional<GatheredSampler<double>> sampler;
    body(guarded_sampler(sampler, pattern_size, guard));
  } else {
    std::optional<GatheredSampler<float>> sampler;
    body(guarded_sampler(sampler, pattern_size, guard));
  }
}

}  // namespace

JointSystem::JointSystem(const std::vector<VertexMap>& frames, const CameraIntrinsics& camera,
                         const NeighbourhoodPattern& pattern, const JointTermParams& params,
                         JointSampling sampling, std::size_t block_memory)
    : pattern_(pattern.offsets), params_(params), sampling_(sampling), block_memory_(block_memory) {
  // The per-pixel kernels hold at most kMaxWindowFrames frames; more would be left out of the
  // sums while the reduced system still counts their poses (singular S).
  if (frames.size() < 2 || frames.size() > static_cast<std::size_t>(kMaxWindowFrames))
    throw std::invalid_argument("JointSystem: " + std::to_string(frames.size()) +
                                " frames; a window holds 2 to " + std::to_string(kMaxWindowFrames));
  for (const VertexMap& f : frames)
    views_.push_back(VertexView{f.data(), f.width(), f.height()});
  camera_ = PinholeProjection{camera.fx, camera.fy, camera.cx, camera.cy};
  width_ = frames.empty() ? 0 : frames[0].width();
  height_ = frames.empty() ? 0 : frames[0].height();
}

std::size_t JointSystem::block_bytes(int frames) {
  return sizeof(QuadricBlocks) +
         static_cast<std::size_t>(std::max(frames - 1, 0)) * sizeof(Matrix6d);
}

ReducedSystem JointSystem::linearize(const JointState& state, double lambda) const {
  ReducedSystem out;
  linearize(state, lambda, out);
  return out;
}

void JointSystem::linearize(const JointState& state, double lambda, ReducedSystem& out) const {
  const int M = frames(), n = 6 * (M - 1);
  const std::vector<RigidMotion<double>> motions = motions_of(state.poses);
  const JointWindowView<double> window = window_view(motions);
  const auto valid = static_cast<std::size_t>(
      std::count(state.valid.begin(), state.valid.end(), static_cast<unsigned char>(1)));
  const bool keep_blocks = params_.estimate_quadrics && valid <= block_memory_ / block_bytes(M);
  out.keeps_blocks = false;  // until linearised (a half-filled system is not stepped)
  out.blocks.resize(keep_blocks ? valid : 0);
  out.couplings.resize(keep_blocks ? valid * (M - 1) : 0);
  out.fixed_active.resize(params_.estimate_quadrics ? 0 : valid);
  std::atomic<std::size_t> blocks_end{0}, fixed_end{0};
  ReductionShare total(n, M - 1);
  ParallelGuard guard;  // e.g. a worker's buffers out of memory: rethrown, not std::terminate
#pragma omp parallel
  {
    std::optional<ReductionShare> share;
    guard.run([&] { share.emplace(n, M - 1); });
    with_sampler(sampling_, window.pattern_size, guard, [&](auto* sampler) {
#pragma omp for schedule(dynamic, kRowChunk) nowait
      for (int v = 0; v < height_; ++v) {
        if (guard.failed() || !sampler || !share) continue;
        try {  // not guard.run's lambda: clang cannot nest it here (parallel_guard.hpp)
          if (M == 2)
            linearize_row<2>(state, window, params_, lambda, v, width_, keep_blocks, *sampler,
                             *share);
          else
            linearize_row<kMaxWindowFrames>(state, window, params_, lambda, v, width_, keep_blocks,
                                            *sampler, *share);
          append_blocks(*share, out, M - 1, blocks_end);
          append_rows(share->fixed_active, out.fixed_active, fixed_end);
        } catch (...) {
          guard.record_current();
        }
      }
    });
#pragma omp critical(jpcr_joint_reduce)
    if (share) {
      for (std::size_t k = 0; k < total.S.size(); ++k) {
        total.S[k] += share->S[k];
        total.A_sum[k] += share->A_sum[k];
      }
      for (int k = 0; k < n; ++k) {
        total.s[k] += share->s[k];
        total.a_sum[k] += share->a_sum[k];
        total.A_diagonal[k] += share->A_diagonal[k];
      }
      for (int j = 0; j + 1 < M; ++j)
        total.seen[j] += share->seen[j];
      total.cost += share->cost;
      total.terms += share->terms;
      total.active += share->active;
    }
  }
  guard.rethrow();
  out.blocks.resize(blocks_end);
  out.couplings.resize(blocks_end * (M - 1));
  out.fixed_active.resize(fixed_end);
  out.S = symmetric_of(total.S, n);
  out.s = Eigen::Map<const Eigen::VectorXd>(total.s.data(), n);
  if (keep_blocks) {
    out.A_sum = symmetric_of(total.A_sum, n);
    out.a_sum = Eigen::Map<const Eigen::VectorXd>(total.a_sum.data(), n);
  } else {
    out.A_sum.resize(0, 0);
    out.a_sum.resize(0);
  }
  out.A_diagonal = Eigen::Map<const Eigen::VectorXd>(total.A_diagonal.data(), n);
  out.damping = lambda;
  out.keeps_blocks = keep_blocks;
  out.cost = total.cost;
  out.terms = total.terms;
  out.active = total.active;
  out.seen = std::move(total.seen);
}

bool JointSystem::redamp(double lambda, ReducedSystem& system) const {
  // A system of this JointSystem's size (not another window's left in the buffers).
  const int poses = frames() - 1, n = 6 * poses;
  if (system.S.rows() != n || system.s.size() != n ||
      system.seen.size() != static_cast<std::size_t>(poses))
    return false;
  if (!params_.estimate_quadrics) {  // Q-full: λ enters only solve_poses
    system.damping = lambda;
    return true;
  }
  if (!system.keeps_blocks || system.A_sum.rows() != n || system.a_sum.size() != n ||
      system.couplings.size() != system.blocks.size() * poses)
    return false;
  // Until the new factors are all in place: a step on a half-redamped system throws (step_kept).
  system.damping = std::numeric_limits<double>::quiet_NaN();
  std::vector<double> S(n * n, 0.0), s(n, 0.0);
  for (int r = 0; r < n; ++r) {
    s[r] = system.a_sum(r);
    for (int c = 0; c <= r; ++c)
      S[r * n + c] = system.A_sum(r, c);
  }
  const long count = static_cast<long>(system.blocks.size());
  constexpr long kChunk = 256;
  ParallelGuard guard;  // e.g. a worker's share out of memory: rethrown, not std::terminate
#pragma omp parallel
  {
    std::vector<double> share_S, share_s;
    guard.run([&] {
      share_S.assign(n * n, 0.0);
      share_s.assign(n, 0.0);
    });
#pragma omp for schedule(static) nowait
    for (long begin = 0; begin < count; begin += kChunk) {
      if (guard.failed() || share_S.empty()) continue;
      try {
        const long end = std::min(begin + kChunk, count);
        if (poses == 1)
          redamp_blocks<2>(system, 2, lambda, begin, end, share_S.data(), share_s.data());
        else
          redamp_blocks<kMaxWindowFrames>(system, poses + 1, lambda, begin, end, share_S.data(),
                                          share_s.data());
      } catch (...) {
        guard.record_current();
      }
    }
#pragma omp critical(jpcr_joint_redamp)
    if (!share_S.empty()) {
      for (int k = 0; k < n * n; ++k)
        S[k] += share_S[k];
      for (int k = 0; k < n; ++k)
        s[k] += share_s[k];
    }
  }
  guard.rethrow();
  system.S = symmetric_of(S, n);
  system.s = Eigen::Map<const Eigen::VectorXd>(s.data(), n);
  system.damping = lambda;
  return true;
}

void JointSystem::start_step(const JointState& state, const std::vector<Vector6d>& pose_steps,
                             JointStep& out) const {
  out.pose_steps = pose_steps;
  out.candidate = state;  // copy-assignment keeps out's buffers when the sizes agree
  for (int j = 1; j < frames(); ++j) {
    Eigen::Isometry3d T = se3_exp(pose_steps[j - 1]) * state.poses[j];  // T ← exp(Δξ^) T
    T.linear() = orthonormalize(T.linear());
    out.candidate.poses[j] = T;
  }
  out.quadric_steps.assign(state.quadrics.size(), QuadricVector<double>::Zero());
}

JointWindowView<double> JointSystem::window_view(
    const std::vector<RigidMotion<double>>& motions) const {
  return {views_.data(), motions.data(),  frames(),
          camera_,       pattern_.data(), static_cast<int>(pattern_.size())};
}

void JointSystem::step_kept(const JointState& state, const ReducedSystem& system, double lambda,
                            const JointWindowView<double>& window,
                            const JointWindowView<double>& next, JointStep& out) const {
  if (lambda != system.damping) {  // also NaN: a redamp that did not finish
    std::ostringstream message;
    message << std::setprecision(17) << "JointSystem::step: damping " << lambda << ", the system's "
            << system.damping;
    throw std::invalid_argument(message.str());
  }
  const long count = static_cast<long>(system.blocks.size());
  double cost = 0.0;
  ParallelGuard guard;  // e.g. a worker's buffers out of memory: rethrown, not std::terminate
#pragma omp parallel reduction(+ : cost)
  with_sampler(sampling_, next.pattern_size, guard, [&](auto* sampler) {
#pragma omp for schedule(dynamic, 256)
    for (long k = 0; k < count; ++k) {
      if (guard.failed() || !sampler) continue;
      try {
        cost += step_blocks(system.blocks[static_cast<std::size_t>(k)],
                            system.couplings.data() + k * (frames() - 1), state, window, next,
                            params_, out.pose_steps.data(), width_, *sampler, out);
      } catch (...) {
        guard.record_current();
      }
    }
  });
  guard.rethrow();
  out.cost = cost;
}

void JointSystem::step_fixed(const JointState& state, const ReducedSystem& system,
                             const JointWindowView<double>& window,
                             const JointWindowView<double>& next, JointStep& out) const {
  const long count = static_cast<long>(system.fixed_active.size());
  double cost = 0.0;
  ParallelGuard guard;  // e.g. a worker's buffers out of memory: rethrown, not std::terminate
#pragma omp parallel reduction(+ : cost)
  with_sampler(sampling_, next.pattern_size, guard, [&](auto* sampler) {
#pragma omp for schedule(dynamic, 256)
    for (long k = 0; k < count; ++k) {
      if (guard.failed() || !sampler) continue;
      try {
        const FixedPixel& f = system.fixed_active[static_cast<std::size_t>(k)];
        const int u = static_cast<int>(f.pixel % width_), v = static_cast<int>(f.pixel / width_);
        const Quadricd& q = state.quadrics[f.pixel];  // fixed: Q-full
        cost += linearized_pixel_cost(q, q, window, next, u, v, f.seen, params_, *sampler);
      } catch (...) {
        guard.record_current();
      }
    }
  });
  guard.rethrow();
  out.cost = cost;
}

void JointSystem::step_window(const JointState& state, double lambda,
                              const JointWindowView<double>& window,
                              const JointWindowView<double>& next, JointStep& out) const {
  double cost = 0.0;
  ParallelGuard guard;  // e.g. a worker's buffers out of memory: rethrown, not std::terminate
#pragma omp parallel reduction(+ : cost)
  with_sampler(sampling_, next.pattern_size, guard, [&](auto* sampler) {
#pragma omp for schedule(dynamic, kRowChunk)
    for (int v = 0; v < height_; ++v) {
      if (guard.failed() || !sampler) continue;
      try {
        cost += step_row<kMaxWindowFrames>(state, window, next, params_, lambda,
                                           out.pose_steps.data(), v, width_, *sampler, out);
      } catch (...) {
        guard.record_current();
      }
    }
  });
  guard.rethrow();
  out.cost = cost;
}

JointStep JointSystem::step(const JointState& state, const ReducedSystem& system, double lambda,
                            const std::vector<Vector6d>& pose_steps) const {
  JointStep out;
  step(state, system, lambda, pose_steps, out);
  return out;
}

void JointSystem::step(const JointState& state, const ReducedSystem& system, double lambda,
                       const std::vector<Vector6d>& pose_steps, JointStep& out) const {
  start_step(state, pose_steps, out);
  const std::vector<RigidMotion<double>> motions = motions_of(state.poses);
  const std::vector<RigidMotion<double>> moved = motions_of(out.candidate.poses);
  const JointWindowView<double> window = window_view(motions), next = window_view(moved);
  // Q-full has no quadric step (only the candidate's cost); J-ftf and J-full back-substitute
  // from their kept blocks, or recompute each quadric's system where the blocks were not kept.
  if (!params_.estimate_quadrics)
    step_fixed(state, system, window, next, out);
  else if (system.keeps_blocks)
    step_kept(state, system, lambda, window, next, out);
  else
    step_window(state, lambda, window, next, out);
}

std::vector<int> reference_inliers(const VertexMap& reference, const NeighbourhoodPattern& pattern,
                                   const JointTermParams& params, const JointState& state) {
  const int width = reference.width(), height = reference.height();
  const int pattern_size = static_cast<int>(pattern.size());
  const VertexView view{reference.data(), width, height};
  std::vector<int> count(state.quadrics.size(), 0);
  ParallelGuard guard;  // e.g. a worker's buffers out of memory: rethrown, not std::terminate
#pragma omp parallel
  with_sampler(JointSampling::kGathered, pattern_size, guard, [&](auto* sampler) {
#pragma omp for schedule(dynamic, kRowChunk)
    for (int v = 0; v < height; ++v) {
      if (guard.failed() || !sampler) continue;
      try {
        for (int u = 0; u < width; ++u) {
          const std::size_t i = static_cast<std::size_t>(v) * width + u;
          if (!state.valid[i]) continue;
          const Quadricd& q = state.quadrics[i];
          sampler->cost(q, q, view, RigidMotion<double>{}, RigidMotion<double>{},
                        pattern.offsets.data(), pattern_size, u, v,
                        SampleGate<double>::at(params.fit, q.center), count[i]);
        }
      } catch (...) {
        guard.record_current();
      }
    }
  });
  guard.rethrow();
  return count;
}

bool JointSystem::solve_poses(const ReducedSystem& system, double lambda,
                              std::vector<Vector6d>& pose_steps) {
  Eigen::MatrixXd S = system.S;
  S.diagonal() += lambda * system.A_diagonal;  // LM on the full system: λ diag A
  const Eigen::LDLT<Eigen::MatrixXd> ldlt(S);
  if (ldlt.info() != Eigen::Success || !ldlt.isPositive()) return false;
  const Eigen::VectorXd x = ldlt.solve(system.s);
  if (!x.allFinite()) return false;
  const double max_pivot = ldlt.vectorD().cwiseAbs().maxCoeff();
  if (!(ldlt.vectorD().minCoeff() > 1e-14 * max_pivot)) return false;  // rank-deficient S
  pose_steps.resize(static_cast<std::size_t>(x.size() / 6));
  for (std::size_t j = 0; j < pose_steps.size(); ++j)
    pose_steps[j] = x.segment<6>(6 * static_cast<Eigen::Index>(j));
  return true;
}

}  // namespace jpcr
