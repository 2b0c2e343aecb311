#include "jpcr/frontend/frame_pyramid.hpp"

#include <algorithm>
#include <cmath>
#include <string>

#include "jpcr/quadric/error.hpp"

namespace jpcr {

namespace {

constexpr int kChunkRows = 16;  // rows per RowPool chunk

// Depth with every non-measurement as 0 and the working range applied, and its vertex map
// (method.md §1), in one pass; returns the number of valid vertices.
std::size_t clean_and_backproject(const DepthImage& raw, const CameraIntrinsics& c,
                                  const PreprocessParams& p, DepthImage& depth, VertexMap& vertices,
                                  RowPool* pool) {
  const int w = raw.width(), h = raw.height();
  depth = DepthImage(w, h);
  vertices = VertexMap(w, h, Eigen::Vector3f::Zero());
  const float fx = static_cast<float>(c.fx), fy = static_cast<float>(c.fy);
  const float cx = static_cast<float>(c.cx), cy = static_cast<float>(c.cy);
  std::vector<std::size_t> valid(pool ? pool->slots() : 1, 0);
  for_rows(pool, h, kChunkRows, [&](int begin, int end, int slot) {
    for (int v = begin; v < end; ++v) {
      for (int u = 0; u < w; ++u) {
        const float z = raw(u, v);
        if (is_valid_depth(z) && z >= p.min_depth && z <= p.max_depth) {
          depth(u, v) = z;
          vertices(u, v) =
              backproject<float>(static_cast<float>(u), static_cast<float>(v), z, fx, fy, cx, cy);
          ++valid[slot];
        } else {
          depth(u, v) = 0.0f;
          vertices(u, v) = invalid_vector();
        }
      }
    }
  });
  std::size_t total = 0;
  for (std::size_t n : valid)
    total += n;
  return total;
}

}  // namespace

DepthImage bilateral_filter(const DepthImage& depth, const PreprocessParams& p, RowPool* pool) {
  const int r = p.bilateral_radius, w = depth.width(), h = depth.height();
  // Spatial weights once; the range weight exp(−Δz²/2σ²) from a table over |Δz| in [0, 3σ).
  std::vector<float> spatial((2 * r + 1) * (2 * r + 1));
  for (int dv = -r; dv <= r; ++dv)
    for (int du = -r; du <= r; ++du)
      spatial[(dv + r) * (2 * r + 1) + du + r] = std::exp(
          -(du * du + dv * dv) / (2.0f * p.bilateral_sigma_space * p.bilateral_sigma_space));
  constexpr int kTable = 256;
  std::array<float, kTable> range;
  const float cutoff = 3.0f * p.bilateral_sigma_depth, to_bin = kTable / cutoff;
  for (int i = 0; i < kTable; ++i) {
    const float d = (i + 0.5f) / to_bin / p.bilateral_sigma_depth;
    range[i] = std::exp(-0.5f * d * d);
  }
  DepthImage out(w, h, 0.0f);
  for_rows(pool, h, kChunkRows, [&](int begin, int end, int) {
    for (int v = begin; v < end; ++v) {
      for (int u = 0; u < w; ++u) {
        const float z = depth(u, v);
        if (!(z > 0.0f) || !std::isfinite(z)) continue;  // no measurement (NaN, Inf, <= 0)
        float sum = 0.0f, weight = 0.0f;
        for (int dv = std::max(-r, -v); dv <= std::min(r, h - 1 - v); ++dv) {
          const float* row = &depth(0, v + dv);
          const float* ws = &spatial[(dv + r) * (2 * r + 1) + r];
          for (int du = std::max(-r, -u); du <= std::min(r, w - 1 - u); ++du) {
            const float zi = row[u + du];
            const float d = std::abs(zi - z);
            if (!(zi > 0.0f) || !(d < cutoff)) continue;  // also NaN (an index of INT_MIN)
            // d < cutoff, yet d · to_bin can round up to kTable in float.
            const float wi = ws[du] * range[std::min(static_cast<int>(d * to_bin), kTable - 1)];
            sum += wi * zi;
            weight += wi;
          }
        }
        out(u, v) = sum / weight;  // weight ≥ the centre's own weight > 0
      }
    }
  });
  return out;
}

double filtered_noise_inflation(const FramePyramid& pyramid, int stride, int level) {
  const int r = pyramid.filter_radius, n = 2 * r + 1;
  if (r <= 0 || stride < 1 || level < 0) return 1.0;
  const double s2 = double(pyramid.filter_sigma_space) * pyramid.filter_sigma_space;
  // Level l's pixel is the mean of a b x b block (b = 2^l) of level 0's: its kernel over level
  // 0's raw samples is the filter's convolved with that block, m = n + b - 1 wide, and its
  // samples lie stride · b level-0 pixels apart.
  const int b = 1 << level, m = n + b - 1, step = stride * b;
  std::vector<double> w(static_cast<std::size_t>(m) * m, 0.0);
  for (int dv = -r; dv <= r; ++dv)
    for (int du = -r; du <= r; ++du) {
      const double g = std::exp(-(du * du + dv * dv) / (2 * s2));
      for (int bv = 0; bv < b; ++bv)
        for (int bu = 0; bu < b; ++bu)
          w[static_cast<std::size_t>((dv + r + bv) * m + du + r + bu)] += g;
    }
  // A(k) = Σ_x w(x) w(x + k) over the kernel's support; the lattice offsets within ±(m − 1).
  const auto autocorrelation = [&](int ku, int kv) {
    double a = 0.0;
    for (int v = 0; v < m; ++v)
      for (int u = 0; u < m; ++u) {
        const int u2 = u + ku, v2 = v + kv;
        if (u2 >= 0 && u2 < m && v2 >= 0 && v2 < m)
          a += w[static_cast<std::size_t>(v * m + u)] * w[static_cast<std::size_t>(v2 * m + u2)];
      }
    return a;
  };
  const int reach = ((m - 1) / step) * step;
  double sum = 0.0;
  for (int kv = -reach; kv <= reach; kv += step)
    for (int ku = -reach; ku <= reach; ku += step)
      sum += autocorrelation(ku, kv);
  return sum / autocorrelation(0, 0);
}

DepthImage downsample_depth(const DepthImage& depth, float max_depth_step, RowPool* pool) {
  DepthImage out(depth.width() / 2, depth.height() / 2, 0.0f);
  for_rows(pool, out.height(), kChunkRows, [&](int begin, int end, int) {
    for (int v = begin; v < end; ++v) {
      for (int u = 0; u < out.width(); ++u) {
        const float z[4] = {depth(2 * u, 2 * v), depth(2 * u + 1, 2 * v), depth(2 * u, 2 * v + 1),
                            depth(2 * u + 1, 2 * v + 1)};
        float nearest = 0.0f;
        for (float zi : z)
          if (zi > 0.0f && (nearest == 0.0f || zi < nearest)) nearest = zi;
        if (nearest == 0.0f) continue;
        float sum = 0.0f;
        int n = 0;
        for (float zi : z) {
          if (zi > 0.0f && zi - nearest <= max_depth_step) {
            sum += zi;
            ++n;
          }
        }
        out(u, v) = sum / static_cast<float>(n);
      }
    }
  });
  return out;
}

NormalMap compute_normal_map(const VertexMap& vertices, int offset, float max_jump, RowPool* pool) {
  const int w = vertices.width(), h = vertices.height(), k = offset;
  NormalMap normals(w, h, invalid_vector());
  const float jump = max_jump * static_cast<float>(2 * k);
  for_rows(pool, h - 2 * k, kChunkRows, [&](int begin, int end, int) {
    for (int v = begin + k; v < end + k; ++v) {
      for (int u = k; u < w - k; ++u) {
        const Eigen::Vector3f& x = vertices(u, v);
        if (!is_valid(x)) continue;
        const Eigen::Vector3f& l = vertices(u - k, v);
        const Eigen::Vector3f& r = vertices(u + k, v);
        const Eigen::Vector3f& t = vertices(u, v - k);
        const Eigen::Vector3f& b = vertices(u, v + k);
        if (!is_valid(l) || !is_valid(r) || !is_valid(t) || !is_valid(b)) continue;
        const Eigen::Vector3f du = r - l, dv = b - t;
        const float limit = jump * x.z();
        if (std::abs(du.z()) > limit || std::abs(dv.z()) > limit) continue;
        Eigen::Vector3f n = du.cross(dv);
        const float norm = n.norm();
        if (!(norm > 0.0f)) continue;
        n /= norm;
        if (n.dot(x) > 0.0f) n = -n;  // toward the camera (method.md §1)
        normals(u, v) = n;
      }
    }
  });
  return normals;
}

NormalLookup normals_for(const FramePyramid& pyramid, int level) {
  const bool own = !pyramid.levels.at(level).normals.empty() ||
                   level + 1 >= static_cast<int>(pyramid.levels.size());
  const PyramidLevel& serving = pyramid.levels[own ? level : level + 1];
  // A pyramid assembled by hand (not by preprocess) may have no normals, or a map of another size.
  if (serving.normals.empty() || serving.normals.width() != serving.vertices.width() ||
      serving.normals.height() != serving.vertices.height())
    throw InputError("pyramid level " + std::to_string(level) +
                     ": no normal map of its own or of the next level's size");
  return {&serving.normals, own ? 0 : 1};
}

FramePyramid preprocess(const Frame& frame, const PreprocessParams& params, RowPool* pool) {
  params.validate();  // a library caller's parameters
  try {
    frame.camera.validate();
  } catch (const std::invalid_argument& e) {
    throw InputError(std::string("frame camera: ") + e.what());
  }
  if (frame.depth.width() != frame.camera.width || frame.depth.height() != frame.camera.height) {
    throw InputError("frame at t = " + std::to_string(frame.timestamp) + ": depth image is " +
                     std::to_string(frame.depth.width()) + "x" +
                     std::to_string(frame.depth.height()) + " but the camera is " +
                     std::to_string(frame.camera.width) + "x" +
                     std::to_string(frame.camera.height));
  }
  if (frame.camera.width < 32 || frame.camera.height < 32) {
    throw InputError("frame: images smaller than 32x32 are too small for a 3-level pyramid");
  }
  FramePyramid pyramid;
  pyramid.timestamp = frame.timestamp;
  pyramid.levels.resize(FramePyramid::kLevels);
  // Level 0: the frame's depth without non-measurements and outside the working range, and
  // optionally filtered; each next level averages 2x2 blocks of the one before.
  for (int l = 0; l < FramePyramid::kLevels; ++l) {
    PyramidLevel& level = pyramid.levels[l];
    level.camera = frame.camera.pyramid_level(l);
    const DepthImage input =
        l == 0 ? frame.depth
               : downsample_depth(pyramid.levels[l - 1].depth, params.pyramid_max_depth_step, pool);
    level.valid_vertices =
        clean_and_backproject(input, level.camera, params, level.depth, level.vertices, pool);
    if (l == 0 && params.bilateral) {
      pyramid.filter_radius = params.bilateral_radius;
      pyramid.filter_sigma_space = params.bilateral_sigma_space;
      const DepthImage filtered = bilateral_filter(level.depth, params, pool);
      level.valid_vertices =
          clean_and_backproject(filtered, level.camera, params, level.depth, level.vertices, pool);
    }
    // The same metric support at every level: ±normal_offset px at full resolution.
    if (l == 0 && !params.full_resolution_normals) continue;
    level.normals = compute_normal_map(level.vertices, std::max(1, params.normal_offset >> l),
                                       params.normal_max_jump, pool);
  }
  return pyramid;
}

}  // namespace jpcr
