// A TUM RGB-D sequence directory: depth.txt (required), rgb.txt, groundtruth.txt and
// associations.txt (optional). Depth frames are associated with ground truth (and colour) by
// timestamp within max_time_difference, as the TUM tools do.
#pragma once

#include <memory>
#include <string>
#include <vector>

#include "jpcr/io/frame_source.hpp"
#include "jpcr/io/tum_lists.hpp"

namespace jpcr {

struct TumDatasetOptions {
  double max_time_difference = 0.02;  // s, association window for ground truth and colour
  bool load_color = false;            // also load the associated rgb/ image
  std::string camera_source;  // where the camera came from, for its errors ("": the directory)
};

class DepthUndistortion;

class TumDataset final : public FrameSource {
 public:
  /// Reads and checks the lists; throws InputError naming the file and line on a problem
  /// (missing directory or depth.txt, malformed or unsorted list, empty sequence).
  TumDataset(const std::string& directory, const CameraIntrinsics& camera,
             const TumDatasetOptions& options = {});
  ~TumDataset() override;

  std::size_t size() const override { return depth_.size(); }
  double timestamp(std::size_t index) const override { return depth_.at(index).timestamp; }
  Frame load(std::size_t index) const override;
  std::optional<Eigen::Isometry3d> ground_truth(std::size_t index) const override;
  /// groundtruth.txt as read (empty without one).
  Trajectory recorded_ground_truth() const override { return recorded_ground_truth_; }
  using FrameSource::recorded_ground_truth;
  const CameraIntrinsics& camera() const override { return camera_; }
  std::string description() const override;

  /// Path of the depth image of frame `index`.
  std::string depth_path(std::size_t index) const;

 private:
  std::string directory_;
  CameraIntrinsics camera_;
  TumDatasetOptions options_;
  std::vector<ListEntry> depth_;
  std::vector<std::optional<std::string>> color_;  // per depth frame
  std::vector<std::optional<Eigen::Isometry3d>> ground_truth_;
  Trajectory recorded_ground_truth_;
  std::unique_ptr<DepthUndistortion> undistortion_;  // with lens distortion
};

}  // namespace jpcr
