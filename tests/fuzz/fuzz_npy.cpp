// libFuzzer target: .npy parsing never reads out of bounds or allocates from a lying header.
#include <cstdint>
#include <string>

#include "jpcr/io/npy.hpp"
#include "jpcr/quadric/error.hpp"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  try {
    const jpcr::NpyArray a = jpcr::parse_npy(data, size, "fuzz.npy");
    if (a.to_float().size() != a.element_count()) __builtin_trap();
  } catch (const jpcr::InputError&) {
  }
  return 0;
}
