#include <unistd.h>

#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <functional>

#include <gtest/gtest.h>

#include "input_error.hpp"
#include "jpcr/io/atomic_file.hpp"
#include "jpcr/io/staged_output.hpp"
#include "jpcr/quadric/error.hpp"
#include "temp_dir.hpp"

namespace jpcr {
namespace {

namespace fs = std::filesystem;

// Entries of a directory, hidden ones (the staging directory) included.
int entries(const std::string& dir) {
  int n = 0;
  for ([[maybe_unused]] const fs::directory_entry& e : fs::directory_iterator(dir))
    ++n;
  return n;
}

void write(const std::string& path, const std::string& text) {
  write_file_atomically(path, [&](std::ostream& out) { out << text; });
}

// Whether `check` throws an InputError whose message holds `message`.
bool refused_with(const std::function<void()>& check, const std::string& message) {
  try {
    check();
  } catch (const InputError& e) {
    return std::string(e.what()).find(message) != std::string::npos;
  }
  return false;
}

TEST(StagedOutput, NothingReachesTheTargetBeforeCommit) {
  test::TempDir dir;
  const std::string target = dir.file("run");
  {
    StagedOutput out(target, {"a.txt"});
    write(out.path("a.txt"), "new");
    EXPECT_FALSE(fs::exists(target));
    out.commit();
  }
  EXPECT_EQ(read_file(dir.file("run/a.txt")), "new");
  EXPECT_EQ(entries(dir.path()), 1);  // only the target: no staging left
}

TEST(StagedOutput, ErrorsOfWritesIntoTheStagingDirectoryCanNameTheTarget) {
  test::TempDir dir;
  const std::string target = dir.file("run");
  const StagedOutput out(target, {"curvature"});
  const std::string error =
      out.path("curvature/1.npy") + ": cannot write (No space left on device)";
  EXPECT_EQ(out.as_target(error),
            target + "/curvature/1.npy: cannot write (No space left on device)");
  EXPECT_EQ(out.as_target("no path here"), "no path here");
}

TEST(StagedOutput, WriteRethrowsAFailedWriteNamedByTheTargetAsTheErrorAsked) {
  struct WriteFailure : InputError {
    using InputError::InputError;
  };
  test::TempDir dir;
  const std::string target = dir.file("run");
  const StagedOutput out(target, {"summary.json"});
  const auto fail = [&] { throw InputError(out.path("summary.json") + ": write failed"); };
  try {
    out.write<WriteFailure>(fail);
    ADD_FAILURE() << "no exception";
  } catch (const WriteFailure& e) {
    EXPECT_STREQ(e.what(), (target + "/summary.json: write failed").c_str());
  }
  EXPECT_THROW(out.write(fail), InputError);
  EXPECT_THROW(out.write([] { throw std::logic_error("not a write error"); }), std::logic_error);
  bool ran = false;
  out.write([&] { ran = true; });
  EXPECT_TRUE(ran);
}

// An earlier run's outputs in `target`: the file `file` and the folder `folder` with one map.
void write_earlier_run(const std::string& target, const std::string& file,
                       const std::string& folder) {
  fs::create_directories(target + "/" + folder);
  write(target + "/" + file, "an earlier run's " + file);
  write(target + "/" + folder + "/old.npy", "an earlier run's map");
}

// Both are still there, unchanged.
void expect_earlier_run(const std::string& target, const std::string& file,
                        const std::string& folder) {
  EXPECT_EQ(read_file(target + "/" + file), "an earlier run's " + file);
  EXPECT_EQ(read_file(target + "/" + folder + "/old.npy"), "an earlier run's map");
}

TEST(StagedOutput, AFailedRunLeavesTheTargetAsItWas) {
  test::TempDir dir;
  const std::string target = dir.file("run");
  write_earlier_run(target, "a.txt", "maps");
  try {
    StagedOutput out(target, {"a.txt", "maps"});
    write(out.path("a.txt"), "half");
    throw std::runtime_error("the run fails");
  } catch (const std::runtime_error&) {
  }
  expect_earlier_run(target, "a.txt", "maps");
  EXPECT_EQ(entries(dir.path()), 1);  // the staging directory is gone
}

TEST(StagedOutput, CommitReplacesEveryLayoutEntryAndKeepsOtherFiles) {
  test::TempDir dir;
  const std::string target = dir.file("run");
  fs::create_directories(target + "/maps");
  write(target + "/maps/old_stamp.npy", "an earlier run's map");
  write(target + "/ply_left_over.txt", "in the layout, not written this time");
  write(target + "/notes.txt", "the user's");
  StagedOutput out(target, {"maps", "ply_left_over.txt"});
  fs::create_directories(out.path("maps"));
  write(out.path("maps/new_stamp.npy"), "this run's map");
  out.commit();
  EXPECT_FALSE(fs::exists(target + "/maps/old_stamp.npy"));  // no stale map beside the new
  EXPECT_EQ(read_file(target + "/maps/new_stamp.npy"), "this run's map");
  EXPECT_FALSE(fs::exists(target + "/ply_left_over.txt"));
  EXPECT_EQ(read_file(target + "/notes.txt"), "the user's");
}

// Makes the directory `path` impossible to rename: immutable for root (chattr +i), which a
// permission cannot stop; without write permission otherwise (moving a directory rewrites its
// ".."). False when neither can be done here (a file system without the attribute).
bool pin(const std::string& path) {
  if (::geteuid() == 0) return std::system(("chattr +i '" + path + "' 2>/dev/null").c_str()) == 0;
  fs::permissions(path, fs::perms::owner_read | fs::perms::owner_exec);
  return true;
}

void unpin(const std::string& path) {
  if (::geteuid() == 0) {
    [[maybe_unused]] const int ignored = std::system(("chattr -i '" + path + "'").c_str());
  } else {
    fs::permissions(path, fs::perms::owner_all);
  }
}

TEST(StagedOutput, ACommitThatCannotReplaceAnEntryLeavesTheTargetAsItWas) {
  test::TempDir dir;
  const std::string target = dir.file("run");
  write_earlier_run(target, "a_report.json", "curvature");
  if (!pin(target + "/curvature")) GTEST_SKIP() << "no immutable attribute on this file system";
  StagedOutput out(target, {"a_report.json", "curvature"});
  write(out.path("a_report.json"), "this run's report");
  fs::create_directories(out.path("curvature"));
  write(out.path("curvature/new.npy"), "this run's map");
  // a_report.json moves first; curvature/ cannot, so a_report.json goes back.
  try {
    out.commit();
    unpin(target + "/curvature");
    FAIL() << "the commit replaced a pinned directory";
  } catch (const InputError& e) {
    unpin(target + "/curvature");
    EXPECT_NE(std::string(e.what()).find(target + "/curvature: cannot replace"), std::string::npos)
        << e.what();
    // This run's outputs are not lost: they wait beside the target, named in the error.
    const std::string kept = dir.file("run.unsaved-" + std::to_string(::getpid()));
    EXPECT_NE(std::string(e.what()).find("this run's outputs are kept in " + kept),
              std::string::npos)
        << e.what();
  }
  expect_earlier_run(target, "a_report.json", "curvature");
  EXPECT_FALSE(fs::exists(target + "/curvature/new.npy"));
  const std::string kept = dir.file("run.unsaved-" + std::to_string(::getpid()));
  EXPECT_EQ(read_file(kept + "/a_report.json"), "this run's report");
  EXPECT_EQ(read_file(kept + "/curvature/new.npy"), "this run's map");
  EXPECT_FALSE(fs::exists(kept + "/.previous"));
  EXPECT_FALSE(fs::exists(out.directory() + "/a_report.json"));  // nothing under the swept name
  // A second failure (the same PID: a container's next run) takes the next name; the next run
  // for the target leaves both alone (they are not abandoned staging directories).
  if (!pin(target + "/curvature")) GTEST_SKIP() << "the attribute went away";
  {
    StagedOutput again(target + "/", {"a_report.json", "curvature"});
    write(again.path("a_report.json"), "the second run's report");
    EXPECT_THROW(again.commit(), InputError);
  }
  unpin(target + "/curvature");
  EXPECT_EQ(read_file(kept + "-2/a_report.json"), "the second run's report");
  { StagedOutput next(target, {"a_report.json", "curvature"}); }
  EXPECT_TRUE(fs::exists(kept + "/a_report.json"));
  EXPECT_TRUE(fs::exists(kept + "-2/a_report.json"));
}

// An existing target this process may not write is refused before the run, not at commit();
// one it may write inside a parent it may not is staged inside the target. Permissions bind
// only a user other than root.
TEST(StagedOutput, WritabilityOfTheTargetDecidesBeforeTheRun) {
  if (::geteuid() == 0) GTEST_SKIP() << "root is not bound by permissions";
  test::TempDir dir;
  const std::string locked = dir.file("locked");
  write_earlier_run(locked, "a_report.json", "curvature");
  fs::permissions(locked, fs::perms::owner_read | fs::perms::owner_exec);
  EXPECT_THROW(StagedOutput(locked, {"a_report.json"}), InputError);
  fs::permissions(locked, fs::perms::owner_all);
  const std::string shared = dir.file("shared"), mine = shared + "/mine";
  fs::create_directories(mine);
  fs::permissions(shared, fs::perms::owner_read | fs::perms::owner_exec);
  {
    StagedOutput out(mine, {"a_report.json"});
    EXPECT_EQ(fs::path(out.directory()).parent_path(), fs::path(mine));
    write(out.path("a_report.json"), "this run's report");
    out.commit();
  }
  fs::permissions(shared, fs::perms::owner_all);
  EXPECT_EQ(read_file(mine + "/a_report.json"), "this run's report");
  EXPECT_EQ(std::distance(fs::directory_iterator(mine), fs::directory_iterator()), 1);
}

TEST(StagedOutput, EmptyLayoutMovesWhatWasStaged) {
  test::TempDir dir;
  const std::string target = dir.file("deep/er/run/");  // parents created, trailing slash
  StagedOutput out(target, {});
  write(out.path("x.txt"), "x");
  out.commit();
  EXPECT_EQ(read_file(dir.file("deep/er/run/x.txt")), "x");
  EXPECT_EQ(entries(dir.file("deep/er")), 1);
}

TEST(StagedOutput, BadTargetsAreInputErrorsNamingThem) {
  test::TempDir dir;
  const std::string file = dir.write("a_file", "x");
  try {
    StagedOutput out(file, {});
    FAIL();
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find(file + ": output path exists and is not a directory"),
              std::string::npos);
  }
  EXPECT_THROW(StagedOutput("", {}), InputError);
  EXPECT_THROW(StagedOutput(file + "/under_a_file", {}), InputError);
  // Links that lead to no directory are refused before the run (they failed only at commit()).
  const std::string nowhere = dir.file("nowhere"), loop = dir.file("loop");
  std::filesystem::create_symlink(dir.file("missing"), nowhere);
  std::filesystem::create_symlink(loop, loop);
  EXPECT_EQ(test::input_error_of([&] {
              StagedOutput out(nowhere, {});
            }).rfind(nowhere + ": a symbolic link to no directory (", 0),
            0u);
  EXPECT_EQ(test::input_error_of([&] {
              StagedOutput out(loop, {});
            }).rfind(loop + ": a symbolic link to no directory (", 0),
            0u);
  EXPECT_EQ(test::input_error_of([&] {
              StagedOutput out(nowhere + "/", {});  // lstat of "nowhere/" follows the link
            }).rfind(nowhere + "/: a symbolic link to no directory (", 0),
            0u);
  const std::string to_dir = dir.file("to_dir");
  std::filesystem::create_directory(dir.file("real"));
  std::filesystem::create_symlink(dir.file("real"), to_dir);
  EXPECT_NO_THROW(StagedOutput(to_dir, {}));
  // A parent where nothing can be created (not even by root): the message names the target.
  try {
    StagedOutput out("/proc/jpcr_out", {});
    FAIL();
  } catch (const InputError& e) {
    EXPECT_EQ(std::string(e.what()).rfind("/proc/jpcr_out: cannot write the output here", 0), 0u)
        << e.what();
  }
}

TEST(StagedOutput, StagingOfAKilledRunIsRemovedAndALiveOneKept) {
  test::TempDir dir;
  const std::string target = dir.file("run");
  const std::string dead = dir.file(".run.partial-" + std::to_string(test::finished_process()));
  const std::string alive = dir.file(".run.partial-" + std::to_string(::getppid()));
  const std::string other = dir.file(".other.partial-" + std::to_string(test::finished_process()));
  const std::string not_a_pid = dir.file(".run.partial-12ab");
  for (const std::string& d : {dead, alive, other, not_a_pid})
    fs::create_directories(d + "/curvature");
  StagedOutput out(target, {});
  EXPECT_FALSE(fs::exists(dead));      // its process is gone: abandoned by a SIGKILL
  EXPECT_TRUE(fs::exists(alive));      // a run still going (here: our parent)
  EXPECT_TRUE(fs::exists(other));      // another target's
  EXPECT_TRUE(fs::exists(not_a_pid));  // not a name StagedOutput makes
  EXPECT_TRUE(fs::exists(out.directory()));
}

// A run killed inside commit(), after setting the target's entries aside: the next run puts back
// the ones the target lacks, and leaves the ones the killed run had already replaced.
TEST(StagedOutput, EntriesSetAsideByARunKilledInCommitGoBack) {
  test::TempDir dir;
  const std::string target = dir.file("run");
  const std::string dead = dir.file(".run.partial-" + std::to_string(test::finished_process()));
  fs::create_directories(target);
  fs::create_directories(dead + "/.previous/curvature");
  write(dead + "/.previous/curvature/old.npy", "an earlier run's map");
  write(dead + "/.previous/report.json", "an earlier run's report");
  write(target + "/report.json", "the killed run's report, already moved in");
  StagedOutput out(target, {"report.json", "curvature"});
  EXPECT_FALSE(fs::exists(dead));
  EXPECT_EQ(read_file(target + "/curvature/old.npy"), "an earlier run's map");
  EXPECT_EQ(read_file(target + "/report.json"), "the killed run's report, already moved in");
}

TEST(RequireOutputFileApartFrom, RefusesTheInputsOwnFilesThroughLinksAndAllowsNewOnes) {
  test::TempDir dir;
  const std::string data = dir.file("data");
  fs::create_directories(data);
  fs::create_directories(dir.file("store/frames"));
  fs::create_directory_symlink(dir.file("store/frames"), data + "/depth");  // on another disk
  write(dir.file("store/gt.txt"), "1 0 0 0 0 0 0 1\n");
  fs::create_symlink(dir.file("store/gt.txt"), data + "/groundtruth.txt");
  write(data + "/depth.txt", "");
  const auto refused = [&](const std::string& target, const std::string& input) {
    try {
      require_output_file_apart_from(target, input, "--dataset");
    } catch (const InputError& e) {
      return std::string(e.what()).find(target + ": is ") == 0;
    }
    return false;
  };
  EXPECT_TRUE(refused(data + "/depth.txt", data));
  EXPECT_TRUE(refused(data + "/depth/0.000000.png", data));  // through the folder's link
  EXPECT_TRUE(refused(data + "/groundtruth.txt", data));     // a link itself
  EXPECT_TRUE(refused(dir.file("store/../data/rgb.txt"), data));
  EXPECT_TRUE(refused(data + "/report.json", data));
  EXPECT_TRUE(refused(dir.file("store/gt.txt"), data + "/groundtruth.txt"));  // the same file
  EXPECT_FALSE(refused(data + "/odometry.txt", data));  // a new file beside the dataset's
  EXPECT_FALSE(refused(dir.file("out/depth.txt"), data));
  EXPECT_FALSE(refused(dir.file("data_copy.txt"), data));
}

// Whatever the inputs, the files of a dataset or of jpcr_run's / jpcr_curvature's results are
// never output files; jpcr_eval's own report.json (no verdicts.txt beside it) may be replaced.
TEST(RequireNotDatasetOrResultsFile, RefusesTheFilesOfDatasetsAndResults) {
  test::TempDir dir;
  fs::create_directories(dir.file("seq/depth"));
  write(dir.file("seq/depth.txt"), "");
  fs::create_directories(dir.file("run1"));
  write(dir.file("run1/report.json"), "{}");
  write(dir.file("run1/verdicts.txt"), "");
  fs::create_directories(dir.file("curv/curvature"));
  write(dir.file("curv/summary.json"), "{}");
  fs::create_directories(dir.file("mine"));
  write(dir.file("mine/report.json"), "{}");
  const auto refused = [&](const std::string& target) {
    return refused_with([&] { require_not_dataset_or_results_file(target); },
                        target + ": is a file of the dataset or results in");
  };
  for (const char* file : {"seq/depth.txt", "seq/groundtruth.txt", "seq/depth/1.png",
                           "run1/report.json", "run1/trajectory.txt", "curv/summary.json"})
    EXPECT_TRUE(refused(dir.file(file))) << file;
  // New files beside them, and jpcr_eval's own report.
  for (const char* file : {"seq/eval.json", "run1/eval.json", "mine/report.json"})
    EXPECT_FALSE(refused(dir.file(file))) << file;
}

// An input inside an entry that commit() replaces is refused; one beside the entries, or in the
// target of an entry that is a link (commit() renames the link only), is not. A failed run
// removes the parent directories the StagedOutput made.
TEST(StagedOutput, RefusesInputsInsideTheEntriesItReplaces) {
  test::TempDir dir;
  fs::create_directories(dir.file("out/curvature/seq"));
  fs::create_directories(dir.file("shared"));
  fs::create_directory_symlink(dir.file("shared"), dir.file("out/ply"));
  write(dir.file("shared/p.yaml"), "");
  write(dir.file("out/p.yaml"), "");
  const StagedOutput out(dir.file("out"), {"curvature", "ply", "summary.json"});
  const auto refused = [&](const std::string& input) {
    return refused_with([&] { out.require_apart_from(input, "--dataset"); }, "--dataset lies in");
  };
  for (const char* input : {"out/curvature/seq", "out/curvature", "out/../out/./curvature/seq"})
    EXPECT_TRUE(refused(dir.file(input))) << input;
  for (const char* input : {"out/p.yaml", "shared/p.yaml", "out/curvature_x"})
    EXPECT_FALSE(refused(dir.file(input))) << input;
  {
    const StagedOutput nested(dir.file("a/b/out"), {"x"});
    EXPECT_TRUE(fs::is_directory(dir.file("a/b")));
  }  // not committed
  EXPECT_FALSE(fs::exists(dir.file("a")));
}

// An OUT on another file system than its parent (a mount point; here a small tmpfs, as root):
// the staging directory goes inside it, so that commit()'s renames do not fail with EXDEV.
TEST(StagedOutput, ATargetOnAnotherFileSystemIsStagedInsideIt) {
  test::TempDir dir;
  const std::string target = dir.file("mounted");
  fs::create_directories(target);
  if (::geteuid() != 0 ||
      std::system(("mount -t tmpfs -o size=1m tmpfs '" + target + "' 2>/dev/null").c_str()) != 0)
    GTEST_SKIP() << "cannot mount a tmpfs here";
  write(target + "/report.json", "an earlier run's");
  std::string staging, error;
  try {
    StagedOutput out(target, {"report.json"});
    staging = out.directory();
    write(out.path("report.json"), "this run's");
    out.commit();
  } catch (const std::exception& e) {  // unmount below whatever happens
    error = e.what();
  }
  const bool inside = fs::path(staging).parent_path() == fs::path(target);
  const std::string report = read_file(target + "/report.json");
  const bool staging_left = fs::exists(staging);
  [[maybe_unused]] const int ignored = std::system(("umount '" + target + "'").c_str());
  EXPECT_EQ(error, "");
  EXPECT_TRUE(inside) << staging;
  EXPECT_EQ(report, "this run's");
  EXPECT_FALSE(staging_left);
}

TEST(StagedOutput, LayoutNamesArePlainVisibleFileNames) {
  test::TempDir dir;
  for (const char* name : {".previous", "", "a/b"})
    EXPECT_THROW(StagedOutput(dir.file("run"), {"report.json", name}), std::invalid_argument)
        << name;
}

}  // namespace
}  // namespace jpcr
