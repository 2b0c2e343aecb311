// The one small interface the back end's refiners share (architecture.md "Interfaces"):
//
//   refine(frames, initial poses) -> {poses, quadric map, covariance, report}
//
// Poses follow method.md §1: T_j maps frame j into the reference frame 1, and T_1 = I is fixed
// (the gauge). A pipeline holding camera-to-world poses passes T_j = T_w1⁻¹ T_wj. The refiners
// are J-ftf (JointFrameToFrame, "j-ftf"), J-full (JointWindow, "j-full") and Q-full
// (FixedQuadricAlignment, "q-full") and, in builds with Ceres, ICP-bundle (IcpBundle,
// "icp-bundle", method.md §9); make_refiner picks one by name.
#pragma once

#include <functional>
#include <memory>
#include <string>
#include <vector>

#include <Eigen/Geometry>

#include "jpcr/backend/icp_bundle_params.hpp"
#include "jpcr/backend/joint_params.hpp"
#include "jpcr/quadric/frame.hpp"
#include "jpcr/quadric/quadric_map.hpp"
#include "jpcr/quadric/se3.hpp"

namespace jpcr {

enum class RefinementVerdict {
  kConverged,       // the last step was below the tolerances
  kMaxIterations,   // still moving after max_iterations accepted steps
  kDiverged,        // the cost could not be lowered (damping ran away) or became non-finite
  kTooFewQuadrics,  // too few quadrics are seen in another frame (no overlap) or a pose is unseen
  kNoOverlap,       // ICP-bundle: a frame overlaps no frame tied to the reference (isolated)
  kDegenerate,      // the poses' system is near singular (a plane, a corridor): some motion of
                    // the camera is not observed, so the poses cannot be trusted
  kError,           // the refiner threw (out of memory, a device error); the report's `error`
                    // says what. The pipeline reports it and keeps the front end's motion.
};

/// "converged", "max_iterations", "diverged", "too_few_quadrics", "no_overlap", "degenerate",
/// "error".
const char* to_string(RefinementVerdict verdict);

/// Converged, or still improving at the iteration cap: a result whose poses the pipeline uses.
bool usable(RefinementVerdict verdict);

/// Whether a result can be trusted (architecture.md: every result says so).
struct RefinementReport {
  std::string method;          // "j-ftf", "j-full", "q-full" or "icp-bundle"
  std::string device = "cpu";  // where it ran: "cpu", or "cuda" (the GPU J-ftf; a refinement
                               // that fell back to the CPU after a GPU failure says "cpu");
                               // empty where the refiner threw (kError)
  RefinementVerdict verdict = RefinementVerdict::kDiverged;
  /// Q-full, whose poses are independent problems (method.md §8): each pose's own verdict, T_2 …
  /// T_M; `verdict` is then usable only when all of these are, and the poses whose own verdict
  /// is usable may be used even when it is not. Empty for the joint refiners, whose one verdict
  /// covers every pose. Q-full's other fields combine its pose problems': iterations the most of
  /// any, rejected_steps, terms and cost summed (a pose that ended keeps its last cost),
  /// active_quadrics the most any pose saw, edge_quadrics each pose's (the same in all),
  /// residual_variance and sample_reuse pooled over all terms (each pose's covariance block uses
  /// its own), degeneracy the least of any pose's, damping the largest.
  std::vector<RefinementVerdict> pose_verdicts;
  std::string error;               // kError: what the refiner threw; empty otherwise
  int iterations = 0;              // accepted steps
  int rejected_steps = 0;          // steps that raised the cost (then damped and retried)
  std::vector<double> cost;        // Σ w r² (m²) at the start and after each accepted step,
                                   // each over its own linearisation's active quadrics and
                                   // samples, so a value can exceed the one before (the step
                                   // test compares the candidate's cost over the previous
                                   // linearisation's quadrics with that linearisation's);
                                   // icp-bundle: Σ ρ(e²) at the start and after each solve
  int active_quadrics = 0;         // quadrics taking part at the end
  int edge_quadrics = 0;           // valid quadrics left out at creases and steps, keeping
                                   // their Quad IT fit (JointParams::edge_tilt)
  int quad_it_fits_restored = 0;   // refined quadrics whose Quad IT start had the lower gated
                                   // cost at the refined poses, or that kept too few samples
                                   // (keep_lower_cost_fit)
  std::vector<int> seen;           // per pose T_2 … T_M: active quadrics that frame sees;
                                   // icp-bundle: residuals that involve the frame
  long terms = 0;                  // residual terms inside the gate at the end
  std::vector<int> isolated;       // icp-bundle: frames (window index) without terms at the
                                   // end (no_overlap), returned as given
  double residual_variance = 0.0;  // m²: final cost / (terms − unknowns)
  /// Terms per distinct sample (terms / (active quadrics + Σ seen), about the number of
  /// neighbourhoods each sample falls in): the factor by which the covariance is inflated.
  double sample_reuse = 0.0;
  double damping = 0.0;  // λ at the end
  /// λmin / λmax of the reduced pose system S made unit-free (each pose's ω block scaled by
  /// √(tr S_vv / tr S_ωω), as the front end's IcpResult::degeneracy): 1 is perfectly
  /// conditioned, 0 unobservable; below JointParams::degeneracy_threshold (icp-bundle:
  /// IcpBundleParams::degeneracy_threshold, its Gauss-Newton system of the poses it solved) the
  /// verdict is kDegenerate.
  double degeneracy = 0.0;
  /// Per pose T_2 … T_M: the predicted RMS length of its translation error (m) and rotation
  /// error (rad) against the reference frame, from RefinementResult::covariance (pose_spread);
  /// empty where the refiner gives no covariance (icp-bundle), 0 where S is singular.
  std::vector<double> translation_sd, rotation_sd;
  /// The same for the steps T_1⁻¹T_2, T_2⁻¹T_3, …, T_{M−1}⁻¹T_M between successive frames, from
  /// RefinementResult::joint_covariance (its cross terms): what a relative pose error metric
  /// sees. For J-ftf the one step is the pose. Empty without a joint covariance (icp-bundle, a
  /// singular S).
  std::vector<double> step_translation_sd, step_rotation_sd;

  bool converged() const { return verdict == RefinementVerdict::kConverged; }
  /// Whether pose T_{j+1} (j = 1 … M−1, the index into RefinementResult::poses) may be used: its
  /// own verdict where there is one (pose_verdicts), else the refinement's.
  bool pose_usable(std::size_t j) const;
};

struct RefinementResult {
  std::vector<Eigen::Isometry3d> poses;  // T_1 = I, T_2 … T_M (frame j → frame 1)
  QuadricMap quadrics;                   // the reference frame's quadrics, curvature recomputed
  /// Per pose, (v, ω) order, of the left update T ← exp(ξ^) T: the blocks of reuse · σ² S⁻¹
  /// (RefinementReport::sample_reuse, residual_variance); [0] = 0 (the gauge). Zero blocks when
  /// S is singular (degeneracy 0); below the degeneracy threshold (verdict `degenerate`) S⁻¹ is
  /// kept, large along the weak direction, and the verdict says not to use the poses. It
  /// describes the spread of the estimate under sensor noise, not its bias.
  std::vector<Matrix6d> covariance;
  /// All poses T_2 … T_M jointly, 6(M−1) square (its diagonal blocks are `covariance`); empty
  /// when unknown (Q-full: block-diagonal, and empty when any pose's S is singular).
  Eigen::MatrixXd joint_covariance;
  RefinementReport report;
};

/// The predicted RMS length of a pose's translation error (m) and rotation error (rad), from its
/// 6x6 covariance in the left update T ← exp(ξ^) T, ξ = (v, ω): to first order the translation
/// moves by δt = v + ω × t = [I, −[t]×] ξ, so its covariance is [I, −[t]×] Σ [I, −[t]×]ᵀ, and the
/// RMS length of a zero-mean error is the square root of its covariance's trace.
struct PoseSpread {
  double translation_m = 0.0;
  double rotation_rad = 0.0;
};
PoseSpread pose_spread(const Matrix6d& covariance, const Eigen::Isometry3d& pose);

/// The degeneracy of a pose system S (6 rows per pose, (v, ω) each): λmin / λmax after each
/// pose's ω rows and columns are scaled by √(tr S_vv / tr S_ωω), the RMS lever arm, so that
/// metres and radians weigh alike (as the front end's IcpResult::degeneracy). 1 is perfectly
/// conditioned, 0 unobservable.
double pose_system_degeneracy(const Eigen::MatrixXd& S);

/// Fills the report's translation_sd / rotation_sd from result.covariance and result.poses, and
/// step_translation_sd / step_rotation_sd from result.joint_covariance: the step
/// T_{j−1}⁻¹ T_j moves, to first order, by the left update Ad(T_{j−1}⁻¹) (ξ_j − ξ_{j−1}) (ξ_1 = 0).
/// The steps stay empty when joint_covariance is (a degenerate S).
void report_pose_spread(RefinementResult& result);

/// Thread safety: refine() is const and keeps no state between calls, so one refiner may be
/// called from several threads at once (the CPU refiners parallelise each call with OpenMP, so
/// concurrent calls share the cores); the GPU J-ftf serialises its calls (they share the device
/// buffers).
class Refiner {
 public:
  virtual ~Refiner() = default;

  /// From depth frames (frames[0] is the reference): vertex maps, Quad IT on the reference
  /// (the initial quadrics), then the refinement. Throws std::invalid_argument when the frames
  /// differ in size or intrinsics, or the poses do not match them.
  virtual RefinementResult refine(const std::vector<Frame>& frames,
                                  const std::vector<Eigen::Isometry3d>& initial_poses) const;

  /// From vertex maps and initial quadrics on vertices[0] (e.g. Quad IT from the GPU).
  virtual RefinementResult refine(const std::vector<VertexMap>& vertices,
                                  const CameraIntrinsics& camera,
                                  const std::vector<Eigen::Isometry3d>& initial_poses,
                                  const QuadricMap& initial_quadrics) const = 0;

  virtual std::string name() const = 0;
  virtual const JointParams& params() const = 0;
  /// Whether RefinementResult::quadrics are refined; Q-full returns the initial ones as given,
  /// ICP-bundle none. A refiner that wraps another must pass this on.
  virtual bool refines_quadrics() const { return true; }
};

/// The frames' vertex maps; throws std::invalid_argument (naming `method`) when there are none
/// or they differ in size or intrinsics.
std::vector<VertexMap> window_vertex_maps(const std::vector<Frame>& frames,
                                          const std::string& method);

/// "j-ftf", "j-full", "q-full" or "icp-bundle" (`bundle` its parameters); throws InputError
/// naming the choices otherwise, and for "icp-bundle" in a build without Ceres.
std::unique_ptr<Refiner> make_refiner(const std::string& name, const JointParams& params = {},
                                      const IcpBundleParams& bundle = {});

/// How the pipeline makes its refiners, by method name; empty means make_refiner above (all on
/// the CPU). An application injects one to run J-ftf elsewhere, e.g. on a GPU
/// (device_refiner_factory in cuda/refiner_factory.hpp).
using RefinerFactory = std::function<std::unique_ptr<Refiner>(
    const std::string& name, const JointParams& params, const IcpBundleParams& bundle)>;

}  // namespace jpcr
