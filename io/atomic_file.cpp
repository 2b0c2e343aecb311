#include "jpcr/io/atomic_file.hpp"

#include <fcntl.h>
#include <signal.h>
#include <unistd.h>

#include <atomic>
#include <cerrno>
#include <chrono>
#include <cstdio>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <mutex>
#include <set>
#include <sstream>

#include "jpcr/quadric/error.hpp"

namespace jpcr {

namespace fs = std::filesystem;

namespace {

const std::string kTemporaryTag = ".jpcr-tmp.";

// `.NAME.jpcr-tmp.PID.N` beside `path`: hidden, and named so that the sweep below cannot take a
// file of the user's for one.
std::string temporary_name(const std::string& path) {
  static std::atomic<unsigned> counter{0};
  const fs::path p(path);
  return (p.parent_path() / ("." + p.filename().string() + kTemporaryTag +
                             std::to_string(::getpid()) + "." + std::to_string(counter++)))
      .string();
}

// The PID in a temporary's name, or 0 when `name` is not one.
long temporary_owner(const std::string& name) {
  const std::size_t tag = name.rfind(kTemporaryTag);
  if (name.empty() || name[0] != '.' || tag == std::string::npos || tag < 2) return 0;
  const std::string rest = name.substr(tag + kTemporaryTag.size());  // PID.N
  const std::size_t dot = rest.find('.');
  const auto digits = [](const std::string& d) {
    return !d.empty() && d.size() <= 9 && d.find_first_not_of("0123456789") == std::string::npos;
  };
  if (dot == std::string::npos || !digits(rest.substr(0, dot)) || !digits(rest.substr(dot + 1)))
    return 0;
  return std::stol(rest.substr(0, dot));
}

// Once per directory and process: the temporaries there of processes killed before they could
// remove them, 10 minutes old or more (a PID another PID namespace sees as gone may still be
// writing). Best effort: nothing here throws, and what cannot be read or removed stays.
void remove_abandoned_temporaries(const fs::path& directory) noexcept {
  try {
    static std::mutex mutex;
    static std::set<std::string> swept;
    {
      const std::lock_guard<std::mutex> lock(mutex);
      if (!swept.insert(directory.string()).second) return;
    }
    const auto old_enough = fs::file_time_type::clock::now() - std::chrono::minutes(10);
    std::error_code ec;
    fs::directory_iterator it(directory.empty() ? fs::path(".") : directory, ec);
    for (; !ec && it != fs::directory_iterator(); it.increment(ec)) {
      const long pid = temporary_owner(it->path().filename().string());
      std::error_code ignored;
      if (pid > 0 && process_is_gone(pid) && it->is_regular_file(ignored) &&
          fs::last_write_time(it->path(), ignored) < old_enough && !ignored)
        fs::remove(it->path(), ignored);
    }
  } catch (...) {  // out of memory for the set: the sweep waits for another run
  }
}

// fsync of a file or directory by name: 0, or the errno of the failure.
int sync_to_disk(const std::string& path) {
  const int fd = ::open(path.c_str(), O_RDONLY | O_CLOEXEC);
  if (fd < 0) return errno;
  const int error = ::fsync(fd) == 0 ? 0 : errno;
  ::close(fd);
  return error;
}

}  // namespace

long owner_pid(const std::string& name, const std::string& prefix) {
  if (name.size() <= prefix.size() || name.compare(0, prefix.size(), prefix) != 0) return 0;
  const std::string digits = name.substr(prefix.size());
  if (digits.size() > 9 || digits.find_first_not_of("0123456789") != std::string::npos) return 0;
  return std::stol(digits);
}

void sync_directory(const std::string& dir) {
  sync_to_disk(dir.empty() ? std::string(".") : dir);
}

bool process_is_gone(long pid) {
  if (pid <= 0 || pid == ::getpid()) return false;
  return ::kill(static_cast<pid_t>(pid), 0) != 0 && errno == ESRCH;
}

std::string output_file_target(const std::string& path) {
  std::error_code ec;
  const fs::file_status own = fs::symlink_status(path, ec);
  if (ec || !fs::exists(own) || fs::is_regular_file(own)) return path;
  const auto refuse = [&](const std::string& what) {
    return InputError(path + ": " + what + "; jpcr writes a whole new file and renames it into " +
                      "place: give the path of a regular file, or of none");
  };
  if (fs::is_symlink(own)) {
    const fs::file_status target = fs::status(path, ec);
    if (ec && ec != std::errc::no_such_file_or_directory)
      throw refuse("a symbolic link that cannot be followed (" + ec.message() + ")");
    if (!fs::exists(target)) throw refuse("a symbolic link to nothing");
    if (!fs::is_regular_file(target)) throw refuse("a symbolic link to no regular file");
    const fs::path resolved = fs::canonical(path, ec);
    if (ec) throw refuse("a symbolic link that cannot be followed (" + ec.message() + ")");
    return resolved.string();
  }
  if (fs::is_directory(own)) throw InputError(path + ": names a directory, not a file to write");
  throw refuse("exists and is no regular file (a device, a pipe or a socket)");
}

void write_file_atomically(const std::string& path,
                           const std::function<void(std::ostream&)>& write) {
  // Errors name the path given; the file replaced is the one a link leads to.
  const std::string target = output_file_target(path);
  const std::string tmp = temporary_name(target);
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
    // On the disk before the rename: otherwise a power loss can leave `path` renamed but empty.
    // EINVAL: a file system without fsync (a pipe-backed one), nothing to wait for.
    const int error = sync_to_disk(tmp);
    if (error != 0 && error != EINVAL)
      throw InputError(path + ": cannot be flushed to the disk (" + std::strerror(error) + ")");
    if (std::rename(tmp.c_str(), target.c_str()) != 0) {
      throw InputError(path + ": cannot be renamed into place (" + std::strerror(errno) + ")");
    }
  } catch (...) {
    std::remove(tmp.c_str());
    throw;
  }
  remove_abandoned_temporaries(fs::path(target).parent_path());
}

void ensure_directory(const std::string& dir) {
  std::error_code ec;
  fs::create_directories(dir, ec);
  if (ec || !fs::is_directory(dir)) {
    throw InputError(dir + ": cannot create directory (" + ec.message() + ")");
  }
}

void ensure_parent_directory(const std::string& file) {
  const std::string parent = fs::path(file).parent_path().string();
  if (!parent.empty()) ensure_directory(parent);
}

std::string read_file(const std::string& path) {
  std::error_code ec;
  if (!fs::exists(path, ec)) throw InputError(path + ": file does not exist");
  if (fs::is_directory(path, ec)) throw InputError(path + ": is a directory");
  // A FIFO would block and a device (/dev/zero) never end: only regular files are read.
  if (!fs::is_regular_file(path, ec)) throw InputError(path + ": not a regular file");
  std::ifstream in(path, std::ios::binary);
  if (!in) throw InputError(path + ": cannot be opened (" + std::strerror(errno) + ")");
  std::ostringstream ss;
  ss << in.rdbuf();
  if (in.bad()) throw InputError(path + ": read failed");
  return ss.str();
}

}  // namespace jpcr
