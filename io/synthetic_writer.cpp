#include "jpcr/io/synthetic_writer.hpp"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <future>
#include <sstream>

#include "jpcr/io/atomic_file.hpp"
#include "jpcr/io/camera_yaml.hpp"
#include "jpcr/io/depth_png.hpp"
#include "jpcr/io/npy.hpp"
#include "jpcr/io/staged_output.hpp"
#include "jpcr/io/tum_lists.hpp"
#include "jpcr/quadric/error.hpp"

namespace fs = std::filesystem;

namespace jpcr {

namespace {

static_assert(sizeof(Eigen::Vector2f) == 2 * sizeof(float), "curvature pixels must be packed");
static_assert(sizeof(Eigen::Vector3f) == 3 * sizeof(float), "normal pixels must be packed");

// The checks of write_synthetic_sequence's target (the writing goes to a staging directory).
void check_directory(const std::string& directory, bool force) {
  std::error_code ec;
  if (fs::exists(directory, ec)) {
    if (!fs::is_directory(directory, ec)) {
      throw InputError(directory + ": output path exists and is not a directory");
    }
    if (!force && !fs::is_empty(directory, ec)) {
      throw InputError(directory +
                       ": output directory is not empty (use --force to write into it)");
    }
    // --force replaces the entries of a sequence, not another program's: the results of jpcr_run
    // or jpcr_curvature would lose their maps and keep reports that describe them, and a
    // recorded dataset its depth. A generated sequence has normals/ beside depth.txt; no
    // recording does.
    if (force) {
      for (const auto& [marker, program] :
           {std::pair<const char*, const char*>{"report.json", "jpcr_run"},
            {"summary.json", "jpcr_curvature"}})
        if (fs::exists(fs::path(directory) / marker, ec))
          throw InputError(directory + ": holds " + program + "'s results (" + marker +
                           "); --force would replace some of them (give another --out)");
      if (fs::exists(fs::path(directory) / "depth.txt", ec) &&
          !fs::is_directory(fs::path(directory) / "normals", ec))
        throw InputError(directory +
                         ": holds a dataset that jpcr_synth did not write (depth.txt without the "
                         "generator's normals/); --force replaces only generated sequences (give "
                         "another --out)");
    }
    // --force replaces the entries written; TUM readers take an associations.txt before
    // depth.txt and rgb.txt, and an old one would pair the old frames (gone) or only some.
    const fs::path associations = fs::path(directory) / "associations.txt";
    if (fs::exists(associations, ec)) {
      throw InputError(associations.string() +
                       ": would stay beside the new depth.txt and rgb.txt, and readers take it "
                       "first (remove it, or write elsewhere)");
    }
  }
}

// A TUM file list: "# comment" lines, a header, then "<stamp> <folder>/<stamp>.<ext>".
std::string file_list(const std::vector<std::string>& stamps, const std::string& folder,
                      const std::string& extension, const std::string& comment) {
  std::ostringstream out;
  std::istringstream comments(comment);
  for (std::string line; std::getline(comments, line);)
    out << "# " << line << '\n';
  out << "# timestamp filename\n";
  for (const std::string& stamp : stamps)
    out << stamp << ' ' << folder << '/' << stamp << extension << '\n';
  return out.str();
}

void write_text(const std::string& path, const std::string& text) {
  write_file_atomically(path, [&](std::ostream& out) { out << text; });
}

// The frames, lists, trajectory and camera of `sequence` into `dir` (staging); errors of the
// frames' consistency name `directory`.
void write_staged_sequence(const SyntheticSequence& sequence, const fs::path& dir,
                           const std::string& directory, const SyntheticWriterOptions& options,
                           SyntheticWriteSummary& summary) {
  for (const char* sub : {"depth", "rgb", "curvature", "normals"})
    ensure_directory((dir / sub).string());
  const CameraIntrinsics& camera = sequence.camera();
  const std::size_t width = static_cast<std::size_t>(camera.width);
  const std::size_t height = static_cast<std::size_t>(camera.height);
  const auto write_frame = [&](const SyntheticFrame& f, const std::string& stamp) {
    save_depth_png((dir / "depth" / (stamp + ".png")).string(), f.frame.depth, camera.depth_scale);
    // What the PNG holds (save_depth_png: 0 < depth · scale < 65535.5): a scene beyond 13.1 m at
    // the TUM scale, or out of view, is no depth at all.
    const bool any = std::any_of(f.frame.depth.begin(), f.frame.depth.end(), [&](float z) {
      const double value = static_cast<double>(z) * camera.depth_scale;
      return std::isfinite(value) && value >= 0.5 && value < 65535.5;
    });
    if (!any) ++summary.frames_without_depth;
    save_color_png((dir / "rgb" / (stamp + ".png")).string(), f.frame.color);
    write_npy((dir / "curvature" / (stamp + ".npy")).string(), {height, width, 2},
              f.curvature.data()->data());
    write_npy((dir / "normals" / (stamp + ".npy")).string(), {height, width, 3},
              f.normals.data()->data());
  };
  // Frame i is encoded and written on a second thread while frame i + 1 is rendered.
  std::vector<std::string> stamps;
  std::future<void> writing;
  for (std::size_t i = 0; i < sequence.size(); ++i) {
    SyntheticFrame f = sequence.render(i);
    const std::string stamp = format_stamp(f.frame.timestamp);
    if (!stamps.empty() && stamp == stamps.back()) {
      throw InputError(directory + ": frames " + std::to_string(i - 1) + " and " +
                       std::to_string(i) + " share the timestamp " + stamp +
                       " at 1 us resolution (check the trajectory's rate and start_time)");
    }
    stamps.push_back(stamp);
    if (writing.valid()) {
      writing.get();  // rethrows a failed write
      if (options.progress) options.progress(i, sequence.size());
    }
    writing = std::async(std::launch::async,
                         [&write_frame, f = std::move(f), stamp] { write_frame(f, stamp); });
  }
  writing.get();
  if (options.progress) options.progress(sequence.size(), sequence.size());
  write_text((dir / "rgb.txt").string(), file_list(stamps, "rgb", ".png", options.comment));
  write_trajectory((dir / "groundtruth.txt").string(), sequence.trajectory(), options.comment);
  write_text((dir / "camera.yaml").string(),
             "# " + sequence.description() + "\n" + format_camera_yaml(camera));
  write_text((dir / "depth.txt").string(), file_list(stamps, "depth", ".png", options.comment));
}

}  // namespace

std::string format_stamp(double timestamp) {
  char text[64];
  std::snprintf(text, sizeof(text), "%.6f", timestamp);
  return text;
}

SyntheticWriteSummary write_synthetic_sequence(const SyntheticSequence& sequence,
                                               const std::string& directory,
                                               const SyntheticWriterOptions& options) {
  check_directory(directory, options.force);
  // Written whole or not at all: into a staging directory, moved into `directory` at the end
  // (with force, the entries written replace those of the same names there).
  StagedOutput out(directory, {});
  const fs::path dir(out.directory());
  // Its errors name `directory`, the user's, not the staging directory gone when they read it.
  SyntheticWriteSummary summary;
  out.write([&] { write_staged_sequence(sequence, dir, directory, options, summary); });
  out.commit();
  summary.frames = sequence.size();
  return summary;
}

}  // namespace jpcr
