// The per-pixel work of J-ftf, J-full and Q-full (method.md §6–§8), written once for the CPU
// and the GPU: every function is JPCR_HD, allocation-free and fixed-size, so the CPU drivers
// (joint_system.cpp) and a CUDA kernel run exactly this code per quadric.
//
// A quadric γ_p lives at pixel p of the reference frame 1. A sample Q of frame j (its camera
// frame) is mapped into frame 1 as X = T_j Q and gives the residual r(X; γ_p) of
// quadric_model.hpp, with
//
//     ∂r/∂γ = J_γ (Quad IT's Jacobian, evaluated at X),
//     ∂r/∂ξ_j = J_ξ = [g_wᵀ, (X × g_w)ᵀ], g_w = Rᵀ g (left update T_j ← exp(ξ^) T_j).
//
// Per quadric the normal equations of the joint system (method.md §6) are
//
//     C_p = Σ w J_γ J_γᵀ (all frames),  b_p = −Σ w J_γ r,
//     B_jp = Σ w J_ξ J_γᵀ (frame j),    A_jp = Σ w J_ξ J_ξᵀ,  a_jp = −Σ w J_ξ r,
//
// and eliminating γ_p (Schur complement, method.md §6/§7; the paper's block inverse is wrong,
// method.md §10, its final formulas are right) gives the quadric's share of the reduced system
//
//     S_jk −= B_jp C_p⁻¹ B_kpᵀ (+ A_jp on the diagonal),  s_j += a_jp − B_jp C_p⁻¹ b_p,
//
// and, once the poses are solved, the back-substitution Δγ_p = C_p⁻¹ (b_p − Σ_j B_jpᵀ Δξ_j).
// The weight w = n₀² / (n₀² + r² + d²) is held fixed in each linearisation (IRLS). The cost is
// Σ w r²; a sample outside the gate |r| ≤ g is dropped from the normal equations and costs the
// constant w(g) g², so the cost stays continuous when a sample crosses the gate. A step is judged
// with the weights held at its linearisation (linearized_pixel_cost).
#pragma once

#include <cmath>

#include <Eigen/Core>

#include "jpcr/quadric/dense_cholesky.hpp"
#include "jpcr/quadric/neighbourhood_pattern.hpp"
#include "jpcr/quadric/quadric_fit_kernel.hpp"
#include "jpcr/quadric/quadric_model.hpp"

namespace jpcr {

/// The tunables the per-pixel work reads, by value (a CUDA kernel receives it as is).
struct JointTermParams {
  QuadricFitParams fit;  // weight n₀ and gate (both frames), min_samples for the frame-1 terms
  float occlusion_threshold = 0.03f;  // m: image j's depth at the projected centre may differ
  float occlusion_fraction = 0.02f;   //    from c_z by threshold + fraction · c_z (occlusion)
  int min_frame_terms = 10;           // a frame j sees the quadric only with this many terms
  double min_pivot_ratio = 1e-2;      // C_p is ill-conditioned when a Cholesky pivot² falls below
                                      // this fraction of its diagonal entry (undamped C_p,
                                      // scale-invariant)
  bool estimate_quadrics = true;      // false: Q-full (quadrics fixed, no C_p, no frame-1 terms)
  // > 0: the lever arms of the other frames' terms at the foot point of each sample's ray
  // (ray_foot_moment, quadric_model.hpp) unless the ray meets the surface at a cosine below
  // this; 0: at the samples themselves, as the paper (see accumulate_frame_terms).
  float ray_min_cosine = 0.0f;

  /// cos²_min for ray_foot_moment; kNoRayFoot (never met) where the lever arms stay at the
  /// samples.
  template <typename Scalar>
  JPCR_HD Scalar ray_min_cos2() const {
    return ray_min_cosine > 0.0f ? Scalar(ray_min_cosine) * Scalar(ray_min_cosine)
                                 : Scalar(kNoRayFoot);
  }
};

/// The pinhole projection of method.md §1 (pixels).
struct PinholeProjection {
  double fx = 525.0, fy = 525.0, cx = 319.5, cy = 239.5;
};

/// T_j = (R, t): frame j → frame 1.
template <typename Scalar>
struct RigidMotion {
  Eigen::Matrix<Scalar, 3, 3> R = Eigen::Matrix<Scalar, 3, 3>::Identity();
  Eigen::Matrix<Scalar, 3, 1> t = Eigen::Matrix<Scalar, 3, 1>::Zero();

  JPCR_HD Eigen::Matrix<Scalar, 3, 1> apply(const Eigen::Matrix<Scalar, 3, 1>& Q) const {
    return R * Q + t;
  }
  JPCR_HD Eigen::Matrix<Scalar, 3, 1> apply_inverse(const Eigen::Matrix<Scalar, 3, 1>& X) const {
    return R.transpose() * (X - t);
  }
};

/// The sums of one quadric's terms in one frame (C and A are symmetric; the lower triangle is
/// what the solvers read).
template <typename Scalar>
struct FrameTerms {
  using Matrix6 = Eigen::Matrix<Scalar, 6, 6>;
  using Vector6 = Eigen::Matrix<Scalar, 6, 1>;
  Matrix6 C = Matrix6::Zero();        // Σ w J_γ J_γᵀ
  Vector6 g_gamma = Vector6::Zero();  // Σ w J_γ r  (= −b)
  Matrix6 B = Matrix6::Zero();        // Σ w J_ξ J_γᵀ (rows ξ, columns γ)
  Matrix6 A = Matrix6::Zero();        // Σ w J_ξ J_ξᵀ
  Vector6 g_xi = Vector6::Zero();     // Σ w J_ξ r  (= −a)
  Scalar cost = 0;                    // Σ w r², gated samples at w(g) g²
  int count = 0;                      // samples inside the gate
};

/// The residual as the cost sees it: r inside the gate, the gate outside.
template <typename Scalar>
JPCR_HD Scalar gated(Scalar r, const SampleGate<Scalar>& limits) {
  return r <= limits.gate && r >= -limits.gate ? r : limits.gate;
}

/// The cost share of one sample at distance² d2 from p̄ (the gate of the file comment), and its
/// weight w = fair_weight(r, d2, n₀), meaningful when inside.
template <typename Scalar>
JPCR_HD Scalar gated_cost(Scalar r, Scalar d2, const SampleGate<Scalar>& limits, bool& inside,
                          Scalar& w) {
  inside = r <= limits.gate && r >= -limits.gate;
  const Scalar e = inside ? r : limits.gate;
  w = fair_weight(e, d2, limits.n0);
  return w * e * e;
}

/// A frame-j sample's Jacobians with the lever arms at its ray's foot point (ray_foot_moment,
/// quadric_model.hpp): J_γ with the tilt entries (J₀, J₁) of m_s = v_s × g, and
/// J_ξ = [g_w; X_s × g_w] = [g_w; p̄ × g_w + Rᵀ m_s] (X_s = p̄ + Rᵀ v_s). `origin` is R (p̄ − o)
/// for camera j's centre o, so the ray is v + origin. On a plane these are −(g_w·u) times the
/// derivatives of the distance along the unit ray u from the sample to the surface, which its
/// range error does not move.
template <typename Scalar>
JPCR_HD void ray_foot_jacobians(const QuadricT<Scalar>& q, const QuadricLinearization<Scalar>& l,
                                const Eigen::Matrix<Scalar, 3, 1>& origin, Scalar min_cos2,
                                Eigen::Matrix<Scalar, 6, 1>& J_gamma,
                                Eigen::Matrix<Scalar, 6, 1>& J_xi) {
  using Vector3 = Eigen::Matrix<Scalar, 3, 1>;
  const Vector3 rho = l.v + origin;
  Scalar m0 = 0, m1 = 0, m2 = 0;
  ray_foot_moment(l.r, l.v.x(), l.v.y(), l.v.z(), l.g.x(), l.g.y(), rho.x(), rho.y(), rho.z(),
                  min_cos2, m0, m1, m2);
  const Vector3 m(m0, m1, m2);
  J_gamma = l.J;
  J_gamma(0) = m.x();
  J_gamma(1) = m.y();
  const Vector3 g_w = q.R.transpose() * l.g;
  J_xi.template head<3>() = g_w;
  J_xi.template tail<3>() = q.center.cross(g_w) + q.R.transpose() * m;
}

/// Adds the samples of `pattern` around (u, v) of `view`, mapped by T into frame 1, to the
/// quadric's normal equations; with_pose also builds the pose blocks B, A and g_xi.
///
/// The terms of a frame with a pose take their lever arms (the tilt entries J₀, J₁ of J_γ and
/// the rotation entries of J_ξ) at the foot point of the sample's ray from camera j (centre T.t)
/// when ray_min_cos2 ≤ 1 (ray_foot_moment, quadric_model.hpp), else at the sample as the paper
/// does. At the sample they move with its range error, which biases the stationary point of the
/// normal equations along the weakly observed coupling of camera rotation and translation.
/// Measured, J-ftf from the true pose at 1 % range noise (n₀ and gate 3 σ), room_spheres, mean
/// error over three noise draws: on the walk pair of seed 5 (8 mm apart) 1.20 mm / 0.74 mrad at
/// the samples against 0.17 mm / 0.15 mrad at the foot points at 640x480, 1.14 against 0.42 mm
/// at 320x240; but on render_window's pair (2.5 cm / 1° apart, tests/backend) at 320x240,
/// 0.40 mm at the samples against 0.54 mm at the foot points; and J-full (windows of 4) on the
/// 10-frame cylinders_boxes walk got worse, 5.3e-4 → 1.11e-3 m RMS relative error, at the frame
/// next to each window's reference. Hence off by default. The frame-1 terms keep their lever
/// arms (at the foot point they brought the bias back: 1.20 mm on the first case). The cost is
/// not changed; these are the normal equations of its errors-in-variables corrected gradient.
template <typename Scalar>
JPCR_HD void accumulate_frame_terms(const QuadricT<Scalar>& q, const VertexView& view,
                                    const RigidMotion<Scalar>& T, bool with_pose,
                                    Scalar ray_min_cos2, const PixelOffset* pattern,
                                    int pattern_size, int u, int v,
                                    const SampleGate<Scalar>& limits, FrameTerms<Scalar>& out) {
  using Vector3 = Eigen::Matrix<Scalar, 3, 1>;
  const bool foot = with_pose && ray_min_cos2 <= Scalar(1);
  const Vector3 origin = q.R * (q.center - T.t);  // p̄ − camera j's centre, in local axes
  for (int k = 0; k < pattern_size; ++k) {
    const int su = u + pattern[k].du, sv = v + pattern[k].dv;
    if (!view.in_bounds(su, sv)) continue;  // 2-D bounds check (method.md §2)
    const Eigen::Vector3f& Qf = view(su, sv);
    if (!is_sample_point(Qf)) continue;  // all three coordinates, as Quad IT
    const Vector3 X = T.apply(Qf.template cast<Scalar>());
    const QuadricLinearization<Scalar> l = linearize_quadric(q, X);
    const Scalar d2 = l.v.squaredNorm();  // |X − p̄|², R orthonormal
    bool inside = false;
    Scalar w = 0;
    out.cost += gated_cost(l.r, d2, limits, inside, w);
    if (!inside) continue;
    // Rank-1 updates of whole 6x6 blocks (Eigen vectorises them; C and A are read as their
    // lower triangles).
    Eigen::Matrix<Scalar, 6, 1> Jg = l.J;
    Eigen::Matrix<Scalar, 6, 1> Jx;
    if (foot)
      ray_foot_jacobians(q, l, origin, ray_min_cos2, Jg, Jx);
    else if (with_pose)
      Jx = quadric_pose_jacobian(q, l, X);
    const Eigen::Matrix<Scalar, 6, 1> wJ = w * Jg;
    out.C.noalias() += wJ * Jg.transpose();
    out.g_gamma += wJ * l.r;
    if (with_pose) {
      const Eigen::Matrix<Scalar, 6, 1> wJx = w * Jx;
      out.B.noalias() += wJx * Jg.transpose();
      out.A.noalias() += wJx * Jx.transpose();
      out.g_xi += wJx * l.r;
    }
    ++out.count;
  }
}

/// The cost Σ w e² (and the gated count) of one frame's samples, without Jacobians, with each
/// sample's weight held at another state: e is the gated residual at quadric q and X = T Q, and
/// w = n₀² / (n₀² + e_h² + d²) takes e_h and d² at q_weight and T_weight Q. With q_weight = q and
/// T_weight = T it is the cost accumulate_frame_terms sums; the step test holds both at the
/// linearisation (linearized_pixel_cost).
template <typename Scalar>
JPCR_HD Scalar frame_cost(const QuadricT<Scalar>& q, const QuadricT<Scalar>& q_weight,
                          const VertexView& view, const RigidMotion<Scalar>& T,
                          const RigidMotion<Scalar>& T_weight, const PixelOffset* pattern,
                          int pattern_size, int u, int v, const SampleGate<Scalar>& limits,
                          int& count) {
  Scalar cost = 0;
  count = 0;
  for (int k = 0; k < pattern_size; ++k) {
    const int su = u + pattern[k].du, sv = v + pattern[k].dv;
    if (!view.in_bounds(su, sv)) continue;
    const Eigen::Vector3f& Qf = view(su, sv);
    if (!is_sample_point(Qf)) continue;  // all three coordinates, as Quad IT
    const Eigen::Matrix<Scalar, 3, 1> Q = Qf.template cast<Scalar>();
    const Eigen::Matrix<Scalar, 3, 1> X_weight = T_weight.apply(Q);
    const Scalar d2 = (X_weight - q.center).squaredNorm();
    const Scalar w =
        fair_weight(gated(quadric_residual(q_weight, X_weight), limits), d2, limits.n0);
    const Scalar r = quadric_residual(q, T.apply(Q));
    cost += w * gated(r, limits) * gated(r, limits);
    count += r <= limits.gate && r >= -limits.gate ? 1 : 0;
  }
  return cost;
}

/// The per-frame sums as accumulate_frame_terms / frame_cost compute them, sample by sample:
/// the sampler of the GPU and of the reference CPU path. The CPU drivers pass a sampler with
/// the same two calls that vectorises across samples (gathered_frame_terms.hpp).
template <typename Scalar>
struct DirectSampler {
  JPCR_HD void accumulate(const QuadricT<Scalar>& q, const VertexView& view,
                          const RigidMotion<Scalar>& T, bool with_pose, Scalar ray_min_cos2,
                          const PixelOffset* pattern, int pattern_size, int u, int v,
                          const SampleGate<Scalar>& limits, FrameTerms<Scalar>& out) const {
    accumulate_frame_terms(q, view, T, with_pose, ray_min_cos2, pattern, pattern_size, u, v, limits,
                           out);
  }
  JPCR_HD Scalar cost(const QuadricT<Scalar>& q, const QuadricT<Scalar>& q_weight,
                      const VertexView& view, const RigidMotion<Scalar>& T,
                      const RigidMotion<Scalar>& T_weight, const PixelOffset* pattern,
                      int pattern_size, int u, int v, const SampleGate<Scalar>& limits,
                      int& count) const {
    return frame_cost(q, q_weight, view, T, T_weight, pattern, pattern_size, u, v, limits, count);
  }
};

/// Projective association (method.md §6): c = T⁻¹ p̄ projected into image j. False when c is
/// behind the camera, projects outside the image, or image j's depth there differs from c_z by
/// more than the occlusion threshold.
template <typename Scalar>
JPCR_HD bool associate(const Eigen::Matrix<Scalar, 3, 1>& centre, const RigidMotion<Scalar>& T,
                       const VertexView& view, const PinholeProjection& cam,
                       const JointTermParams& p, int& u, int& v) {
  const Eigen::Matrix<Scalar, 3, 1> c = T.apply_inverse(centre);
  if (!(c.z() > Scalar(0))) return false;
  const Scalar fu = Scalar(cam.fx) * c.x() / c.z() + Scalar(cam.cx);
  const Scalar fv = Scalar(cam.fy) * c.y() / c.z() + Scalar(cam.cy);
  if (!(fu > Scalar(-0.5) && fv > Scalar(-0.5) && fu < Scalar(view.width) - Scalar(0.5) &&
        fv < Scalar(view.height) - Scalar(0.5)))
    return false;
  u = static_cast<int>(std::floor(fu + Scalar(0.5)));
  v = static_cast<int>(std::floor(fv + Scalar(0.5)));
  if (!view.in_bounds(u, v)) return false;
  const float z = view(u, v).z();
  if (!is_finite_value(z)) return false;
  const Scalar limit = Scalar(p.occlusion_threshold) + Scalar(p.occlusion_fraction) * c.z();
  const Scalar dz = Scalar(z) - c.z();
  return dz <= limit && dz >= -limit;
}

/// The inputs of one window that every pixel reads: frame j's vertex view and T_j (j = 0 is the
/// reference frame, T_0 = I), the camera and the sampling pattern.
template <typename Scalar>
struct JointWindowView {
  const VertexView* views = nullptr;
  const RigidMotion<Scalar>* motions = nullptr;
  int frames = 0;  // M
  PinholeProjection camera;
  const PixelOffset* pattern = nullptr;
  int pattern_size = 0;
};

/// One quadric's linearised system over a window of at most MaxFrames frames, and its Schur
/// factors K_j = C_p⁻¹ B_jpᵀ and k = C_p⁻¹ b_p. J-ftf is MaxFrames = 2.
template <typename Scalar, int MaxFrames>
struct JointPixelSystem {
  using Matrix6 = Eigen::Matrix<Scalar, 6, 6>;
  using Vector6 = Eigen::Matrix<Scalar, 6, 1>;
  static constexpr int kPoses = MaxFrames - 1;  // T_2 … T_M

  Matrix6 L;             // Cholesky factor of the damped C_p (lower)
  Vector6 k;             // C_p⁻¹ b_p
  Matrix6 B[kPoses];     // B_jp
  Matrix6 K[kPoses];     // C_p⁻¹ B_jpᵀ
  Matrix6 A[kPoses];     // A_jp (symmetric; the lower triangle is read)
  Vector6 g_xi[kPoses];  // −a_jp
  Vector6 g_gamma;       // −b_p
  bool seen[kPoses];     // frame j+2 sees the quadric
  Scalar cost = 0;       // Σ w r² over all its terms
  int count = 0;         // terms inside the gate
  bool active = false;   // takes part in this iteration
};

/// The Schur factors of sys for the damping λ (LM on the full system: C_p + λ diag C_p): L, then
/// k = C_p⁻¹ b_p (from sys.g_gamma = −b_p) and K_j = C_p⁻¹ B_jpᵀ for each frame that sees the
/// quadric. C is the undamped C_p. False when the damped C_p is not positive definite.
template <typename Scalar, int MaxFrames>
JPCR_HD bool factor_damped_quadric(const Eigen::Matrix<Scalar, 6, 6>& C, Scalar lambda, int frames,
                                   JointPixelSystem<Scalar, MaxFrames>& sys) {
  sys.L = C;
  for (int i = 0; i < 6; ++i)
    sys.L(i, i) *= Scalar(1) + lambda;
  if (!cholesky_factor<Scalar, 6>(sys.L, Scalar(0))) return false;
  sys.k = -sys.g_gamma;
  cholesky_solve<Scalar, 6>(sys.L, sys.k);
  for (int j = 0; j + 1 < frames && j < sys.kPoses; ++j) {
    if (!sys.seen[j]) continue;
    sys.K[j] = sys.B[j].transpose();  // K_j = C⁻¹ B_jᵀ
    cholesky_solve_columns<Scalar, 6, 6>(sys.L, sys.K[j]);
  }
  return true;
}

/// Builds the system of the quadric at reference pixel (u, v) (method.md §6/§7) with the
/// Levenberg damping λ on the diagonal of C_p. Inactive when the frame-1 terms are too few, no
/// other frame sees it, or C_p is ill-conditioned; an inactive quadric keeps its γ_p. With
/// `undamped_C`, an active quadric's C_p without the damping goes there too (the CPU J-ftf keeps
/// it, to apply another damping without new sums: JointSystem::redamp).
template <typename Scalar, int MaxFrames, typename Sampler>
JPCR_HD void linearize_joint_pixel(const QuadricT<Scalar>& q, const JointWindowView<Scalar>& w,
                                   int u, int v, const JointTermParams& p, Scalar lambda,
                                   Sampler& sampler, JointPixelSystem<Scalar, MaxFrames>& sys,
                                   Eigen::Matrix<Scalar, 6, 6>* undamped_C = nullptr) {
  using Matrix6 = Eigen::Matrix<Scalar, 6, 6>;
  const SampleGate<Scalar> limits = SampleGate<Scalar>::at(p.fit, q.center);
  sys.active = false;
  sys.cost = 0;
  sys.count = 0;
  for (int j = 0; j < sys.kPoses; ++j)
    sys.seen[j] = false;
  Matrix6 C = Matrix6::Zero();
  sys.g_gamma.setZero();
  if (p.estimate_quadrics) {  // frame-1 terms: as Quad IT, T = I, no pose
    FrameTerms<Scalar> f1;
    sampler.accumulate(q, w.views[0], RigidMotion<Scalar>{}, false, Scalar(kNoRayFoot), w.pattern,
                       w.pattern_size, u, v, limits, f1);
    if (f1.count < p.fit.min_samples) return;
    C = f1.C;
    sys.g_gamma = f1.g_gamma;
    sys.cost = f1.cost;
    sys.count = f1.count;
  }
  bool any = false;
  for (int j = 0; j + 1 < w.frames && j < sys.kPoses; ++j) {
    int su = 0, sv = 0;
    if (!associate(q.center, w.motions[j + 1], w.views[j + 1], w.camera, p, su, sv)) continue;
    FrameTerms<Scalar> f;
    sampler.accumulate(q, w.views[j + 1], w.motions[j + 1], true, p.ray_min_cos2<Scalar>(),
                       w.pattern, w.pattern_size, su, sv, limits, f);
    if (f.count < p.min_frame_terms) continue;
    sys.seen[j] = any = true;
    C += f.C;
    sys.g_gamma += f.g_gamma;
    sys.B[j] = f.B;
    sys.A[j] = f.A;
    sys.g_xi[j] = f.g_xi;
    sys.cost += f.cost;
    sys.count += f.count;
  }
  if (!any) return;
  if (p.estimate_quadrics) {
    // The pivot test runs on the undamped C_p, relative to each diagonal entry: the damping
    // would lift the pivot of a direction the samples do not observe (e.g. the curvature across
    // a line of samples along a depth edge) and let it drift over the iterations.
    sys.L = C;
    if (!cholesky_factor<Scalar, 6>(sys.L, Scalar(0))) return;
    for (int i = 0; i < 6; ++i)
      if (!(sys.L(i, i) * sys.L(i, i) >= Scalar(p.min_pivot_ratio) * C(i, i))) return;
    if (!factor_damped_quadric(C, lambda, w.frames, sys)) return;
    if (undamped_C) *undamped_C = C;
  }
  sys.active = true;
}

/// linearize_joint_pixel with the sample-by-sample sums (the GPU and the reference CPU path).
template <typename Scalar, int MaxFrames>
JPCR_HD void linearize_joint_pixel(const QuadricT<Scalar>& q, const JointWindowView<Scalar>& w,
                                   int u, int v, const JointTermParams& p, Scalar lambda,
                                   JointPixelSystem<Scalar, MaxFrames>& sys) {
  DirectSampler<Scalar> sampler;
  linearize_joint_pixel(q, w, u, v, p, lambda, sampler, sys);
}

/// The frames that see the quadric as bits (bit j − 1 for frame j), as linearized_pixel_cost reads
/// them.
template <typename Scalar, int MaxFrames>
JPCR_HD unsigned seen_bits(const JointPixelSystem<Scalar, MaxFrames>& sys, int frames) {
  unsigned bits = 0;
  for (int j = 0; j + 1 < frames && j < sys.kPoses; ++j)
    bits |= sys.seen[j] ? 1u << j : 0u;
  return bits;
}

/// Adds an active quadric's pose terms to the reduced system (lower triangle of the dense
/// n x n matrix S, n = 6 (M − 1), row-major, and s), and diag A to A_diagonal (unless null):
///   S_jj += A_jp,   s_j += −g_xi_j.
template <typename Scalar, int MaxFrames, typename Acc>
JPCR_HD void add_pose_terms(const JointPixelSystem<Scalar, MaxFrames>& sys, int frames, Acc* S,
                            Acc* s, Acc* A_diagonal) {
  const int n = 6 * (frames - 1);
  for (int j = 0; j + 1 < frames && j < sys.kPoses; ++j) {
    if (!sys.seen[j]) continue;
    for (int r = 0; r < 6; ++r) {
      const int row = 6 * j + r;
      for (int c = 0; c <= r; ++c)
        S[row * n + 6 * j + c] += Acc(sys.A[j](r, c));
      if (A_diagonal) A_diagonal[row] += Acc(sys.A[j](r, r));
      s[row] += Acc(-sys.g_xi[j](r));
    }
  }
}

/// Eliminates the quadric from the reduced system (its factors k, K_j; the same layout):
///   S_jk −= B_jp K_k,   s_j −= B_jp k.
template <typename Scalar, int MaxFrames, typename Acc>
JPCR_HD void eliminate_quadric(const JointPixelSystem<Scalar, MaxFrames>& sys, int frames, Acc* S,
                               Acc* s) {
  const int n = 6 * (frames - 1);
  for (int j = 0; j + 1 < frames && j < sys.kPoses; ++j) {
    if (!sys.seen[j]) continue;
    for (int r = 0; r < 6; ++r)
      s[6 * j + r] -= Acc(sys.B[j].row(r).dot(sys.k));
    for (int k = 0; k <= j; ++k) {
      if (!sys.seen[k]) continue;
      const Eigen::Matrix<Scalar, 6, 6> BK = sys.B[j] * sys.K[k];  // B_jp C_p⁻¹ B_kpᵀ
      for (int r = 0; r < 6; ++r)
        for (int c = 0; c < (k == j ? r + 1 : 6); ++c)
          S[(6 * j + r) * n + 6 * k + c] -= Acc(BK(r, c));
    }
  }
}

/// An active quadric's share of the reduced system: its pose terms, and with estimate_quadrics
/// its elimination, S_jk += δ_jk A_jp − B_jp K_k and s_j += −g_xi_j − B_jp k.
template <typename Scalar, int MaxFrames, typename Acc>
JPCR_HD void add_schur_terms(const JointPixelSystem<Scalar, MaxFrames>& sys, int frames,
                             bool estimate_quadrics, Acc* S, Acc* s, Acc* A_diagonal) {
  add_pose_terms(sys, frames, S, s, A_diagonal);
  if (estimate_quadrics) eliminate_quadric(sys, frames, S, s);
}

/// Back-substitution (method.md §7): Δγ_p = C_p⁻¹ (b_p − Σ_j B_jpᵀ Δξ_j) = k − Σ_j K_j Δξ_j.
/// pose_steps[j] is Δξ of T_{j+2}.
template <typename Scalar, int MaxFrames>
JPCR_HD QuadricVector<Scalar> back_substitute(const JointPixelSystem<Scalar, MaxFrames>& sys,
                                              int frames,
                                              const Eigen::Matrix<Scalar, 6, 1>* pose_steps) {
  QuadricVector<Scalar> delta = sys.k;
  for (int j = 0; j + 1 < frames && j < sys.kPoses; ++j)
    if (sys.seen[j]) delta -= sys.K[j] * pose_steps[j];
  return delta;
}

/// The cost of one quadric at the candidate (its quadric q, the poses `next`) over the terms
/// of its linearisation at the poses `window` (this project's reading of method.md §6's "accept
/// the step only if the robust cost does not increase": the cost the linearisation models): the
/// frame-1 terms at (u, v) (not in Q-full, whose quadrics are fixed), and each frame
/// j that saw it there (`seen`: bit j − 1), that frame's pattern taken at the pixel the quadric
/// was associated to at `window`; each sample's residual at `next` and quadric q, its weight
/// n₀² / (n₀² + r² + d²) at `window` and the linearisation's quadric q_lin (held, as the normal
/// equations hold the weights: IRLS). Samples outside the gate cost w gate², so a step that moves
/// samples out of it pays for them. With the weights held, the cost is the one whose Gauss-Newton
/// step the normal equations give, so a small enough damped step always lowers it. With the r²
/// term of the weight taken at the candidate (Σ w(r) r², the Geman-McClure cost, whose gradient
/// is 2 w² r (n₀² + d²) / n₀², not the 2 w r of the normal equations), steps near the optimum
/// raised it to first order: Q-full rejected every step from its 14th linearisation on, at every
/// damping (a review's reproducer at 160x120, 0.5 % range noise), and J-ftf and J-full ended by
/// the tolerance on ever smaller damped steps instead of at the stationary point. Re-associated at
/// the candidate, a step was credited with the cost of every frame it moved out of view, and with
/// d² at the candidate, a step that carried a frame's samples far from the quadrics made their
/// weights vanish: J-full accepted a 170 m step on a corridor (cost 0.0002 against 0.29), and
/// single-pose Q-full accepted steps whose cost on the same pairs rose. The next linearisation
/// re-associates.
template <typename Scalar, typename Sampler>
JPCR_HD Scalar linearized_pixel_cost(const QuadricT<Scalar>& q, const QuadricT<Scalar>& q_lin,
                                     const JointWindowView<Scalar>& window,
                                     const JointWindowView<Scalar>& next, int u, int v,
                                     unsigned seen, const JointTermParams& p, Sampler& sampler) {
  const SampleGate<Scalar> limits = SampleGate<Scalar>::at(p.fit, q.center);
  Scalar cost = 0;
  int count = 0;
  if (p.estimate_quadrics)
    cost += sampler.cost(q, q_lin, next.views[0], RigidMotion<Scalar>{}, RigidMotion<Scalar>{},
                         next.pattern, next.pattern_size, u, v, limits, count);
  for (int j = 1; j < window.frames; ++j) {
    if (((seen >> (j - 1)) & 1u) == 0u) continue;
    int su = 0, sv = 0;
    if (!associate(q.center, window.motions[j], window.views[j], window.camera, p, su, sv))
      continue;  // not reached: the frame saw it at these poses (the centre does not move)
    cost += sampler.cost(q, q_lin, next.views[j], next.motions[j], window.motions[j], next.pattern,
                         next.pattern_size, su, sv, limits, count);
  }
  return cost;
}

/// linearized_pixel_cost with the sample-by-sample sums.
template <typename Scalar>
JPCR_HD Scalar linearized_pixel_cost(const QuadricT<Scalar>& q, const QuadricT<Scalar>& q_lin,
                                     const JointWindowView<Scalar>& window,
                                     const JointWindowView<Scalar>& next, int u, int v,
                                     unsigned seen, const JointTermParams& p) {
  DirectSampler<Scalar> sampler;
  return linearized_pixel_cost(q, q_lin, window, next, u, v, seen, p, sampler);
}

}  // namespace jpcr
