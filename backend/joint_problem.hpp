// The Levenberg-Marquardt loop of the joint refiners (method.md §6 "Update"), written once over
// an abstract joint system: the CPU JointSystem (joint_system.hpp, through CpuJointProblem) and
// the GPU J-ftf (cuda/cuda_joint_ftf.hpp) both provide linearise / propose / accept, so J-ftf,
// J-full and Q-full on the CPU and J-ftf on the GPU step, damp and stop identically.
#pragma once

#include <string>
#include <utility>
#include <vector>

#include "jpcr/backend/joint_system.hpp"
#include "jpcr/backend/refiner.hpp"

namespace jpcr {

/// A joint system that holds its current state T_2 … T_M, γ_p (wherever it keeps them).
class JointProblem {
 public:
  virtual ~JointProblem() = default;

  /// The reduced system (S, s, diag A, cost, counts) at the current state, with the Levenberg
  /// damping λ on diag C_p.
  virtual ReducedSystem linearize(double lambda) = 0;

  /// linearize(λ) into `out`, which holds an earlier system whose buffers an implementation
  /// may reuse.
  virtual void relinearize(double lambda, ReducedSystem& out) { out = linearize(lambda); }

  /// linearize(λ) into `out` when `out` is the system of the current state at another damping,
  /// unchanged since (after a rejected step, and for the final undamped system): an
  /// implementation may then only apply the new damping. By default relinearize.
  virtual void redamp(double lambda, ReducedSystem& out) { relinearize(lambda, out); }

  /// Back-substitutes the quadric steps for `pose_steps` (solved from `system`, the most recent
  /// linearize, relinearize or redamp at this λ) into a candidate state and returns Σ w r²
  /// there, re-associated at the candidate poses.
  virtual double propose(const ReducedSystem& system, double lambda,
                         const std::vector<Vector6d>& pose_steps) = 0;

  /// The candidate of the last propose() becomes the current state.
  virtual void accept() = 0;

  /// The current state on the host.
  virtual const JointState& state() = 0;
};

/// JointProblem over the CPU driver JointSystem (which stays stateless).
class CpuJointProblem final : public JointProblem {
 public:
  CpuJointProblem(const JointSystem& system, JointState initial)
      : system_(system), state_(std::move(initial)) {}
  ReducedSystem linearize(double lambda) override { return system_.linearize(state_, lambda); }
  void relinearize(double lambda, ReducedSystem& out) override {
    system_.linearize(state_, lambda, out);
  }
  /// JointSystem::redamp (J-ftf and J-full with kept blocks: no new sums; Q-full: nothing to
  /// do), else linearize again.
  void redamp(double lambda, ReducedSystem& out) override {
    if (!system_.redamp(lambda, out)) system_.linearize(state_, lambda, out);
  }
  double propose(const ReducedSystem& system, double lambda,
                 const std::vector<Vector6d>& pose_steps) override {
    system_.step(state_, system, lambda, pose_steps, candidate_);
    return candidate_.cost;
  }
  // A swap, not a move: the next propose() reuses the old state's buffers for its candidate.
  void accept() override { std::swap(state_, candidate_.candidate); }
  const JointState& state() override { return state_; }

 private:
  const JointSystem& system_;
  JointState state_;
  JointStep candidate_;
};

/// Throws std::invalid_argument unless 2 ≤ M ≤ kMaxWindowFrames frames of the camera's size,
/// M poses with T_1 = I, and a quadric map of frame 1's size.
void check_joint_inputs(const std::vector<VertexMap>& vertices, const CameraIntrinsics& camera,
                        const std::vector<Eigen::Isometry3d>& poses, const QuadricMap& quadrics);

/// The initial state: the poses (T_1 set to I exactly) and the valid quadrics of `map`.
JointState initial_joint_state(const std::vector<Eigen::Isometry3d>& poses, const QuadricMap& map);
/// The same into `out`, reusing its buffers (a refiner that keeps its state from pair to pair
/// avoids fresh pages: 39 MB of quadrics at 640x480).
void fill_joint_state(const std::vector<Eigen::Isometry3d>& poses, const QuadricMap& map,
                      JointState& out);

/// The quadrics the joint refiners leave out (JointParams::edge_tilt): 1 at each pixel of the
/// reference whose initial normal came from a quadrant of its window tilted more than edge_tilt
/// from the window's plane (estimate_normals, quadrant_tilt), i.e. whose window straddles a
/// crease or a depth step; empty when edge_tilt is 0.
///
/// Such a quadric fits the centre's face, but the other face's samples near the edge line lie
/// within the gate of its extension, differently in each frame. Measured noise-free (640x480
/// walks, J-ftf frames 0–3, 30 iterations: the minimum, not an early stop), RMS relative
/// translation with all quadrics / with these left out: cylinders_boxes 18.6 / 3.4 µm,
/// torus_saddle 18.3 / 12.0 µm, room_spheres 8.7 / 5.9 µm; leaving out every quadrant pixel,
/// those tilted by rounding alone included (17 % of the quadrics), 5.2 / 12.4 / 7.0 µm. The
/// creases carry it: on cylinders_boxes leaving out only the windows with a depth step gave
/// 18.3 µm, only the others 5.4 µm. edge_tilt 0.5° gave 3.1 / 12.4 µm on the first two, 10°
/// 15.1 / 14.0 µm: a window that reaches a pixel or two across a crease tilts by a few degrees.
/// Under range noise a quadrant rarely fits 100 times better than its window (quadrant_ratio):
/// at 1 % 43–91 of about 300k quadrics were left out, and the poses moved by at most 0.3 µm.
std::vector<unsigned char> edge_quadrics(const VertexMap& reference, const JointParams& params);

/// Marks the `edges` of edge_quadrics invalid in `state`, so that they take no part and keep the
/// initial map's fit; returns how many valid quadrics it left out. Empty edges leave all in.
/// Throws std::invalid_argument when edges is neither empty nor one flag per quadric.
int leave_out(const std::vector<unsigned char>& edges, JointState& state);

/// Linearise, solve the reduced system, back-substitute, accept the step only when Σ w r² does
/// not increase (else raise λ on diag A and diag C_p and retry), until the pose steps are below
/// the tolerances; then the report, the covariance from the undamped system and the refined map
/// (initial_quadrics with the refined quadrics of the valid pixels; a quadric left with fewer
/// than min_samples of its reference-frame samples in its gate is invalid). estimate_quadrics =
/// false is Q-full.
RefinementResult run_joint_refinement(JointProblem& problem, const JointParams& params,
                                      bool estimate_quadrics, const std::string& method,
                                      const QuadricMap& initial_quadrics,
                                      const VertexMap& reference);

}  // namespace jpcr
