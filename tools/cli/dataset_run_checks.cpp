#include "cli/dataset_run_checks.hpp"

#include <string>

#include "jpcr/io/staged_output.hpp"
#include "jpcr/quadric/error.hpp"

namespace jpcr::cli {

void check_dataset_run(const Arguments& args, const FrameSource& dataset,
                       const PatternParams& pattern) {
  require_output_apart_from(args.get("out"), args.get("dataset"), "--dataset");
  try {
    pattern.for_width(dataset.camera().width);
  } catch (const InputError& e) {
    const bool file = args.has("params") && !args.get("params").empty();
    throw InputError((file ? args.get("params") : std::string("the built-in parameters")) +
                     ": quadric: " + e.what());
  }
}

}  // namespace jpcr::cli
