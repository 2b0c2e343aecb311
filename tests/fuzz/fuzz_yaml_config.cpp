// libFuzzer target: camera, parameter and synthetic scene YAML load or fail with an InputError
// naming the key.
#include <cstdint>
#include <string>

#include "jpcr/io/camera_yaml.hpp"
#include "jpcr/io/params.hpp"
#include "jpcr/io/synthetic_scene.hpp"
#include "jpcr/quadric/error.hpp"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  const std::string text(reinterpret_cast<const char*>(data), size);
  try {
    jpcr::parse_camera_yaml(text, "fuzz.yaml").validate();
  } catch (const jpcr::InputError&) {
  }
  try {
    jpcr::parse_params(text, "fuzz.yaml");
  } catch (const jpcr::InputError&) {
  }
  try {
    jpcr::parse_scene(text, "fuzz.yaml", "fuzz");
  } catch (const jpcr::InputError&) {
  }
  return 0;
}
