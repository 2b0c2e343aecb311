// Checks of a dataset run's inputs, made before the run starts (jpcr_run, jpcr_curvature), so
// that a mistake costs no run and names what to change.
#pragma once

#include "cli/arguments.hpp"
#include "jpcr/io/frame_source.hpp"
#include "jpcr/io/staged_output.hpp"
#include "jpcr/quadric/quadric_params.hpp"

namespace jpcr::cli {

/// Throws InputError when --out is the --dataset directory itself (writing there would replace
/// the dataset's own curvature/ ground truth), or, for a run that fits quadrics
/// (`fits_quadrics`), when check_quadric_pattern refuses the dataset's width.
void check_dataset_run(const Arguments& args, const FrameSource& dataset,
                       const QuadricParams& quadric, bool fits_quadrics = true);

/// Throws InputError when the quadric pattern cannot be scaled to images `width` px wide or then
/// has fewer samples than min_samples, named with the --params file or "the built-in parameters".
void check_quadric_pattern(const Arguments& args, const QuadricParams& quadric, int width);

/// Throws InputError when --dataset, --config or --params lies in one of the entries of OUT
/// that `out` replaces (StagedOutput::require_apart_from).
void require_inputs_apart_from(const StagedOutput& out, const Arguments& args);

/// Throws InputError when --out holds another program's results, told by its `marker` file
/// (jpcr_curvature's summary.json, jpcr_run's report.json): the two share curvature/, so writing
/// there would replace that program's maps and leave its marker describing maps that are gone.
void require_not_results_of(const Arguments& args, const std::string& marker,
                            const std::string& program);

}  // namespace jpcr::cli
