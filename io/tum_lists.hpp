// The text files of the TUM RGB-D layout: file lists (depth.txt, rgb.txt) and trajectories
// (groundtruth.txt, estimates: "timestamp tx ty tz qx qy qz qw").
#pragma once

#include <string>
#include <vector>

#include "jpcr/quadric/frame.hpp"

namespace jpcr {

struct ListEntry {
  double timestamp = 0.0;
  std::string path;  // as written in the list, relative to the dataset directory
  int line = 0;      // 1-based line in the list file, for messages
};

/// `text` without a leading UTF-8 byte-order mark (which Windows editors write): the lists and
/// trajectories are read without it, where it made the first line "timestamp '﻿#' is not a
/// number", naming an invisible character.
std::string without_utf8_bom(const std::string& text);

/// Parses a TUM file list. '#' lines are comments. Throws InputError "file:line: problem" on a
/// malformed line, a non-finite timestamp, or timestamps that are not strictly increasing.
std::vector<ListEntry> parse_file_list(const std::string& text, const std::string& name);
std::vector<ListEntry> read_file_list(const std::string& path);

/// Parses a TUM trajectory. Quaternions are normalised; a quaternion whose norm is far from 1,
/// NaN/Inf anywhere, a wrong number of fields, or timestamps that are not strictly increasing
/// throw InputError "file:line: problem".
Trajectory parse_trajectory(const std::string& text, const std::string& name);
Trajectory read_trajectory(const std::string& path);

/// Writes a TUM trajectory at full precision, atomically. `comment` lines are prefixed with '#'.
void write_trajectory(const std::string& path, const Trajectory& trajectory,
                      const std::string& comment = "");
std::string format_trajectory(const Trajectory& trajectory, const std::string& comment = "");

}  // namespace jpcr
