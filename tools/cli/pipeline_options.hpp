// The pipeline's command-line options shared by jpcr_run and jpcr_node: --params, --method and
// --window on top of the parameter file (sections frontend, quadric, joint, pipeline).
#pragma once

#include <string>

#include "cli/arguments.hpp"
#include "jpcr/io/params.hpp"
#include "jpcr/quadric/error.hpp"

namespace jpcr::cli {

/// The parameter file (or the built-in defaults) with --method and --window applied; a bad flag
/// is a UsageError, a bad file an InputError naming it.
inline PipelineParams pipeline_params_from(const Arguments& args, Params* loaded = nullptr) {
  const Params params = args.has("params") ? load_params(args.get("params")) : Params{};
  if (loaded) *loaded = params;
  PipelineParams pipeline = params.pipeline;
  try {
    if (args.has("method")) pipeline.method = parse_pipeline_method(args.get("method"));
  } catch (const jpcr::InputError& e) {
    throw UsageError(std::string("--method: ") + e.what());
  }
  if (args.has("window")) pipeline.window = args.get_int("window");
  if (pipeline.window < 2 || pipeline.window > kMaxWindowFrames)
    throw UsageError("--window must be in [2, " + std::to_string(kMaxWindowFrames) + "]");
  return pipeline;
}

}  // namespace jpcr::cli
