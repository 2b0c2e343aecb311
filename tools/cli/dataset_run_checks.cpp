#include "cli/dataset_run_checks.hpp"

#include <filesystem>
#include <string>

#include "jpcr/io/staged_output.hpp"
#include "jpcr/quadric/error.hpp"

namespace jpcr::cli {

void check_dataset_run(const Arguments& args, const FrameSource& dataset,
                       const QuadricParams& quadric, bool fits_quadrics) {
  require_output_apart_from(args.get("out"), args.get("dataset"), "--dataset");
  if (fits_quadrics) check_quadric_pattern(args, quadric, dataset.camera().width);
}

void check_quadric_pattern(const Arguments& args, const QuadricParams& quadric, int width) {
  try {
    quadric.pattern_for(width);
  } catch (const InputError& e) {
    const bool file = args.has("params") && !args.get("params").empty();
    throw InputError((file ? args.get("params") : std::string("the built-in parameters")) +
                     ": quadric: " + e.what());
  }
}

void require_inputs_apart_from(const StagedOutput& out, const Arguments& args) {
  for (const char* input : {"dataset", "config", "params"})
    if (args.has(input)) out.require_apart_from(args.get(input), std::string("--") + input);
}

void require_not_results_of(const Arguments& args, const std::string& marker,
                            const std::string& program) {
  const std::string out = args.get("out");
  std::error_code ec;
  if (std::filesystem::exists(std::filesystem::path(out) / marker, ec))
    throw InputError(out + ": holds " + program + "'s results (" + marker +
                     "); writing there would replace some of them (give another --out)");
}

}  // namespace jpcr::cli
