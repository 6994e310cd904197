// Error types that cross module boundaries.
//
// InputError: the user's input is wrong (a file, a field, an option). main() prints its message
// as one line and exits with code 2. InternalError: something that should not happen did; exit 1.
// Programming errors use MS_CHECK (base/check.h), which aborts with a message.
#pragma once

#include <stdexcept>
#include <string>

namespace ms {

class InputError : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

class InternalError : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

// Exit codes of the manisweep binary.
constexpr int kExitOk = 0;
constexpr int kExitInternal = 1;
constexpr int kExitBadInput = 2;
constexpr int kExitInterrupted = 130;

}  // namespace ms
