#include "jpcr/io/synthetic_noise.hpp"

#include <algorithm>
#include <cmath>

#include "jpcr/io/number_format.hpp"
#include "jpcr/io/synthetic_random.hpp"
#include "jpcr/quadric/error.hpp"

namespace jpcr {

namespace {

constexpr double kDegree = EIGEN_PI / 180.0;
// Range noise above 100 % of the range leaves no depth that describes the scene (and at 1e308 %
// every factor overflows to no measurement): refused instead of writing such frames.
constexpr double kMaxRangePercent = 100.0;

// Range noise: the range r becomes r (1 + σ_rel g), and z with it (same ray). A factor ≤ 0 (only
// possible for σ_rel of tens of percent) is no measurement.
double range_noise(double z, double relative_sigma, double g) {
  const double factor = 1.0 + relative_sigma * g;
  return factor > 0.0 ? z * factor : 0.0;
}

// Kinect axial noise then disparity quantisation: d = f b / z is rounded to the step and turned
// back into depth (Khoshelham & Elberink 2012).
double kinect_depth(double z, const KinectNoiseParams& k, double g) {
  const double sigma =
      k.sigma_constant + k.sigma_quadratic * (z - k.sigma_offset) * (z - k.sigma_offset);
  double noisy = z + sigma * g;
  if (k.disparity_step > 0.0 && noisy > 0.0) {
    const double fb = k.disparity_focal * k.baseline;
    const double disparity = std::round(fb / noisy / k.disparity_step) * k.disparity_step;
    noisy = disparity > 0.0 ? fb / disparity : 0.0;
  }
  return (noisy >= k.min_depth && noisy <= k.max_depth) ? noisy : 0.0;
}

bool is_depth_edge(const DepthImage& exact, int u, int v, double jump) {
  const float z = exact(u, v);
  const int du[4] = {1, -1, 0, 0}, dv[4] = {0, 0, 1, -1};
  for (int i = 0; i < 4; ++i) {
    if (!exact.in_bounds(u + du[i], v + dv[i])) continue;
    const float n = exact(u + du[i], v + dv[i]);
    if (!(n > 0.0f) || std::abs(n - z) > jump * z) return true;
  }
  return false;
}

// Dropout probability from the incidence angle (ramping from grazing_start to grazing_full) and
// from depth edges.
double kinect_dropout(const DepthImage& exact, const NormalMap& normals,
                      const CameraIntrinsics& camera, int u, int v, const KinectNoiseParams& k) {
  const Eigen::Vector3d ray =
      backproject<double>(u, v, 1.0, camera.fx, camera.fy, camera.cx, camera.cy).normalized();
  const Eigen::Vector3d n = normals(u, v).cast<double>();
  const double incidence = std::acos(std::clamp(-n.dot(ray), -1.0, 1.0)) / kDegree;
  double p =
      std::clamp((incidence - k.grazing_start) / (k.grazing_full - k.grazing_start), 0.0, 1.0);
  if (is_depth_edge(exact, u, v, k.edge_jump)) p = std::max(p, k.edge_dropout);
  return p;
}

}  // namespace

void KinectNoiseParams::validate() const {
  const auto check = [](bool ok, const char* field, const char* why) {
    if (!ok) throw InputError(std::string(field) + ": " + why);
  };
  check(sigma_constant >= 0.0, "sigma_constant", "must be non-negative (m)");
  check(sigma_quadratic >= 0.0, "sigma_quadratic", "must be non-negative (1/m)");
  check(std::isfinite(sigma_offset), "sigma_offset", "must be finite (m)");
  check(baseline > 0.0 && std::isfinite(baseline), "baseline", "must be positive (m)");
  check(disparity_focal > 0.0 && std::isfinite(disparity_focal), "disparity_focal",
        "must be positive (px)");
  check(disparity_step >= 0.0 && std::isfinite(disparity_step), "disparity_step",
        "must be non-negative (px)");
  check(min_depth >= 0.0 && max_depth > min_depth, "max_depth", "must exceed min_depth (m)");
  check(grazing_start >= 0.0 && grazing_full > grazing_start && grazing_full <= 90.0,
        "grazing_full", "need 0 ≤ grazing_start < grazing_full ≤ 90 (deg)");
  check(edge_jump > 0.0 && std::isfinite(edge_jump), "edge_jump", "must be positive (fraction)");
  check(edge_dropout >= 0.0 && edge_dropout <= 1.0, "edge_dropout", "must be in [0, 1]");
}

std::string NoiseModel::describe() const {
  switch (kind) {
    case NoiseKind::kNone:
      return "none";
    case NoiseKind::kRange:
      return "range:" + format_double(range_percent);
    case NoiseKind::kKinect:
      return "kinect";
  }
  return "?";
}

NoiseModel parse_noise(const std::string& spec) {
  NoiseModel model;
  if (spec == "none") return model;
  if (spec == "kinect") {
    model.kind = NoiseKind::kKinect;
    return model;
  }
  const std::string prefix = "range:";
  if (spec.rfind(prefix, 0) == 0) {
    double percent = 0.0;
    if (!parse_double(spec.substr(prefix.size()), percent) || !std::isfinite(percent) ||
        percent < 0.0 || percent > kMaxRangePercent) {
      throw InputError("noise '" + spec +
                       "': range:K needs a percentage 0 ≤ K ≤ 100, e.g. range:1");
    }
    model.kind = NoiseKind::kRange;
    model.range_percent = percent;
    return model;
  }
  throw InputError("noise '" + spec + "': expected none, range:K (K % of the range) or kinect");
}

DepthImage add_depth_noise(const DepthImage& exact, const NormalMap& normals,
                           const CameraIntrinsics& camera, const NoiseModel& noise,
                           std::uint64_t seed, std::uint64_t frame_index) {
  if (noise.kind == NoiseKind::kKinect) noise.kinect.validate();
  DepthImage depth = exact;
  if (noise.kind == NoiseKind::kNone) return depth;
  const CounterRandom gaussian(seed, RandomStream::kDepthNoise, frame_index);
  const CounterRandom dropout(seed, RandomStream::kDropout, frame_index);
  const int width = exact.width(), height = exact.height();
#pragma omp parallel for schedule(static)
  for (int v = 0; v < height; ++v) {
    for (int u = 0; u < width; ++u) {
      const double z = exact(u, v);
      if (!(z > 0.0)) continue;
      const std::uint64_t pixel = static_cast<std::uint64_t>(v) * width + u;
      const double g = gaussian.gaussian(pixel);
      double noisy;
      if (noise.kind == NoiseKind::kRange) {
        noisy = range_noise(z, 0.01 * noise.range_percent, g);
      } else {
        noisy = kinect_depth(z, noise.kinect, g);
        if (dropout.uniform(pixel) < kinect_dropout(exact, normals, camera, u, v, noise.kinect))
          noisy = 0.0;
      }
      depth(u, v) = static_cast<float>(noisy);
    }
  }
  return depth;
}

}  // namespace jpcr
