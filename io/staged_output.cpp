#include "jpcr/io/staged_output.hpp"

#include <sys/stat.h>
#include <unistd.h>

#include <cerrno>
#include <cstring>
#include <filesystem>
#include <iterator>
#include <stdexcept>
#include <system_error>

#include "jpcr/io/atomic_file.hpp"
#include "jpcr/quadric/error.hpp"

namespace jpcr {

namespace fs = std::filesystem;

namespace {

// Inside the staging directory: the target's entries that commit() replaces, until it is done.
const char* const kPrevious = ".previous";

// Removes the staging directories `prefix`PID in `parent` whose process no longer exists: those
// of runs that were killed (SIGKILL, a second Ctrl-C) before they could clean up. A PID that is
// alive, or that this process may not signal, is left alone. A run killed inside commit() may
// have set the target's entries aside without moving the new ones in: those go back first, to
// `target` where it lacks them.
void remove_abandoned_staging(const fs::path& parent, const std::string& prefix,
                              const fs::path& target) {
  std::error_code ec;
  for (const fs::directory_entry& e : fs::directory_iterator(parent, ec)) {
    const long pid = owner_pid(e.path().filename().string(), prefix);
    if (pid == 0 || !process_is_gone(pid)) continue;
    std::error_code ignored;
    for (const fs::directory_entry& aside : fs::directory_iterator(e.path() / kPrevious, ignored))
      if (!fs::exists(fs::symlink_status(target / aside.path().filename(), ignored)))
        fs::rename(aside.path(), target / aside.path().filename(), ignored);
    fs::remove_all(e.path(), ignored);
  }
}

}  // namespace

StagedOutput::StagedOutput(std::string target, std::vector<std::string> layout)
    : target_(std::move(target)), layout_(std::move(layout)) {
  if (target_.empty()) throw InputError("output directory: the path is empty");
  std::error_code ec;
  if (fs::exists(target_, ec) && !fs::is_directory(target_, ec))
    throw InputError(target_ + ": output path exists and is not a directory");
  fs::path t = fs::path(target_).lexically_normal();
  if (t.filename().empty()) t = t.parent_path();  // "out/" → "out"
  // A link that leads nowhere, or in a loop, would be refused only at commit(), after the run
  // (tested without a trailing '/', through which lstat follows the link).
  if (fs::is_symlink(fs::symlink_status(t, ec)) && !fs::is_directory(t, ec))
    throw InputError(target_ + ": a symbolic link to no directory (" +
                     (ec ? ec.message() : std::string("it leads nowhere")) +
                     "): give the path of a directory, or of none");
  fs::path parent = t.has_parent_path() ? t.parent_path() : fs::path(".");
  for (fs::path missing = parent; !missing.empty() && !fs::exists(missing, ec);
       missing = missing.parent_path())
    created_.insert(created_.begin(), missing.string());
  ensure_directory(parent.string());
  // A hidden sibling, so that renames into the target stay on one file system; inside the
  // target when that is another file system (a mount point, a link to another disk), where a
  // sibling would fail only at commit(), after the whole run.
  struct stat target_stat {
  }, parent_stat{};
  if (::stat(t.c_str(), &target_stat) == 0 && ::stat(parent.c_str(), &parent_stat) == 0 &&
      target_stat.st_dev != parent_stat.st_dev)
    parent = t;
  const std::string prefix = "." + t.filename().string() + ".partial-";
  remove_abandoned_staging(parent, prefix, t);
  for (const std::string& name : layout_)
    if (name.empty() || name[0] == '.' || name.find('/') != std::string::npos)
      throw std::invalid_argument("StagedOutput: layout name '" + name +
                                  "' must be a plain, visible file name");
  // An existing target that this process may not write would fail at commit(), after the whole
  // run: refused now.
  if (fs::is_directory(t, ec) && ::access(t.c_str(), W_OK | X_OK) != 0)
    throw InputError(target_ + ": cannot write the output here (" + std::strerror(errno) + ")");
  staging_ = (parent / (prefix + std::to_string(::getpid()))).string();
  fs::remove_all(staging_, ec);
  try {
    ensure_directory(staging_);
  } catch (const InputError& e) {
    // A writable target in a parent this process may not write (a user's directory in a
    // shared one): staged inside the target, which is all commit() needs.
    if (parent != t && fs::is_directory(t, ec)) {
      remove_abandoned_staging(t, prefix, t);
      staging_ = (t / (prefix + std::to_string(::getpid()))).string();
      fs::remove_all(staging_, ec);
    }
    try {
      ensure_directory(staging_);
    } catch (const InputError&) {  // name the output the user gave, not the staging directory
      throw InputError(target_ + ": cannot write the output here (staging directory " + e.what() +
                       ")");
    }
  }
}

StagedOutput::~StagedOutput() {
  if (committed_ || keep_staging_) return;
  std::error_code ec;
  fs::remove_all(staging_, ec);  // a failed run leaves nothing behind
  for (auto d = created_.rbegin(); d != created_.rend(); ++d)
    fs::remove(*d, ec);  // only while empty
}

void StagedOutput::require_apart_from(const std::string& input, const std::string& option) const {
  if (input.empty()) return;
  std::error_code ec;
  const fs::path in = fs::weakly_canonical(fs::absolute(input, ec), ec);
  // The entry itself is not resolved: commit() renames a link, never what it points to.
  const fs::path target = fs::weakly_canonical(fs::absolute(target_, ec), ec);
  for (const std::string& name : layout_) {
    const fs::path entry = fs::path(target_) / name;
    const fs::path inside = in.lexically_relative(target / name);
    if (!inside.empty() && *inside.begin() != "..")
      throw InputError(input + ": " + option + " lies in " + entry.string() +
                       ", which this run replaces with its own output (give another --out)");
  }
}

std::string StagedOutput::as_target(std::string message) const {
  for (std::size_t at = 0; (at = message.find(staging_, at)) != std::string::npos;
       at += target_.size())
    message.replace(at, staging_.size(), target_);
  return message;
}

std::string StagedOutput::path(const std::string& name) const {
  return (fs::path(staging_) / name).string();
}

// After a failed commit: the staged outputs (not .previous) into NAME.unsaved-PID beside the
// staging directory (-2, -3, ... when taken); keep_staging_ where some could not move.
std::string StagedOutput::keep_outputs() {
  std::error_code ec;
  fs::path t = fs::path(target_).lexically_normal();
  if (t.filename().empty()) t = t.parent_path();  // "out/" → "out"
  const std::string stem = (t.filename().empty() ? std::string("output") : t.filename().string()) +
                           ".unsaved-" + std::to_string(::getpid());
  const fs::path staged(staging_);
  fs::path kept;
  for (int k = 1; k <= 100 && kept.empty(); ++k) {
    const fs::path candidate =
        staged.parent_path() / (k == 1 ? stem : stem + "-" + std::to_string(k));
    if (fs::create_directory(candidate, ec)) kept = candidate;
    if (ec) break;  // not a name taken: this directory cannot hold it
  }
  bool all_moved = !kept.empty();
  std::vector<fs::path> entries;
  for (const fs::directory_entry& e : fs::directory_iterator(staged, ec))
    if (e.path().filename() != kPrevious) entries.push_back(e.path().filename());
  for (const fs::path& entry : entries) {
    if (kept.empty()) break;
    std::error_code moved;
    fs::rename(staged / entry, kept / entry, moved);
    all_moved = all_moved && !moved;
  }
  if (all_moved) return "; this run's outputs are kept in " + kept.string();
  keep_staging_ = true;
  return "; this run's outputs are in " + staging_ + (kept.empty() ? "" : " and " + kept.string()) +
         ", which the next run into " + target_ + " removes: move them elsewhere first";
}

// All or nothing, by renames on one file system: the target's entries of the layout first move
// aside into the staging directory, then the staged ones move in. When a rename fails (an
// immutable or foreign-owned entry, a full directory), the entries moved so far go back, so the
// target holds the earlier run's outputs, untouched, and the error names the entry.
void StagedOutput::commit() {
  ensure_directory(target_);
  std::vector<std::string> names = layout_;
  if (names.empty())
    for (const fs::directory_entry& e : fs::directory_iterator(staging_))
      if (e.path().filename() != kPrevious) names.push_back(e.path().filename().string());
  const fs::path previous = fs::path(staging_) / kPrevious;
  ensure_directory(previous.string());
  std::vector<std::string> moved_aside, moved_in;
  // Puts the moved-aside entries back; the ones that cannot go back stay in `previous`. This
  // run's outputs go back into the staging directory and from there into a directory of their
  // own (keep_outputs), named in the error: a run of hours is not lost to a target it cannot
  // replace.
  const auto roll_back = [&]() -> std::string {
    std::error_code ec;
    for (const std::string& name : moved_in) {
      fs::rename(fs::path(target_) / name, fs::path(staging_) / name, ec);
      if (ec) fs::remove_all(fs::path(target_) / name, ec);
    }
    bool all_back = true;
    for (const std::string& name : moved_aside) {
      fs::rename(previous / name, fs::path(target_) / name, ec);
      all_back = all_back && !ec;
    }
    // This run's outputs move to a visible directory of their own beside the staging directory
    // (beside the target, or inside it where the run was staged there), out of the reach of
    // the next run's sweep of abandoned staging directories; earlier entries that could not be
    // put back stay in the staging directory's .previous, which that sweep restores.
    const std::string outputs = keep_outputs();
    keep_staging_ = keep_staging_ || !all_back;
    if (all_back) return "; the earlier outputs in " + target_ + " are kept as they were" + outputs;
    return "; some earlier outputs could not be put back and are kept in " + previous.string() +
           " (the next run into " + target_ + " puts them back)" + outputs;
  };
  std::error_code ec;
  for (const std::string& name : names) {
    const fs::path to = fs::path(target_) / name;
    if (!fs::exists(fs::symlink_status(to, ec))) continue;
    fs::rename(to, previous / name, ec);
    if (ec) {
      const std::string why = ec.message();
      throw InputError(to.string() + ": cannot replace (" + why + ")" + roll_back());
    }
    moved_aside.push_back(name);
  }
  for (const std::string& name : names) {
    const fs::path from = fs::path(staging_) / name, to = fs::path(target_) / name;
    if (!fs::exists(fs::symlink_status(from, ec))) continue;
    fs::rename(from, to, ec);
    if (ec) {
      const std::string why = ec.message();
      throw InputError(to.string() + ": cannot be moved into place (" + why + ")" + roll_back());
    }
    moved_in.push_back(name);
  }
  sync_directory(target_);  // the renames, on the disk
  fs::remove_all(staging_, ec);
  committed_ = true;
}

void require_output_apart_from(const std::string& target, const std::string& input,
                               const std::string& option) {
  std::error_code ec;
  if (fs::equivalent(target, input, ec))
    throw InputError(target + ": the output directory is " + option + " " + input +
                     " itself; writing there would replace its own files (give another --out)");
  // Another dataset (a copy of the input, a second sequence): its curvature/ ground truth has
  // one of the layout's names.
  for (const char* list : {"depth.txt", "associations.txt"}) {
    if (fs::exists(fs::path(target) / list, ec))
      throw InputError(target + ": the output directory holds a dataset (" + list +
                       "); writing there would replace its files (give another --out)");
  }
  // One of the dataset's own folders (its ground-truth curvature/, its depth/) or a folder in
  // one: the outputs would land among its files.
  if (!fs::is_directory(input, ec)) return;
  const fs::path inside =
      fs::weakly_canonical(fs::absolute(target, ec), ec)
          .lexically_relative(fs::weakly_canonical(fs::absolute(input, ec), ec));
  if (inside.empty() || *inside.begin() == ".." || inside.is_absolute()) return;
  const std::string first = inside.begin()->string();
  for (const char* folder : {"depth", "rgb", "curvature", "normals", "curvature_png", "ply"})
    if (first == folder)
      throw InputError(target + ": the output directory lies in " + option + " " + input + "'s " +
                       folder + "/; writing there would mix with its files (give another --out)");
}

namespace {

// Whether `inside`, a path relative to a dataset or results directory, names one of its files:
// the TUM layout's lists and folders, and what jpcr_run and jpcr_curvature write there.
bool is_input_directory_file(const fs::path& inside) {
  if (inside.empty() || *inside.begin() == ".." || inside.is_absolute()) return false;
  const std::string first = inside.begin()->string();
  if (std::distance(inside.begin(), inside.end()) > 1) {
    for (const char* folder : {"depth", "rgb", "curvature", "normals", "curvature_png", "ply"})
      if (first == folder) return true;
    return false;
  }
  for (const char* file :
       {"depth.txt", "rgb.txt", "groundtruth.txt", "camera.yaml", "report.json", "summary.json",
        "trajectory.txt", "verdicts.txt", "front_end.txt", "keyframes.txt"})
    if (first == file) return true;
  return first.rfind("associations", 0) == 0 && inside.extension() == ".txt";
}

// Whether `dir` is a dataset (depth.txt, associations*.txt), jpcr_run's results (report.json
// beside verdicts.txt) or jpcr_curvature's (summary.json beside curvature/). A report.json
// alone is not enough: it may be jpcr_eval's own, which a second run replaces.
bool is_dataset_or_results(const fs::path& dir) {
  std::error_code ec;
  if (fs::exists(dir / "depth.txt", ec) ||
      (fs::exists(dir / "report.json", ec) && fs::exists(dir / "verdicts.txt", ec)) ||
      (fs::exists(dir / "summary.json", ec) && fs::is_directory(dir / "curvature", ec)))
    return true;
  for (const fs::directory_entry& e : fs::directory_iterator(dir, ec)) {
    const std::string name = e.path().filename().string();
    if (name.rfind("associations", 0) == 0 && e.path().extension() == ".txt") return true;
  }
  return false;
}

}  // namespace

void require_output_file_apart_from(const std::string& target, const std::string& input,
                                    const std::string& option) {
  std::error_code ec;
  if (fs::equivalent(target, input, ec))
    throw InputError(target + ": is " + option + " " + input +
                     " itself; writing it would destroy the input (give another output file)");
  if (fs::is_directory(input, ec)) {
    // Both as written (a folder of the dataset may be a link to elsewhere) and with the links of
    // the target's folder resolved (the dataset reached by another path); the file name itself is
    // kept, so a groundtruth.txt that is a link still reads as groundtruth.txt.
    const fs::path as_written = fs::absolute(target, ec)
                                    .lexically_normal()
                                    .lexically_relative(fs::absolute(input, ec).lexically_normal());
    const fs::path file = fs::path(target).filename();
    const fs::path resolved =
        (fs::weakly_canonical(fs::absolute(target, ec).parent_path(), ec) / file)
            .lexically_relative(fs::weakly_canonical(input, ec));
    if (is_input_directory_file(as_written) || is_input_directory_file(resolved))
      throw InputError(target + ": is a file of " + option + " " + input +
                       "; writing it would destroy the input (give another output file)");
  }
}

void require_not_dataset_or_results_file(const std::string& target) {
  std::error_code ec;
  const fs::path absolute = fs::absolute(target, ec).lexically_normal();
  for (fs::path dir = absolute.parent_path(); !dir.empty(); dir = dir.parent_path()) {
    if (is_dataset_or_results(dir) && is_input_directory_file(absolute.lexically_relative(dir)))
      throw InputError(target + ": is a file of the dataset or results in " + dir.string() +
                       "; writing it would destroy them (give another output file)");
    if (dir == dir.root_path()) break;
  }
}

}  // namespace jpcr
