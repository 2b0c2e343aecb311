#include "peers/cgal_jet_curvature.hpp"

#include <algorithm>
#include <stdexcept>
#include <vector>

#include <CGAL/Monge_via_jet_fitting.h>
#include <CGAL/Simple_cartesian.h>

#include "jpcr/quadric/error.hpp"
#include "jpcr/quadric/neighbourhood_pattern.hpp"
#include "jpcr/quadric/parallel_guard.hpp"

namespace jpcr::peers {

namespace {

using Kernel = CGAL::Simple_cartesian<double>;
using JetFitting = CGAL::Monge_via_jet_fitting<Kernel>;

bool finite_vertex(const Eigen::Vector3f& X) {
  return std::isfinite(X.x()) && std::isfinite(X.y()) && std::isfinite(X.z());
}

Eigen::Vector3d eigen(const Kernel::Vector_3& v) {
  return {v.x(), v.y(), v.z()};
}

}  // namespace

CgalJetCurvature::CgalJetCurvature(const QuadricParams& params, int degree)
    : params_(params), degree_(degree) {
  params_.validate();
  if (degree_ < 2 || degree_ > 4) throw InputError("cgal-jet: degree must be 2, 3 or 4");
}

QuadricMap CgalJetCurvature::estimate(const VertexMap& vertices, const NormalMap& normals) const {
  if (normals.width() != vertices.width() || normals.height() != vertices.height())
    throw std::invalid_argument("CgalJetCurvature: normal map and vertex map differ in size");
  const NeighbourhoodPattern pattern = params_.pattern.for_width(vertices.width());
  // A jet of degree d has (d + 1)(d + 2)/2 coefficients; CGAL needs at least that many points.
  const int needed = std::max(params_.fit.min_samples, (degree_ + 1) * (degree_ + 2) / 2);
  QuadricMap map(vertices.width(), vertices.height());
  ParallelGuard guard;  // out of memory, a CGAL exception: rethrown, not std::terminate
#pragma omp parallel
  {
    std::vector<Kernel::Point_3> points;
    guard.run([&] { points.reserve(pattern.offsets.size()); });
#pragma omp for schedule(dynamic, 4)
    for (int v = 0; v < vertices.height(); ++v)
      guard.run([&] {
        for (int u = 0; u < vertices.width(); ++u) {
          const Eigen::Vector3f& centre = vertices(u, v);
          if (!finite_vertex(centre)) {
            map.set_invalid(u, v, QuadricStatus::kNoCentre);
            continue;
          }
          // Centred, for the SVD's conditioning; the centre first: CGAL evaluates the Monge form
          // at the first point of the range.
          points.clear();
          points.emplace_back(0.0, 0.0, 0.0);
          for (const PixelOffset& o : pattern.offsets) {
            const int su = u + o.du, sv = v + o.dv;
            if ((o.du == 0 && o.dv == 0) || !vertices.in_bounds(su, sv) ||
                !finite_vertex(vertices(su, sv)))
              continue;
            const Eigen::Vector3f d = vertices(su, sv) - centre;
            points.emplace_back(d.x(), d.y(), d.z());
          }
          if (static_cast<int>(points.size()) < needed) {
            map.set_invalid(u, v, QuadricStatus::kTooFewSamples);
            continue;
          }
          JetFitting fit;
          JetFitting::Monge_form monge =
              fit(points.begin(), points.end(), static_cast<std::size_t>(degree_), 2);
          // Toward the camera, as jpcr's normals: the camera sits at −centre in these coordinates.
          monge.comply_wrt_given_normal(Kernel::Vector_3(-centre.x(), -centre.y(), -centre.z()));
          double k1 = monge.principal_curvatures(0), k2 = monge.principal_curvatures(1);
          Eigen::Vector3d d1 = eigen(monge.maximal_principal_direction());
          const Eigen::Vector3d d2 = eigen(monge.minimal_principal_direction());
          if (k2 > k1) {
            std::swap(k1, k2);
            d1 = d2;
          }
          if (!std::isfinite(k1) || !std::isfinite(k2)) {
            map.set_invalid(u, v, QuadricStatus::kSingular);
            continue;
          }
          // The record: the Monge frame (rows d₁, d₂, n) at the vertex, K = diag(κ₁, κ₂).
          Quadricd q;
          const Eigen::Vector3d n = eigen(monge.normal_direction()).normalized();
          q.R.row(0) = d1.normalized();
          q.R.row(1) = n.cross(q.R.row(0).transpose()).transpose();
          q.R.row(2) = n;
          q.center = centre.cast<double>();
          q.a = k1;
          q.c = k2;
          map.set(u, v, q.cast<float>(),
                  Eigen::Vector2f(static_cast<float>(k1), static_cast<float>(k2)),
                  d1.normalized().cast<float>());
        }
      });
  }
  guard.rethrow();
  return map;
}

}  // namespace jpcr::peers
