#include "jpcr/quadric/quadric_map.hpp"

#include <limits>

namespace jpcr {

namespace {
const Eigen::Vector2f kNoCurvature =
    Eigen::Vector2f::Constant(std::numeric_limits<float>::quiet_NaN());
}  // namespace

QuadricMap::QuadricMap(int width, int height)
    : quadrics(width, height),
      curvature(width, height, kNoCurvature),
      direction(width, height, invalid_vector()),
      status(width, height, QuadricStatus::kNoCentre) {}

std::size_t QuadricMap::valid_count() const {
  std::size_t n = 0;
  for (QuadricStatus s : status)
    n += s == QuadricStatus::kValid ? 1 : 0;
  return n;
}

void QuadricMap::set(int u, int v, const Quadric& q) {
  set(u, v, q, principal_curvatures(q.a, q.b, q.c), principal_direction(q));
}

void QuadricMap::set(int u, int v, const Quadric& q, const Eigen::Vector2f& kappa,
                     const Eigen::Vector3f& d1) {
  if (!is_finite_value(kappa.x()) || !is_finite_value(kappa.y())) {
    set_invalid(u, v, QuadricStatus::kSingular);
    return;
  }
  quadrics(u, v) = q;
  curvature(u, v) = kappa;
  direction(u, v) = d1;
  status(u, v) = QuadricStatus::kValid;
}

void QuadricMap::set_invalid(int u, int v, QuadricStatus why) {
  quadrics(u, v) = Quadric{};
  curvature(u, v) = kNoCurvature;
  direction(u, v) = invalid_vector();
  status(u, v) = why;
}

NormalMap QuadricMap::normals() const {
  NormalMap n(width(), height(), invalid_vector());
  for (int v = 0; v < height(); ++v)
    for (int u = 0; u < width(); ++u)
      if (valid(u, v)) n(u, v) = quadrics(u, v).normal();
  return n;
}

QuadricMapSummary summarize(const QuadricMap& map) {
  QuadricMapSummary s;
  s.pixels = map.status.size();
  for (QuadricStatus st : map.status) {
    switch (st) {
      case QuadricStatus::kValid:
        ++s.valid;
        break;
      case QuadricStatus::kNoCentre:
        ++s.no_centre;
        break;
      case QuadricStatus::kNoNormal:
        ++s.no_normal;
        break;
      case QuadricStatus::kTooFewSamples:
        ++s.too_few_samples;
        break;
      case QuadricStatus::kSingular:
        ++s.singular;
        break;
      case QuadricStatus::kNoStep:
        ++s.no_step;
        break;
    }
  }
  return s;
}

}  // namespace jpcr
