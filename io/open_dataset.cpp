#include "jpcr/io/open_dataset.hpp"

#include <cctype>
#include <filesystem>
#include <optional>
#include <string>

#include "jpcr/io/camera_yaml.hpp"
#include "jpcr/io/number_format.hpp"
#include "jpcr/io/rawlog_dataset.hpp"
#include "jpcr/io/tum_dataset.hpp"
#include "jpcr/quadric/error.hpp"

namespace fs = std::filesystem;

namespace jpcr {

namespace {
// The camera a caller passes: the tools' --config.
constexpr const char* kGivenCamera = "the camera given (--config)";
}  // namespace

std::unique_ptr<FrameSource> open_dataset(const std::string& path,
                                          const std::optional<CameraIntrinsics>& camera,
                                          const DatasetParams& params) {
  std::error_code ec;
  if (fs::is_directory(path, ec)) {
    const fs::path dir(path);
    if (!fs::exists(dir / "depth.txt", ec) && !fs::exists(dir / "associations.txt", ec))
      throw InputError(path +
                       ": not a TUM RGB-D directory (no depth.txt or associations.txt in it)");
    std::optional<CameraIntrinsics> cam = camera;
    const fs::path own = fs::path(path) / "camera.yaml";
    if (!cam && fs::exists(own, ec)) cam = load_camera_yaml(own.string());
    // A camera given in place of the directory's own keeps its intrinsics (a calibration), but
    // the depth PNGs were written at the own file's scale: another one read every depth wrong
    // (a factor of 5 at 1000 against 5000) without a word. An own file that does not load is
    // the one the caller replaces.
    if (camera && fs::exists(own, ec)) {
      std::optional<CameraIntrinsics> written;
      try {
        written = load_camera_yaml(own.string());
      } catch (const InputError&) {
      }
      if (written && written->depth_scale != camera->depth_scale)
        throw InputError(path + ": the camera given has depth_scale " +
                         format_double(camera->depth_scale) + " but " + own.string() +
                         ", which the depth images were written with, has " +
                         format_double(written->depth_scale));
    }
    if (!cam) {
      throw InputError(path +
                       ": no camera given (pass --config CAM.yaml, e.g. configs/tum_fr1.yaml)");
    }
    TumDatasetOptions options;
    options.max_time_difference = params.max_time_difference;
    options.camera_source = camera ? std::string(kGivenCamera) : own.string();
    return std::make_unique<TumDataset>(path, *cam, options);
  }
  std::string extension = fs::path(path).extension().string();
  for (char& c : extension)
    c = static_cast<char>(std::tolower(static_cast<unsigned char>(c)));
  if (extension == ".rawlog") return std::make_unique<RawlogDataset>(path, camera);
  if (!fs::exists(path, ec)) throw InputError(path + ": dataset does not exist");
  throw InputError(path +
                   ": not a dataset (expected a TUM RGB-D directory or an MRPT .rawlog file)");
}

}  // namespace jpcr
