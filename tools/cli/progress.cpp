#include "cli/progress.hpp"

#include <unistd.h>

#include <algorithm>
#include <cerrno>  // program_invocation_short_name
#include <cstdio>
#include <iostream>

#include "cli/arguments.hpp"

namespace jpcr::cli {

Progress::Progress(std::string program, Clock::time_point start)
    : program_(std::move(program)), start_(start), terminal_(isatty(2) != 0) {}

double Progress::seconds() const {
  return std::chrono::duration<double>(Clock::now() - start_).count();
}

void Progress::note(const std::string& message) const {
  std::fprintf(stderr, "%s%s: %s\n", terminal_ ? "\r\033[K" : "", program_.c_str(),
               message.c_str());
}

void Progress::operator()(std::size_t done, std::size_t total, const std::string& extra) {
  if (total == 0) return;
  const bool tenth = done == 1 || done * 10 / total != (done - 1) * 10 / total;
  if (!terminal_ && !tenth && done != total) return;
  const double s = seconds();
  std::fprintf(stderr, "%s%s: frame %zu/%zu  %.1f s  %.1f frames/s%s%s%s", terminal_ ? "\r" : "",
               program_.c_str(), done, total, s, done / std::max(s, 1e-9),
               extra.empty() ? "" : "  ", extra.c_str(),
               terminal_ && done != total ? "\033[K" : "\n");
}

FrameRange parse_frame_range(const std::string& text, std::size_t size) {
  auto number = [&](const std::string& part, std::size_t fallback) -> std::size_t {
    if (part.empty()) return fallback;
    std::size_t used = 0;
    unsigned long long value = 0;
    try {
      value = std::stoull(part, &used);
    } catch (const std::exception&) {
      used = 0;
    }
    if (used != part.size() || part[0] == '-' || part[0] == '+')
      throw UsageError("--frames expects FIRST:LAST (0-based, LAST excluded), got '" + text + "'");
    return static_cast<std::size_t>(value);
  };
  FrameRange r{0, size};
  const std::size_t colon = text.find(':');
  if (colon == std::string::npos) {
    if (!text.empty()) r.first = number(text, 0), r.last = r.first + 1;
  } else {
    r.first = number(text.substr(0, colon), 0);
    r.last = number(text.substr(colon + 1), size);
  }
  if (r.last > size && r.first < size)
    std::cerr << program_invocation_short_name << ": warning: --frames " << text
              << ": the dataset has " << size << " frames; running " << r.first << ":" << size
              << '\n';
  r.last = std::min(r.last, size);
  if (r.first >= r.last)
    throw UsageError("--frames '" + text + "' selects no frame of the " + std::to_string(size) +
                     " in the dataset");
  return r;
}

}  // namespace jpcr::cli
