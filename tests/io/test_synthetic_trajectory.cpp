// Trajectories: the rail's exact 10 mm translation-only steps, the orbit's geometry, and the
// random walk's bounds (derived from its construction), smoothness and determinism.
#include <algorithm>
#include <cmath>
#include <cstdio>

#include <gtest/gtest.h>

#include "jpcr/io/synthetic_trajectory.hpp"
#include "jpcr/quadric/error.hpp"
#include "jpcr/quadric/se3.hpp"

namespace jpcr {
namespace {

constexpr double kDegree = EIGEN_PI / 180.0;

SceneView view() {
  SceneView v;
  v.eye = Eigen::Vector3d(0.0, -1.8, 1.4);
  v.target = Eigen::Vector3d(0.0, 0.0, 0.5);
  v.rail_direction = Eigen::Vector3d(1, 0, 0);
  return v;
}

double step_translation(const Trajectory& t, std::size_t i) {
  return (t[i].pose.translation() - t[i - 1].pose.translation()).norm();
}

double step_rotation(const Trajectory& t, std::size_t i) {
  return rotation_angle(t[i - 1].pose.linear().transpose() * t[i].pose.linear());
}

TEST(SyntheticTrajectory, LookAtPointsTheOpticalAxisAtTheTarget) {
  const Eigen::Matrix3d R = look_at({1, 2, 3}, {4, 0, 1}, Eigen::Vector3d::UnitZ());
  EXPECT_NEAR(R.determinant(), 1.0, 1e-12);
  EXPECT_TRUE((R.transpose() * R).isIdentity(1e-12));
  EXPECT_TRUE(R.col(2).isApprox(Eigen::Vector3d(3, -2, -2).normalized(), 1e-12));
  EXPECT_NEAR(R.col(0).z(), 0.0, 1e-12);  // image rows stay level
  EXPECT_LT(R.col(1).z(), 0.0);           // image y points down
}

TEST(SyntheticTrajectory, RailIsTranslationOnlyInTenMillimetreSteps) {
  const Trajectory rail = make_trajectory(TrajectoryKind::kRail, view(), 101);
  ASSERT_EQ(rail.size(), 101u);
  for (std::size_t i = 1; i < rail.size(); ++i) {
    EXPECT_NEAR(step_translation(rail, i), 0.01, 1e-12);
    const Eigen::Vector3d d = rail[i].pose.translation() - rail[i - 1].pose.translation();
    EXPECT_NEAR(d.normalized().x(), 1.0, 1e-9);
    EXPECT_EQ(rail[i].pose.linear(), rail[0].pose.linear());
  }
  // Centred on the eye: frame 50 of 101 is there.
  EXPECT_TRUE(rail[50].pose.translation().isApprox(view().eye, 1e-12));
  TrajectoryParams params;
  params.rail_step = 0.005;
  const Trajectory fine = make_trajectory(TrajectoryKind::kRail, view(), 3, params);
  EXPECT_NEAR(step_translation(fine, 1), 0.005, 1e-12);
}

TEST(SyntheticTrajectory, OrbitCirclesTheTargetLookingAtIt) {
  const SceneView v = view();
  const Trajectory orbit = make_trajectory(TrajectoryKind::kOrbit, v, 1440);
  const double radius = std::hypot(v.eye.x() - v.target.x(), v.eye.y() - v.target.y());
  const double step = 0.25 * kDegree;
  for (std::size_t i = 0; i < orbit.size(); ++i) {
    const Eigen::Vector3d eye = orbit[i].pose.translation();
    EXPECT_NEAR(std::hypot(eye.x(), eye.y()), radius, 1e-9);
    EXPECT_NEAR(eye.z(), v.eye.z(), 1e-12);
    const Eigen::Vector3d axis = orbit[i].pose.linear().col(2);
    EXPECT_NEAR(axis.dot((v.target - eye).normalized()), 1.0, 1e-12);
    if (i == 0) continue;
    EXPECT_NEAR(step_translation(orbit, i), 2.0 * radius * std::sin(step / 2.0), 1e-9);
    EXPECT_NEAR(step_rotation(orbit, i), step, 1e-9);
  }
  // 1440 steps of 0.25° come back to the start.
  const Trajectory closed = make_trajectory(TrajectoryKind::kOrbit, v, 1441);
  EXPECT_TRUE(closed.back().pose.translation().isApprox(v.eye, 1e-9));
}

TEST(SyntheticTrajectory, WalkIsSmoothBoundedHandHeldMotion) {
  const SceneView v = view();
  const TrajectoryParams p;
  const double rate = p.rate;
  double sum = 0.0, largest = 0.0, largest_rotation = 0.0;
  for (const std::uint64_t seed : {0u, 1u, 2u, 3u}) {
    const Trajectory walk = make_trajectory(TrajectoryKind::kWalk, v, 900, p, seed);
    EXPECT_TRUE(walk[0].pose.translation().isApprox(v.eye, 1e-12));
    for (std::size_t i = 1; i < walk.size(); ++i) {
      const double dt = step_translation(walk, i);
      // The construction bounds the speed by walk_max_speed.
      EXPECT_LE(dt, p.walk_max_speed / rate * (1 + 1e-9));
      sum += dt;
      largest = std::max(largest, dt);
      largest_rotation = std::max(largest_rotation, step_rotation(walk, i));
      if (i < 2) continue;
      // Smooth: the acceleration is at most 2π / walk_min_period times the speed bound.
      const Eigen::Vector3d a = walk[i].pose.translation() - 2 * walk[i - 1].pose.translation() +
                                walk[i - 2].pose.translation();
      EXPECT_LE(a.norm(), p.walk_max_speed * 2 * EIGEN_PI / p.walk_min_period / (rate * rate));
    }
  }
  // Realistic hand-held motion at 30 Hz: a few mm to ~1.5 cm and < 1.5° per frame (the
  // rotation adds the head's rate, ≤ 0.5°/frame, to looking at the target from a moving eye).
  const double mean = sum / (4 * 899);
  EXPECT_GT(mean, 0.002);
  EXPECT_LT(largest, 0.015);
  EXPECT_LT(largest_rotation, 1.5 * kDegree);
}

TEST(SyntheticTrajectory, WalkIsDeterministicPerSeed) {
  const Trajectory a = make_trajectory(TrajectoryKind::kWalk, view(), 50, {}, 9);
  const Trajectory b = make_trajectory(TrajectoryKind::kWalk, view(), 50, {}, 9);
  const Trajectory c = make_trajectory(TrajectoryKind::kWalk, view(), 50, {}, 10);
  for (std::size_t i = 0; i < a.size(); ++i)
    EXPECT_EQ(a[i].pose.matrix(), b[i].pose.matrix());
  EXPECT_GT((a[49].pose.translation() - c[49].pose.translation()).norm(), 1e-4);
}

TEST(SyntheticTrajectory, TimestampsAreWholeMicrosecondsThatReadBack) {
  TrajectoryParams p;
  p.start_time = 1305031102.0;
  const Trajectory t = make_trajectory(TrajectoryKind::kRail, view(), 300, p);
  for (std::size_t i = 0; i < t.size(); ++i) {
    // Half a microsecond of rounding, plus two ulps of a double near 1.3e9 s (2.4e-7 each).
    EXPECT_NEAR(t[i].timestamp, p.start_time + i / 30.0, 0.5e-6 + 4.8e-7);
    char text[64];
    std::snprintf(text, sizeof(text), "%.6f", t[i].timestamp);
    EXPECT_EQ(std::stod(text), t[i].timestamp) << text;
    if (i > 0) {
      EXPECT_GT(t[i].timestamp, t[i - 1].timestamp);
    }
  }
}

TEST(SyntheticTrajectory, BadInput) {
  EXPECT_EQ(parse_trajectory_kind("orbit"), TrajectoryKind::kOrbit);
  EXPECT_EQ(to_string(TrajectoryKind::kWalk), "walk");
  EXPECT_THROW(parse_trajectory_kind("spiral"), InputError);
  EXPECT_THROW(make_trajectory(TrajectoryKind::kRail, view(), 0), InputError);
  TrajectoryParams p;
  p.rate = 0.0;
  EXPECT_THROW(make_trajectory(TrajectoryKind::kRail, view(), 5, p), InputError);
  p = TrajectoryParams{};
  p.walk_max_period = 1.0;  // below walk_min_period
  try {
    make_trajectory(TrajectoryKind::kWalk, view(), 5, p);
    ADD_FAILURE() << "no error";
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find("walk_max_period"), std::string::npos);
  }
  // Periods far out of range made the walk's scale infinite (NaN poses) or zero (no motion).
  for (const double period : {1e300, 1e-300, 2e6}) {
    p = TrajectoryParams{};
    p.walk_min_period = period;
    p.walk_max_period = std::max(period, p.walk_max_period);
    try {
      make_trajectory(TrajectoryKind::kWalk, view(), 5, p);
      ADD_FAILURE() << "no error for a period of " << period << " s";
    } catch (const InputError& e) {
      EXPECT_NE(std::string(e.what()).find("walk_min_period: must be in [0.001, 1e6] s"),
                std::string::npos)
          << e.what();
    }
  }
  p = TrajectoryParams{};
  p.walk_max_period = 1e300;
  EXPECT_THROW(make_trajectory(TrajectoryKind::kWalk, view(), 5, p), InputError);
}

}  // namespace
}  // namespace jpcr
