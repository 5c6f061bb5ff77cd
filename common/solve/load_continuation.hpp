#pragma once
// Load continuation from load factor 0 to 1 (thesis §2.5: large loads are
// applied in increments), shared by the static Newton solver and the
// quasistatic press: `steps` equal increments; an increment that fails is
// retried at half its size from the state before it, at most
// `max_halvings` times in a row; after a success the increment grows back
// (doubling, up to 1 / steps).
#include <cstdio>
#include <functional>
#include <sstream>
#include <string>
#include <vector>

namespace msfab {

struct LoadContinuation {
  int steps = 1;
  int max_halvings = 8;
  // Solves at load factor s (load_step counts attempts from 1); false with
  // `why` set when it did not converge.
  std::function<bool(double s, int load_step, std::string& why)> solve_at;
  std::function<void()> save;                                        // the state before an increment
  std::function<void()> restore;                                     // back to it after a failure
  std::function<void(double s)> on_converged;                        // optional
  std::function<void(double s, const std::string& why)> on_halving;  // optional
};

struct LoadContinuationResult {
  bool converged = false;
  int load_steps = 0;    // increments tried, failed ones included
  double failed_at = 0;  // the load factor that failed last (when not converged)
  int halvings = 0;      // consecutive halvings before the final failure
  std::string why;       // the final failure's reason
};

// When it does not converge, the state is restored to the last converged
// increment's.
LoadContinuationResult continue_load(const LoadContinuation& c);

// The columns an iteration table of a Newton continuation starts with: load
// step, load factor, iteration, residual, energy, step length and shift.
template <class Iteration>
std::string newton_iteration_columns(const Iteration& h) {
  char line[160];
  std::snprintf(line, sizeof line, "  %4d  %.4f  %4d  %.4e  % .6e  %.3e  %.2e", h.load_step, h.load_factor, h.iteration,
                h.residual, h.energy, h.step_length, h.shift);
  return line;
}

// The iteration table of a continuation: `header`, then one line per
// iteration from format_line(iteration), the last max_lines of them, with a
// line saying how many earlier ones were left out.
template <class Iteration, class FormatLine>
std::string format_iteration_table(const std::vector<Iteration>& history, std::size_t max_lines, const char* header,
                                   FormatLine format_line) {
  std::ostringstream out;
  out << header;
  const std::size_t first = history.size() > max_lines ? history.size() - max_lines : 0;
  if (first > 0) out << "  ... (" << first << " earlier iterations)\n";
  for (std::size_t i = first; i < history.size(); ++i) out << format_line(history[i]);
  return out.str();
}

}  // namespace msfab
