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

  /// Ground truth of all frames that have one, at the frames' timestamps.
  Trajectory ground_truth_trajectory() const;
  /// Ground truth as recorded, at its own timestamps, for metrics that associate by time as the
  /// TUM tools do (a TUM directory: groundtruth.txt, ~100 Hz, whose gaps leave frames without
  /// one). By default, ground_truth_trajectory(). Evaluating against the frame-stamped ground
  /// truth instead would let RPE's tolerance (twice the median interval) pair a frame without
  /// ground truth with its neighbour's.
  virtual Trajectory recorded_ground_truth() const { return ground_truth_trajectory(); }
  /// recorded_ground_truth() from `max_difference` before frame `first` to as far after frame
  /// `last - 1` (a range of frames, as a run over part of a sequence uses).
  Trajectory recorded_ground_truth(std::size_t first, std::size_t last,
                                   double max_difference = 0.02) const;
};

}  // namespace jpcr
