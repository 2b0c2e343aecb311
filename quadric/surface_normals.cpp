#include "jpcr/quadric/surface_normals.hpp"

#include <algorithm>
#include <cmath>
#include <optional>
#include <vector>

#include "jpcr/quadric/error.hpp"
#include "jpcr/quadric/parallel_guard.hpp"
#include "jpcr/quadric/plane_normal_kernel.hpp"

namespace jpcr {

namespace {

// Σ (x, y, z) and Σ (xx, xy, xz, yy, yz, zz) of a set of vertices, in double.
struct Moments {
  double s[9] = {0, 0, 0, 0, 0, 0, 0, 0, 0};

  void add(const Eigen::Vector3f& X) {
    const double x = X.x(), y = X.y(), z = X.z();
    s[0] += x, s[1] += y, s[2] += z;
    s[3] += x * x, s[4] += x * y, s[5] += x * z, s[6] += y * y, s[7] += y * z, s[8] += z * z;
  }
  void add(const Moments& o) {
    for (int k = 0; k < 9; ++k)
      s[k] += o.s[k];
  }
  /// Σ X and Σ X Xᵀ.
  void to(Eigen::Vector3d& sum, Eigen::Matrix3d& outer) const {
    sum = Eigen::Vector3d(s[0], s[1], s[2]);
    outer << s[3], s[4], s[5], s[4], s[6], s[7], s[5], s[7], s[8];
  }
};

// The plane fit of plane_normal, separably, for the pixels whose whole window is clean: inside
// the image, every vertex finite and within the depth jump of the centre, so that no point is
// left out (almost every pixel of a smooth surface). One row of column sums over the window's
// 2h+1 rows, then 2h+1 of them per pixel: about a quarter of the additions. The same moments up
// to rounding (uncentred here, so the scatter matrix loses about log10(|X|² / window²) digits of
// the 16, far below the float normal), and the same choice of a quadrant where the window holds
// no single smooth surface (choose_quadrant); any other pixel takes plane_normal itself.
class CleanWindows {
 public:
  CleanWindows(const VertexMap& vertices, const NormalEstimationParams& p)
      : vertices_(vertices),
        p_(p),
        columns_(vertices.width()),
        upper_(vertices.width()),
        lower_(vertices.width()),
        finite_(vertices.width()),
        z_min_(vertices.width()),
        z_max_(vertices.width()) {}

  /// The column sums for the windows of row v (and for their upper and lower h+1 rows, the
  /// quadrants' columns); false when they leave the image.
  bool load_row(int v) {
    const int h = p_.half_window;
    if (v < h || v + h >= vertices_.height()) return false;
    for (int u = 0; u < vertices_.width(); ++u) {
      Moments up, down;
      bool finite = true;
      float lo = vertices_(u, v - h).z(), hi = lo;
      for (int r = v - h; r <= v + h; ++r) {
        const Eigen::Vector3f& X = vertices_(u, r);
        finite = finite && is_sample_point(X);
        lo = std::min(lo, X.z());
        hi = std::max(hi, X.z());
        if (r < v) up.add(X);
        if (r > v) down.add(X);
      }
      Moments centre;
      centre.add(vertices_(u, v));
      Moments m = up;
      m.add(down);
      m.add(centre);
      up.add(centre);
      down.add(centre);
      upper_[u] = up;
      lower_[u] = down;
      columns_[u] = m;
      finite_[u] = finite ? 1 : 0;
      z_min_[u] = lo;
      z_max_[u] = hi;
    }
    return true;
  }

  /// The normal at (u, v) of the loaded row, and the window's own plane normal; false when the
  /// window is not clean.
  bool normal(int u, int v, Eigen::Vector3f& n, Eigen::Vector3f& window) const {
    const int h = p_.half_window;
    if (u < h || u + h >= vertices_.width()) return false;
    const Eigen::Vector3f& centre = vertices_(u, v);
    float lo = centre.z(), hi = lo;
    for (int c = u - h; c <= u + h; ++c) {
      if (!finite_[c]) return false;
      lo = std::min(lo, z_min_[c]);
      hi = std::max(hi, z_max_[c]);
    }
    // plane_normal drops X when |X_z − centre_z| > jump (float); no X is dropped exactly when
    // the extremes pass, the float difference being monotonic in X_z.
    const float jump = p_.max_depth_jump * centre.z();
    if (!(hi - centre.z() <= jump && centre.z() - lo <= jump)) return false;
    Moments m;
    for (int c = u - h; c <= u + h; ++c)
      m.add(columns_[c]);
    Eigen::Vector3d sum;
    Eigen::Matrix3d outer;
    m.to(sum, outer);
    double residual = 0.0;
    n = plane_normal_from_moments(sum, outer, (2 * h + 1) * (2 * h + 1), centre, p_, &residual);
    window = n;
    if (!may_take_a_quadrant(n, residual, p_)) return true;
    QuadrantMoments quadrants;
    for (int q = 0; q < 4; ++q) {
      const std::vector<Moments>& band = (q & 2) ? lower_ : upper_;
      const int c0 = (q & 1) ? u : u - h;
      Moments mq;
      for (int c = c0; c <= c0 + h; ++c)
        mq.add(band[c]);
      mq.to(quadrants.sum[q], quadrants.outer[q]);
      quadrants.count[q] = (h + 1) * (h + 1);
    }
    n = choose_quadrant(quadrants, centre, p_, n, residual);
    return true;
  }

 private:
  const VertexMap& vertices_;
  const NormalEstimationParams& p_;
  std::vector<Moments> columns_, upper_, lower_;  // rows v−h…v+h, v−h…v and v…v+h
  std::vector<unsigned char> finite_;
  std::vector<float> z_min_, z_max_;
};

}  // namespace

void NormalEstimationParams::validate() const {
  if (half_window < 1 || half_window > 32) throw InputError("half_window: must be in [1, 32]");
  if (min_points < 3) throw InputError("min_points: must be at least 3");
  const int window = (2 * half_window + 1) * (2 * half_window + 1);
  if (min_points > window)  // no pixel could get a normal, nor a quadric
    throw InputError("min_points: " + std::to_string(min_points) + " exceeds the " +
                     std::to_string(window) + " points of the normals' window (half_window " +
                     std::to_string(half_window) + ")");
  if (!(max_depth_jump > 0.0f))
    throw InputError("max_depth_jump: must be positive (fraction of depth)");
  if (!(quadrant_ratio == 0.0f || (quadrant_ratio >= 1.0f && quadrant_ratio <= 1e12f)))
    throw InputError("quadrant_ratio: must be 0 (off) or in [1, 1e12]");
}

NormalMap estimate_normals(const VertexMap& vertices, const NormalEstimationParams& params,
                           Image<float>* quadrant_tilt) {
  NormalMap normals(vertices.width(), vertices.height(), invalid_vector());
  if (quadrant_tilt) *quadrant_tilt = Image<float>(vertices.width(), vertices.height(), 0.0f);
  const VertexView view{vertices.data(), vertices.width(), vertices.height()};
  ParallelGuard guard;  // e.g. a worker's buffers out of memory: rethrown, not std::terminate
#pragma omp parallel
  {
    std::optional<CleanWindows> windows;
    guard.run([&] { windows.emplace(vertices, params); });
#pragma omp for schedule(dynamic, 8)
    for (int v = 0; v < vertices.height(); ++v)
      guard.run([&] {
        if (!windows) return;
        const bool loaded = windows->load_row(v);
        for (int u = 0; u < vertices.width(); ++u) {
          if (!is_sample_point(vertices(u, v))) continue;  // no centre: no normal
          Eigen::Vector3f& n = normals(u, v);
          Eigen::Vector3f window;
          if (!loaded || !windows->normal(u, v, n, window))
            n = plane_normal(view, u, v, params, &window);
          if (quadrant_tilt && n.x() == n.x() && window.x() == window.x() && n != window)
            (*quadrant_tilt)(u, v) = std::acos(std::clamp(n.dot(window), -1.0f, 1.0f));
        }
      });
  }
  guard.rethrow();
  return normals;
}

}  // namespace jpcr
