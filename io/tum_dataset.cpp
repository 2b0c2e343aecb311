#include "jpcr/io/tum_dataset.hpp"

#include <cmath>
#include <filesystem>
#include <sstream>

#include "jpcr/io/atomic_file.hpp"
#include "jpcr/io/depth_png.hpp"
#include "jpcr/io/depth_undistortion.hpp"
#include "jpcr/io/timestamp_association.hpp"
#include "jpcr/quadric/error.hpp"

namespace fs = std::filesystem;

namespace jpcr {

namespace {

std::vector<double> stamps(const std::vector<ListEntry>& entries) {
  std::vector<double> out;
  for (const ListEntry& e : entries)
    out.push_back(e.timestamp);
  return out;
}

// associations.txt lines are "t_a file_a t_b file_b"; the depth side is the one whose file
// lies under depth/. Returns the depth list and the matching colour files.
void read_associations(const std::string& path, std::vector<ListEntry>& depth,
                       std::vector<std::optional<std::string>>& color) {
  const std::string text = read_file(path);
  std::istringstream in(without_utf8_bom(text));
  std::string line;
  int number = 0;
  std::string previous_line;
  for (; std::getline(in, line);) {
    ++number;
    if (line.find('\0') != std::string::npos)  // it would cut a file name short (tum_lists.cpp)
      throw InputError(path + ":" + std::to_string(number) +
                       ": holds a NUL byte (a binary file, not a text list?)");
    const auto first = line.find_first_not_of(" \t\r");
    if (first == std::string::npos || line[first] == '#') {
      previous_line += "\n";  // keeps the list parser's line numbers those of this file
      continue;
    }
    std::istringstream fields(line);
    std::string t_a, f_a, t_b, f_b;
    if (!(fields >> t_a >> f_a >> t_b >> f_b)) {
      throw InputError(path + ":" + std::to_string(number) +
                       ": expected 'timestamp file timestamp file'");
    }
    const bool a_is_depth = f_a.rfind("depth", 0) == 0;
    const bool b_is_depth = f_b.rfind("depth", 0) == 0;
    if (a_is_depth == b_is_depth) {
      throw InputError(path + ":" + std::to_string(number) +
                       ": cannot tell which file is the depth image (expected one under depth/)");
    }
    const std::string entry = a_is_depth ? t_a + " " + f_a : t_b + " " + f_b;
    previous_line += entry + "\n";
    color.emplace_back(a_is_depth ? f_b : f_a);
  }
  // Reuse the list parser for number and order checks, with line numbers of this file.
  depth = parse_file_list(previous_line, path);
}

}  // namespace

TumDataset::TumDataset(const std::string& directory, const CameraIntrinsics& camera,
                       const TumDatasetOptions& options)
    : directory_(directory), camera_(camera), options_(options) {
  std::error_code ec;
  if (!fs::is_directory(directory, ec)) {
    throw InputError(directory + ": dataset directory does not exist");
  }
  const fs::path dir(directory);
  const fs::path associations = dir / "associations.txt";
  if (fs::exists(associations, ec)) {
    read_associations(associations.string(), depth_, color_);
  } else {
    const fs::path depth_list = dir / "depth.txt";
    if (!fs::exists(depth_list, ec)) {
      throw InputError(depth_list.string() + ": file does not exist (not a TUM RGB-D directory)");
    }
    depth_ = read_file_list(depth_list.string());
    color_.assign(depth_.size(), std::nullopt);
    const fs::path rgb_list = dir / "rgb.txt";
    if (options_.load_color && fs::exists(rgb_list, ec)) {
      const std::vector<ListEntry> rgb = read_file_list(rgb_list.string());
      for (const auto& [i, j] :
           associate_timestamps(stamps(depth_), stamps(rgb), options_.max_time_difference)) {
        color_[i] = rgb[j].path;
      }
    }
  }
  if (depth_.empty()) throw InputError(directory + ": the sequence has no depth frames");
  // Every listed depth image exists: a missing one found only when its frame is reached would
  // cost the run up to it.
  for (std::size_t i = 0; i < depth_.size(); ++i)
    if (!fs::is_regular_file(dir / depth_[i].path, ec))
      throw InputError((dir / depth_[i].path).string() +
                       (fs::exists(dir / depth_[i].path, ec)
                            ? ": not a regular file (a pipe, a device or a directory; frame "
                            : ": file does not exist (frame ") +
                       std::to_string(i) + " of the " +
                       (fs::exists(associations, ec) ? "associations.txt" : "depth.txt") +
                       " list)");

  ground_truth_.assign(depth_.size(), std::nullopt);
  const fs::path gt_path = dir / "groundtruth.txt";
  if (fs::exists(gt_path, ec)) {
    recorded_ground_truth_ = read_trajectory(gt_path.string());
    const Trajectory& gt = recorded_ground_truth_;
    std::vector<double> gt_stamps;
    for (const StampedPose& p : gt)
      gt_stamps.push_back(p.timestamp);
    for (const auto& [i, j] :
         associate_timestamps(stamps(depth_), gt_stamps, options_.max_time_difference)) {
      ground_truth_[i] = gt[j].pose;
    }
  }

  // Built once per dataset when the camera has distortion coefficients.
  if (camera_.has_distortion())
    undistortion_ = std::make_unique<DepthUndistortion>(
        camera_, options_.camera_source.empty() ? directory_
                                                : directory_ + " with " + options_.camera_source);
}

TumDataset::~TumDataset() = default;

std::string TumDataset::depth_path(std::size_t index) const {
  return (fs::path(directory_) / depth_.at(index).path).string();
}

Frame TumDataset::load(std::size_t index) const {
  Frame frame;
  frame.timestamp = depth_.at(index).timestamp;
  frame.camera = camera_;
  frame.depth =
      load_depth_png(depth_path(index), camera_.depth_scale, camera_.width, camera_.height);
  if (undistortion_) {
    undistortion_->apply(frame.depth);
    frame.camera.distortion = {};  // the depth as delivered is rectified (same K)
  }
  if (options_.load_color && color_[index]) {
    frame.color = load_color_image((fs::path(directory_) / *color_[index]).string(), camera_.width,
                                   camera_.height);
  }
  return frame;
}

std::optional<Eigen::Isometry3d> TumDataset::ground_truth(std::size_t index) const {
  return ground_truth_.at(index);
}

std::string TumDataset::description() const {
  std::size_t with_gt = 0;
  for (const auto& g : ground_truth_)
    with_gt += g ? 1 : 0;
  return "TUM directory " + directory_ + ": " + std::to_string(depth_.size()) + " depth frames, " +
         std::to_string(with_gt) + " with ground truth";
}

}  // namespace jpcr
