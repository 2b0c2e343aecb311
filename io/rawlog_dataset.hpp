// MRPT rawlogs as a depth source: every CObservation3DRangeScan with a range image, in either
// rawlog format (observations, or sensory frames), of one sensor, in time order. The intrinsics
// come from the observations' depth camera unless a camera file overrides them. Range images
// stored outside the rawlog are read from its images directory, as MRPT's tools find it
// (<name>_Images beside the file). Rawlogs carry no ground truth.
#pragma once

#include <memory>
#include <optional>
#include <string>
#include <vector>

#include "jpcr/io/frame_source.hpp"

namespace jpcr {

class DepthUndistortion;

class RawlogDataset final : public FrameSource {
 public:
  /// Loads the rawlog; throws InputError naming the file when it cannot be read, holds no 3-D
  /// range scan with a range image, holds scans of more than one sensor label, scans out of
  /// time order, or (without `camera`) scans whose intrinsics differ. `camera` overrides the
  /// intrinsics stored in the file (its size must match the range images); when it has lens
  /// distortion, the depth is rectified as a TUM directory's is (DepthUndistortion) and the
  /// frames' cameras carry none.
  explicit RawlogDataset(const std::string& path,
                         const std::optional<CameraIntrinsics>& camera = std::nullopt);
  ~RawlogDataset() override;

  std::size_t size() const override;
  double timestamp(std::size_t index) const override;
  /// Loads take turns (MRPT rewrites a scan's images as it loads them). For an externally
  /// stored range image, MRPT's process-wide images path (CImage::setImagesPathBase) is this
  /// rawlog's images directory during the load and is put back after it: a program that loads
  /// MRPT images on another thread at the same time may see it changed meanwhile.
  Frame load(std::size_t index) const override;
  std::optional<Eigen::Isometry3d> ground_truth(std::size_t) const override { return {}; }
  const CameraIntrinsics& camera() const override { return camera_; }
  std::string description() const override;

 private:
  struct Scans;
  std::string path_;
  std::string images_directory_;  // where externally stored range images are
  CameraIntrinsics camera_;
  std::unique_ptr<Scans> scans_;
  std::unique_ptr<DepthUndistortion> undistortion_;  // a --config camera with lens distortion
  std::vector<float> ray_lengths_;  // per raw pixel, when scans store ranges along the ray
};

/// Writes frames as a rawlog of CObservation3DRangeScan (range = depth, units 1/depth_scale of
/// each frame's camera, intrinsics from the frame), atomically. For tests and conversions.
void write_rawlog(const std::string& path, const std::vector<Frame>& frames);

}  // namespace jpcr
