#include "jpcr/io/staged_output.hpp"

#include <signal.h>
#include <unistd.h>

#include <cerrno>
#include <filesystem>
#include <iterator>
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
// alive, or that this process may not signal, is left alone.
void remove_abandoned_staging(const fs::path& parent, const std::string& prefix) {
  std::error_code ec;
  for (const fs::directory_entry& e : fs::directory_iterator(parent, ec)) {
    const std::string name = e.path().filename().string();
    if (name.size() <= prefix.size() || name.compare(0, prefix.size(), prefix) != 0) continue;
    const std::string digits = name.substr(prefix.size());
    if (digits.size() > 9 || digits.find_first_not_of("0123456789") != std::string::npos) continue;
    const long pid = std::stol(digits);
    if (pid <= 0 || pid == ::getpid() || ::kill(static_cast<pid_t>(pid), 0) == 0 || errno != ESRCH)
      continue;
    std::error_code ignored;
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
  const fs::path parent = t.has_parent_path() ? t.parent_path() : fs::path(".");
  ensure_directory(parent.string());
  // A hidden sibling: renames into the target stay on one file system.
  const std::string prefix = "." + t.filename().string() + ".partial-";
  remove_abandoned_staging(parent, prefix);
  staging_ = (parent / (prefix + std::to_string(::getpid()))).string();
  fs::remove_all(staging_, ec);
  try {
    ensure_directory(staging_);
  } catch (const InputError& e) {  // name the output the user gave, not the staging directory
    throw InputError(target_ + ": cannot write the output here (staging directory " + e.what() +
                     ")");
  }
}

StagedOutput::~StagedOutput() {
  if (committed_) return;
  std::error_code ec;
  fs::remove_all(staging_, ec);  // a failed run leaves nothing behind
}

std::string StagedOutput::path(const std::string& name) const {
  return (fs::path(staging_) / name).string();
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
  const auto roll_back = [&] {
    std::error_code ignored;
    for (const std::string& name : moved_in)
      fs::remove_all(fs::path(target_) / name, ignored);
    for (const std::string& name : moved_aside)
      fs::rename(previous / name, fs::path(target_) / name, ignored);
  };
  std::error_code ec;
  for (const std::string& name : names) {
    const fs::path to = fs::path(target_) / name;
    if (!fs::exists(fs::symlink_status(to, ec))) continue;
    fs::rename(to, previous / name, ec);
    if (ec) {
      roll_back();
      throw InputError(to.string() + ": cannot replace (" + ec.message() +
                       "); the earlier outputs in " + target_ + " are kept as they were");
    }
    moved_aside.push_back(name);
  }
  for (const std::string& name : names) {
    const fs::path from = fs::path(staging_) / name, to = fs::path(target_) / name;
    if (!fs::exists(fs::symlink_status(from, ec))) continue;
    fs::rename(from, to, ec);
    if (ec) {
      roll_back();
      throw InputError(to.string() + ": cannot be moved into place (" + ec.message() +
                       "); the earlier outputs in " + target_ + " are kept as they were");
    }
    moved_in.push_back(name);
  }
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
}

void require_output_file_apart_from(const std::string& target, const std::string& input,
                                    const std::string& option) {
  std::error_code ec;
  if (fs::equivalent(target, input, ec))
    throw InputError(target + ": is " + option + " " + input +
                     " itself; writing it would destroy the input (give another output file)");
  if (!fs::is_directory(input, ec)) return;
  const fs::path inside =
      fs::weakly_canonical(target, ec).lexically_relative(fs::weakly_canonical(input, ec));
  if (ec || inside.empty() || *inside.begin() == "..") return;
  const std::string first = inside.begin()->string();
  const bool dataset_file =
      std::distance(inside.begin(), inside.end()) > 1
          ? (first == "depth" || first == "rgb" || first == "curvature" || first == "normals")
          : (first == "depth.txt" || first == "rgb.txt" || first == "groundtruth.txt" ||
             first == "camera.yaml" ||
             (first.rfind("associations", 0) == 0 && inside.extension() == ".txt"));
  if (dataset_file)
    throw InputError(target + ": is a file of the " + option + " dataset " + input +
                     "; writing it would destroy the input (give another output file)");
}

}  // namespace jpcr
