// A sequence of depth frames with optional ground truth: a TUM directory, an MRPT rawlog, a
// synthetic sequence. Tools open any of them through open_dataset().
#pragma once

#include <cstddef>
#include <memory>
#include <optional>
#include <string>

#include "jpcr/quadric/frame.hpp"

namespace jpcr {

class FrameSource {
 public:
  virtual ~FrameSource() = default;

  virtual std::size_t size() const = 0;
  virtual double timestamp(std::size_t index) const = 0;
  /// Loads frame `index`; throws InputError naming the file on bad data.
  virtual Frame load(std::size_t index) const = 0;
  /// Camera-to-world ground-truth pose associated with frame `index`, when there is one.
  virtual std::optional<Eigen::Isometry3d> ground_truth(std::size_t index) const = 0;
  virtual const CameraIntrinsics& camera() const = 0;
  /// A short description for logs ("TUM directory data/fr1_xyz, 300 frames").
  virtual std::string description() const = 0;

  /// Ground truth of all frames that have one.
  Trajectory ground_truth_trajectory() const;
};

}  // namespace jpcr
