#include "jpcr/io/synthetic_surfaces.hpp"

#include <algorithm>
#include <cmath>
#include <limits>

namespace jpcr {

namespace {

// Below this |cos| a ray counts as parallel to a plane or an axis (no intersection).
constexpr double kParallel = 1e-12;

// Keeps the nearer of two candidate hits.
void keep_nearer(std::optional<SurfacePoint>& best, const SurfacePoint& candidate) {
  if (!best || candidate.t < best->t) best = candidate;
}

// Roots of a·t² + 2·b·t + c = 0 (a > 0), ascending; false when there are none.
bool solve_quadratic(double a, double b, double c, double& t0, double& t1) {
  const double discriminant = b * b - a * c;
  if (discriminant < 0.0) return false;
  // The numerically stable pair (Numerical Recipes §5.6): no cancellation in either root.
  const double q = -(b + std::copysign(std::sqrt(discriminant), b));
  if (q == 0.0) {
    t0 = t1 = 0.0;
    return true;
  }
  t0 = q / a;
  t1 = c / q;
  if (t0 > t1) std::swap(t0, t1);
  return true;
}

// ---- Real roots of a polynomial of degree ≤ 4 (for the torus) -----------------------------------
// A polynomial is monotone between consecutive roots of its derivative, so the roots of p in
// [lo, hi] are isolated by the roots of p' (found the same way, recursively) and each one is then
// bracketed by a sign change and polished by safeguarded Newton. Unlike closed-form quartic
// formulas this keeps full double accuracy, also for the near-double roots of grazing rays.

double evaluate(const double* c, int n, double t) {
  double p = c[n];
  for (int k = n - 1; k >= 0; --k)
    p = p * t + c[k];
  return p;
}

double evaluate_derivative(const double* c, int n, double t) {
  double p = n * c[n];
  for (int k = n - 1; k >= 1; --k)
    p = p * t + k * c[k];
  return p;
}

// The root in [a, b] where p changes sign from pa = p(a) to pb = p(b); p is monotone there.
// Newton from the secant point, bisecting whenever a step leaves the bracket; stops when the step
// falls below `tolerance` (relative to 1 + |t|).
double polish_root(const double* c, int n, double a, double b, double pa, double pb,
                   double tolerance) {
  const bool increasing = pa < 0.0;
  double t = a + (b - a) * pa / (pa - pb);
  if (!(t > a && t < b)) t = 0.5 * (a + b);
  for (int iteration = 0; iteration < 100; ++iteration) {
    const double p = evaluate(c, n, t);
    if (p == 0.0) return t;
    if ((p < 0.0) == increasing)
      a = t;
    else
      b = t;
    const double slope = evaluate_derivative(c, n, t);
    double next = slope != 0.0 ? t - p / slope : 0.5 * (a + b);
    if (!(next > a && next < b)) next = 0.5 * (a + b);  // Newton left the bracket: bisect
    const double scale = tolerance * (1.0 + std::abs(t));
    if (std::abs(next - t) <= scale || b - a <= scale) return next;
    t = next;
  }
  return t;
}

// Ascending real roots of Σ c[k] t^k (degree n, 1 ≤ n ≤ 4) in [lo, hi], at most max_roots of
// them (the smallest); returns their count. Critical points only need to separate the roots, so
// they are polished to a looser tolerance than the roots: an error δ there changes p by O(δ²).
int real_roots(const double* c, int n, double lo, double hi, double* roots, int max_roots = 4,
               double tolerance = 1e-15) {
  if (n == 1) {
    if (c[1] == 0.0) return 0;
    const double t = -c[0] / c[1];
    if (t < lo || t > hi) return 0;
    roots[0] = t;
    return 1;
  }
  if (n == 2 && c[2] != 0.0) {
    double t0, t1;
    if (!solve_quadratic(c[2], 0.5 * c[1], c[0], t0, t1)) return 0;
    int count = 0;
    for (const double t : {t0, t1}) {
      if (t >= lo && t <= hi) roots[count++] = t;
    }
    return count;
  }
  double derivative[4];
  for (int k = 1; k <= n; ++k)
    derivative[k - 1] = k * c[k];
  double critical[4];
  const int m = real_roots(derivative, n - 1, lo, hi, critical, 4, 1e-10);
  int count = 0;
  double a = lo, pa = evaluate(c, n, lo);
  for (int i = 0; i <= m && count < max_roots; ++i) {
    const double b = i < m ? critical[i] : hi;
    const double pb = evaluate(c, n, b);
    if (pa == 0.0) {
      if (count == 0 || roots[count - 1] != a) roots[count++] = a;
    } else if (pb != 0.0 && (pa < 0.0) != (pb < 0.0)) {
      roots[count++] = polish_root(c, n, a, b, pa, pb, tolerance);
    }
    a = b;
    pa = pb;
  }
  if (pa == 0.0 && count < max_roots && (count == 0 || roots[count - 1] != a)) roots[count++] = a;
  return count;
}

}  // namespace

std::optional<SurfacePoint> intersect(const Plane& plane, const Ray& ray, double t_min) {
  const double cosine = ray.direction.dot(plane.normal);
  if (std::abs(cosine) < kParallel) return std::nullopt;
  const double t = (plane.point - ray.origin).dot(plane.normal) / cosine;
  if (!(t > t_min)) return std::nullopt;
  return SurfacePoint{t, plane.normal, Eigen::Vector2d::Zero(), 0};
}

std::optional<SurfacePoint> intersect(const Sphere& sphere, const Ray& ray, double t_min) {
  const Eigen::Vector3d oc = ray.origin - sphere.center;
  double t0, t1;
  if (!solve_quadratic(1.0, oc.dot(ray.direction), oc.squaredNorm() - sphere.radius * sphere.radius,
                       t0, t1)) {
    return std::nullopt;
  }
  const double t = t0 > t_min ? t0 : t1;  // from inside, the far root
  if (!(t > t_min)) return std::nullopt;
  const Eigen::Vector3d normal = (oc + t * ray.direction) / sphere.radius;
  const double k = -1.0 / sphere.radius;  // a ball bulges toward its outward normal
  return SurfacePoint{t, normal.normalized(), Eigen::Vector2d(k, k), 0};
}

std::optional<SurfacePoint> intersect(const Cylinder& cylinder, const Ray& ray, double t_min) {
  const Eigen::Vector3d& axis = cylinder.axis;
  const Eigen::Vector3d oc = ray.origin - cylinder.center;
  const double o_along = oc.dot(axis), d_along = ray.direction.dot(axis);
  const Eigen::Vector3d o_across = oc - o_along * axis;
  const Eigen::Vector3d d_across = ray.direction - d_along * axis;
  const bool infinite = cylinder.length <= 0.0;
  const double half = 0.5 * cylinder.length;
  std::optional<SurfacePoint> best;

  // Side: |o_across + t d_across| = R. Curvatures (0, −1/R): straight along the axis, a circle
  // of radius R across it.
  const double a = d_across.squaredNorm();
  double t0, t1;
  if (a > kParallel * kParallel &&
      solve_quadratic(a, o_across.dot(d_across),
                      o_across.squaredNorm() - cylinder.radius * cylinder.radius, t0, t1)) {
    for (const double t : {t0, t1}) {
      if (!(t > t_min) || (!infinite && std::abs(o_along + t * d_along) > half)) continue;
      const Eigen::Vector3d normal = (o_across + t * d_across).normalized();
      keep_nearer(best, {t, normal, Eigen::Vector2d(0.0, -1.0 / cylinder.radius), 0});
      break;
    }
  }
  // Caps: flat discs at ±length/2.
  if (!infinite && cylinder.capped && std::abs(d_along) > kParallel) {
    for (const int side : {-1, 1}) {
      const double t = (side * half - o_along) / d_along;
      if (!(t > t_min)) continue;
      if ((o_across + t * d_across).squaredNorm() > cylinder.radius * cylinder.radius) continue;
      keep_nearer(best, {t, side * axis, Eigen::Vector2d::Zero(), side < 0 ? 1 : 2});
    }
  }
  return best;
}

std::optional<SurfacePoint> intersect(const Box& box, const Ray& ray, double t_min) {
  // Slab method in box coordinates: the ray is inside the box for t in [t_near, t_far].
  const Eigen::Vector3d o = box.rotation.transpose() * (ray.origin - box.center);
  const Eigen::Vector3d d = box.rotation.transpose() * ray.direction;
  const Eigen::Vector3d half = 0.5 * box.size;
  double t_near = -std::numeric_limits<double>::infinity();
  double t_far = std::numeric_limits<double>::infinity();
  int near_axis = -1, far_axis = -1;
  for (int i = 0; i < 3; ++i) {
    if (std::abs(d[i]) < kParallel) {
      if (std::abs(o[i]) > half[i]) return std::nullopt;
      continue;
    }
    const double ta = (-half[i] - o[i]) / d[i], tb = (half[i] - o[i]) / d[i];
    if (std::min(ta, tb) > t_near) {
      t_near = std::min(ta, tb);
      near_axis = i;
    }
    if (std::max(ta, tb) < t_far) {
      t_far = std::max(ta, tb);
      far_axis = i;
    }
  }
  if (t_near > t_far) return std::nullopt;
  // Entering through a face whose outward normal opposes the ray, or (from inside, as in a
  // room) leaving through one whose outward normal goes with it.
  const bool entering = t_near > t_min;
  const double t = entering ? t_near : t_far;
  const int axis = entering ? near_axis : far_axis;
  if (!(t > t_min) || axis < 0) return std::nullopt;
  const double sign = (d[axis] > 0.0) == entering ? -1.0 : 1.0;
  const Eigen::Vector3d normal = sign * box.rotation.col(axis);
  return SurfacePoint{t, normal, Eigen::Vector2d::Zero(), 2 * axis + (sign > 0.0 ? 1 : 0)};
}

std::optional<SurfacePoint> intersect(const Torus& torus, const Ray& ray, double t_min) {
  const double R = torus.major_radius, r = torus.minor_radius;
  // Only the part of the ray inside the bounding sphere of radius R + r can hit.
  const Eigen::Vector3d oc = ray.origin - torus.center;
  double enter, leave;
  if (!solve_quadratic(1.0, oc.dot(ray.direction), oc.squaredNorm() - (R + r) * (R + r), enter,
                       leave)) {
    return std::nullopt;
  }
  // ... and, within it, inside the slab |(p − c)·a| ≤ r that holds the tube.
  const double oc_axis = oc.dot(torus.axis), dc_axis = ray.direction.dot(torus.axis);
  if (std::abs(dc_axis) > kParallel) {
    const double ta = (-r - oc_axis) / dc_axis, tb = (r - oc_axis) / dc_axis;
    enter = std::max(enter, std::min(ta, tb));
    leave = std::min(leave, std::max(ta, tb));
  } else if (std::abs(oc_axis) > r) {
    return std::nullopt;
  }
  const double start = std::max(enter, t_min);
  if (!(leave > start)) return std::nullopt;

  // Implicit torus F(p) = (|p|² + R² − r²)² − 4R²(|p|² − (p·a)²), F < 0 inside the tube. Along
  // p = o + s d with o the point at t = start (|o| ≤ R + r keeps the coefficients well scaled),
  // F is the quartic s⁴ + 4α s³ + (4α² + 2β − 4R²e) s² + (4αβ − 8R²f) s + β² − 4R²g.
  const Eigen::Vector3d o = oc + start * ray.direction;
  const Eigen::Vector3d& d = ray.direction;
  const double o_axis = o.dot(torus.axis), d_axis = d.dot(torus.axis);
  const double alpha = o.dot(d), beta = o.squaredNorm() + R * R - r * r;
  const double e = 1.0 - d_axis * d_axis;
  const double f = alpha - o_axis * d_axis;
  const double g = o.squaredNorm() - o_axis * o_axis;
  const double c[5] = {beta * beta - 4.0 * R * R * g, 4.0 * alpha * beta - 8.0 * R * R * f,
                       4.0 * alpha * alpha + 2.0 * beta - 4.0 * R * R * e, 4.0 * alpha, 1.0};
  // The nearest root beyond t_min (a root at t_min itself is a ray leaving the surface).
  double roots[4], lo = 0.0;
  while (real_roots(c, 4, lo, leave - start, roots, 1) == 1) {
    const double t = start + roots[0];
    if (!(t > t_min)) {
      lo = std::nextafter(roots[0], leave - start);
      continue;
    }
    // Outward normal from the tube's centre circle; the point is snapped onto the surface.
    const Eigen::Vector3d p = oc + t * d;
    const Eigen::Vector3d radial = p - p.dot(torus.axis) * torus.axis;
    const Eigen::Vector3d circle = R * radial.normalized();
    const Eigen::Vector3d normal = (p - circle).normalized();
    const Eigen::Vector3d on_surface = torus.center + circle + r * normal;
    return SurfacePoint{t, normal, torus_curvature(torus, on_surface), 0};
  }
  return std::nullopt;
}

bool encloses(const Plane&, const Eigen::Vector3d&) {
  return false;
}

bool encloses(const Sphere& sphere, const Eigen::Vector3d& point) {
  return (point - sphere.center).norm() < sphere.radius;
}

bool encloses(const Cylinder& cylinder, const Eigen::Vector3d& point) {
  if (cylinder.length <= 0.0 || !cylinder.capped) return false;
  const Eigen::Vector3d d = point - cylinder.center;
  const double along = d.dot(cylinder.axis);
  return std::abs(along) < 0.5 * cylinder.length &&
         (d - along * cylinder.axis).norm() < cylinder.radius;
}

bool encloses(const Torus& torus, const Eigen::Vector3d& point) {
  const Eigen::Vector3d d = point - torus.center;
  const double along = d.dot(torus.axis);
  const double from_ring = (d - along * torus.axis).norm() - torus.major_radius;
  return from_ring * from_ring + along * along < torus.minor_radius * torus.minor_radius;
}

bool encloses(const Box& box, const Eigen::Vector3d& point) {
  const Eigen::Vector3d local = box.rotation.transpose() * (point - box.center);
  return (local.cwiseAbs().array() < 0.5 * box.size.array()).all();
}

BoundingSphere bounding_sphere(const Plane& plane) {
  return {plane.point, std::numeric_limits<double>::infinity()};
}

BoundingSphere bounding_sphere(const Sphere& sphere) {
  return {sphere.center, sphere.radius};
}

BoundingSphere bounding_sphere(const Cylinder& cylinder) {
  const double half = 0.5 * cylinder.length;
  return {cylinder.center, cylinder.length > 0.0
                               ? std::sqrt(cylinder.radius * cylinder.radius + half * half)
                               : std::numeric_limits<double>::infinity()};
}

BoundingSphere bounding_sphere(const Torus& torus) {
  return {torus.center, torus.major_radius + torus.minor_radius};
}

BoundingSphere bounding_sphere(const Box& box) {
  return {box.center, 0.5 * box.size.norm()};
}

Eigen::Vector2d torus_curvature(const Torus& torus, const Eigen::Vector3d& point) {
  const Eigen::Vector3d p = point - torus.center;
  const double rho = (p - p.dot(torus.axis) * torus.axis).norm();
  const double r = torus.minor_radius;
  const double along_tube = -1.0 / r;  // the meridian circle of radius r, always convex
  // Along the parallel circle of radius ρ, κ = cos θ / ρ with cos θ = (ρ − R)/r: convex on the
  // outer half (ρ > R), saddle-shaped on the inner half (ρ < R).
  const double along_parallel = -(rho - torus.major_radius) / (r * rho);
  return {std::max(along_tube, along_parallel), std::min(along_tube, along_parallel)};
}

}  // namespace jpcr
