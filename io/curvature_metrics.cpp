#include "jpcr/io/curvature_metrics.hpp"

#include <algorithm>
#include <cmath>
#include <string>

#include "jpcr/quadric/error.hpp"

namespace jpcr {

void CurvatureErrorAccumulator::add(const CurvatureImage& gt, const CurvatureImage& est) {
  if (gt.width() != est.width() || gt.height() != est.height()) {
    throw InputError("curvature maps differ in size: ground truth " + std::to_string(gt.width()) +
                     "x" + std::to_string(gt.height()) + ", estimate " +
                     std::to_string(est.width()) + "x" + std::to_string(est.height()));
  }
  for (std::size_t i = 0; i < gt.size(); ++i) {
    if (!std::isfinite(gt[i].x()) || !std::isfinite(gt[i].y())) continue;
    ++gt_valid_;
    if (!std::isfinite(est[i].x()) || !std::isfinite(est[i].y())) continue;
    const double d1 = est[i].x() - gt[i].x(), d2 = est[i].y() - gt[i].y();
    sum_k1_ += d1 * d1;
    sum_k2_ += d2 * d2;
    abs_errors_.push_back(static_cast<float>(std::abs(d1)));
    abs_errors_.push_back(static_cast<float>(std::abs(d2)));
    ++compared_;
  }
  ++frames_;
}

CurvatureErrors CurvatureErrorAccumulator::result() const {
  CurvatureErrors r;
  r.frames = frames_;
  r.compared = compared_;
  r.gt_valid = gt_valid_;
  r.coverage = gt_valid_ ? double(compared_) / gt_valid_ : 0.0;
  if (compared_ == 0) {
    r.rms_k1 = r.rms_k2 = r.rms = r.median_abs = std::nan("");
    return r;
  }
  r.rms_k1 = std::sqrt(sum_k1_ / compared_);
  r.rms_k2 = std::sqrt(sum_k2_ / compared_);
  r.rms = std::sqrt((sum_k1_ + sum_k2_) / (2.0 * compared_));
  std::vector<float> e = abs_errors_;
  std::nth_element(e.begin(), e.begin() + e.size() / 2, e.end());
  r.median_abs = e[e.size() / 2];
  return r;
}

}  // namespace jpcr
