#include "jpcr/io/frame_source.hpp"

namespace jpcr {

Trajectory FrameSource::ground_truth_trajectory() const {
  Trajectory trajectory;
  for (std::size_t i = 0; i < size(); ++i) {
    if (const auto pose = ground_truth(i)) trajectory.push_back({timestamp(i), *pose});
  }
  return trajectory;
}

}  // namespace jpcr
