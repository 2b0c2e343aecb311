#include "jpcr/io/npy.hpp"

#include <cstring>
#include <limits>
#include <type_traits>

#include "jpcr/io/atomic_file.hpp"
#include "jpcr/quadric/error.hpp"

namespace jpcr {

namespace {

constexpr char kMagic[] = "\x93NUMPY";
constexpr std::size_t kMagicLength = 6;

template <typename T>
constexpr const char* descr() {
  if constexpr (std::is_same_v<T, float>) return "<f4";
  if constexpr (std::is_same_v<T, double>) return "<f8";
  if constexpr (std::is_same_v<T, std::uint8_t>) return "|u1";
  if constexpr (std::is_same_v<T, std::uint16_t>) return "<u2";
  if constexpr (std::is_same_v<T, std::int32_t>) return "<i4";
}

std::size_t dtype_size(const std::string& dtype) {
  if (dtype.size() != 2) return 0;
  const char digit = dtype[1];
  if (digit != '1' && digit != '2' && digit != '4' && digit != '8') return 0;
  if (dtype[0] != 'f' && dtype[0] != 'u' && dtype[0] != 'i') return 0;
  if (dtype[0] == 'f' && digit != '4' && digit != '8') return 0;
  return static_cast<std::size_t>(digit - '0');
}

// Extracts the value text of 'key' from the header dict, e.g. "'<f4'" or "(480, 640, 2)".
std::string dict_value(const std::string& header, const std::string& key, const std::string& name) {
  const std::string quoted = "'" + key + "'";
  const auto k = header.find(quoted);
  if (k == std::string::npos) throw InputError(name + ": .npy header has no '" + key + "'");
  auto colon = header.find(':', k + quoted.size());
  if (colon == std::string::npos) throw InputError(name + ": .npy header is malformed");
  auto start = header.find_first_not_of(' ', colon + 1);
  if (start == std::string::npos) throw InputError(name + ": .npy header is malformed");
  std::size_t end;
  if (header[start] == '(') {
    end = header.find(')', start);
    if (end == std::string::npos) throw InputError(name + ": .npy shape is malformed");
    ++end;
  } else {
    end = header.find_first_of(",}", start);
    if (end == std::string::npos) throw InputError(name + ": .npy header is malformed");
  }
  return header.substr(start, end - start);
}

std::vector<std::size_t> parse_shape(const std::string& text, const std::string& name) {
  std::vector<std::size_t> shape;
  std::size_t i = 1;  // skip '('
  while (i < text.size()) {
    while (i < text.size() && (text[i] == ' ' || text[i] == ','))
      ++i;
    if (i >= text.size() || text[i] == ')') break;
    std::size_t value = 0;
    bool digits = false;
    while (i < text.size() && text[i] >= '0' && text[i] <= '9') {
      if (value > (std::numeric_limits<std::size_t>::max() - 9) / 10) {
        throw InputError(name + ": .npy shape is too large");
      }
      value = value * 10 + static_cast<std::size_t>(text[i] - '0');
      digits = true;
      ++i;
    }
    if (!digits) throw InputError(name + ": .npy shape '" + text + "' is malformed");
    shape.push_back(value);
  }
  return shape;
}

template <typename T>
T load_le(const std::uint8_t* p) {
  T value;
  std::memcpy(&value, p, sizeof(T));
  return value;  // this code base targets little-endian hosts (x86-64, aarch64)
}

}  // namespace

std::size_t NpyArray::element_count() const {
  std::size_t n = 1;
  for (std::size_t d : shape)
    n *= d;
  return n;
}

std::vector<float> NpyArray::to_float() const {
  const std::size_t n = element_count();
  std::vector<float> out(n);
  const std::uint8_t* p = bytes.data();
  for (std::size_t i = 0; i < n; ++i) {
    if (dtype == "f4")
      out[i] = load_le<float>(p + 4 * i);
    else if (dtype == "f8")
      out[i] = static_cast<float>(load_le<double>(p + 8 * i));
    else if (dtype == "u1")
      out[i] = p[i];
    else if (dtype == "u2")
      out[i] = load_le<std::uint16_t>(p + 2 * i);
    else if (dtype == "i2")
      out[i] = load_le<std::int16_t>(p + 2 * i);
    else if (dtype == "i4")
      out[i] = static_cast<float>(load_le<std::int32_t>(p + 4 * i));
    else
      throw InputError("npy: cannot convert dtype '" + dtype + "' to float");
  }
  return out;
}

NpyArray parse_npy(const std::uint8_t* data, std::size_t size, const std::string& name) {
  if (size < kMagicLength + 4 || std::memcmp(data, kMagic, kMagicLength) != 0) {
    throw InputError(name + ": not a .npy file (bad magic)");
  }
  const int major = data[6];
  std::size_t header_length = 0, offset = 0;
  if (major == 1) {
    header_length = static_cast<std::size_t>(data[8]) | (static_cast<std::size_t>(data[9]) << 8);
    offset = 10;
  } else if (major == 2 || major == 3) {
    if (size < 12) throw InputError(name + ": truncated .npy header");
    header_length = 0;
    for (int b = 3; b >= 0; --b)
      header_length = (header_length << 8) | data[8 + b];
    offset = 12;
  } else {
    throw InputError(name + ": unsupported .npy version " + std::to_string(major));
  }
  if (header_length > size - offset) throw InputError(name + ": truncated .npy header");
  const std::string header(reinterpret_cast<const char*>(data + offset), header_length);
  offset += header_length;

  NpyArray array;
  const std::string descr_text = dict_value(header, "descr", name);
  if (descr_text.size() != 5 || descr_text.front() != '\'' || descr_text.back() != '\'') {
    throw InputError(name + ": unsupported .npy descr " + descr_text);
  }
  const char order = descr_text[1];
  array.dtype = descr_text.substr(2, 2);
  const std::size_t element_size = dtype_size(array.dtype);
  if (element_size == 0) throw InputError(name + ": unsupported .npy dtype " + descr_text);
  if (order == '>' && element_size > 1) {
    throw InputError(name + ": big-endian .npy data is not supported");
  }
  if (dict_value(header, "fortran_order", name) != "False") {
    throw InputError(name + ": Fortran-order .npy arrays are not supported");
  }
  array.shape = parse_shape(dict_value(header, "shape", name), name);

  std::size_t count = 1;
  for (std::size_t d : array.shape) {
    if (d != 0 && count > std::numeric_limits<std::size_t>::max() / d) {
      throw InputError(name + ": .npy shape overflows");
    }
    count *= d;
  }
  const std::size_t available = size - offset;
  if (count > available / element_size || count * element_size != available) {
    throw InputError(name + ": .npy data length " + std::to_string(available) +
                     " bytes does not match the shape (" + std::to_string(count) + " elements of " +
                     std::to_string(element_size) + " bytes)");
  }
  array.bytes.assign(data + offset, data + size);
  return array;
}

NpyArray read_npy(const std::string& path) {
  const std::string content = read_file(path);
  return parse_npy(reinterpret_cast<const std::uint8_t*>(content.data()), content.size(), path);
}

template <typename T>
std::string format_npy(const std::vector<std::size_t>& shape, const T* data) {
  std::string dict =
      std::string("{'descr': '") + descr<T>() + "', 'fortran_order': False, 'shape': (";
  std::size_t count = 1;
  for (std::size_t i = 0; i < shape.size(); ++i) {
    dict += std::to_string(shape[i]) + (shape.size() == 1 || i + 1 < shape.size() ? "," : "");
    if (i + 1 < shape.size()) dict += " ";
    count *= shape[i];
  }
  dict += "), }";
  // Pad with spaces so that magic + version + length + header is a multiple of 64, ending '\n'.
  const std::size_t unpadded = kMagicLength + 2 + 2 + dict.size() + 1;
  dict.append((64 - unpadded % 64) % 64, ' ');
  dict += '\n';
  std::string out(kMagic, kMagicLength);
  out += static_cast<char>(1);
  out += static_cast<char>(0);
  out += static_cast<char>(dict.size() & 0xff);
  out += static_cast<char>((dict.size() >> 8) & 0xff);
  out += dict;
  out.append(reinterpret_cast<const char*>(data), count * sizeof(T));
  return out;
}

template <typename T>
void write_npy(const std::string& path, const std::vector<std::size_t>& shape, const T* data) {
  const std::string bytes = format_npy(shape, data);
  write_file_atomically(path, [&](std::ostream& out) { out.write(bytes.data(), bytes.size()); });
}

#define JPCR_INSTANTIATE_NPY(T)                                                  \
  template std::string format_npy<T>(const std::vector<std::size_t>&, const T*); \
  template void write_npy<T>(const std::string&, const std::vector<std::size_t>&, const T*);
JPCR_INSTANTIATE_NPY(float)
JPCR_INSTANTIATE_NPY(double)
JPCR_INSTANTIATE_NPY(std::uint8_t)
JPCR_INSTANTIATE_NPY(std::uint16_t)
JPCR_INSTANTIATE_NPY(std::int32_t)
#undef JPCR_INSTANTIATE_NPY

}  // namespace jpcr
