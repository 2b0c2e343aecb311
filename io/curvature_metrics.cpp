#include "jpcr/io/curvature_metrics.hpp"

#include <algorithm>
#include <cmath>
#include <string>

#include "jpcr/quadric/error.hpp"

namespace jpcr {
namespace {

bool finite(const Eigen::Vector2f& k) {
  return std::isfinite(k.x()) && std::isfinite(k.y());
}

// 1 where the (2R+1)² window around the pixel lies inside the image and every pixel of it has
// ground truth: a separable test, rows first (runs of finite pixels), then columns.
Image<unsigned char> interior_mask(const CurvatureImage& gt, int R) {
  const int w = gt.width(), h = gt.height();
  Image<int> run_x(w, h, 0);  // finite pixels in the row window [u−R, u+R], 2R+1 when all
  for (int v = 0; v < h; ++v) {
    std::vector<int> prefix(static_cast<std::size_t>(w) + 1, 0);
    for (int u = 0; u < w; ++u)
      prefix[u + 1] = prefix[u] + (finite(gt(u, v)) ? 1 : 0);
    for (int u = R; u + R < w; ++u)
      run_x(u, v) = prefix[u + R + 1] - prefix[u - R];
  }
  Image<unsigned char> mask(w, h, 0);
  const int full = 2 * R + 1;
  for (int u = R; u + R < w; ++u) {
    int rows = 0;  // rows of the column window whose row window is full
    for (int v = 0; v < h; ++v) {
      rows += run_x(u, v) == full ? 1 : 0;
      if (v >= full) rows -= run_x(u, v - full) == full ? 1 : 0;
      if (v >= 2 * R && rows == full) mask(u, v - R) = 1;
    }
  }
  return mask;
}

}  // namespace

CurvatureErrorAccumulator::CurvatureErrorAccumulator(int support_radius)
    : support_radius_(support_radius) {
  // Images are at most 16384 px wide (CameraIntrinsics::validate), so a larger radius leaves
  // no interior pixel; the bound also keeps u + R and 2R + 1 far from int overflow.
  if (support_radius < 0 || support_radius > kMaxSupportRadius)
    throw InputError("support radius: must be in 0.." + std::to_string(kMaxSupportRadius) +
                     " pixels, got " + std::to_string(support_radius));
}

void CurvatureErrorAccumulator::add(const CurvatureImage& gt, const CurvatureImage& est,
                                    const Image<float>* sd) {
  if (gt.width() != est.width() || gt.height() != est.height()) {
    throw InputError("curvature maps differ in size: ground truth " + std::to_string(gt.width()) +
                     "x" + std::to_string(gt.height()) + ", estimate " +
                     std::to_string(est.width()) + "x" + std::to_string(est.height()));
  }
  if (sd && (sd->width() != est.width() || sd->height() != est.height()))
    throw InputError("the sd map is " + std::to_string(sd->width()) + "x" +
                     std::to_string(sd->height()) + " but its curvature map is " +
                     std::to_string(est.width()) + "x" + std::to_string(est.height()));
  const Image<unsigned char> interior =
      support_radius_ > 0 ? interior_mask(gt, support_radius_) : Image<unsigned char>();
  for (std::size_t i = 0; i < gt.size(); ++i) {
    if (!finite(gt[i]) || (support_radius_ > 0 && !interior[i])) continue;
    ++gt_valid_;
    if (!finite(est[i])) continue;
    const double d1 = est[i].x() - gt[i].x(), d2 = est[i].y() - gt[i].y();
    sum_k1_ += d1 * d1;
    sum_k2_ += d2 * d2;
    add_abs_error(std::abs(d1));
    add_abs_error(std::abs(d2));
    ++compared_;
    // A negative sd is no spread: the pixel is left out like a NaN one.
    if (sd && std::isfinite((*sd)[i]) && (*sd)[i] >= 0.0f) {
      const double s = (*sd)[i], e2 = (d1 * d1 + d2 * d2) / 2.0;
      sum_sd2_ += s * s;
      sum_e2_where_sd_ += e2;
      within_2sd_ += e2 < 4.0 * s * s ? 1 : 0;
      ++sd_compared_;
    }
  }
  ++frames_;
}

void CurvatureErrorAccumulator::add_abs_error(double e) {
  const double log_r = std::log1p(kMedianStep);
  if (abs_error_bins_.empty()) {
    const double bins = std::ceil(std::log(kMedianCeiling / kMedianFloor) / log_r) + 2;
    abs_error_bins_.assign(static_cast<std::size_t>(bins), 0);
  }
  std::size_t k = 0;
  if (e >= kMedianFloor) {  // false for NaN (never given: both maps are finite here)
    const double at = 1.0 + std::floor(std::log(e / kMedianFloor) / log_r);
    k = static_cast<std::size_t>(std::min(at, double(abs_error_bins_.size() - 1)));
  }
  ++abs_error_bins_[k];
}

CurvatureErrors CurvatureErrorAccumulator::result() const {
  CurvatureErrors r;
  r.frames = frames_;
  r.support_radius = support_radius_;
  r.compared = compared_;
  r.gt_valid = gt_valid_;
  r.coverage = gt_valid_ ? double(compared_) / gt_valid_ : 0.0;
  r.sd_compared = sd_compared_;
  if (sd_compared_ > 0) {
    r.sd_rms = std::sqrt(sum_sd2_ / double(sd_compared_));
    r.rms_where_sd = std::sqrt(sum_e2_where_sd_ / double(sd_compared_));
    r.within_2sd = double(within_2sd_) / double(sd_compared_);
  }
  if (compared_ == 0) {
    r.rms_k1 = r.rms_k2 = r.rms = r.median_abs = std::nan("");
    return r;
  }
  r.rms_k1 = std::sqrt(sum_k1_ / compared_);
  r.rms_k2 = std::sqrt(sum_k2_ / compared_);
  r.rms = std::sqrt((sum_k1_ + sum_k2_) / (2.0 * compared_));
  // The (n/2)-th smallest of the n = 2·compared errors (0-based), at its bin's geometric middle:
  // within r^½ − 1 ≈ 5e-5 relative of the exact value.
  const std::uint64_t wanted = compared_;  // = (2·compared) / 2
  std::uint64_t below = 0;
  std::size_t k = 0;
  while (below + abs_error_bins_[k] <= wanted)
    below += abs_error_bins_[k++];
  r.median_abs =
      k == 0 ? 0.0 : kMedianFloor * std::pow(1.0 + kMedianStep, static_cast<double>(k) - 0.5);
  return r;
}

}  // namespace jpcr
