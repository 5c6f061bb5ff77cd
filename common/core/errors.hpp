#pragma once
// Error types and the process exit codes they map to (DESIGN §6).
#include <stdexcept>
#include <string>

namespace msfab {

enum ExitCode : int {
  kExitOk = 0,
  kExitInternal = 1,   // a bug: an invariant of ours was violated
  kExitBadInput = 2,   // bad usage or bad input: names file, field, problem
  kExitNumerical = 3,  // a numerical method did not converge
};

// Bad usage or bad input. The message must say which file / field and what
// was wrong, so a user can fix it without reading code.
class InputError : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

// A solver did not converge or met an impossible state (e.g. a matrix that
// is not positive definite after regularization). The message carries the
// residual history or the quantity that failed.
class NumericalError : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

}  // namespace msfab
