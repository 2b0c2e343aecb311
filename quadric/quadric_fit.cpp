#include "jpcr/quadric/quadric_fit.hpp"

#include <algorithm>
#include <cmath>
#include <cstddef>
#include <cstdint>
#include <cstdlib>
#include <limits>
#include <optional>
#include <stdexcept>
#include <string>
#include <vector>

#include "jpcr/quadric/error.hpp"
#include "jpcr/quadric/parallel_guard.hpp"
#include "jpcr/quadric/pixel_lane_steps.hpp"
#include "jpcr/quadric/pixel_lane_sums.hpp"
#include "jpcr/quadric/simd_clones.hpp"

namespace jpcr {

namespace {

// The vertex map as three float planes (x, y, z) with a NaN margin: `margin` on the left, top
// and bottom, margin + kPixelLanes on the right, so that every sample of every pixel, and the
// lanes of a last group that run past the image, read inside the planes. A sample in the margin
// has no depth and is skipped: the 2-D bounds check of method.md §2.
class VertexPlanes {
 public:
  VertexPlanes(const VertexMap& vertices, int margin)
      : margin_(margin), stride_(vertices.width() + 2 * margin + kPixelLanes) {
    const std::size_t size = static_cast<std::size_t>(stride_) * (vertices.height() + 2 * margin);
    for (std::vector<float>& plane : planes_)
      plane.assign(size, std::numeric_limits<float>::quiet_NaN());
    for (int v = 0; v < vertices.height(); ++v) {
      for (int u = 0; u < vertices.width(); ++u) {
        // A vertex that is no sample (is_sample_point; fit_quadric_pixel skips it too): all
        // three NaN.
        const Eigen::Vector3f& X = vertices(u, v);
        if (!is_sample_point(X)) continue;
        const std::size_t i = index(u, v);
        for (int axis = 0; axis < 3; ++axis)
          planes_[axis][i] = X(axis);
      }
    }
  }

  int stride() const { return stride_; }
  const float* at(int axis, int u, int v) const { return planes_[axis].data() + index(u, v); }

 private:
  std::size_t index(int u, int v) const {
    return static_cast<std::size_t>(v + margin_) * stride_ + (u + margin_);
  }

  int margin_, stride_;
  std::vector<float> planes_[3];
};

// Quad IT for kPixelLanes horizontally adjacent pixels at once, the CPU way: each Gauss-Newton
// pass sums every pixel's normal equations in its own SIMD lane (pixel_lane_sums), then every
// pixel takes its step, also lane by lane (pixel_lane_steps.hpp). Same math, parameters and
// stopping rule as fit_quadric_pixel (quadric_fit_kernel.hpp), which the CUDA kernel runs;
// tests compare the two.
class PixelGroupFit {
 public:
  PixelGroupFit(const VertexMap& vertices, const NormalMap& normals, const VertexPlanes& planes,
                const std::vector<std::ptrdiff_t>& offsets, const QuadricFitParams& p)
      : vertices_(vertices), normals_(normals), planes_(planes), offsets_(offsets), p_(p) {}

  // Fits the pixels u0 … u0 + kPixelLanes − 1 of row v (those inside the image) into map.
  void run(int u0, int v, QuadricMap& map) {
    const int lanes = std::min(kPixelLanes, vertices_.width() - u0);
    for (int l = 0; l < kPixelLanes; ++l)
      start(l, l < lanes ? u0 + l : -1, v);
    for (int it = 0; it <= p_.iterations; ++it) {
      const bool last = it == p_.iterations;  // one pass more than steps: it checks the last one
      to_float();
      pixel_lane_sums(in_, planes_.at(0, u0, v), planes_.at(1, u0, v), planes_.at(2, u0, v),
                      offsets_.data(), static_cast<int>(offsets_.size()), !last, sums_);
      if (!last) pixel_lane_steps(sums_, damping_, range_, delta_, ok_);
      for (int l = 0; l < kPixelLanes; ++l)
        decide(l, last);
      // Undone lanes return to their previous quadric; stepping lanes keep theirs as previous.
      for (int i = 0; i < LaneQuadrics::kRows; ++i) {
        for (int l = 0; l < kPixelLanes; ++l) {
          if (undo_[l]) q_.row[i][l] = previous_.row[i][l];
          if (take_[l]) previous_.row[i][l] = q_.row[i][l];
        }
      }
      if (last) break;
      pixel_lane_updates(q_, delta_, take_, p_, converged_);
      bool any = false;
      for (int l = 0; l < kPixelLanes; ++l) {
        stepped_[l] = stepped_[l] || take_[l];
        kept_[l] = kept_[l] || (take_[l] && converged_[l]);  // a step this small: where it stands
        active_[l] = (take_[l] && !converged_[l]) || retry_[l];
        any |= active_[l];
      }
      if (!any) break;
    }
    for (int l = 0; l < lanes; ++l) {
      if (status_[l] == QuadricStatus::kValid && !kept_[l]) status_[l] = QuadricStatus::kNoStep;
      if (status_[l] == QuadricStatus::kValid)
        map.set(u0 + l, v, lane_quadric(l));
      else
        map.set_invalid(u0 + l, v, status_[l]);
    }
  }

 private:
  // Lane l starts at pixel (u, v) (u < 0: no pixel) from the plane of its initial normal.
  void start(int l, int u, int v) {
    active_[l] = false;
    previous_cost_[l] = 1e300;  // as fit_quadric_pixel
    damping_[l] = p_.damping;
    kept_[l] = p_.iterations == 0;
    stepped_[l] = retry_[l] = false;
    Eigen::Matrix3d R = Eigen::Matrix3d::Identity();
    Eigen::Vector3f centre = Eigen::Vector3f::Zero();
    status_[l] = QuadricStatus::kNoCentre;
    double range = 0.0;
    if (u >= 0 && centre_with_range(vertices_(u, v), range)) {
      centre = vertices_(u, v);
      const Eigen::Vector3f& normal = normals_(u, v);
      status_[l] = is_finite_value(normal.z()) ? QuadricStatus::kValid : QuadricStatus::kNoNormal;
      if (status_[l] == QuadricStatus::kValid) {
        R = local_frame<double>(normal.cast<double>().normalized());
        active_[l] = true;
      }
    }
    range_[l] = active_[l] ? range : 1.0;  // 1: any finite scale for an idle lane
    for (int i = 0; i < 9; ++i)
      q_.row[i][l] = R(i / 3, i % 3);
    for (int i = LaneQuadrics::kTz; i < LaneQuadrics::kRows; ++i)
      q_.row[i][l] = 0.0;
    const SampleGate<double> limits = SampleGate<double>::at(p_, centre.cast<double>());
    for (int axis = 0; axis < 3; ++axis)
      in_.centre[axis][l] = centre(axis);
    in_.gate[l] = static_cast<float>(limits.gate);
    in_.n0[l] = static_cast<float>(limits.n0);
  }

  // The lanes' quadrics as the float inputs of pixel_lane_sums.
  void to_float() {
    for (int l = 0; l < kPixelLanes; ++l) {
      for (int i = 0; i < 9; ++i)
        in_.R[i][l] = static_cast<float>(q_.row[i][l]);
      in_.t_z[l] = static_cast<float>(q_.row[LaneQuadrics::kTz][l]);
      in_.a[l] = static_cast<float>(q_.row[LaneQuadrics::kA][l]);
      in_.b[l] = static_cast<float>(q_.row[LaneQuadrics::kB][l]);
      in_.c[l] = static_cast<float>(q_.row[LaneQuadrics::kC][l]);
    }
  }

  // Lane l after a pass: undo_ where the last step raised the gated cost or left fewer
  // than min_samples inliers (and retry_ from the plane with more damping where no step was kept
  // yet), take_ where it takes another step; every other active lane stops here (or is
  // invalid). As fit_quadric_pixel.
  void decide(int l, bool last) {
    undo_[l] = take_[l] = retry_[l] = false;
    if (!active_[l]) return;
    active_[l] = false;
    const int count = static_cast<int>(sums_.count[l]);
    const double cost = double(sums_.gated[l]);  // Σ w(e) e² over the samples with depth
    const bool too_few = count < p_.min_samples;
    if (stepped_[l] && (cost > previous_cost_[l] || too_few)) {
      undo_[l] = true;
      stepped_[l] = false;
      if (!kept_[l]) {
        damping_[l] *= kRetryDampingFactor;
        retry_[l] = true;  // the next pass sums at the plane again and steps from it
      }
      return;
    }
    if (too_few) {  // the starting plane
      status_[l] = QuadricStatus::kTooFewSamples;
      return;
    }
    kept_[l] = kept_[l] || stepped_[l];
    stepped_[l] = false;  // checked
    if (last) return;
    if (!ok_[l]) {
      status_[l] = QuadricStatus::kSingular;
      return;
    }
    previous_cost_[l] = cost;
    take_[l] = true;
  }

  Quadric lane_quadric(int l) const {
    Quadric q;
    for (int i = 0; i < 9; ++i)
      q.R(i / 3, i % 3) = static_cast<float>(q_.row[i][l]);
    q.center = Eigen::Vector3f(in_.centre[0][l], in_.centre[1][l], in_.centre[2][l]);
    q.t_z = static_cast<float>(q_.row[LaneQuadrics::kTz][l]);
    q.a = static_cast<float>(q_.row[LaneQuadrics::kA][l]);
    q.b = static_cast<float>(q_.row[LaneQuadrics::kB][l]);
    q.c = static_cast<float>(q_.row[LaneQuadrics::kC][l]);
    return q;
  }

  const VertexMap& vertices_;
  const NormalMap& normals_;
  const VertexPlanes& planes_;
  const std::vector<std::ptrdiff_t>& offsets_;
  const QuadricFitParams& p_;
  PixelLaneQuadrics in_{};
  PixelLaneSums sums_{};
  LaneQuadrics q_{}, previous_{};
  double previous_cost_[kPixelLanes];
  double damping_[kPixelLanes];   // λ of each lane's next step: p.damping, more after a retry
  double range_[kPixelLanes];     // |p̄| of each lane (solve_damped_step's range units)
  double delta_[6][kPixelLanes];  // each lane's step (pixel_lane_steps)
  QuadricStatus status_[kPixelLanes];
  bool active_[kPixelLanes], ok_[kPixelLanes], undo_[kPixelLanes], take_[kPixelLanes],
      converged_[kPixelLanes], retry_[kPixelLanes];
  bool stepped_[kPixelLanes];  // the lane's quadric is a step no pass has checked yet
  bool kept_[kPixelLanes];     // a step was kept: the lane's quadric is a fit, not the plane
};

}  // namespace

NeighbourhoodPattern PatternParams::for_width(int width) const {
  try {
    return NeighbourhoodPattern::scaled(radius, stride, width, reference_width);
  } catch (const std::invalid_argument& e) {
    throw InputError("pattern (radius " + std::to_string(radius) + ", stride " +
                     std::to_string(stride) + " at reference_width " +
                     std::to_string(reference_width) + ") scaled to " + std::to_string(width) +
                     " px wide: " + e.what());
  }
}

void PatternParams::validate() const {
  if (radius < 1 || radius > 64) throw InputError("radius: must be in [1, 64]");
  if (stride < 1 || stride > 64) throw InputError("stride: must be in [1, 64]");
  if (reference_width < 1) throw InputError("reference_width: must be positive (px)");
}

void QuadricFitParams::validate() const {
  if (iterations < 1 || iterations > 100) throw InputError("iterations: must be in [1, 100]");
  if (!(fair_n0 > 0.0f)) throw InputError("fair_n0: must be positive (m)");
  if (!(residual_gate > 0.0f)) throw InputError("residual_gate: must be positive (m)");
  if (!(fair_n0_per_range >= 0.0f)) throw InputError("fair_n0_per_range: must be >= 0 (m/m)");
  if (!(gate_per_range >= 0.0f)) throw InputError("gate_per_range: must be >= 0 (m/m)");
  if (!(damping >= 0.0f)) throw InputError("damping: must be >= 0");
  if (min_samples < 6) throw InputError("min_samples: must be at least 6 (six parameters)");
  if (!(angle_tolerance >= 0.0f)) throw InputError("angle_tolerance: must be >= 0 (rad)");
  if (!(offset_tolerance >= 0.0f)) throw InputError("offset_tolerance: must be >= 0 (m)");
  if (!(curvature_tolerance >= 0.0f)) throw InputError("curvature_tolerance: must be >= 0 (1/m)");
}

void QuadricParams::validate() const {
  pattern.validate();
  normals.validate();
  fit.validate();
  // Quad IT sees at most the pattern's samples; more required would leave every pixel invalid.
  const int samples = NeighbourhoodPattern::make(pattern.radius, pattern.stride).size();
  if (fit.min_samples > samples)
    throw InputError("min_samples: " + std::to_string(fit.min_samples) + " exceeds the " +
                     std::to_string(samples) + " samples of the pattern (radius " +
                     std::to_string(pattern.radius) + "): no pixel could have a quadric");
}

NeighbourhoodPattern QuadricParams::pattern_for(int width) const {
  NeighbourhoodPattern scaled = pattern.for_width(width);
  if (fit.min_samples > scaled.size())
    throw InputError("min_samples: " + std::to_string(fit.min_samples) + " exceeds the " +
                     std::to_string(scaled.size()) + " samples of the pattern scaled to " +
                     std::to_string(width) + " px wide (radius " + std::to_string(scaled.radius) +
                     ", stride " + std::to_string(scaled.stride) +
                     "): no pixel could have a quadric");
  return scaled;
}

QuadricMap CurvatureEstimator::estimate(const VertexMap& vertices) const {
  return estimate(vertices, estimate_normals(vertices, params().normals));
}

QuadricFit::QuadricFit(const QuadricParams& params) : params_(params) {
  params_.validate();
}

QuadricMap QuadricFit::estimate(const VertexMap& vertices, const NormalMap& normals) const {
  if (normals.width() != vertices.width() || normals.height() != vertices.height())
    throw std::invalid_argument("QuadricFit: normal map and vertex map differ in size");
  // The offsets that can land inside the image (the others fail the bounds check at every
  // pixel), so that the planes' margin is at most the image's size.
  std::vector<PixelOffset> inside;
  int reach = 0;
  for (const PixelOffset& o : params_.pattern_for(vertices.width()).offsets) {
    if (std::abs(o.du) >= vertices.width() || std::abs(o.dv) >= vertices.height()) continue;
    inside.push_back(o);
    reach = std::max({reach, std::abs(o.du), std::abs(o.dv)});
  }
  const VertexPlanes planes(vertices, reach);
  std::vector<std::ptrdiff_t> offsets;
  for (const PixelOffset& o : inside)
    offsets.push_back(static_cast<std::ptrdiff_t>(o.dv) * planes.stride() + o.du);
  QuadricMap map(vertices.width(), vertices.height());
  const int groups = (vertices.width() + kPixelLanes - 1) / kPixelLanes;
  ParallelGuard guard;  // e.g. a worker's buffers out of memory: rethrown, not std::terminate
#pragma omp parallel
  {
    std::optional<PixelGroupFit> fit;
    guard.run([&] { fit.emplace(vertices, normals, planes, offsets, params_.fit); });
#pragma omp for schedule(dynamic, 4)
    for (int v = 0; v < vertices.height(); ++v)
      guard.run([&] {
        for (int g = 0; g < groups && fit; ++g)
          fit->run(g * kPixelLanes, v, map);
      });
  }
  guard.rethrow();
  return map;
}

}  // namespace jpcr
