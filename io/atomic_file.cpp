#include "jpcr/io/atomic_file.hpp"

#include <unistd.h>

#include <atomic>
#include <cerrno>
#include <cstdio>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <sstream>

#include "jpcr/quadric/error.hpp"

namespace jpcr {

namespace {

std::string temporary_name(const std::string& path) {
  static std::atomic<unsigned> counter{0};
  return path + ".tmp." + std::to_string(::getpid()) + "." + std::to_string(counter++);
}

}  // namespace

void write_file_atomically(const std::string& path,
                           const std::function<void(std::ostream&)>& write) {
  const std::string tmp = temporary_name(path);
  try {
    {
      std::ofstream out(tmp, std::ios::binary | std::ios::trunc);
      if (!out) throw InputError(path + ": cannot be written (" + std::strerror(errno) + ")");
      const auto failed = [&](int error) {
        return InputError(path + ": write failed (" +
                          (error != 0 ? std::strerror(error) : "disk full or I/O error") + ")");
      };
      errno = 0;
      write(out);
      if (!out) throw failed(errno);
      // Closed here, not by the destructor: a delayed write error (NFS, a quota) shows at close.
      out.close();
      if (!out) throw failed(errno);
    }
    if (std::rename(tmp.c_str(), path.c_str()) != 0) {
      throw InputError(path + ": cannot be renamed into place (" + std::strerror(errno) + ")");
    }
  } catch (...) {
    std::remove(tmp.c_str());
    throw;
  }
}

void ensure_directory(const std::string& dir) {
  std::error_code ec;
  std::filesystem::create_directories(dir, ec);
  if (ec || !std::filesystem::is_directory(dir)) {
    throw InputError(dir + ": cannot create directory (" + ec.message() + ")");
  }
}

void ensure_parent_directory(const std::string& file) {
  const std::string parent = std::filesystem::path(file).parent_path().string();
  if (!parent.empty()) ensure_directory(parent);
}

std::string read_file(const std::string& path) {
  std::error_code ec;
  if (!std::filesystem::exists(path, ec)) throw InputError(path + ": file does not exist");
  if (std::filesystem::is_directory(path, ec)) throw InputError(path + ": is a directory");
  // A FIFO would block and a device (/dev/zero) never end: only regular files are read.
  if (!std::filesystem::is_regular_file(path, ec)) throw InputError(path + ": not a regular file");
  std::ifstream in(path, std::ios::binary);
  if (!in) throw InputError(path + ": cannot be opened (" + std::strerror(errno) + ")");
  std::ostringstream ss;
  ss << in.rdbuf();
  if (in.bad()) throw InputError(path + ": read failed");
  return ss.str();
}

}  // namespace jpcr
