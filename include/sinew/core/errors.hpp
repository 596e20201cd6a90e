// Error classes that reach the user. Each names its culprit; the driver turns them into one message and
// a non-zero exit code.
#pragma once

#include <stdexcept>
#include <string>

namespace sinew {

// Bad input: XML syntax, unknown key, wrong type, value out of range, inconsistent settings.
struct InputError : std::runtime_error {
  using std::runtime_error::runtime_error;
};

}  // namespace sinew
