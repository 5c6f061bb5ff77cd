#pragma once
// The Newton step of a system that may be indefinite, taken as interior-
// point codes do (inertia correction): factorize K + shift I with shift 0,
// then a small multiple of the system's scale, growing ten-fold per retry,
// until the step is finite and acceptable (a descent direction). One rule
// for the static Newton solver, the quasistatic press and the Newmark step,
// so all three regularize alike.
#include <functional>
#include <string>

#include "solve/linear_solver.hpp"

namespace msfab {

// How the shift grows: 0 first, then first_shift times the system's scale,
// times growth per retry, at most max_factorizations in all. The defaults
// are the static solver's and the press's; the Newmark step, whose inertia
// term keeps its system far from singular, starts lower (1e-10).
struct RegularizationSchedule {
  double first_shift = 1e-8;
  double growth = 10;
  int max_factorizations = 12;
};

struct RegularizedStep {
  bool ok = false;
  double shift = 0;               // the shift of the last factorization tried
  std::string last_linear_error;  // what the last failed solve reported (iterative solvers), if any
};

// At most 12 factorizations. `right_hand_side(shift, rhs)` fills the system's
// right-hand side (it may depend on the shift, e.g. on rows held fixed);
// `accept(step)` may complete the step in place (held rows, tied unknowns)
// and says whether it will do. `context` prefixes the debug messages.
// `rhs` and `step` are the caller's work vectors (their sizes are kept).
RegularizedStep solve_regularized_step(LinearSolver& solver, const SpMat& K, double scale,
                                       const std::function<void(double shift, VecX& rhs)>& right_hand_side,
                                       const std::function<bool(VecX& step)>& accept, VecX& rhs, VecX& step,
                                       const char* context, const RegularizationSchedule& schedule = {});

}  // namespace msfab
