// Writes a synthetic sequence in the TUM RGB-D layout, with its exact ground truth, so every tool
// reads generated and real data the same way (evaluation.md "Data"):
//
//   DIR/depth/<stamp>.png       16-bit depth at camera.depth_scale (5000 = 0.2 mm), 0 = none
//   DIR/rgb/<stamp>.png         colour shaded by normal (shade_normals)
//   DIR/curvature/<stamp>.npy   float32 H×W×2: κ1 ≥ κ2 in 1/m, NaN where undefined
//   DIR/normals/<stamp>.npy     float32 H×W×3: unit normals in camera axes toward the camera
//   DIR/depth.txt, rgb.txt      TUM file lists; <stamp> is the timestamp text written there
//   DIR/groundtruth.txt         exact camera-to-world poses at full precision
//   DIR/camera.yaml             the intrinsics, for --config DIR/camera.yaml
// Each file is written atomically, and depth.txt last: a run that stops early leaves no list, so
// the directory never passes for a complete sequence.
#pragma once

#include <cstddef>
#include <functional>
#include <string>

#include "jpcr/io/synthetic_sequence.hpp"

namespace jpcr {

struct SyntheticWriterOptions {
  bool force = false;   // write into a non-empty directory (files of the layout are replaced)
  std::string comment;  // '#' header of depth.txt and groundtruth.txt, e.g. the command line
  std::function<void(std::size_t done, std::size_t total)> progress;  // called after each frame
};

/// What was written: frames, and those whose depth PNG holds no depth at all (nothing in view,
/// or all of it beyond the PNG's range, 65535 / depth_scale: 13.1 m at the TUM scale).
struct SyntheticWriteSummary {
  std::size_t frames = 0;
  std::size_t frames_without_depth = 0;
};

/// Throws InputError naming the directory when it is not empty (unless options.force), is not a
/// directory, or cannot be written; with options.force also when it holds another program's
/// results (report.json, summary.json) or a dataset the generator did not write (a depth.txt
/// without normals/).
SyntheticWriteSummary write_synthetic_sequence(const SyntheticSequence& sequence,
                                               const std::string& directory,
                                               const SyntheticWriterOptions& options = {});

/// The timestamp text of the file lists and file names: 6 decimals, as TUM ("0.033333").
std::string format_stamp(double timestamp);

}  // namespace jpcr
