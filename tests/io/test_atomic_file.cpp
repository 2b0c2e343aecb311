#include <sys/stat.h>

#include <fstream>
#include <sstream>

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

// A FIFO would block the read forever and /dev/zero never end; both are refused by name.
TEST(AtomicFile, ReadingSomethingOtherThanARegularFileIsAnInputError) {
  const test::TempDir dir;
  const std::string fifo = dir.file("fifo");
  ASSERT_EQ(mkfifo(fifo.c_str(), 0600), 0);
  for (const std::string& path : {fifo, std::string("/dev/zero")})
    EXPECT_EQ(test::input_error_of([&] { read_file(path); }), path + ": not a regular file");
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
