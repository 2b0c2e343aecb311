#include "jpcr/io/rawlog_dataset.hpp"

#include <fcntl.h>
#include <sys/wait.h>
#include <unistd.h>

#include <algorithm>
#include <cerrno>
#include <cmath>
#include <csignal>
#include <cstdio>
#include <filesystem>
#include <limits>
#include <mutex>
#include <set>

#include <mrpt/img/CImage.h>
#include <mrpt/io/CFileGZInputStream.h>
#include <mrpt/io/CFileGZOutputStream.h>
#include <mrpt/obs/CObservation3DRangeScan.h>
#include <mrpt/obs/CSensoryFrame.h>
#include <mrpt/serialization/CArchive.h>

#include "jpcr/io/depth_undistortion.hpp"
#include "jpcr/io/number_format.hpp"
#include "jpcr/quadric/error.hpp"

namespace jpcr {

using mrpt::obs::CObservation3DRangeScan;

struct RawlogDataset::Scans {
  std::vector<CObservation3DRangeScan::Ptr> observations;
};

namespace {

void collect(const mrpt::obs::CObservation::Ptr& o,
             std::vector<CObservation3DRangeScan::Ptr>& out) {
  auto scan = std::dynamic_pointer_cast<CObservation3DRangeScan>(o);
  if (scan && scan->hasRangeImage) out.push_back(scan);
}

CameraIntrinsics camera_of(const CObservation3DRangeScan& scan) {
  CameraIntrinsics c;
  const mrpt::img::TCamera& p = scan.cameraParams;
  c.fx = p.fx();
  c.fy = p.fy();
  c.cx = p.cx();
  c.cy = p.cy();
  c.width = static_cast<int>(p.ncols);
  c.height = static_cast<int>(p.nrows);
  c.depth_scale = 1.0 / static_cast<double>(scan.rangeUnits);
  for (std::size_t i = 0; i < c.distortion.size(); ++i)
    c.distortion[i] = p.dist[i];
  return c;
}

// Reads object by object (instead of CRawlog::loadFromRawLogFile, which prints MRPT's stack
// traces on bad input): EOF ends the file, any other failure is a corrupt rawlog.
void read_scans(const std::string& path, std::vector<CObservation3DRangeScan::Ptr>& out) {
  std::size_t objects = 0;
  try {
    mrpt::io::CFileGZInputStream file(path);
    auto archive = mrpt::serialization::archiveFrom(file);
    for (;; ++objects) {
      mrpt::serialization::CSerializable::Ptr object;
      try {
        archive >> object;
      } catch (const mrpt::serialization::CExceptionEOF&) {
        break;
      }
      if (auto o = std::dynamic_pointer_cast<mrpt::obs::CObservation>(object)) {
        collect(o, out);
      } else if (auto sf = std::dynamic_pointer_cast<mrpt::obs::CSensoryFrame>(object)) {
        for (const auto& so : *sf)
          collect(so, out);
      }
    }
  } catch (const std::exception&) {
    throw InputError(path + ": not a readable MRPT rawlog (object " + std::to_string(objects) +
                     " cannot be parsed)");
  }
}

// MRPT's reader trusts the sizes stored in the file: a corrupt range-image size or point count
// makes it write where it allocated nothing (SIGSEGV in CObservation3DRangeScan's
// rangeImage_setSize, measured on a rawlog with one size field changed), which no exception
// handler can catch. So the file is read once in a child process first; a child that does not
// come back with "read" or "refused" (a signal, or a sanitizer's report) means a rawlog that
// MRPT cannot read. The file is then read a second time, here, so a rawlog takes twice as long
// to open. The child runs MRPT code after fork(): a program that opens rawlogs while other
// threads of its own use MRPT should open them first.
void check_mrpt_survives(const std::string& path) {
  constexpr int kRead = 0, kRefused = 3;
  std::fflush(nullptr);  // nothing buffered twice
  const pid_t child = fork();
  if (child < 0) return;  // no process to spare: read it here, unguarded
  if (child == 0) {
    const int null = open("/dev/null", O_WRONLY);  // MRPT's and a sanitizer's noise
    if (null >= 0) {
      dup2(null, STDOUT_FILENO);
      dup2(null, STDERR_FILENO);
    }
    int code = kRead;
    try {
      std::vector<CObservation3DRangeScan::Ptr> scans;
      read_scans(path, scans);
    } catch (...) {
      code = kRefused;
    }
    _exit(code);
  }
  int status = 0;
  while (waitpid(child, &status, 0) < 0) {
    if (errno != EINTR) return;
  }
  if (WIFEXITED(status) && (WEXITSTATUS(status) == kRead || WEXITSTATUS(status) == kRefused))
    return;  // a refusal is reported by the read here, with its message
  if (WIFSIGNALED(status) && WTERMSIG(status) == SIGKILL)
    throw InputError(path +
                     ": the process reading it was killed (SIGKILL: out of memory, or "
                     "stopped from outside)");
  const std::string how = WIFSIGNALED(status) ? "signal " + std::to_string(WTERMSIG(status))
                                              : "exit code " + std::to_string(WEXITSTATUS(status));
  throw InputError(path + ": not a readable MRPT rawlog (MRPT's reader crashed on it, " + how +
                   ": a corrupt size field)");
}

// An MRPT exception's message without its call stack: the lines before "Call stack", minus the
// banner and empty fields, joined.
std::string mrpt_message(const std::exception& e) {
  std::string text = e.what();
  text = text.substr(0, text.find("Call stack"));
  std::string out;
  std::size_t start = 0;
  while (start < text.size()) {
    std::size_t end = text.find('\n', start);
    if (end == std::string::npos) end = text.size();
    std::string line = text.substr(start, end - start);
    start = end + 1;
    for (const char* prefix : {"Message: ", "Location: "})
      if (line.rfind(prefix, 0) == 0) line.erase(0, std::char_traits<char>::length(prefix));
    if (line.empty() || line.find("MRPT exception") != std::string::npos) continue;
    out += (out.empty() ? "" : "; ") + line;
  }
  return out.empty() ? text : out;
}

// Where MRPT's tools keep a rawlog's externally stored images: the first of <name>_Images,
// <name>_images, <name>_IMAGES and Images beside it that exists, else <name>_Images.
std::string images_directory_of(const std::string& rawlog) {
  namespace fs = std::filesystem;
  const fs::path file(rawlog);
  const std::string stem = file.stem().string();
  std::error_code ec;
  for (const std::string& name :
       {stem + "_Images", stem + "_images", stem + "_IMAGES", std::string("Images")})
    if (fs::is_directory(file.parent_path() / name, ec))
      return (file.parent_path() / name).string();
  return (file.parent_path() / (stem + "_Images")).string();
}

// The scans must be one sensor's, in time order, with one camera: a rawlog of two cameras, or
// one joined out of order, would otherwise be tracked as one camera jumping between views.
void check_scans(const std::string& path, const std::vector<CObservation3DRangeScan::Ptr>& scans,
                 bool check_cameras) {
  std::set<std::string> labels;
  for (const auto& scan : scans)
    labels.insert(scan->sensorLabel);
  if (labels.size() > 1) {
    std::string names;
    for (const std::string& l : labels)
      names += (names.empty() ? "'" : ", '") + l + "'";
    throw InputError(path + ": the rawlog holds range scans of " + std::to_string(labels.size()) +
                     " sensors (" + names +
                     "); jpcr tracks one camera (keep one with MRPT's rawlog-edit --keep-label)");
  }
  const CameraIntrinsics first = camera_of(*scans.front());
  for (std::size_t i = 1; i < scans.size(); ++i) {
    const double t0 = mrpt::Clock::toDouble(scans[i - 1]->timestamp);
    const double t1 = mrpt::Clock::toDouble(scans[i]->timestamp);
    if (!(t1 > t0))
      throw InputError(path + ": scan " + std::to_string(i) + " (t = " + std::to_string(t1) +
                       ") is not after scan " + std::to_string(i - 1) +
                       " (t = " + std::to_string(t0) + "): the scans must be in time order");
    const CameraIntrinsics c = camera_of(*scans[i]);
    if (check_cameras && !same_pinhole(c, first))
      throw InputError(path + ": scan " + std::to_string(i) + "'s camera differs from scan 0's (" +
                       describe(c) + " against " + describe(first) +
                       "); give one with --config to use it for every scan");
  }
}

}  // namespace

RawlogDataset::RawlogDataset(const std::string& path, const std::optional<CameraIntrinsics>& camera)
    : path_(path), scans_(std::make_unique<Scans>()) {
  std::error_code ec;
  if (!std::filesystem::exists(path, ec)) throw InputError(path + ": file does not exist");
  if (!std::filesystem::is_regular_file(path, ec))
    throw InputError(path + ": not a regular file (a rawlog is read twice, so no pipe or device)");
  check_mrpt_survives(path);
  read_scans(path, scans_->observations);
  if (scans_->observations.empty()) {
    throw InputError(path + ": the rawlog holds no CObservation3DRangeScan with a range image");
  }
  check_scans(path, scans_->observations, !camera);
  images_directory_ = images_directory_of(path);
  camera_ = camera ? *camera : camera_of(*scans_->observations.front());
  if (!camera) camera_.distortion = {};  // MRPT range images are used as stored
  try {
    camera_.validate();
  } catch (const std::invalid_argument& e) {
    throw InputError(path + ": invalid camera in the rawlog: " + e.what());
  }
  // Only a given camera has distortion here (the rawlog's own is used as stored).
  if (camera_.has_distortion())
    undistortion_ =
        std::make_unique<DepthUndistortion>(camera_, path + " with the camera given (--config)");
  const auto& scans = scans_->observations;
  if (std::any_of(scans.begin(), scans.end(), [](const auto& s) { return !s->range_is_depth; }))
    ray_lengths_ = DepthUndistortion::ray_lengths(camera_);
}

RawlogDataset::~RawlogDataset() = default;

std::size_t RawlogDataset::size() const {
  return scans_->observations.size();
}

double RawlogDataset::timestamp(std::size_t index) const {
  return mrpt::Clock::toDouble(scans_->observations.at(index)->timestamp);
}

Frame RawlogDataset::load(std::size_t index) const {
  const CObservation3DRangeScan& scan = *scans_->observations.at(index);
  const std::string where = path_ + ": scan " + std::to_string(index) + ": ";
  // MRPT's load() rewrites the scan's images in place and finds externally stored ones through
  // its process-wide images path. So loads through jpcr take turns, with that path set to this
  // rawlog's images directory and put back however the load ends, and an external image is
  // unloaded again once copied: the scans hold no more than the rawlog itself.
  static std::mutex mrpt_load;
  const std::lock_guard<std::mutex> lock(mrpt_load);
  struct ImagesPath {
    explicit ImagesPath(const std::string& path) : before(mrpt::img::CImage::getImagesPathBase()) {
      mrpt::img::CImage::setImagesPathBase(path);
    }
    ~ImagesPath() { mrpt::img::CImage::setImagesPathBase(before); }
    const std::string before;
  } images_path(images_directory_);
  const bool external = scan.rangeImage_isExternallyStored();
  try {
    if (external) {
      const std::string file = scan.rangeImage_getExternalStorageFileAbsolutePath("");
      std::error_code ec;
      if (!std::filesystem::is_regular_file(file, ec))
        throw InputError(where + "its range image is stored in " + file +
                         ", which is not a file (MRPT looks in the rawlog's images directory, " +
                         images_directory_ + ")");
    }
    scan.load();
  } catch (const InputError&) {
    throw;
  } catch (const std::exception& e) {
    throw InputError(where + mrpt_message(e));
  }
  const auto& range = scan.rangeImage;
  if (range.cols() != camera_.width || range.rows() != camera_.height) {
    throw InputError(where + "it is " + std::to_string(range.cols()) + "x" +
                     std::to_string(range.rows()) + " but the camera is " +
                     std::to_string(camera_.width) + "x" + std::to_string(camera_.height));
  }
  const double units = scan.rangeUnits;
  if (!(units > 0.0) || !std::isfinite(units)) {
    if (external) scan.unload();
    throw InputError(where + "its rangeUnits (" + format_double(units) +
                     ") is not a positive length in metres per unit");
  }
  Frame frame;
  frame.timestamp = timestamp(index);
  frame.camera = camera_;
  frame.depth = DepthImage(camera_.width, camera_.height, 0.0f);
  for (int v = 0; v < camera_.height; ++v) {
    for (int u = 0; u < camera_.width; ++u) {
      double value = range(v, u) * units;
      if (!scan.range_is_depth && value > 0.0)  // a range along the ray: depth = range / |ray|
        value /= ray_lengths_[static_cast<std::size_t>(v) * camera_.width + u];
      frame.depth(u, v) = static_cast<float>(value);
    }
  }
  if (external) scan.unload();
  if (undistortion_) {
    undistortion_->apply(frame.depth);
    frame.camera.distortion = {};  // the depth as delivered is rectified (same K)
  }
  return frame;
}

std::string RawlogDataset::description() const {
  return "MRPT rawlog " + path_ + ": " + std::to_string(size()) + " 3-D range scans, " +
         std::to_string(camera_.width) + "x" + std::to_string(camera_.height) + ", no ground truth";
}

void write_rawlog(const std::string& path, const std::vector<Frame>& frames) {
  const std::string tmp = path + ".tmp";
  try {
    mrpt::io::CFileGZOutputStream file(tmp);
    auto archive = mrpt::serialization::archiveFrom(file);
    for (const Frame& frame : frames) {
      auto scan = CObservation3DRangeScan::Create();
      const CameraIntrinsics& c = frame.camera;
      scan->timestamp = mrpt::Clock::fromDouble(frame.timestamp);
      scan->sensorLabel = "jpcr_depth";
      scan->hasRangeImage = true;
      scan->range_is_depth = true;
      scan->rangeUnits = static_cast<float>(1.0 / c.depth_scale);
      scan->rangeImage_setSize(frame.depth.height(), frame.depth.width());
      for (int v = 0; v < frame.depth.height(); ++v) {
        for (int u = 0; u < frame.depth.width(); ++u) {
          const double raw = static_cast<double>(frame.depth(u, v)) * c.depth_scale;
          scan->rangeImage(v, u) = (std::isfinite(raw) && raw > 0.0 && raw < 65535.5)
                                       ? static_cast<std::uint16_t>(std::lround(raw))
                                       : 0;
        }
      }
      scan->cameraParams.ncols = static_cast<uint32_t>(c.width);
      scan->cameraParams.nrows = static_cast<uint32_t>(c.height);
      scan->cameraParams.setIntrinsicParamsFromValues(c.fx, c.fy, c.cx, c.cy);
      for (std::size_t i = 0; i < c.distortion.size(); ++i)
        scan->cameraParams.dist[i] = c.distortion[i];
      scan->cameraParamsIntensity = scan->cameraParams;
      archive << *scan;
    }
  } catch (const std::exception& e) {
    std::filesystem::remove(tmp);
    throw InputError(path + ": cannot write the rawlog (" + std::string(e.what()) + ")");
  }
  std::error_code ec;
  std::filesystem::rename(tmp, path, ec);
  if (ec) {
    std::filesystem::remove(tmp);
    throw InputError(path + ": cannot be renamed into place (" + ec.message() + ")");
  }
}

}  // namespace jpcr
