// The message of the jpcr::InputError a call throws, for tests of error messages.
#pragma once

#include <functional>
#include <string>

#include "jpcr/quadric/error.hpp"

namespace jpcr::test {

/// What f() throws as InputError, or "<no error>".
inline std::string input_error_of(const std::function<void()>& f) {
  try {
    f();
  } catch (const InputError& e) {
    return e.what();
  }
  return "<no error>";
}

}  // namespace jpcr::test
