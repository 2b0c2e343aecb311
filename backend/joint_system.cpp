#include "jpcr/backend/joint_system.hpp"

#include <cmath>

#include <Eigen/Cholesky>

#include "jpcr/backend/joint_params.hpp"

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

// One thread's share of the reduced system, merged into the total at the end (double).
struct ReductionShare {
  explicit ReductionShare(int n, int poses)
      : S(static_cast<std::size_t>(n) * n, 0.0), s(n, 0.0), A_diagonal(n, 0.0), seen(poses, 0) {}
  std::vector<double> S, s, A_diagonal;
  std::vector<int> seen;
  double cost = 0.0;
  long terms = 0;
  int active = 0;
};

// The pixels are processed row by row; rows are handed out in small dynamic chunks because the
// number of valid quadrics per row varies.
constexpr int kRowChunk = 4;

}  // namespace

JointSystem::JointSystem(const std::vector<VertexMap>& frames, const CameraIntrinsics& camera,
                         const NeighbourhoodPattern& pattern, const JointTermParams& params)
    : pattern_(pattern.offsets), params_(params) {
  for (const VertexMap& f : frames)
    views_.push_back(VertexView{f.data(), f.width(), f.height()});
  camera_ = PinholeProjection{camera.fx, camera.fy, camera.cx, camera.cy};
  width_ = frames.empty() ? 0 : frames[0].width();
  height_ = frames.empty() ? 0 : frames[0].height();
}

template <int MaxFrames>
ReducedSystem JointSystem::linearize_impl(const JointState& state, double lambda) const {
  const int M = frames(), n = 6 * (M - 1);
  const std::vector<RigidMotion<double>> motions = motions_of(state.poses);
  const JointWindowView<double> window{
      views_.data(), motions.data(),  M,
      camera_,       pattern_.data(), static_cast<int>(pattern_.size())};
  ReductionShare total(n, M - 1);
#pragma omp parallel
  {
    ReductionShare share(n, M - 1);
    JointPixelSystem<double, MaxFrames> sys;
#pragma omp for schedule(dynamic, kRowChunk) nowait
    for (int v = 0; v < height_; ++v) {
      for (int u = 0; u < width_; ++u) {
        const std::size_t i = static_cast<std::size_t>(v) * width_ + u;
        if (!state.valid[i]) continue;
        linearize_joint_pixel(state.quadrics[i], window, u, v, params_, lambda, sys);
        if (!sys.active) continue;
        add_schur_terms(sys, M, params_.estimate_quadrics, share.S.data(), share.s.data(),
                        share.A_diagonal.data());
        share.cost += sys.cost;
        share.terms += sys.count;
        ++share.active;
        for (int j = 0; j + 1 < M; ++j)
          share.seen[j] += sys.seen[j] ? 1 : 0;
      }
    }
#pragma omp critical(jpcr_joint_reduce)
    {
      for (std::size_t k = 0; k < total.S.size(); ++k)
        total.S[k] += share.S[k];
      for (int k = 0; k < n; ++k) {
        total.s[k] += share.s[k];
        total.A_diagonal[k] += share.A_diagonal[k];
      }
      for (int j = 0; j + 1 < M; ++j)
        total.seen[j] += share.seen[j];
      total.cost += share.cost;
      total.terms += share.terms;
      total.active += share.active;
    }
  }
  ReducedSystem out;
  // total.S is row-major with its lower triangle filled: as a column-major map that is the upper
  // triangle of S.
  out.S = Eigen::Map<const Eigen::MatrixXd>(total.S.data(), n, n).selfadjointView<Eigen::Upper>();
  out.s = Eigen::Map<const Eigen::VectorXd>(total.s.data(), n);
  out.A_diagonal = Eigen::Map<const Eigen::VectorXd>(total.A_diagonal.data(), n);
  out.cost = total.cost;
  out.terms = total.terms;
  out.active = total.active;
  out.seen = total.seen;
  return out;
}

template <int MaxFrames>
JointStep JointSystem::step_impl(const JointState& state, double lambda,
                                 const std::vector<Vector6d>& pose_steps) const {
  const int M = frames();
  JointStep out;
  out.pose_steps = pose_steps;
  out.candidate = state;
  for (int j = 1; j < M; ++j) {
    Eigen::Isometry3d T = se3_exp(pose_steps[j - 1]) * state.poses[j];  // T ← exp(Δξ^) T
    T.linear() = orthonormalize(T.linear());
    out.candidate.poses[j] = T;
  }
  out.quadric_steps.assign(state.quadrics.size(), QuadricVector<double>::Zero());
  const std::vector<RigidMotion<double>> motions = motions_of(state.poses);
  const std::vector<RigidMotion<double>> moved = motions_of(out.candidate.poses);
  const int pattern_size = static_cast<int>(pattern_.size());
  const JointWindowView<double> window{views_.data(), motions.data(),  M,
                                       camera_,       pattern_.data(), pattern_size};
  const JointWindowView<double> next{views_.data(), moved.data(),    M,
                                     camera_,       pattern_.data(), pattern_size};
  double cost = 0.0;
#pragma omp parallel reduction(+ : cost)
  {
    JointPixelSystem<double, MaxFrames> sys;
#pragma omp for schedule(dynamic, kRowChunk) nowait
    for (int v = 0; v < height_; ++v) {
      for (int u = 0; u < width_; ++u) {
        const std::size_t i = static_cast<std::size_t>(v) * width_ + u;
        if (!state.valid[i]) continue;
        linearize_joint_pixel(state.quadrics[i], window, u, v, params_, lambda, sys);
        if (!sys.active) continue;
        Quadricd& q = out.candidate.quadrics[i];
        if (params_.estimate_quadrics) {
          out.quadric_steps[i] = back_substitute(sys, M, pose_steps.data());
          apply_quadric_update(q, out.quadric_steps[i]);
        }
        cost += joint_pixel_cost(q, next, u, v, params_);
      }
    }
  }
  out.cost = cost;
  return out;
}

ReducedSystem JointSystem::linearize(const JointState& state, double lambda) const {
  return frames() == 2 ? linearize_impl<2>(state, lambda)
                       : linearize_impl<kMaxWindowFrames>(state, lambda);
}

JointStep JointSystem::step(const JointState& state, double lambda,
                            const std::vector<Vector6d>& pose_steps) const {
  return frames() == 2 ? step_impl<2>(state, lambda, pose_steps)
                       : step_impl<kMaxWindowFrames>(state, lambda, pose_steps);
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
