#include <sys/stat.h>
#include <unistd.h>

#include <cerrno>
#include <chrono>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <vector>

#include <gtest/gtest.h>

#include "input_error.hpp"
#include "jpcr/io/atomic_file.hpp"
#include "jpcr/quadric/error.hpp"
#include "temp_dir.hpp"

namespace jpcr {
namespace {

TEST(AtomicFile, FailedWriteKeepsThePreviousContent) {
  test::TempDir dir;
  const std::string path = dir.write("out.txt", "old content");
  EXPECT_THROW(write_file_atomically(path,
                                     [](std::ostream& out) {
                                       out << "half of the new";
                                       throw std::runtime_error("crash in the middle");
                                     }),
               std::runtime_error);
  EXPECT_EQ(read_file(path), "old content");
  EXPECT_EQ(test::count_files(dir.path()), 1);  // no temporary left behind
}

TEST(AtomicFile, WritesWholeContent) {
  test::TempDir dir;
  write_file_atomically(dir.file("a.txt"), [](std::ostream& out) { out << "hello"; });
  EXPECT_EQ(read_file(dir.file("a.txt")), "hello");
}

TEST(AtomicFile, UnwritableDirectoryIsAnInputErrorNamingThePath) {
  try {
    write_file_atomically("/nonexistent_dir_jpcr/x.txt", [](std::ostream& out) { out << 1; });
    FAIL();
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find("/nonexistent_dir_jpcr/x.txt"), std::string::npos);
  }
}

// A full disk (a 64 kB tmpfs, as root): the error says why with the system's words (it said
// "disk full?" for every failure), and the earlier content and no temporary remain.
TEST(AtomicFile, AFullDiskIsNamedAndKeepsThePreviousContent) {
  test::TempDir dir;
  const test::SmallDisk disk(dir.file("small"), "64k");
  if (!disk.mounted()) GTEST_SKIP() << "cannot mount a tmpfs here";
  const std::string path = dir.file("small/out.txt");
  write_file_atomically(path, [](std::ostream& out) { out << "old content"; });
  EXPECT_EQ(test::input_error_of([&] {
              write_file_atomically(path,
                                    [](std::ostream& out) { out << std::string(1 << 20, 'x'); });
            }),
            path + ": write failed (" + std::strerror(ENOSPC) + ")");
  EXPECT_EQ(read_file(path), "old content");
  EXPECT_EQ(test::count_files(dir.file("small")), 1);
}

// A writer killed outright leaves its hidden temporary; the next write into that directory
// removes it once it is 10 minutes old, and only it: not a live process's (PID 1, this one's),
// not a younger one (another PID namespace may see a live writer's PID as gone), not a file that
// merely looks alike.
TEST(AtomicFile, TheTemporaryOfAKilledWriterIsRemovedByTheNextWrite) {
  test::TempDir dir;
  const long gone = test::finished_process();
  ASSERT_TRUE(process_is_gone(gone));
  const std::string abandoned = ".a.txt.jpcr-tmp." + std::to_string(gone) + ".0";
  const std::vector<std::string> kept = {
      ".a.txt.jpcr-tmp.1.0",                                   // a live process
      ".a.txt.jpcr-tmp." + std::to_string(::getpid()) + ".7",  // this one (another thread)
      "a.txt.jpcr-tmp." + std::to_string(gone) + ".0",         // not hidden
      ".a.txt.jpcr-tmp." + std::to_string(gone),               // no counter
      ".a.txt.tmp." + std::to_string(gone) + ".0",             // another tag
      ".c.txt.jpcr-tmp." + std::to_string(gone) + ".1"};       // young: written just now
  const auto eleven_minutes_ago =
      std::filesystem::file_time_type::clock::now() - std::chrono::minutes(11);
  for (const std::string& name : kept) {
    dir.write(name, "x");
    if (name[1] != 'c') std::filesystem::last_write_time(dir.file(name), eleven_minutes_ago);
  }
  dir.write(abandoned, "half");
  std::filesystem::last_write_time(dir.file(abandoned), eleven_minutes_ago);
  write_file_atomically(dir.file("b.txt"), [](std::ostream& out) { out << "new"; });
  EXPECT_FALSE(std::filesystem::exists(dir.file(abandoned)));
  for (const std::string& name : kept)
    EXPECT_TRUE(std::filesystem::exists(dir.file(name))) << name;
  EXPECT_EQ(read_file(dir.file("b.txt")), "new");
  EXPECT_EQ(test::count_files(dir.path()), static_cast<int>(kept.size()) + 1);
  EXPECT_FALSE(process_is_gone(1));
  EXPECT_FALSE(process_is_gone(::getpid()));
  EXPECT_FALSE(process_is_gone(0));
}

// A FIFO would block the read forever and /dev/zero never end; both are refused by name.
TEST(AtomicFile, ReadingSomethingOtherThanARegularFileIsAnInputError) {
  const test::TempDir dir;
  const std::string fifo = dir.file("fifo");
  ASSERT_EQ(mkfifo(fifo.c_str(), 0600), 0);
  for (const std::string& path : {fifo, std::string("/dev/zero")})
    EXPECT_EQ(test::input_error_of([&] { read_file(path); }), path + ": not a regular file");
}

// A whole-file write renames a new file into place: over a device, a pipe or a link to one it
// would replace them (as root, `jpcr_odometry --out /dev/null` deleted the device node). Those
// are refused, untouched; a link to a regular file writes that file and stays a link.
TEST(AtomicFile, OnlyRegularFilesAreReplaced) {
  const test::TempDir dir;
  const std::string fifo = dir.file("fifo");
  ASSERT_EQ(mkfifo(fifo.c_str(), 0600), 0);
  const std::string to_fifo = dir.file("to_fifo"), nowhere = dir.file("nowhere"),
                    loop = dir.file("loop"), to_dir = dir.file("to_dir");
  std::filesystem::create_symlink(fifo, to_fifo);
  std::filesystem::create_symlink(dir.file("missing"), nowhere);
  std::filesystem::create_symlink(loop, loop);
  std::filesystem::create_symlink(dir.path(), to_dir);
  const auto write = [](const std::string& path) {
    return test::input_error_of(
        [&] { write_file_atomically(path, [](std::ostream& out) { out << "new"; }); });
  };
  const std::string why = "; jpcr writes a whole new file and renames it into place";
  EXPECT_EQ(write(fifo).rfind(fifo + ": exists and is no regular file (a device, a pipe", 0), 0u);
  EXPECT_EQ(write(to_fifo).rfind(to_fifo + ": a symbolic link to no regular file" + why, 0), 0u);
  EXPECT_EQ(write(nowhere).rfind(nowhere + ": a symbolic link to nothing" + why, 0), 0u);
  EXPECT_EQ(write(loop).rfind(loop + ": a symbolic link that cannot be followed", 0), 0u);
  EXPECT_EQ(write(to_dir).rfind(to_dir + ": a symbolic link to no regular file", 0), 0u);
  EXPECT_EQ(write(dir.path()), dir.path() + ": names a directory, not a file to write");
  EXPECT_TRUE(std::filesystem::is_fifo(fifo));
  EXPECT_EQ(write("/dev/null").rfind("/dev/null: exists and is no regular file", 0), 0u);
  EXPECT_TRUE(std::filesystem::is_character_file("/dev/null"));

  const std::string file = dir.write("file.txt", "old"), link = dir.file("link.txt");
  std::filesystem::create_symlink(file, link);
  EXPECT_EQ(output_file_target(link), std::filesystem::canonical(file).string());
  EXPECT_EQ(output_file_target(file), file);
  EXPECT_EQ(output_file_target(dir.file("new.txt")), dir.file("new.txt"));
  write_file_atomically(link, [](std::ostream& out) { out << "through the link"; });
  EXPECT_TRUE(std::filesystem::is_symlink(link));
  EXPECT_EQ(read_file(file), "through the link");
}

TEST(AtomicFile, ReadMissingFileNamesIt) {
  try {
    read_file("/no/such/file.txt");
    FAIL();
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find("/no/such/file.txt: file does not exist"),
              std::string::npos);
  }
}

}  // namespace
}  // namespace jpcr
