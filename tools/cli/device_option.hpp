// The --device option of the programs that refine or fit (jpcr_run, jpcr_node, jpcr_curvature,
// jpcr_eval noise):
// where J-ftf and Quad IT run, on top of the parameter file's `device:` key (issue 7).
#pragma once

#include <string>

#include "cli/arguments.hpp"
#include "jpcr/cuda/device_selection.hpp"
#include "jpcr/io/params.hpp"
#include "jpcr/quadric/error.hpp"

namespace jpcr::cli {

/// `what`: the work --device places, in the program's words.
inline void add_device_option(Arguments& args, const std::string& what = "J-ftf and Quad IT") {
  args.option("device", "auto | cpu | cuda for " + what +
                            "; auto takes a usable GPU, else the CPU (default: the parameter "
                            "file's device:, auto)");
}

/// --device, else the parameter file's setting; a bad value is a UsageError.
inline ComputeDevice device_from(const Arguments& args, const Params& params) {
  if (!args.has("device")) return params.device;
  try {
    return parse_compute_device(args.get("device"));
  } catch (const InputError& e) {
    throw UsageError(std::string("--device: ") + e.what());
  }
}

}  // namespace jpcr::cli
