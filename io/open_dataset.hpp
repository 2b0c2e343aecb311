// One entry point for every dataset kind a program accepts as --dataset:
//   - a TUM RGB-D directory (depth.txt; jpcr_synth writes this layout too),
//   - an MRPT rawlog file (*.rawlog).
#pragma once

#include <memory>
#include <optional>
#include <string>

#include "jpcr/io/frame_source.hpp"
#include "jpcr/io/params.hpp"

namespace jpcr {

/// Opens `path`. `camera` is the --config camera; when absent, a TUM directory's own camera.yaml
/// (written by jpcr_synth) or a rawlog's stored intrinsics are used. Throws InputError naming the
/// path when it is neither kind, or no camera is known.
std::unique_ptr<FrameSource> open_dataset(const std::string& path,
                                          const std::optional<CameraIntrinsics>& camera,
                                          const DatasetParams& params = {});

}  // namespace jpcr
