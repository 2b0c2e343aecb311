#include "jpcr/io/synthetic_trajectory.hpp"

#include <array>
#include <cmath>

#include "jpcr/io/synthetic_random.hpp"
#include "jpcr/quadric/error.hpp"
#include "jpcr/quadric/se3.hpp"

namespace jpcr {

namespace {

constexpr double kTwoPi = 2.0 * EIGEN_PI;
constexpr double kDegree = EIGEN_PI / 180.0;
constexpr double kMinWeight = 0.5;  // the sinusoids' relative amplitudes are in [kMinWeight, 1]

// Three random sinusoids for each of three coordinates, zero at t = 0:
//   x_j(t) = Σ_k A_jk (sin(2π f_jk t + φ_jk) − sin φ_jk).
// The amplitudes are scaled so that max_rate bounds the rate |dx/dt| at every t, using
//   |dx/dt|² ≤ Σ_j (Σ_k A_jk 2π f_jk)².
class SmoothRandomMotion {
 public:
  SmoothRandomMotion(const CounterRandom& random, double max_rate, double min_period,
                     double max_period) {
    double bound = 0.0;
    std::uint64_t n = 0;
    for (auto& axis : waves_) {
      double axis_bound = 0.0;
      for (Wave& w : axis) {
        const double period = min_period + (max_period - min_period) * random.uniform(n++);
        w.angular_frequency = kTwoPi / period;
        w.phase = kTwoPi * random.uniform(n++);
        w.amplitude = kMinWeight + (1.0 - kMinWeight) * random.uniform(n++);
        axis_bound += w.amplitude * w.angular_frequency;
      }
      bound += axis_bound * axis_bound;
    }
    const double scale = max_rate / std::sqrt(bound);
    for (auto& axis : waves_) {
      for (Wave& w : axis)
        w.amplitude *= scale;
    }
  }

  Eigen::Vector3d operator()(double t) const {
    Eigen::Vector3d x;
    for (int j = 0; j < 3; ++j) {
      x[j] = 0.0;
      for (const Wave& w : waves_[j])
        x[j] += w.amplitude * (std::sin(w.angular_frequency * t + w.phase) - std::sin(w.phase));
    }
    return x;
  }

 private:
  struct Wave {
    double amplitude = 0.0, angular_frequency = 0.0, phase = 0.0;
  };
  std::array<std::array<Wave, 3>, 3> waves_;
};

Eigen::Isometry3d make_pose(const Eigen::Matrix3d& rotation, const Eigen::Vector3d& position) {
  Eigen::Isometry3d pose = Eigen::Isometry3d::Identity();
  pose.linear() = rotation;
  pose.translation() = position;
  return pose;
}

}  // namespace

TrajectoryKind parse_trajectory_kind(const std::string& text) {
  if (text == "rail") return TrajectoryKind::kRail;
  if (text == "orbit") return TrajectoryKind::kOrbit;
  if (text == "walk") return TrajectoryKind::kWalk;
  throw InputError("unknown trajectory '" + text + "' (expected rail, orbit or walk)");
}

std::string to_string(TrajectoryKind kind) {
  switch (kind) {
    case TrajectoryKind::kRail:
      return "rail";
    case TrajectoryKind::kOrbit:
      return "orbit";
    case TrajectoryKind::kWalk:
      return "walk";
  }
  return "?";
}

void TrajectoryParams::validate() const {
  const auto positive = [](double v, const char* name, const char* unit) {
    if (!(std::isfinite(v) && v > 0.0))
      throw InputError(std::string(name) + ": must be positive (" + unit + ")");
  };
  positive(rate, "rate", "Hz");
  positive(rail_step, "rail_step", "m");
  positive(orbit_step, "orbit_step", "deg");
  positive(walk_max_speed, "walk_max_speed", "m/s");
  positive(walk_max_head_rate, "walk_max_head_rate", "deg/s");
  // The walk's speed bound scales its amplitudes by 1 / Σ amplitude · 2π / period: periods far
  // out of this range gave an infinite scale (NaN poses, refused only when written) or a zero
  // one (a camera standing still).
  constexpr double kMinPeriod = 1e-3, kMaxPeriod = 1e6;  // s
  const auto period = [&](double v, const char* name) {
    if (!(v >= kMinPeriod && v <= kMaxPeriod))
      throw InputError(std::string(name) + ": must be in [0.001, 1e6] s");
  };
  period(walk_min_period, "walk_min_period");
  period(walk_max_period, "walk_max_period");
  if (!std::isfinite(start_time)) throw InputError("start_time: must be finite (s)");
  if (!(walk_max_period >= walk_min_period)) {
    throw InputError("walk_max_period: must be at least walk_min_period (s)");
  }
}

Eigen::Matrix3d look_at(const Eigen::Vector3d& eye, const Eigen::Vector3d& target,
                        const Eigen::Vector3d& up) {
  const Eigen::Vector3d z = (target - eye).normalized();
  const Eigen::Vector3d x = z.cross(up).normalized();
  Eigen::Matrix3d rotation;
  rotation << x, z.cross(x), z;
  return rotation;
}

Trajectory make_trajectory(TrajectoryKind kind, const SceneView& view, int frames,
                           const TrajectoryParams& params, std::uint64_t seed) {
  try {
    params.validate();
  } catch (const InputError& e) {
    throw InputError(std::string("trajectory parameter ") + e.what());
  }
  if (frames < 1) throw InputError("a trajectory needs at least 1 frame");
  const Eigen::Vector3d up = view.up.normalized();
  // The walk's position and head rotation draw from two keys of the seed's walk stream.
  const SmoothRandomMotion walk_position(CounterRandom(seed, RandomStream::kWalk, 0),
                                         params.walk_max_speed, params.walk_min_period,
                                         params.walk_max_period);
  const SmoothRandomMotion walk_head(CounterRandom(seed, RandomStream::kWalk, 1),
                                     params.walk_max_head_rate * kDegree, params.walk_min_period,
                                     params.walk_max_period);
  Trajectory trajectory(static_cast<std::size_t>(frames));
  for (int i = 0; i < frames; ++i) {
    const double t = i / params.rate;
    StampedPose& p = trajectory[static_cast<std::size_t>(i)];
    p.timestamp = std::round((params.start_time + t) * 1e6) / 1e6;
    switch (kind) {
      case TrajectoryKind::kRail: {
        const double offset = (i - 0.5 * (frames - 1)) * params.rail_step;
        p.pose = make_pose(look_at(view.eye, view.target, up),
                           view.eye + offset * view.rail_direction.normalized());
        break;
      }
      case TrajectoryKind::kOrbit: {
        const Eigen::AngleAxisd turn(i * params.orbit_step * kDegree, up);
        const Eigen::Vector3d eye = view.target + turn * (view.eye - view.target);
        p.pose = make_pose(look_at(eye, view.target, up), eye);
        break;
      }
      case TrajectoryKind::kWalk: {
        const Eigen::Vector3d eye = view.eye + walk_position(t);
        // Head rotation about the camera's own axes, applied after looking at the target.
        p.pose = make_pose(look_at(eye, view.target, up) * so3_exp(walk_head(t)), eye);
        break;
      }
    }
  }
  return trajectory;
}

}  // namespace jpcr
