// An output directory written whole or not at all. A program writes into a staging directory
// next to the target; commit() then replaces the target's entries of the program's layout with
// the staged ones. A run that fails before commit() (an exception unwinds the StagedOutput)
// removes the staging directory and leaves the target exactly as it was, so an earlier run's
// outputs are never mixed with a new run's, and a failed run leaves nothing half written.
// The staging directory is `.NAME.partial-PID` beside the target; one left by a process that
// was killed outright (SIGKILL) is removed by the next StagedOutput for the same target once
// that PID no longer exists. A process killed inside commit(), between setting the target's
// entries aside and moving the new ones in, leaves them in `.NAME.partial-PID/.previous`; that
// next StagedOutput puts them back where the target lacks them.
//
//   StagedOutput out("run1", {"trajectory.txt", "curvature"});
//   write_trajectory(out.path("trajectory.txt"), ...);   // into run1/.staging
//   out.commit();                                         // run1/trajectory.txt, run1/curvature
#pragma once

#include <string>
#include <vector>

#include "jpcr/quadric/error.hpp"

namespace jpcr {

class StagedOutput {
 public:
  /// `target`: the output directory (created at commit when missing; its parent now); staged
  /// beside it, or inside it when that is the only place this process may write. `layout`:
  /// every top-level name the program may write there; commit() removes each of them from the
  /// target, staged this time or not, so no output of an earlier run survives beside the new
  /// ones, and leaves every other entry alone. Empty `layout`: the names staged this time.
  /// Throws InputError naming `target` when it is empty, exists and is not a directory or may
  /// not be written by this process, or its parent cannot be created. The parent directories it
  /// creates are removed again (when still empty) unless commit() succeeds.
  StagedOutput(std::string target, std::vector<std::string> layout);
  ~StagedOutput();  // removes the staging directory unless committed
  StagedOutput(const StagedOutput&) = delete;
  StagedOutput& operator=(const StagedOutput&) = delete;

  /// `message` with the staging directory's path replaced by the target's: for the errors of
  /// writes into the staging directory (a full disk), since the user knows the target (--out).
  std::string as_target(std::string message) const;

  /// Runs `write_staged()`, which writes into the staging directory, and re-throws its
  /// InputError as an `Error` whose message names the target (as_target). A program picks
  /// `Error` when a write failure must not be mistaken for one of its other input errors.
  template <class Error = InputError, class Write>
  void write(Write&& write_staged) const {
    try {
      write_staged();
    } catch (const InputError& e) {
      throw Error(as_target(e.what()));
    }
  }

  /// The staging directory, and a path inside it.
  const std::string& directory() const { return staging_; }
  std::string path(const std::string& name) const;
  const std::string& target() const { return target_; }

  /// Throws InputError when `input` (a dataset, a --config or --params file) is, or lies
  /// inside, one of the target's entries of the layout, which commit() replaces: e.g. a
  /// dataset copied to OUT/curvature. `option` names the input in the message ("--dataset").
  /// An entry that is a symbolic link is replaced as a link (its target is left alone), so an
  /// input in the link's target is fine. With an empty layout nothing is checked.
  void require_apart_from(const std::string& input, const std::string& option) const;

  /// Moves the staged entries into the target (same file system: renames), all or nothing:
  /// when an entry cannot be replaced, the ones already moved go back and the target is left as
  /// it was, and this run's outputs are kept in `NAME.unsaved-PID` beside the staging
  /// directory (beside the target, or inside it where the run was staged there; -2, -3, ...
  /// when the name is taken), which no later run removes. Throws InputError naming that entry
  /// and where the outputs are.
  void commit();

 private:
  std::string keep_outputs();

  std::string target_, staging_;
  std::vector<std::string> layout_;
  std::vector<std::string> created_;  // the target's missing ancestors, made here, deepest last
  bool committed_ = false;
  bool keep_staging_ = false;  // a failed commit left this run's outputs (and earlier) in it
};

/// Throws InputError when `target` is `input` itself (the same directory after links and ".."),
/// or holds another dataset (depth.txt or associations.txt): commit() would replace the
/// dataset's entries of the layout's names, e.g. the curvature/ ground truth of a synthetic
/// dataset; or lies in one of the folders of a dataset directory `input` (depth/, rgb/,
/// curvature/, normals/, curvature_png/, ply/). `option` names the input in the message
/// ("--dataset").
void require_output_apart_from(const std::string& target, const std::string& input,
                               const std::string& option);

/// Throws InputError when writing the file `target` would overwrite an input: `input` itself (a
/// trajectory, a rawlog; the same file after links and ".."), or, when `input` is a dataset or
/// results directory, one of its files: depth.txt, rgb.txt, groundtruth.txt, associations*.txt,
/// camera.yaml, what jpcr_run and jpcr_curvature write (report.json, summary.json,
/// trajectory.txt, verdicts.txt, front_end.txt, keyframes.txt), or anything under depth/, rgb/,
/// curvature/, normals/, curvature_png/, ply/. Other new files inside such a directory are
/// allowed. `option` names the input in the message ("--gt").
void require_output_file_apart_from(const std::string& target, const std::string& input,
                                    const std::string& option);

/// Throws InputError when the file `target` is one of those files (as above) of any dataset or
/// results directory, an input of this run or not: one that holds depth.txt or
/// associations*.txt, report.json beside verdicts.txt (jpcr_run) or summary.json beside
/// curvature/ (jpcr_curvature). Writing run1/report.json or seq/depth.txt would destroy them.
/// Checked after require_output_file_apart_from, whose message names the input.
void require_not_dataset_or_results_file(const std::string& target);

}  // namespace jpcr
