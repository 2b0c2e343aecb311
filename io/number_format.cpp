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
  // Decimal or scientific notation, with an optional sign, and the whole token: no leading
  // space and no hex float (strtod took "0x1.11p-5" as a timestamp, and named its map by the
  // decimal value). "nan" and "inf" parse; the callers check finiteness themselves.
  const char* first = token.data();
  const char* last = first + token.size();
  if (first != last && *first == '+') {  // from_chars takes '-' only
    ++first;
    if (first != last && *first == '-') return false;
  }
  const auto result = std::from_chars(first, last, value, std::chars_format::general);
  return result.ec == std::errc() && result.ptr == last;
}

}  // namespace jpcr
