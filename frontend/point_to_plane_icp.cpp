#include "jpcr/frontend/point_to_plane_icp.hpp"

#include <algorithm>
#include <cmath>
#include <iterator>
#include <string>
#include <vector>

#include <Eigen/Cholesky>
#include <Eigen/Eigenvalues>

#include "jpcr/frontend/point_to_plane_residual.hpp"
#include "jpcr/quadric/error.hpp"
#include "jpcr/quadric/se3.hpp"

namespace jpcr {

namespace {

constexpr double kDegToRad = M_PI / 180.0;
constexpr int kChunkRows = 8;  // sample rows per RowPool chunk

// Source pixels visited at a level with the given stride.
double samples(const PyramidLevel& level, int stride) {
  return std::ceil(level.camera.width / static_cast<double>(stride)) *
         std::ceil(level.camera.height / static_cast<double>(stride));
}

// σ² per tangent axis of both frames' normals from the mean of |d|² = |R n_s − n_t|² over the
// pairs the normal-angle test kept, |d|² ≤ c = 2 − 2 cos(max_angle): |d|² is exponential with
// mean 4σ², so E[|d|² | |d|² ≤ c] = 4σ² − c e^(−c/4σ²) / (1 − e^(−c/4σ²)), rising from 0 to c/2;
// solved by bisection (a mean at c/2 or above gives the largest σ² searched, c).
double normal_noise(double kept_mean, double max_angle_deg) {
  const double c = 2.0 - 2.0 * std::cos(max_angle_deg * kDegToRad);
  const auto truncated_mean = [c](double s2) {
    const double e = std::exp(-c / (4.0 * s2));
    return 4.0 * s2 - c * e / (1.0 - e);
  };
  double lo = 0.0, hi = c;
  for (int i = 0; i < 60; ++i) {
    const double mid = 0.5 * (lo + hi);
    (truncated_mean(mid) < kept_mean ? lo : hi) = mid;
  }
  return 0.5 * (lo + hi);
}

// A linearisation's degeneracy and the normals' noise σ² per tangent axis it was corrected for.
struct Observability {
  double degeneracy = 0.0;
  double normal_noise = 0.0;
};

// Up to this σ² per tangent axis (about 14°) the second-order correction below holds: measured,
// a plane at 320x240 under 1 % range noise (σ² 0.045) reads 0; at 640x480 (σ² 0.09–0.10 on the
// two finer levels) it read 0.008–0.015, as observed as a room.
constexpr double kCorrectableNormalNoise = 0.06;

// One linearisation's JᵀWJ without the normals' noise (G), in unit-free coordinates y = D⁻¹ ξ
// (max_normal_angle: the pairs' normal-angle test, deg).
struct UnitFreeGeometry {
  Matrix6d scaled = Matrix6d::Zero();  // D G D
  Vector6d d = Vector6d::Ones();       // ξ = D y
  double normal_noise = 0.0;           // σ² per tangent axis G was corrected for
  bool valid = false;                  // false without pairs (or with no lever arm)
};

UnitFreeGeometry unit_free_geometry(const NormalEquations& eq, double max_normal_angle) {
  UnitFreeGeometry out;
  const Matrix6d H = eq.hessian();
  // The degeneracy sees the geometry, not the normals' noise. J = B n with B = [I; [p]×]; with
  // n = (n̄ + δ) / |n̄ + δ|, δ tangent of variance σ² per axis, E[n nᵀ] = (1 − 3σ²) n̄ n̄ᵀ + σ² I
  // to second order, so E[H] = (1 − 3σ²) H̄ + σ² Σ w B Bᵀ: noisy normals of one plane read as
  // observing the motions along it (at 1 % range noise more than a room's geometry does). That
  // part is taken out (the covariance keeps H as it is). σ² comes from the pairs themselves: a
  // pair's two normals see the same surface point, so |d|² = |R n_s − n_t|² is exponential with
  // mean 4σ² whatever the surface's shape (normal_noise() undoes the normal-angle test's cut).
  // That test keeps the pairs of small |d|, whose target normals are less noisy: with
  // d = δ_s − δ_t and s = δ_s + δ_t independent (Gaussian), δ_t = (s − d)/2 has variance
  // σ²/2 + E[|d|² | kept]/8 per axis among the kept pairs. Means weighted as JᵀWJ is.
  double& s2 = out.normal_noise;
  if (eq.sum_weights > 0.0) {
    const double kept = eq.normal_disagreement / eq.sum_weights;  // E_w[|d|² | kept]
    s2 = std::clamp(0.5 * normal_noise(kept, max_normal_angle) + kept / 8.0, 0.0, 0.25);
  }
  const double* m = eq.point_moments;
  const Eigen::Vector3d sum_p(m[0], m[1], m[2]);  // Σ w p
  Eigen::Matrix3d sum_ppt;                        // Σ w p pᵀ
  sum_ppt << m[3], m[4], m[5], m[4], m[6], m[7], m[5], m[7], m[8];
  Matrix6d BBt;  // Σ w B Bᵀ = Σ w [I, −[p]×; [p]×, |p|² I − p pᵀ]
  BBt.topLeftCorner<3, 3>() = eq.sum_weights * Eigen::Matrix3d::Identity();
  BBt.bottomLeftCorner<3, 3>() = skew(sum_p);
  BBt.topRightCorner<3, 3>() = -skew(sum_p);
  BBt.bottomRightCorner<3, 3>() = sum_ppt.trace() * Eigen::Matrix3d::Identity() - sum_ppt;
  const Matrix6d G = (H - s2 * BBt) / (1.0 - 3.0 * s2);
  // Unit-free conditioning: ω columns divided by the RMS lever arm (trace ratio of the blocks).
  const double trans = H.topLeftCorner<3, 3>().trace(), rot = H.bottomRightCorner<3, 3>().trace();
  if (trans > 0.0 && rot > 0.0) {
    out.d.tail<3>().setConstant(std::sqrt(trans / rot));
    out.scaled = out.d.asDiagonal() * G * out.d.asDiagonal();
    out.valid = true;
  }
  return out;
}

// λmin / λmax of one linearisation's unit-free G; 0 without pairs.
Observability noise_corrected_degeneracy(const NormalEquations& eq, double max_normal_angle) {
  const UnitFreeGeometry g = unit_free_geometry(eq, max_normal_angle);
  if (!g.valid) return {0.0, g.normal_noise};
  const Vector6d l =
      Eigen::SelfAdjointEigenSolver<Matrix6d>(g.scaled, Eigen::EigenvaluesOnly).eigenvalues();
  return {l[5] > 0.0 ? std::max(l[0], 0.0) / l[5] : 0.0, g.normal_noise};
}

// Below this λ/λmax of the unit-free G a direction is unobserved: a plane's or a corridor's
// read 0 (up to rounding and what the noise correction leaves), while 2 cm bumps on a wall,
// which observe the motions along it weakly but truly, read 6e-4 to 1e-3 (a noise-free walk
// along it: ATE 0.96 mm with such alignments accepted): those are kept, and the verdict's
// degeneracy_threshold judges them.
constexpr double kUnobserved = 1e-5;

// How many of the unit-free G's eigenvalues (ascending) are below kUnobserved λmax: 0 where the
// noise correction does not hold (σ² > kCorrectableNormalNoise) or G is zero.
int unobserved_count(const UnitFreeGeometry& g, const Vector6d& l) {
  if (!g.valid || g.normal_noise > kCorrectableNormalNoise || !(l[5] > 0.0)) return 0;
  int unobserved = 0;
  while (unobserved < 6 && !(l[unobserved] >= kUnobserved * l[5]))
    ++unobserved;
  return unobserved;
}

// The Gauss-Newton step of (H + λ tr(H)/6 I) ξ = −b (method.md §10: the minus sign the paper
// lacks) restricted to the directions the geometry observes. Along a direction G does not
// observe (a corridor's axis, a plane's in-plane motions) the gradient is the normals' noise,
// and the full step moved the pose there by 8.9 mm in a noise-free pair of a corridor, past
// max_translation in 5 of 9 pairs of a corridor walk. Such directions are taken out of the step
// (the step minimises the linearisation over the rest, as a degeneracy-aware solver does: Zhang,
// Kaess and Singh, ICRA 2016); they keep the initial guess. Only where the noise correction holds
// (σ² ≤ kCorrectableNormalNoise): beyond it G is not the geometry's.
Vector6d observable_step(const NormalEquations& eq, const IcpParams& params) {
  Matrix6d H = eq.hessian();
  H.diagonal().array() += params.damping * H.trace() / 6.0;
  const Vector6d b = eq.gradient();
  const UnitFreeGeometry g = unit_free_geometry(eq, params.max_normal_angle);
  if (g.valid) {
    const Eigen::SelfAdjointEigenSolver<Matrix6d> eig(g.scaled);
    const int unobserved = unobserved_count(g, eig.eigenvalues());
    if (unobserved > 0) {
      // ξ = D V z over the observed eigenvectors V: (Vᵀ D H D V) z = −Vᵀ D b.
      const Eigen::MatrixXd basis = g.d.asDiagonal() * eig.eigenvectors().rightCols(6 - unobserved);
      const Eigen::VectorXd z =
          (basis.transpose() * H * basis).ldlt().solve(-basis.transpose() * b);
      return basis * z;
    }
  }
  return H.ldlt().solve(-b);
}

// Final statistics of an alignment from its last normal equations (max_normal_angle: the pairs'
// normal-angle test, deg).
void describe(const NormalEquations& eq, double max_normal_angle, IcpResult& r) {
  r.inliers = eq.inliers;
  r.inlier_ratio = eq.valid > 0 ? static_cast<double>(eq.inliers) / eq.valid : 0.0;
  r.rms = eq.inliers > 0 ? std::sqrt(eq.sum_squares / eq.inliers) : 0.0;
  const Eigen::SelfAdjointEigenSolver<Matrix6d> eig(eq.hessian());
  r.eigenvalues = eig.eigenvalues();
  r.degeneracy = noise_corrected_degeneracy(eq, max_normal_angle).degeneracy;
  const double lmax = std::max(r.eigenvalues[5], 1e-300);
  const Vector6d inv = r.eigenvalues.cwiseMax(1e-12 * lmax).cwiseInverse();
  // σ² of a unit-weight residual: Σ w e² over the residuals' degrees of freedom. Not Σ w − 6:
  // the z⁻ᵏ depth weights have no unit scale (Σ w is 1/16 of the count at 2 m for k = 4).
  const double dof = std::max(static_cast<double>(eq.inliers) - 6.0, 1.0);
  r.covariance =
      (eq.cost / dof) * eig.eigenvectors() * inv.asDiagonal() * eig.eigenvectors().transpose();
  // No pair at all (0 · ∞ above): nothing is known of the motion, 1 m and 1 rad per axis.
  if (!r.covariance.allFinite()) r.covariance = Matrix6d::Identity();
}

// Along the directions the geometry does not observe (a plane's in-plane motions) the step kept
// the guess (observable_step), and H's information there is the normals' noise: σ² H⁻¹
// predicted 1 mm where the error was 5-22 mm (review of 2026-12-06). They are unknown, as
// without pairs: variance 1 (m², rad², or the mix of a mixed direction) is added along each,
// last (after the filter's inflation and the statistical convergence test, which see σ² H⁻¹).
void add_unknown_directions(const NormalEquations& eq, double max_normal_angle, IcpResult& r) {
  const UnitFreeGeometry g = unit_free_geometry(eq, max_normal_angle);
  if (!g.valid || !r.covariance.allFinite()) return;
  const Eigen::SelfAdjointEigenSolver<Matrix6d> geometry(g.scaled);
  const int unobserved = unobserved_count(g, geometry.eigenvalues());
  for (int k = 0; k < unobserved; ++k) {
    const Vector6d e = (g.d.asDiagonal() * geometry.eigenvectors().col(k)).normalized();
    r.covariance += e * e.transpose();
  }
}

// Sums over one image row in single precision (at most a few hundred terms), added to the
// double-precision NormalEquations once per row: float speed, double accumulation.
struct FloatSums {
  float upper[21], b[6], cost, sum_squares, sum_weights, moments[9];
  float normal_disagreement;
  std::size_t inliers;

  void clear() {
    std::fill(std::begin(upper), std::end(upper), 0.0f);
    std::fill(std::begin(b), std::end(b), 0.0f);
    std::fill(std::begin(moments), std::end(moments), 0.0f);
    cost = sum_squares = sum_weights = normal_disagreement = 0.0f;
    inliers = 0;
  }

  // For describe()'s correction: |R n_s − n|² = 2 − 2 cos of unit normals, and the moments of
  // the point p at which J = [n; p × n] is taken.
  void add_noise_terms(const Eigen::Vector3f& p, float w, float cos_normals) {
    normal_disagreement += w * (2.0f - 2.0f * cos_normals);
    const Eigen::Vector3f wp = w * p;
    moments[0] += wp.x();
    moments[1] += wp.y();
    moments[2] += wp.z();
    moments[3] += wp.x() * p.x();
    moments[4] += wp.x() * p.y();
    moments[5] += wp.x() * p.z();
    moments[6] += wp.y() * p.y();
    moments[7] += wp.y() * p.z();
    moments[8] += wp.z() * p.z();
  }

  void add(const Eigen::Matrix<float, 6, 1>& J, float e, float w) {
    int k = 0;
    for (int i = 0; i < 6; ++i) {
      const float wj = w * J[i];
      for (int j = i; j < 6; ++j)
        upper[k++] += wj * J[j];
      b[i] += wj * e;
    }
    cost += w * e * e;
    sum_squares += e * e;
    sum_weights += w;
    ++inliers;
  }

  void flush_into(NormalEquations& eq) const {
    for (int k = 0; k < 21; ++k)
      eq.upper[k] += upper[k];
    for (int i = 0; i < 6; ++i)
      eq.b[i] += b[i];
    eq.cost += cost;
    eq.sum_squares += sum_squares;
    eq.sum_weights += sum_weights;
    eq.normal_disagreement += normal_disagreement;
    for (int k = 0; k < 9; ++k)
      eq.point_moments[k] += moments[k];
    eq.inliers += inliers;
  }
};

bool is_finite(const Eigen::Isometry3d& T) {
  return T.matrix().allFinite();
}

}  // namespace

const char* to_string(IcpVerdict verdict) {
  switch (verdict) {
    case IcpVerdict::ok:
      return "ok";
    case IcpVerdict::degenerate:
      return "degenerate";
    case IcpVerdict::diverged:
      return "diverged";
    case IcpVerdict::too_few_points:
      return "too_few_points";
  }
  return "?";
}

float robust_weight(float e, RobustLoss loss, float scale) {
  const float a = std::abs(e);
  switch (loss) {
    case RobustLoss::none:
      return 1.0f;
    case RobustLoss::huber:
      return a <= scale ? 1.0f : scale / a;
    case RobustLoss::tukey: {
      if (a >= scale) return 0.0f;
      const float t = 1.0f - (e / scale) * (e / scale);
      return t * t;
    }
  }
  return 1.0f;
}

NormalEquations linearize_point_to_plane(const FramePyramid& source_pyramid,
                                         const FramePyramid& target_pyramid, int level,
                                         const Eigen::Isometry3d& T, const IcpParams& params,
                                         int stride, RowPool* pool) {
  if (stride < 1)
    throw InputError("linearize_point_to_plane: stride " + std::to_string(stride) +
                     " must be at least 1");
  const PyramidLevel& source = source_pyramid.levels.at(level);
  const PyramidLevel& target = target_pyramid.levels.at(level);
  const NormalLookup source_normals = normals_for(source_pyramid, level);
  const NormalLookup target_normals = normals_for(target_pyramid, level);
  const Eigen::Matrix3f R = T.linear().cast<float>();
  const Eigen::Vector3f t = T.translation().cast<float>();
  const CameraIntrinsics& c = target.camera;
  const float fx = static_cast<float>(c.fx), fy = static_cast<float>(c.fy);
  const float cx = static_cast<float>(c.cx), cy = static_cast<float>(c.cy);
  const int tw = target.vertices.width(), th = target.vertices.height();
  const float max_d2 = params.max_distance * params.max_distance;
  const float min_cos = std::cos(params.max_normal_angle * static_cast<float>(kDegToRad));
  const RobustLoss loss = params.robust_loss;
  const float scale = params.robust_scale;
  const int depth_exponent = params.depth_weight_exponent;
  const int sw = source.vertices.width(), sh = source.vertices.height();
  std::vector<NormalEquations> sums(pool ? pool->slots() : 1);
  const int sample_rows = (sh + stride - 1) / stride;
  for_rows(pool, sample_rows, kChunkRows, [&](int begin, int end, int slot) {
    NormalEquations& local = sums[slot];
    FloatSums row;
    for (int v = begin * stride; v < end * stride; v += stride) {
      row.clear();
      for (int u = 0; u < sw; u += stride) {
        const Eigen::Vector3f& X = source.vertices(u, v);
        if (!is_valid(X)) continue;
        ++local.valid;
        // Projective association (method.md §5): p = T X, projected into the target.
        const Eigen::Vector3f p = R * X + t;
        if (p.z() <= 0.0f) continue;
        const float inv_z = 1.0f / p.z();
        const float uf = fx * p.x() * inv_z + cx + 0.5f, vf = fy * p.y() * inv_z + cy + 0.5f;
        if (!(uf >= 0.0f && vf >= 0.0f && uf < tw && vf < th)) continue;  // also rejects NaN
        const int ut = static_cast<int>(uf), vt = static_cast<int>(vf);   // round to nearest
        const Eigen::Vector3f& q = target.vertices(ut, vt);
        if (!is_valid(q)) continue;  // a borrowed normal can exist where the vertex does not
        ++local.visible;
        const Eigen::Vector3f& ns = source_normals(u, v);
        if (!is_valid(ns)) continue;
        const Eigen::Vector3f& n = target_normals(ut, vt);
        if (!is_valid(n)) continue;
        // Rejection: distance and normal angle.
        const Eigen::Vector3f d = p - q;
        if (d.squaredNorm() > max_d2) continue;
        const float cos_normals = (R * ns).dot(n);
        if (cos_normals < min_cos) continue;
        const float e = n.dot(d);  // PointToPlaneResidual::error
        float w = robust_weight(e, loss, scale);
        if (w <= 0.0f) continue;
        // Inverse variance of an axial noise σ(z) ∝ z^(k/2): w ∝ z^−k (Kinect: k = 4), at the
        // mean of the pair's two depths. The target's alone is correlated with the residual
        // (q_z = z + η, e ∋ −η n_z): E[w e] / E[w] ≈ −k σ² / z, a shift along the view in every
        // alignment (−0.6 mm at 1 % range noise in a room); with the mean the two frames'
        // noise terms cancel to first order (review of 2026-12-06).
        const float inv_z_pair = 2.0f / (p.z() + q.z());
        for (int k = 0; k < depth_exponent; ++k)
          w *= inv_z_pair;
        row.add(PointToPlaneResidual<float>::jacobian(p, n), e, w);
        row.add_noise_terms(p, w, cos_normals);
      }
      row.flush_into(local);
    }
  });
  NormalEquations total;
  for (const NormalEquations& s : sums)
    total += s;
  return total;
}

IcpResult align_point_to_plane(const FramePyramid& source, const FramePyramid& target,
                               const Eigen::Isometry3d& initial, const IcpParams& params,
                               RowPool* pool) {
  params.validate();  // a library caller's parameters (a stride of 0 divided by zero)
  // A library caller's pyramids and guess: iterations are given per level, and the guess is
  // composed with each step as a rigid motion.
  if (source.levels.size() > params.iterations.size() ||
      target.levels.size() > params.iterations.size())
    throw InputError(
        "align_point_to_plane: a pyramid has more levels than IcpParams::iterations (" +
        std::to_string(params.iterations.size()) + ")");
  if (!is_rigid(initial))
    throw InputError("align_point_to_plane: the initial guess is not a finite rigid motion");
  IcpResult result;
  result.pose = initial;
  const int levels = std::min<int>(source.levels.size(), target.levels.size());
  // The coarsest level that runs sets the scale of min_inliers.
  int coarsest = -1;
  for (int l = levels - 1; l >= 0 && coarsest < 0; --l)
    if (params.iterations[l] > 0) coarsest = l;
  if (coarsest < 0) return result;
  const auto stride_of = [&](int l) { return l == 0 ? params.level0_stride : 1; };
  const double base = samples(source.levels[coarsest], stride_of(coarsest));
  // min_inliers is stated for a 640x480 frame: a smaller one has proportionally fewer pixels.
  const CameraIntrinsics& full = source.levels[0].camera;
  const double area_scale =
      std::min(1.0, static_cast<double>(full.width) * full.height / (640.0 * 480.0));

  Eigen::Isometry3d T = initial;
  NormalEquations last;
  int last_stride = 1, last_level = 0;
  bool have_system = false;
  Vector6d last_step = Vector6d::Zero();
  // Each level's observability at its last linearisation, coarsest first. The verdict takes the
  // finest level whose normals are within what the noise correction holds for: at 640x480
  // under 1 % range noise the finest levels' normals are beyond it and a plane read as well
  // observed as a room, while a coarse level (block-averaged depth, a longer baseline in the
  // scene) sees it as one; but a coarse level also loses small structure (2 cm bumps on a wall
  // at 320x240), so it is not asked when the fine one can answer.
  std::vector<Observability> observed;
  for (int l = coarsest; l >= 0; --l) {
    const int iterations = params.iterations[l];
    if (iterations <= 0) continue;
    const int stride = stride_of(l);
    const double needed =
        std::max(6.0, params.min_inliers * area_scale * samples(source.levels[l], stride) / base);
    result.converged = false;
    for (int it = 0; it < iterations; ++it) {
      const NormalEquations eq =
          linearize_point_to_plane(source, target, l, T, params, stride, pool);
      last = eq;
      last_stride = stride;
      last_level = l;
      have_system = true;
      if (static_cast<double>(eq.inliers) < needed) {
        describe(eq, params.max_normal_angle, result);
        add_unknown_directions(eq, params.max_normal_angle, result);
        result.pose = initial;
        result.verdict = IcpVerdict::too_few_points;
        return result;
      }
      const Vector6d xi = observable_step(eq, params);
      ++result.iterations;
      if (!xi.allFinite()) {
        describe(eq, params.max_normal_angle, result);
        add_unknown_directions(eq, params.max_normal_angle, result);
        result.verdict = IcpVerdict::diverged;
        return result;
      }
      last_step = xi;
      T = se3_exp(xi) * T;
      T.linear() = orthonormalize(T.linear());
      if (xi.head<3>().norm() < params.min_step_translation &&
          xi.tail<3>().norm() < params.min_step_rotation * kDegToRad) {
        result.converged = true;
        break;
      }
    }
    observed.push_back(noise_corrected_degeneracy(last, params.max_normal_angle));
  }
  if (have_system) {
    describe(last, params.max_normal_angle, result);
    const auto usable = std::find_if(
        observed.rbegin(), observed.rend(),
        [](const Observability& o) { return o.normal_noise <= kCorrectableNormalNoise; });
    result.degeneracy =
        usable != observed.rend() ? usable->degeneracy : observed.front().degeneracy;
    // Filtered depth: the residuals' errors are shared between neighbouring pixels (both
    // frames' noise enters each residual; each frame's filter counts for its half).
    if (last.inliers > 0)
      result.covariance *= 0.5 * (filtered_noise_inflation(source, last_stride, last_level) +
                                  filtered_noise_inflation(target, last_stride, last_level));
    // Statistically converged: the last step moved the pose by less than one standard deviation
    // of the estimate (ξᵀ Σ⁻¹ ξ ≤ 1), so further iterations would not change it beyond its
    // noise. On fr1/xyz the default schedule's last step measured 0.5 σ (median), 1.2 σ at the
    // 90th percentile, while it was never below min_step (the level's cap came first).
    if (!result.converged && last.inliers > 0)
      result.converged = last_step.dot(result.covariance.ldlt().solve(last_step)) <= 1.0;
    add_unknown_directions(last, params.max_normal_angle, result);
  }
  result.pose = T;
  const Eigen::Isometry3d motion = initial.inverse() * T;
  if (!is_finite(T) || motion.translation().norm() > params.max_translation ||
      rotation_angle(motion.linear()) > params.max_rotation * kDegToRad) {
    result.verdict = IcpVerdict::diverged;
  } else if (result.inlier_ratio < params.min_inlier_ratio) {
    result.verdict = IcpVerdict::too_few_points;
  } else if (result.degeneracy < params.degeneracy_threshold) {
    result.verdict = IcpVerdict::degenerate;
  } else {
    result.verdict = IcpVerdict::ok;
  }
  return result;
}

}  // namespace jpcr
