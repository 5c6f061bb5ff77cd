#include "solve/regularized_step.hpp"

#include <spdlog/spdlog.h>

#include "core/errors.hpp"

namespace msfab {
namespace {

constexpr int kMaxFactorizations = 12;
constexpr double kFirstShift = 1e-8;  // relative to the system's scale
constexpr double kShiftGrowth = 10;

}  // namespace

RegularizedStep solve_regularized_step(LinearSolver& solver, const SpMat& K, double scale,
                                       const std::function<void(double, VecX&)>& right_hand_side,
                                       const std::function<bool(VecX&)>& accept, VecX& rhs, VecX& step,
                                       const char* context) {
  RegularizedStep out;
  for (int attempt = 0; attempt < kMaxFactorizations && !out.ok; ++attempt) {
    if (attempt > 0) out.shift = (out.shift == 0) ? kFirstShift * scale : out.shift * kShiftGrowth;
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
