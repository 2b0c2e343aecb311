// The one exception type for bad input: a missing or corrupt file, a malformed line, an invalid
// configuration. Its message names the file (and line or key) and the problem, ready to print.
#pragma once

#include <stdexcept>
#include <string>

namespace jpcr {

class InputError : public std::runtime_error {
 public:
  explicit InputError(const std::string& what) : std::runtime_error(what) {}
};

}  // namespace jpcr
