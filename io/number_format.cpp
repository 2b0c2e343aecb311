#include "jpcr/io/number_format.hpp"

#include <charconv>
#include <cmath>
#include <cstdlib>

namespace jpcr {

std::string format_double(double value) {
  if (std::isnan(value)) return "nan";
  if (std::isinf(value)) return value > 0 ? "inf" : "-inf";
  char buffer[64];
  const auto result = std::to_chars(buffer, buffer + sizeof(buffer), value);
  return std::string(buffer, result.ptr);
}

std::string format_timestamp(double value) {
  if (!std::isfinite(value)) return format_double(value);
  char buffer[400];  // fixed notation of any finite double fits (DBL_MAX has 309 digits)
  const auto result =
      std::to_chars(buffer, buffer + sizeof(buffer), value, std::chars_format::fixed);
  return std::string(buffer, result.ptr);
}

bool parse_double(const std::string& token, double& value) {
  if (token.empty()) return false;
  // strtod accepts "nan"/"inf" and hex floats; the callers check finiteness themselves.
  char* end = nullptr;
  value = std::strtod(token.c_str(), &end);
  return end == token.c_str() + token.size();
}

}  // namespace jpcr
