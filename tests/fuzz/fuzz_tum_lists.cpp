// libFuzzer target: TUM file lists and trajectories parse or fail with an InputError.
#include <cstdint>
#include <string>

#include "jpcr/io/tum_lists.hpp"
#include "jpcr/quadric/error.hpp"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  const std::string text(reinterpret_cast<const char*>(data), size);
  try {
    jpcr::parse_file_list(text, "fuzz.txt");
  } catch (const jpcr::InputError&) {
  }
  try {
    const jpcr::Trajectory t = jpcr::parse_trajectory(text, "fuzz.txt");
    // What parses must write back and parse to the same number of poses.
    if (jpcr::parse_trajectory(jpcr::format_trajectory(t), "again").size() != t.size()) {
      __builtin_trap();
    }
  } catch (const jpcr::InputError&) {
  }
  return 0;
}
