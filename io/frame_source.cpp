#include "jpcr/io/frame_source.hpp"

namespace jpcr {

Trajectory FrameSource::ground_truth_trajectory() const {
  Trajectory trajectory;
  for (std::size_t i = 0; i < size(); ++i) {
    if (const auto pose = ground_truth(i)) trajectory.push_back({timestamp(i), *pose});
  }
  return trajectory;
}

Trajectory FrameSource::recorded_ground_truth(std::size_t first, std::size_t last,
                                              double max_difference) const {
  Trajectory trajectory;
  if (first >= last || last > size()) return trajectory;
  const double begin = timestamp(first) - max_difference,
               end = timestamp(last - 1) + max_difference;
  for (const StampedPose& p : recorded_ground_truth())
    if (p.timestamp >= begin && p.timestamp <= end) trajectory.push_back(p);
  return trajectory;
}

}  // namespace jpcr
