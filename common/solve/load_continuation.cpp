#include "solve/load_continuation.hpp"

#include <algorithm>

namespace msfab {

LoadContinuationResult continue_load(const LoadContinuation& c) {
  LoadContinuationResult out;
  const int steps = std::max(1, c.steps);
  double s_done = 0, ds = 1.0 / steps;
  int halvings = 0;
  // Round-off in the summed increments must not ask for a last sliver.
  while (s_done < 1.0 - 1e-12) {
    const double s = std::min(1.0, s_done + ds);
    c.save();
    std::string why;
    ++out.load_steps;
    if (c.solve_at(s, out.load_steps, why)) {
      if (c.on_converged) c.on_converged(s);
      s_done = s;
      if (halvings > 0) ds = std::min(2 * ds, 1.0 / steps);  // recover after a cut
      halvings = 0;
      continue;
    }
    c.restore();
    if (halvings >= c.max_halvings) {
      out.failed_at = s;
      out.halvings = halvings;
      out.why = why;
      return out;
    }
    if (c.on_halving) c.on_halving(s, why);
    ds *= 0.5;
    ++halvings;
  }
  out.converged = true;
  return out;
}

}  // namespace msfab
