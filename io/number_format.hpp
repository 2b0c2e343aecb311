// Shortest decimal text that reads back to the same double (std::to_chars), for trajectory
// files and JSON: full precision without noise digits.
#pragma once

#include <string>

namespace jpcr {

/// Shortest round-trip representation; "nan", "inf" and "-inf" for non-finite values.
std::string format_double(double value);

/// A timestamp for text files: the shortest fixed-point text that reads back to the same double
/// ("1700000000", "1305031102.175304"), never an exponent form ("1.7e+09") that some TUM tools
/// and readers do not expect; non-finite values as format_double.
std::string format_timestamp(double value);

/// Parses a whole token as a double; false when the token is not entirely a number.
bool parse_double(const std::string& token, double& value);

}  // namespace jpcr
