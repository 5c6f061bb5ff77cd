#include "design_search.hpp"

#include <spdlog/spdlog.h>

#include <algorithm>
#include <cmath>
#include <iterator>
#include <nlopt.hpp>
#include <string>
#include <utility>

#include "core/errors.hpp"
#include "design_checkpoint.hpp"
#include "parallel/fan_out.hpp"

namespace msfab {

namespace {

// The radical inverse of k in base b: the k-th Halton coordinate.
double radical_inverse(int k, int base) {
  double inverse = 0, digit = 1.0 / base;
  for (; k > 0; k /= base, digit /= base) inverse += digit * (k % base);
  return inverse;
}

}  // namespace

std::vector<double> start_point(const DesignProblem& p, int start) {
  std::vector<double> x;
  const int n = static_cast<int>(p.parameters.size());
  const int corners = n < 20 ? 1 << n : 1 << 20;
  static constexpr int kPrimes[] = {2, 3, 5, 7, 11, 13, 17, 19, 23, 29, 31, 37, 41, 43, 47, 53, 59, 61, 67, 71};
  if (p.space_filling_starts && n > static_cast<int>(std::size(kPrimes)))
    throw InputError("design loop: space-filling starts take at most 20 parameters");
  for (int i = 0; i < n; ++i) {
    const DesignParameter& q = p.parameters[i];
    double value = q.initial;
    if (start > 0 && p.space_filling_starts) {
      // Halton point `start` (point 0 is the box's corner, so the sequence
      // begins at 1): low discrepancy for every number of starts.
      value = q.lower + radical_inverse(start, kPrimes[i]) * (q.upper - q.lower);
    } else if (start > 0) {
      // Corners first at `spread` steps, then again further out, so no two
      // starts coincide before clamping.
      const int k = start - 1;
      const double sign = (k % corners >> i & 1) ? -1.0 : 1.0;
      value += sign * p.spread * q.step * (1 + k / corners);
    }
    x.push_back(std::clamp(value, q.lower, q.upper));
  }
  return x;
}

namespace {

struct StartState {
  const DesignProblem* problem;
  const DesignEvaluator* evaluator;
  const SearchControl* control;
  int start = 0;
  std::vector<Evaluation> evaluations;
  std::vector<double> last_x;      // normalized point of evaluations.back()
  std::vector<Evaluation> replay;  // from the checkpoint, not yet asked for again
  int simulated = 0;               // evaluations simulated in this run
  bool stopped = false;            // stopped at control->max_new_evaluations
};

std::vector<double> physical(const DesignProblem& p, const double* u) {
  std::vector<double> x;
  for (std::size_t i = 0; i < p.parameters.size(); ++i) {
    const DesignParameter& q = p.parameters[i];
    x.push_back(q.lower + std::clamp(u[i], 0.0, 1.0) * (q.upper - q.lower));
  }
  return x;
}

double objective_scale(const DesignProblem& p) { return p.task == DesignTask::kTarget ? p.length_scale : 1.0; }

void log_evaluation(const DesignProblem& p, const Evaluation& e) {
  std::string params, constraints;
  for (std::size_t i = 0; i < p.parameters.size(); ++i)
    params += fmt::format("{}{} = {:.5f}", i ? ", " : "", p.parameters[i].name, e.parameters[i]);
  const std::vector<std::string> names = constraint_names(p.task);
  for (std::size_t i = 0; i < e.constraints.size(); ++i)
    constraints += fmt::format(", {} = {:+.4f} m", names[i], e.constraints[i]);
  const std::string confirm = e.confirmed
                                  ? fmt::format(" (at the confirm step {:.5g}, flip {:.1f} deg)", e.confirm_objective,
                                                e.confirm_outcome.flip_at_landing * 180 / M_PI)
                                  : "";
  std::string scaled;
  for (const ScaledRun& r : e.scaled)
    scaled +=
        fmt::format("{}E x {:g}: {:.5g}, flip {:.1f} deg, x {:.4f} m", scaled.empty() ? " (" : "; ", r.modulus_scale,
                    r.objective, r.outcome.flip_at_landing * 180 / M_PI, r.outcome.com_at_landing.x());
  if (!scaled.empty()) scaled += ")";
  spdlog::info("start {} evaluation {}: {}: objective {:.5g}{}{}{}, flip at landing {:.1f} deg{}, {:.1f} s", e.start,
               e.index, params, e.objective, confirm, scaled, constraints, e.outcome.flip_at_landing * 180 / M_PI,
               e.ok ? "" : " (simulation failed)", e.seconds);
}

// The evaluation at normalized point u, reusing the last one when COBYLA
// asks for the constraints at the point whose objective it just had, and
// the checkpoint's when COBYLA asks for the point it recorded.
const Evaluation& evaluation_at(StartState& s, const double* u) {
  const std::size_t n = s.problem->parameters.size();
  if (!s.evaluations.empty() && std::equal(u, u + n, s.last_x.begin())) return s.evaluations.back();
  const std::vector<double> x = physical(*s.problem, u);
  const std::size_t k = s.evaluations.size();
  if (k < s.replay.size()) {
    if (s.replay[k].parameters == x) {
      s.evaluations.push_back(s.replay[k]);
      s.last_x.assign(u, u + n);
      return s.evaluations.back();
    }
    // Only another binary (other round-off) leads COBYLA elsewhere.
    spdlog::warn("start {}: evaluation {} is not at the checkpoint's point; simulating from here on", s.start, k);
    s.replay.resize(k);
  }
  const SearchControl& c = *s.control;
  if (c.max_new_evaluations > 0 && s.simulated == c.max_new_evaluations) {
    s.stopped = true;
    throw nlopt::forced_stop();
  }
  s.evaluations.push_back(s.evaluator->evaluate(x, s.start, static_cast<int>(k)));
  ++s.simulated;
  s.last_x.assign(u, u + n);
  log_evaluation(*s.problem, s.evaluations.back());
  if (!c.checkpoint_out.empty()) {
    // NLopt would swallow an exception here and stop the start; a
    // checkpoint that cannot be written (a full disk) must not end a search.
    const std::string path = start_checkpoint_path(c.checkpoint_out, s.start);
    try {
      write_evaluations_checkpoint(path, c.run_text, *s.problem, s.evaluations);
    } catch (const std::exception& e) {
      spdlog::warn("start {}: checkpoint {} not written ({}); the search goes on", s.start, path, e.what());
    }
  }
  return s.evaluations.back();
}

double objective(unsigned, const double* u, double*, void* data) {
  auto* s = static_cast<StartState*>(data);
  return evaluation_at(*s, u).objective / objective_scale(*s->problem);
}

void constraints(unsigned m, double* result, unsigned, const double* u, double*, void* data) {
  auto* s = static_cast<StartState*>(data);
  const Evaluation& e = evaluation_at(*s, u);
  for (unsigned i = 0; i < m; ++i) result[i] = e.constraints[i] / s->problem->length_scale;
}

}  // namespace

StartResult run_start(const DesignProblem& p, const DesignEvaluator& evaluator, int start, const SearchControl& control,
                      std::vector<Evaluation> replay) {
  const unsigned n = static_cast<unsigned>(p.parameters.size());
  StartState state{&p, &evaluator, &control, start, {}, {}, std::move(replay), 0, false};
  if (!state.replay.empty())
    spdlog::info("start {}: resuming with {} recorded evaluations", start, state.replay.size());
  nlopt::opt opt(nlopt::LN_COBYLA, n);
  std::vector<double> u(n), step(n);
  const std::vector<double> x0 = start_point(p, start);
  for (unsigned i = 0; i < n; ++i) {
    const DesignParameter& q = p.parameters[i];
    u[i] = (x0[i] - q.lower) / (q.upper - q.lower);
    step[i] = q.step / (q.upper - q.lower);
  }
  opt.set_lower_bounds(std::vector<double>(n, 0.0));
  opt.set_upper_bounds(std::vector<double>(n, 1.0));
  opt.set_min_objective(objective, &state);
  const std::size_t m = constraint_names(p.task).size();
  if (m > 0) opt.add_inequality_mconstraint(constraints, &state, std::vector<double>(m, 1e-6 / p.length_scale));
  opt.set_initial_step(step);
  opt.set_maxeval(p.max_evaluations);
  opt.set_xtol_abs(p.xtol);
  if (p.stop_below > 0) opt.set_stopval(p.stop_below / objective_scale(p));
  double f = 0;
  try {
    const nlopt::result r = opt.optimize(u, f);
    spdlog::info("start {}: COBYLA stopped ({}) after {} evaluations", start,
                 r == nlopt::MAXEVAL_REACHED   ? "evaluation budget"
                 : r == nlopt::STOPVAL_REACHED ? "objective reached"
                 : r == nlopt::XTOL_REACHED    ? "step below xtol"
                                               : "converged",
                 state.evaluations.size());
  } catch (const nlopt::forced_stop&) {
    if (!state.stopped) throw;
    spdlog::info("start {}: stopped after {} new evaluations ({} in all); the checkpoint is kept", start,
                 state.simulated, state.evaluations.size());
  } catch (const nlopt::roundoff_limited&) {
    spdlog::info("start {}: COBYLA stopped on round-off after {} evaluations", start, state.evaluations.size());
  } catch (const InputError&) {
    throw;
  } catch (const std::runtime_error& e) {
    // An NLopt failure keeps what was evaluated; the best of it still counts.
    spdlog::warn("start {}: COBYLA failed: {}", start, e.what());
  }
  return {state.evaluations, state.stopped};
}

std::vector<Evaluation> run_all_starts(const DesignProblem& p, const DesignEvaluator& evaluator,
                                       const SearchControl& control, bool* stopped) {
  const int per = evaluation_record_size(p);
  const int row = 2 + p.max_evaluations * per;  // count, stopped, the evaluations
  // Read before the fan-out, which would report a checkpoint of another run
  // (bad input) as a numerical failure.
  std::vector<std::vector<Evaluation>> replays(p.starts);
  if (control.resume && !control.checkpoint_out.empty())
    for (int start = 0; start < p.starts; ++start)
      replays[start] =
          read_evaluations_checkpoint(start_checkpoint_path(control.checkpoint_out, start), control.run_text, p);
  const std::vector<double> records = fan_out(p.starts, row, [&](int start, double* r) {
    const StartResult result = run_start(p, evaluator, start, control, std::move(replays[start]));
    const std::size_t count =
        std::min<std::size_t>(result.evaluations.size(), static_cast<std::size_t>(p.max_evaluations));
    r[0] = static_cast<double>(count);
    r[1] = result.stopped ? 1 : 0;
    for (std::size_t k = 0; k < count; ++k) pack_evaluation(p, result.evaluations[k], r + 2 + k * per);
  });
  std::vector<Evaluation> all;
  if (stopped) *stopped = false;
  for (int start = 0; start < p.starts; ++start) {
    const double* r = records.data() + static_cast<std::size_t>(start) * row;
    if (stopped && r[1] != 0) *stopped = true;
    const int count = static_cast<int>(r[0]);
    if (count == 0) spdlog::warn("start {}: no evaluation came back", start);
    for (int k = 0; k < count; ++k) all.push_back(unpack_evaluation(p, r + 2 + k * per));
  }
  if (all.empty()) throw NumericalError("design loop: no start produced an evaluation");
  return all;
}

std::size_t best_evaluation(const std::vector<Evaluation>& e) {
  std::size_t best = 0;
  auto better = [](const Evaluation& a, const Evaluation& b) {
    if (a.feasible() != b.feasible()) return a.feasible();
    if (!a.feasible() && a.violation() != b.violation()) return a.violation() < b.violation();
    return a.objective < b.objective;  // equal: the earlier (start, index) stays
  };
  for (std::size_t i = 1; i < e.size(); ++i)
    if (better(e[i], e[best])) best = i;
  return best;
}

}  // namespace msfab
