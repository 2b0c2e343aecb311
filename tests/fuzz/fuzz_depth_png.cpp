// libFuzzer target: the depth PNG decoder must turn any bytes into a DepthImage or an InputError.
#include <cstdint>
#include <string>

#include "jpcr/io/depth_png.hpp"
#include "jpcr/quadric/error.hpp"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  const std::string bytes(reinterpret_cast<const char*>(data), size);
  try {
    const jpcr::DepthImage depth = jpcr::decode_depth_png(bytes, "fuzz.png", 5000.0);
    volatile float sink = depth.empty() ? 0.0f : depth[depth.size() / 2];
    (void)sink;
  } catch (const jpcr::InputError&) {
  }
  return 0;
}
