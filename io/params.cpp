#include "jpcr/io/params.hpp"

#include "jpcr/io/atomic_file.hpp"
#include "jpcr/io/yaml_reader.hpp"

namespace jpcr {

namespace {

void read_dataset(YamlSection yaml, DatasetParams& p) {
  yaml.read("max_time_difference", p.max_time_difference);
  if (p.max_time_difference <= 0.0) yaml.fail("max_time_difference", "must be positive (s)");
  yaml.finish();
}

}  // namespace

Params load_params(const std::string& path) {
  return parse_params(read_file(path), path);
}

Params parse_params(const std::string& text, const std::string& path) {
  YamlSection yaml(parse_yaml(text, path), path);
  Params params;
  read_dataset(yaml.section("dataset"), params.dataset);
  yaml.finish();
  return params;
}

}  // namespace jpcr
