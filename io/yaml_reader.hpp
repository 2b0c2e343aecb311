// Strict mapping of YAML onto plain config structs (architecture.md: "a flat config struct has
// in-class defaults, and YAML maps onto it in io/ only"). Keys that are absent keep the struct's
// default; unknown keys and wrong types are errors that name the file, line and key.
#pragma once

#include <array>
#include <set>
#include <string>
#include <vector>

#include <yaml-cpp/yaml.h>

namespace jpcr {

class YamlSection {
 public:
  /// `node` must be a map (or null/absent, which reads as empty); `path` is the dotted key
  /// prefix for messages ("" at the top), `file` the file name.
  YamlSection(const YAML::Node& node, std::string file, std::string path = "");

  bool has(const std::string& key) const;

  /// Reads key into value when present; throws InputError on a wrong type or out-of-range value.
  void read(const std::string& key, double& value);
  void read(const std::string& key, float& value);
  void read(const std::string& key, int& value);
  void read(const std::string& key, bool& value);
  void read(const std::string& key, std::string& value);
  void read(const std::string& key, std::vector<double>& value);
  template <std::size_t N>
  void read(const std::string& key, std::array<double, N>& value) {
    YAML::Node unused;
    if (!has(key)) {
      take(key, unused);  // marks a null key as known
      return;
    }
    std::vector<double> v;
    read(key, v);
    if (v.size() != N) fail(key, "expected a list of " + std::to_string(N) + " numbers");
    for (std::size_t i = 0; i < N; ++i)
      value[i] = v[i];
  }

  /// Reads a string that must be one of `choices`.
  void read_choice(const std::string& key, std::string& value,
                   const std::vector<std::string>& choices);

  /// A nested map (absent reads as empty). The child must be finished by the caller.
  YamlSection section(const std::string& key);

  /// A list of maps (absent reads as empty), named "key[i]" in messages. Each must be finished
  /// by the caller.
  std::vector<YamlSection> sections(const std::string& key);

  /// Throws InputError naming the first key that was never read.
  void finish() const;

  [[noreturn]] void fail(const std::string& key, const std::string& problem) const;
  std::string qualified(const std::string& key) const;

 private:
  bool take(const std::string& key, YAML::Node& out);

  YAML::Node node_;
  std::string file_;
  std::string path_;
  std::set<std::string> used_;
};

/// Loads a YAML file; throws InputError naming the file on a missing file or a syntax error.
YAML::Node load_yaml_file(const std::string& path);

/// Parses YAML text; `name` is used in messages. Throws InputError on a syntax error or on
/// nesting deeper than a config ever needs (deep nesting would exhaust yaml-cpp's stack).
YAML::Node parse_yaml(const std::string& text, const std::string& name);

}  // namespace jpcr
