#include "solve/regularized_step.hpp"

#include <spdlog/spdlog.h>

#include "core/errors.hpp"

namespace msfab {

RegularizedStep solve_regularized_step(LinearSolver& solver, const SpMat& K, double scale,
                                       const std::function<void(double, VecX&)>& right_hand_side,
                                       const std::function<bool(VecX&)>& accept, VecX& rhs, VecX& step,
                                       const char* context, const RegularizationSchedule& schedule) {
  RegularizedStep out;
  for (int attempt = 0; attempt < schedule.max_factorizations && !out.ok; ++attempt) {
    if (attempt > 0) out.shift = (out.shift == 0) ? schedule.first_shift * scale : out.shift * schedule.growth;
    if (!solver.factorize(K, out.shift)) continue;
    right_hand_side(out.shift, rhs);
    try {
      step = solver.solve(rhs);
    } catch (const NumericalError& e) {
      // An iterative solver meets indefiniteness only while solving.
      spdlog::debug("{}linear solve failed with shift {:.2e}: {}", context, out.shift, e.what());
      out.last_linear_error = e.what();
      continue;
    }
    if (!step.allFinite()) continue;
    out.ok = accept(step);
  }
  return out;
}

}  // namespace msfab
