// NumPy .npy files (format versions 1–3, little-endian, C order): the float maps of curvature
// and normals that Python reads with numpy.load.
#pragma once

#include <cstddef>
#include <cstdint>
#include <string>
#include <vector>

namespace jpcr {

/// An array read from .npy with its element type kept. dtype is numpy's descr without the byte
/// order: "f4", "f8", "u1", "u2", "i4", ...
struct NpyArray {
  std::string dtype;
  std::vector<std::size_t> shape;
  std::vector<std::uint8_t> bytes;  // raw little-endian elements

  std::size_t element_count() const;
  /// The elements converted to float (f4, f8, u1, u2, i2, i4 supported); throws otherwise.
  std::vector<float> to_float() const;
};

/// Parses .npy bytes; throws InputError "<name>: problem" on anything malformed (bad magic,
/// unsupported dtype or order, a shape that does not match the data length).
NpyArray parse_npy(const std::uint8_t* data, std::size_t size, const std::string& name);
NpyArray read_npy(const std::string& path);

/// Serialises an array; T is float, double, uint8_t, uint16_t or int32_t.
template <typename T>
std::string format_npy(const std::vector<std::size_t>& shape, const T* data);

/// Writes an array atomically.
template <typename T>
void write_npy(const std::string& path, const std::vector<std::size_t>& shape, const T* data);

}  // namespace jpcr
