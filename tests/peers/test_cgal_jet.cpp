// The curvature peer (tools/peers/cgal_jet_curvature.hpp) in jpcr's conventions: on a ray-cast
// sphere of radius R seen from outside, κ₁ = κ₂ = −1/R on the pixels that face the camera (the
// degree-2 jet drops the same ρ⁴/(8R³) term as jpcr's fits: a bias of about 1 % there), with the
// directions orthogonal to the normal; on a plane κ = 0; pixels without depth are invalid.
#include <gtest/gtest.h>

#include <cmath>

#include "jpcr/quadric/vertex_map.hpp"
#include "peers/cgal_jet_curvature.hpp"

namespace jpcr {
namespace {

// The vertex map of a pinhole camera at the origin looking down +z at a sphere (centre c,
// radius R), NaN where the ray misses.
VertexMap sphere_view(int width, int height, double f, const Eigen::Vector3d& c, double R) {
  VertexMap map(width, height);
  for (int v = 0; v < height; ++v)
    for (int u = 0; u < width; ++u) {
      const Eigen::Vector3d ray =
          Eigen::Vector3d((u - 0.5 * (width - 1)) / f, (v - 0.5 * (height - 1)) / f, 1.0)
              .normalized();
      const double b = ray.dot(c), disc = b * b - (c.squaredNorm() - R * R);
      map(u, v) = disc < 0 ? Eigen::Vector3f(Eigen::Vector3f::Constant(NAN))
                           : Eigen::Vector3f(((b - std::sqrt(disc)) * ray).cast<float>());
    }
  return map;
}

TEST(CgalJetCurvature, SphereGivesMinusOneOverRAndPlaneZero) {
  const double R = 0.3, f = 262.5;
  const Eigen::Vector3d c(0, 0, 1.2);
  const VertexMap sphere = sphere_view(320, 240, f, c, R);
  const peers::CgalJetCurvature jet;
  const QuadricMap map = jet.estimate(sphere);
  int checked = 0;
  for (int v = 0; v < 240; ++v)
    for (int u = 0; u < 320; ++u) {
      const Eigen::Vector3f X = sphere(u, v);
      if (!std::isfinite(X.z())) {
        EXPECT_FALSE(map.valid(u, v));
        continue;
      }
      const Eigen::Vector3d n = (X.cast<double>() - c).normalized();
      const double facing = -n.dot(X.cast<double>().normalized());
      if (facing < std::cos(30.0 * M_PI / 180.0)) continue;  // the pattern stays on the ball
      ASSERT_TRUE(map.valid(u, v)) << u << "," << v;
      const Eigen::Vector2f k = map.curvature(u, v);
      EXPECT_NEAR(k.x(), -1.0 / R, 0.03 / R) << u << "," << v;
      EXPECT_NEAR(k.y(), -1.0 / R, 0.03 / R) << u << "," << v;
      EXPECT_NEAR(map.direction(u, v).cast<double>().dot(n), 0.0, 0.05);
      ++checked;
    }
  EXPECT_GT(checked, 1000);

  VertexMap plane(320, 240);  // z = 2 − 0.3 x, seen at an angle
  for (int v = 0; v < 240; ++v)
    for (int u = 0; u < 320; ++u) {
      const double x = (u - 159.5) / f, y = (v - 119.5) / f, z = 2.0 / (1.0 + 0.3 * x);
      plane(u, v) = Eigen::Vector3f(x * z, y * z, z);
    }
  const QuadricMap flat = jet.estimate(plane);
  for (int v = 30; v < 210; v += 7)
    for (int u = 30; u < 290; u += 7) {
      ASSERT_TRUE(flat.valid(u, v));
      EXPECT_NEAR(flat.curvature(u, v).x(), 0.0, 1e-3);
      EXPECT_NEAR(flat.curvature(u, v).y(), 0.0, 1e-3);
    }
}

}  // namespace
}  // namespace jpcr
