// Exact geometry of the synthetic surfaces: intersections, normals and the signed principal
// curvatures of method.md §1, checked against closed forms and, for the torus, against the
// curvature of its implicit equation (an independent derivation).
#include <cmath>
#include <random>

#include <gtest/gtest.h>
#include <Eigen/Eigenvalues>
#include <Eigen/Geometry>

#include "jpcr/io/synthetic_scene.hpp"

namespace jpcr {
namespace {

// Curvatures are compared to 1e-6 1/m (the bar); double arithmetic gives ~1e-12.
constexpr double kCurvatureTolerance = 1e-6;

Ray ray_through(const Eigen::Vector3d& origin, const Eigen::Vector3d& towards) {
  return Ray{origin, (towards - origin).normalized()};
}

SyntheticScene scene_of(std::vector<Surface> surfaces) {
  SyntheticScene scene;
  scene.surfaces = std::move(surfaces);
  return scene;
}

TEST(SyntheticSurfaces, BallFromOutsideIsNegativeAndFromInsidePositive) {
  const Sphere ball{Eigen::Vector3d(0.3, -0.2, 3.0), 0.7};
  const SyntheticScene scene = scene_of({ball});
  std::mt19937 rng(1);
  std::uniform_real_distribution<double> offset(-0.6, 0.6);
  int hits = 0;
  for (int i = 0; i < 200; ++i) {
    const double dx = offset(rng), dy = offset(rng);
    const Eigen::Vector3d aim = ball.center + Eigen::Vector3d(dx, dy, 0.0);
    const auto hit = cast_ray(scene, ray_through(Eigen::Vector3d::Zero(), aim));
    if (!hit) continue;
    ++hits;
    EXPECT_NEAR(hit->curvature.x(), -1.0 / 0.7, kCurvatureTolerance);
    EXPECT_NEAR(hit->curvature.y(), -1.0 / 0.7, kCurvatureTolerance);
    EXPECT_NEAR((hit->point - ball.center).norm(), 0.7, 1e-12);
    EXPECT_LT(hit->normal.dot(hit->point), 0.0);  // toward the camera
  }
  EXPECT_GT(hits, 100);
  // From the centre every ray hits the inside: a concave bowl, +1/R.
  const auto inside = cast_ray(scene, Ray{ball.center, Eigen::Vector3d(1, 2, -3).normalized()});
  ASSERT_TRUE(inside);
  EXPECT_NEAR(inside->range, 0.7, 1e-12);
  EXPECT_NEAR(inside->curvature.x(), 1.0 / 0.7, kCurvatureTolerance);
  EXPECT_NEAR(inside->curvature.y(), 1.0 / 0.7, kCurvatureTolerance);
}

TEST(SyntheticSurfaces, CylinderSideCapsAndInside) {
  const Cylinder tube{Eigen::Vector3d(0, 0, 4), Eigen::Vector3d(1, 0, 0), 0.5, 2.0, true};
  const SyntheticScene scene = scene_of({tube});
  // Side from outside: straight along the axis, −1/R across it.
  const auto side = cast_ray(scene, ray_through(Eigen::Vector3d::Zero(), {0.3, 0.1, 4.0}));
  ASSERT_TRUE(side);
  EXPECT_EQ(side->patch, 0);
  EXPECT_NEAR(side->curvature.x(), 0.0, kCurvatureTolerance);
  EXPECT_NEAR(side->curvature.y(), -2.0, kCurvatureTolerance);
  const Eigen::Vector3d radial = side->point - tube.center - side->point.x() * tube.axis;
  EXPECT_NEAR(radial.norm(), 0.5, 1e-12);
  // A cap seen along the axis is flat, and its normal is the axis.
  const auto cap = cast_ray(scene, ray_through({-3, 0.1, 4.1}, {0, 0.1, 4.1}));
  ASSERT_TRUE(cap);
  EXPECT_EQ(cap->patch, 1);
  EXPECT_NEAR(cap->range, 2.0, 1e-12);
  EXPECT_EQ(cap->curvature, Eigen::Vector2d::Zero());
  EXPECT_NEAR(cap->normal.x(), -1.0, 1e-12);
  // An open tube shows its inside through the end: (+1/R, 0).
  Cylinder open = tube;
  open.capped = false;
  const auto inside = cast_ray(scene_of({open}), ray_through({-3, 0.05, 4.0}, {0, 0.3, 4.4}));
  ASSERT_TRUE(inside);
  EXPECT_NEAR(inside->curvature.x(), 2.0, kCurvatureTolerance);
  EXPECT_NEAR(inside->curvature.y(), 0.0, kCurvatureTolerance);
  const Eigen::Vector3d inner = inside->point - tube.center - inside->point.x() * tube.axis;
  EXPECT_NEAR(inside->normal.dot(inner.normalized()), -1.0, 1e-9) << "the inside faces the axis";
  // Infinite cylinders have no ends.
  Cylinder infinite = tube;
  infinite.length = 0.0;
  EXPECT_FALSE(cast_ray(scene_of({infinite}), Ray{{-100, 0, 4}, {-1, 0, 0}}));
  EXPECT_TRUE(cast_ray(scene_of({infinite}), ray_through({0, 0, 0}, {50.0, 0.2, 4.0})));
}

TEST(SyntheticSurfaces, PlaneAndBoxFacesAreFlatWithTheRightNormals) {
  const Plane wall{Eigen::Vector3d(0, 0, 2), Eigen::Vector3d(0, 0, -1)};
  const auto hit = cast_ray(scene_of({wall}), ray_through({0, 0, 0}, {1, 1, 2}));
  ASSERT_TRUE(hit);
  EXPECT_NEAR(hit->range, std::sqrt(6.0), 1e-12);
  EXPECT_EQ(hit->curvature, Eigen::Vector2d::Zero());
  // A plane seen from its back is turned toward the camera too.
  const auto back =
      cast_ray(scene_of({Plane{wall.point, -wall.normal}}), Ray{{0, 0, 0}, {0, 0, 1}});
  ASSERT_TRUE(back);
  EXPECT_NEAR(back->normal.z(), -1.0, 1e-12);

  Box box{Eigen::Vector3d(0, 0, 3), Eigen::Vector3d(1, 2, 0.5), Eigen::Matrix3d::Identity()};
  const auto front = cast_ray(scene_of({box}), Ray{{0.1, 0.2, 0}, {0, 0, 1}});
  ASSERT_TRUE(front);
  EXPECT_NEAR(front->range, 2.75, 1e-12);
  EXPECT_NEAR(front->normal.z(), -1.0, 1e-12);
  EXPECT_EQ(front->curvature, Eigen::Vector2d::Zero());
  // Inside the box (a room) the far wall is seen, with its normal pointing back inside.
  const auto wall_inside = cast_ray(scene_of({box}), Ray{box.center, {1, 0, 0}});
  ASSERT_TRUE(wall_inside);
  EXPECT_NEAR(wall_inside->range, 0.5, 1e-12);
  EXPECT_NEAR(wall_inside->normal.x(), -1.0, 1e-12);
  EXPECT_NE(wall_inside->patch, front->patch);
  // A rotated box: 90° about z swaps its x and y extents.
  box.rotation = Eigen::AngleAxisd(EIGEN_PI / 2, Eigen::Vector3d::UnitZ()).toRotationMatrix();
  const auto turned = cast_ray(scene_of({box}), Ray{box.center, {1, 0, 0}});
  ASSERT_TRUE(turned);
  EXPECT_NEAR(turned->range, 1.0, 1e-12);
}

TEST(SyntheticSurfaces, NearestSurfaceWins) {
  const SyntheticScene scene =
      scene_of({Plane{{0, 0, 5}, {0, 0, -1}}, Sphere{{0, 0, 3}, 0.5}, Sphere{{0, 0, 4}, 0.5}});
  const auto hit = cast_ray(scene, Ray{{0, 0, 0}, {0, 0, 1}});
  ASSERT_TRUE(hit);
  EXPECT_EQ(hit->surface, 1);
  EXPECT_NEAR(hit->range, 2.5, 1e-12);
  EXPECT_FALSE(cast_ray(scene, Ray{{0, 0, 0}, {0, 0, -1}}));
}

// ---- Torus
// ---------------------------------------------------------------------------------------

// F(p) = (|p|² + R² − r²)² − 4R²(|p|² − (p·a)²) around the centre, its gradient and Hessian.
struct TorusImplicit {
  Torus torus;
  double value(const Eigen::Vector3d& x) const {
    const Eigen::Vector3d p = x - torus.center;
    const double R = torus.major_radius, r = torus.minor_radius;
    const double s = p.squaredNorm() + R * R - r * r;
    return s * s - 4 * R * R * (p.squaredNorm() - std::pow(p.dot(torus.axis), 2));
  }
  Eigen::Vector3d gradient(const Eigen::Vector3d& x) const {
    const Eigen::Vector3d p = x - torus.center;
    const double R = torus.major_radius, r = torus.minor_radius;
    const double s = p.squaredNorm() + R * R - r * r;
    return 4 * s * p - 8 * R * R * (p - p.dot(torus.axis) * torus.axis);
  }
  Eigen::Matrix3d hessian(const Eigen::Vector3d& x) const {
    const Eigen::Vector3d p = x - torus.center;
    const double R = torus.major_radius, r = torus.minor_radius;
    const double s = p.squaredNorm() + R * R - r * r;
    const Eigen::Matrix3d I = Eigen::Matrix3d::Identity();
    return 8 * p * p.transpose() + 4 * s * I -
           8 * R * R * (I - torus.axis * torus.axis.transpose());
  }
  // Exact distance to the tube, for sphere tracing: |(ρ − R, h)| − r.
  double distance(const Eigen::Vector3d& x) const {
    const Eigen::Vector3d p = x - torus.center;
    const double h = p.dot(torus.axis);
    const double rho = (p - h * torus.axis).norm();
    return std::hypot(rho - torus.major_radius, h) - torus.minor_radius;
  }
};

// Principal curvatures of the level set F = 0 about the outward normal ∇F/|∇F|, in method.md
// §1's sign: κ = −eig(P H P) / |∇F| on the tangent plane (a ball gives −1/R).
Eigen::Vector2d implicit_curvature(const TorusImplicit& f, const Eigen::Vector3d& x) {
  const Eigen::Vector3d g = f.gradient(x);
  const Eigen::Vector3d n = g.normalized();
  const Eigen::Vector3d t1 = n.unitOrthogonal(), t2 = n.cross(t1);
  Eigen::Matrix<double, 3, 2> T;
  T << t1, t2;
  const Eigen::Matrix2d shape = -T.transpose() * f.hessian(x) * T / g.norm();
  const Eigen::Vector2d k = Eigen::SelfAdjointEigenSolver<Eigen::Matrix2d>(shape).eigenvalues();
  return {k.maxCoeff(), k.minCoeff()};
}

// The first hit by sphere tracing on the exact distance: slow, but cannot skip a surface.
std::optional<double> sphere_trace(const TorusImplicit& f, const Ray& ray) {
  double t = 0.0;
  for (int step = 0; step < 200000 && t < 100.0; ++step) {
    const double d = f.distance(ray.origin + t * ray.direction);
    if (d < 1e-11) return t;
    t += d;
  }
  return std::nullopt;
}

// Uniform in [−1, 1]³, drawn in a fixed order (the order in which function arguments are
// evaluated is unspecified, and differs between compilers).
Eigen::Vector3d random_vector(std::mt19937& rng) {
  std::uniform_real_distribution<double> unit(-1.0, 1.0);
  Eigen::Vector3d v;
  for (int i = 0; i < 3; ++i)
    v[i] = unit(rng);
  return v;
}

TEST(SyntheticSurfaces, TorusMatchesItsImplicitEquationAndClosedForm) {
  std::mt19937 rng(7);
  int hits = 0, saddles = 0, grazing_checked = 0;
  for (int trial = 0; trial < 20; ++trial) {
    Torus torus;
    const Eigen::Vector3d shape = random_vector(rng);
    torus.center = random_vector(rng) + Eigen::Vector3d(0, 0, 3);
    torus.axis = random_vector(rng).normalized();
    torus.major_radius = 0.5 + 0.2 * shape.x();
    torus.minor_radius = 0.1 + 0.05 * shape.y();
    const TorusImplicit f{torus};
    const SyntheticScene scene = scene_of({torus});
    for (int i = 0; i < 200; ++i) {
      const Eigen::Vector3d aim =
          torus.center + 0.8 * random_vector(rng).cwiseProduct(Eigen::Vector3d(1, 1, 0));
      const Ray ray = ray_through(Eigen::Vector3d::Zero(), aim);
      const auto hit = cast_ray(scene, ray);
      const std::optional<double> traced = sphere_trace(f, ray);
      ASSERT_EQ(hit.has_value(), traced.has_value()) << "trial " << trial << " ray " << i;
      if (!hit) continue;
      ++hits;
      EXPECT_NEAR(hit->range, *traced, 1e-8);  // sphere tracing stops within 1e-11 of the surface
      EXPECT_NEAR(f.distance(hit->point), 0.0, 1e-10);
      // Closed form (what the renderer reports) against the implicit surface's curvature.
      const Eigen::Vector2d expected = implicit_curvature(f, hit->point);
      const Eigen::Vector3d outward = f.gradient(hit->point).normalized();
      const double facing = outward.dot(ray.direction) < 0.0 ? 1.0 : -1.0;
      const Eigen::Vector2d oriented =
          facing > 0 ? expected : Eigen::Vector2d(-expected.y(), -expected.x());
      EXPECT_NEAR(hit->curvature.x(), oriented.x(), kCurvatureTolerance);
      EXPECT_NEAR(hit->curvature.y(), oriented.y(), kCurvatureTolerance);
      EXPECT_NEAR(hit->normal.dot(facing * outward), 1.0, 1e-9);
      EXPECT_NEAR(torus_curvature(torus, hit->point).y(), -1.0 / torus.minor_radius, 1e-9);
      saddles += hit->curvature.x() > 0.0 && hit->curvature.y() < 0.0;
      grazing_checked += std::abs(hit->normal.dot(ray.direction)) < 0.2;
    }
  }
  // This seed gives 931 hits, 398 on saddles and 31 grazing: the checks are not vacuous.
  EXPECT_GT(hits, 700);
  EXPECT_GT(saddles, 200) << "the inner half of a torus is a saddle (κ1 > 0 > κ2)";
  EXPECT_GT(grazing_checked, 20) << "grazing hits (near-double roots) are covered";
}

TEST(SyntheticSurfaces, TorusClosedFormAtKnownPoints) {
  const Torus torus{Eigen::Vector3d::Zero(), Eigen::Vector3d::UnitZ(), 1.0, 0.25};
  // Outer equator: convex both ways, like a ball: (−1/(R + r), −1/r).
  Eigen::Vector2d k = torus_curvature(torus, {1.25, 0, 0});
  EXPECT_NEAR(k.x(), -1.0 / 1.25, 1e-12);
  EXPECT_NEAR(k.y(), -4.0, 1e-12);
  // Inner equator: a saddle, (+1/(R − r), −1/r).
  k = torus_curvature(torus, {0, -0.75, 0});
  EXPECT_NEAR(k.x(), 1.0 / 0.75, 1e-12);
  EXPECT_NEAR(k.y(), -4.0, 1e-12);
  // Top circle: flat along the parallel, (0, −1/r).
  k = torus_curvature(torus, {0, 1.0, 0.25});
  EXPECT_NEAR(k.x(), 0.0, 1e-12);
  // Seen straight down the axis from above, the ray through ρ = R hits the top circle.
  const auto hit = cast_ray(scene_of({torus}), Ray{{1.0, 0, 3}, {0, 0, -1}});
  ASSERT_TRUE(hit);
  EXPECT_NEAR(hit->range, 2.75, 1e-12);
  EXPECT_NEAR(hit->curvature.x(), 0.0, 1e-9);
  EXPECT_NEAR(hit->curvature.y(), -4.0, 1e-9);
  // Through the hole along the axis: nothing.
  EXPECT_FALSE(cast_ray(scene_of({torus}), Ray{{0, 0, 3}, {0, 0, -1}}));
}

// Inside the solid a closed surface bounds; planes, open tubes and infinite cylinders bound none.
TEST(SyntheticSurfaces, EnclosesIsTheInsideOfClosedSurfaces) {
  const Eigen::Vector3d o = Eigen::Vector3d::Zero(), x = Eigen::Vector3d::UnitX(),
                        z = Eigen::Vector3d::UnitZ();
  EXPECT_TRUE(encloses(Sphere{o, 1.0}, 0.99 * x));
  EXPECT_FALSE(encloses(Sphere{o, 1.0}, 1.01 * x));
  const Cylinder can{o, z, 0.5, 2.0, true};
  EXPECT_TRUE(encloses(can, 0.49 * x + 0.99 * z));
  EXPECT_FALSE(encloses(can, 0.51 * x));
  EXPECT_FALSE(encloses(can, 1.01 * z));
  EXPECT_FALSE(encloses(Cylinder{o, z, 0.5, 2.0, false}, o));  // an open tube
  EXPECT_FALSE(encloses(Cylinder{o, z, 0.5, 0.0, true}, o));   // infinite
  const Torus tyre{o, z, 1.0, 0.25};
  EXPECT_TRUE(encloses(tyre, 1.2 * x + 0.1 * z));
  EXPECT_FALSE(encloses(tyre, o));  // the hole
  EXPECT_FALSE(encloses(tyre, 1.0 * x + 0.26 * z));
  Box crate{o, Eigen::Vector3d(2.0, 1.0, 1.0), Eigen::Matrix3d::Identity()};
  EXPECT_TRUE(encloses(crate, 0.9 * x));
  crate.rotation = Eigen::AngleAxisd(EIGEN_PI / 2, z).toRotationMatrix();  // long side along y
  EXPECT_FALSE(encloses(crate, 0.9 * x));
  EXPECT_TRUE(encloses(crate, 0.9 * Eigen::Vector3d::UnitY()));
  EXPECT_FALSE(encloses(Plane{o, z}, -z));
}

TEST(SyntheticSurfaces, BoundingSpheresEncloseTheSurfaces) {
  const Torus torus{Eigen::Vector3d(1, 2, 3), Eigen::Vector3d::UnitY(), 0.5, 0.2};
  EXPECT_DOUBLE_EQ(bounding_sphere(torus).radius, 0.7);
  const Cylinder capped{Eigen::Vector3d::Zero(), Eigen::Vector3d::UnitZ(), 0.3, 0.8, true};
  EXPECT_DOUBLE_EQ(bounding_sphere(capped).radius, 0.5);
  Cylinder infinite = capped;
  infinite.length = 0.0;
  EXPECT_TRUE(std::isinf(bounding_sphere(infinite).radius));
  EXPECT_TRUE(std::isinf(bounding_sphere(Surface(Plane{})).radius));
  const Box box{Eigen::Vector3d::Zero(), Eigen::Vector3d(2, 3, 6), Eigen::Matrix3d::Identity()};
  EXPECT_DOUBLE_EQ(bounding_sphere(box).radius, 3.5);
}

}  // namespace
}  // namespace jpcr
