// Errors for bad input. accel/, tracer/ and datasets/ throw these; harness/ catches them at one
// boundary, prints the message as one line and exits 2.
#pragma once

#include <stdexcept>
#include <string>

namespace ab {

/// Bad input: a missing or malformed file, a bad value. The message names the file or option.
struct InputError : std::runtime_error {
  using std::runtime_error::runtime_error;
};

}  // namespace ab
