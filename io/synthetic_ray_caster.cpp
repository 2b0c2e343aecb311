#include "jpcr/io/synthetic_ray_caster.hpp"

#include <algorithm>
#include <cmath>
#include <limits>
#include <stdexcept>
#include <utility>
#include <vector>

#include "jpcr/io/synthetic_tiles.hpp"
#include "jpcr/quadric/error.hpp"

namespace jpcr {

namespace {

// Tells smooth patches apart for the footprint test: surface index, face (< 8 per surface) and
// side: an open tube's outside and inside are one face, but its rim is a crease between them.
std::int32_t patch_id(const std::optional<SurfaceHit>& hit) {
  return hit ? (hit->surface * 8 + hit->patch) * 2 + (hit->inside ? 1 : 0) : -1;
}

}  // namespace

CameraIntrinsics synthetic_camera(int width, int height) {
  CameraIntrinsics camera;
  camera.fx = camera.fy = 550.0;
  camera.cx = 319.5;
  camera.cy = 239.5;
  camera.width = 640;
  camera.height = 480;
  camera.depth_scale = 5000.0;
  return (width == 640 && height == 480) ? camera : camera.resized(width, height);
}

void check_synthetic_camera(const CameraIntrinsics& camera) {
  try {
    camera.validate();
  } catch (const std::invalid_argument& e) {
    throw InputError(std::string("synthetic camera: ") + e.what());
  }
  if (camera.has_distortion()) {
    throw InputError("synthetic camera: the renderer is an ideal pinhole; distortion must be zero");
  }
}

SyntheticFrame render(const SyntheticScene& scene, const CameraIntrinsics& camera,
                      const Eigen::Isometry3d& pose_wc, const NoiseModel& noise, std::uint64_t seed,
                      std::uint64_t frame_index, double timestamp) {
  check_synthetic_camera(camera);
  const int width = camera.width, height = camera.height;
  const float nan = std::numeric_limits<float>::quiet_NaN();
  SyntheticFrame out;
  out.pose_wc = pose_wc;
  out.frame.timestamp = timestamp;
  out.frame.camera = camera;
  out.exact_depth = DepthImage(width, height, 0.0f);
  out.curvature = CurvatureImage(width, height, Eigen::Vector2f(nan, nan));
  out.normals = NormalMap(width, height, invalid_vector());
  out.surface = Image<std::int32_t>(width, height, -1);
  Image<std::int32_t> centre_patch(width, height, -1);
  Image<std::int32_t> corner_patch(width + 1, height + 1, -1);  // pixel corners (u ± ½, v ± ½)
  Image<double> centre_range(width, height, 0.0), corner_range(width + 1, height + 1, 0.0);
  const Eigen::Matrix3d R = pose_wc.linear();
  const Eigen::Vector3d origin = pose_wc.translation();
  const SurfaceTiles tiles(scene, camera, pose_wc);

#pragma omp parallel for schedule(dynamic, 2)
  for (int v = 0; v < height; ++v) {
    for (int u = 0; u < width; ++u) {
      const Eigen::Vector3d d = pixel_ray_direction(camera, u, v);
      const std::optional<SurfaceHit> hit = cast_ray(scene, Ray{origin, R * d}, tiles.at(u, v));
      if (!hit) continue;
      out.exact_depth(u, v) = static_cast<float>(hit->range * d.z());  // z along the optical axis
      out.normals(u, v) = (R.transpose() * hit->normal).cast<float>();
      out.curvature(u, v) = hit->curvature.cast<float>();
      out.surface(u, v) = hit->surface;
      centre_patch(u, v) = patch_id(hit);
      centre_range(u, v) = hit->range;
    }
  }
#pragma omp parallel for schedule(dynamic, 2)
  for (int v = 0; v <= height; ++v) {
    for (int u = 0; u <= width; ++u) {
      const Eigen::Vector3d d = pixel_ray_direction(camera, u - 0.5, v - 0.5);
      const std::vector<int>& candidates =
          tiles.at(std::min(u, width - 1), std::min(v, height - 1));
      const std::optional<SurfaceHit> hit = cast_ray(scene, Ray{origin, R * d}, candidates);
      corner_patch(u, v) = patch_id(hit);
      corner_range(u, v) = hit ? hit->range : 0.0;
    }
  }
  // Curvature is undefined where the footprint holds a crease or a silhouette: a corner ray hits
  // another patch than the centre's, or the same patch behind an edge of it (a torus's near tube
  // hiding its far tube), told by a range jump of over kMaxCornerJump. On one smooth patch the
  // corner's range differs from the centre's by about (0.71 / fx) tan θ at incidence θ: the test
  // also drops pixels seen within a few degrees of grazing (beyond 84° at fx = 137.5, 160 px
  // wide; 88.5° at 640 px), where no estimator measures curvature either. Measured on the first
  // frames of the three report scenes at 160x120 and 640x480: only torus pixels change.
  constexpr double kMaxCornerJump = 0.05;  // of the centre's range
  for (int v = 0; v < height; ++v) {
    for (int u = 0; u < width; ++u) {
      const std::int32_t id = centre_patch(u, v);
      if (id < 0) continue;
      const double range = centre_range(u, v);
      bool smooth = true;
      for (const auto& [cu, cv] : {std::pair{u, v}, {u + 1, v}, {u, v + 1}, {u + 1, v + 1}})
        smooth = smooth && corner_patch(cu, cv) == id &&
                 std::abs(corner_range(cu, cv) - range) <= kMaxCornerJump * range;
      if (!smooth) out.curvature(u, v) = Eigen::Vector2f(nan, nan);
    }
  }
  out.frame.depth = add_depth_noise(out.exact_depth, out.normals, camera, noise, seed, frame_index);
  // Ground truth only where there is a measurement: not at a dropout of the noise model, nor
  // past what a depth PNG holds (65535 / depth_scale, 13.1 m at 5000 per metre), nor under
  // half its step, where the written depth is 0. A method can return nothing there, and its
  // coverage should not count it.
  for (std::size_t i = 0; i < out.frame.depth.size(); ++i) {
    float& z = out.frame.depth[i];
    const double written = static_cast<double>(z) * camera.depth_scale;
    if (written >= 65535.5 || written < 0.5) z = 0.0f;  // as save_depth_png
    if (z <= 0.0f && out.surface[i] >= 0) {
      out.curvature[i] = Eigen::Vector2f(nan, nan);
      out.normals[i] = invalid_vector();
    }
  }
  out.frame.color = shade_normals(out.normals);
  return out;
}

ColorImage shade_normals(const NormalMap& normals) {
  ColorImage image(normals.width(), normals.height());
  const auto channel = [](float x) {
    return static_cast<std::uint8_t>(std::lround(127.5f * (1.0f + std::clamp(x, -1.0f, 1.0f))));
  };
  for (std::size_t i = 0; i < normals.size(); ++i) {
    const Eigen::Vector3f& n = normals[i];
    if (is_valid(n)) image[i] = Rgb8{channel(n.x()), channel(n.y()), channel(-n.z())};
  }
  return image;
}

}  // namespace jpcr
