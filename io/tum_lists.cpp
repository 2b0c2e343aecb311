#include "jpcr/io/tum_lists.hpp"

#include <cmath>
#include <sstream>

#include "jpcr/io/atomic_file.hpp"
#include "jpcr/io/number_format.hpp"
#include "jpcr/quadric/error.hpp"

namespace jpcr {

namespace {

std::vector<std::string> split_fields(const std::string& line) {
  std::vector<std::string> fields;
  std::istringstream ss(line);
  std::string field;
  while (ss >> field)
    fields.push_back(field);
  return fields;
}

// A NUL byte ends a C string: a file name holding one would name another file, and every
// message quoting it would stop there (the file list's name and line lost with it).
void check_text_line(const std::string& line, const std::string& name, int number);

bool is_comment_or_blank(const std::string& line) {
  const auto first = line.find_first_not_of(" \t\r");
  return first == std::string::npos || line[first] == '#';
}

[[noreturn]] void fail(const std::string& name, int line, const std::string& problem) {
  throw InputError(name + ":" + std::to_string(line) + ": " + problem);
}

void check_text_line(const std::string& line, const std::string& name, int number) {
  if (line.find('\0') != std::string::npos)
    fail(name, number, "holds a NUL byte (a binary file, not a text list?)");
}

double parse_timestamp(const std::string& token, const std::string& name, int line) {
  double t = 0.0;
  if (!parse_double(token, t)) fail(name, line, "timestamp '" + token + "' is not a number");
  if (!std::isfinite(t)) fail(name, line, "timestamp is not finite");
  return t;
}

void check_increasing(double previous, double current, bool has_previous, const std::string& name,
                      int line) {
  if (!has_previous) return;
  if (current == previous) fail(name, line, "duplicate timestamp " + format_double(current));
  if (current < previous) {
    fail(name, line,
         "timestamps are not sorted (" + format_double(current) + " after " +
             format_double(previous) + ")");
  }
}

}  // namespace

std::string without_utf8_bom(const std::string& text) {
  return text.rfind("\xEF\xBB\xBF", 0) == 0 ? text.substr(3) : text;
}

std::vector<ListEntry> parse_file_list(const std::string& text, const std::string& name) {
  std::vector<ListEntry> entries;
  std::istringstream in(without_utf8_bom(text));
  std::string line;
  int number = 0;
  while (std::getline(in, line)) {
    ++number;
    check_text_line(line, name, number);
    if (is_comment_or_blank(line)) continue;
    const std::vector<std::string> fields = split_fields(line);
    if (fields.size() < 2) fail(name, number, "expected 'timestamp filename'");
    ListEntry entry{parse_timestamp(fields[0], name, number), fields[1], number};
    check_increasing(entries.empty() ? 0.0 : entries.back().timestamp, entry.timestamp,
                     !entries.empty(), name, number);
    entries.push_back(std::move(entry));
  }
  return entries;
}

std::vector<ListEntry> read_file_list(const std::string& path) {
  return parse_file_list(read_file(path), path);
}

Trajectory parse_trajectory(const std::string& text, const std::string& name) {
  Trajectory trajectory;
  std::istringstream in(without_utf8_bom(text));
  std::string line;
  int number = 0;
  while (std::getline(in, line)) {
    ++number;
    check_text_line(line, name, number);
    if (is_comment_or_blank(line)) continue;
    const std::vector<std::string> fields = split_fields(line);
    if (fields.size() != 8) {
      fail(name, number,
           "expected 8 fields 'timestamp tx ty tz qx qy qz qw', got " +
               std::to_string(fields.size()));
    }
    double v[8];
    for (int k = 0; k < 8; ++k) {
      if (!parse_double(fields[k], v[k])) {
        fail(name, number,
             "field " + std::to_string(k + 1) + " '" + fields[k] + "' is not a number");
      }
      if (!std::isfinite(v[k]))
        fail(name, number, "field " + std::to_string(k + 1) + " is NaN/Inf");
    }
    Eigen::Quaterniond q(v[7], v[4], v[5], v[6]);
    const double norm = q.norm();
    if (std::abs(norm - 1.0) > 1e-2) {
      fail(name, number, "quaternion norm is " + format_double(norm) + ", not 1");
    }
    q.normalize();
    StampedPose pose;
    pose.timestamp = v[0];
    pose.pose.linear() = q.toRotationMatrix();
    pose.pose.translation() = Eigen::Vector3d(v[1], v[2], v[3]);
    check_increasing(trajectory.empty() ? 0.0 : trajectory.back().timestamp, pose.timestamp,
                     !trajectory.empty(), name, number);
    trajectory.push_back(pose);
  }
  return trajectory;
}

Trajectory read_trajectory(const std::string& path) {
  return parse_trajectory(read_file(path), path);
}

std::string format_trajectory(const Trajectory& trajectory, const std::string& comment) {
  std::ostringstream out;
  std::istringstream comments(comment);
  std::string line;
  while (std::getline(comments, line))
    out << "# " << line << '\n';
  out << "# timestamp tx ty tz qx qy qz qw\n";
  for (const StampedPose& p : trajectory) {
    Eigen::Quaterniond q(p.pose.linear());
    q.normalize();
    if (q.w() < 0.0) q.coeffs() = -q.coeffs();  // one canonical sign
    const Eigen::Vector3d t = p.pose.translation();
    out << format_timestamp(p.timestamp) << ' ' << format_double(t.x()) << ' '
        << format_double(t.y()) << ' ' << format_double(t.z()) << ' ' << format_double(q.x()) << ' '
        << format_double(q.y()) << ' ' << format_double(q.z()) << ' ' << format_double(q.w())
        << '\n';
  }
  return out.str();
}

void write_trajectory(const std::string& path, const Trajectory& trajectory,
                      const std::string& comment) {
  for (const StampedPose& p : trajectory) {
    if (!std::isfinite(p.timestamp) || !p.pose.matrix().allFinite()) {
      throw InputError(path + ": refusing to write a pose with NaN/Inf (timestamp " +
                       format_double(p.timestamp) + ")");
    }
  }
  const std::string text = format_trajectory(trajectory, comment);
  write_file_atomically(path, [&](std::ostream& out) { out << text; });
}

}  // namespace jpcr
