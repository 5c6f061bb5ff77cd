#include "design_report.hpp"

#include <cmath>
#include <cstdio>
#include <string>

namespace msfab {

namespace {

void row(const char* name, const std::string& a, const std::string& b) {
  std::printf("  %-26s %18s %18s\n", name, a.c_str(), b.c_str());
}
std::string num(double x, const char* format = "%.5f") {
  char buf[48];
  std::snprintf(buf, sizeof buf, format, x);
  return buf;
}
std::string yes(bool b) { return b ? "yes" : "no"; }
std::string xz(const Vec3& v) { return "(" + num(v.x(), "%.4f") + ", " + num(v.z(), "%.4f") + ")"; }

}  // namespace

void print_design_summary(const DesignProblem& p, const DesignRun& run, const std::string& out) {
  const Evaluation& a = run.evaluations[run.initial];
  const Evaluation& b = run.evaluations[run.final];
  double simulated = 0;
  for (const Evaluation& e : run.evaluations) simulated += e.seconds;
  std::printf("msfab-jump-design: task %s, scene %s, %d elements\n", design_task_name(p.task), p.scene_path.c_str(),
              a.elements);
  std::printf("  %zu evaluations in %d start(s) of at most %d; %d rank(s) x %d thread(s)\n", run.evaluations.size(),
              p.starts, p.max_evaluations, run.ranks, run.threads);
  std::printf("  final design: start %d, evaluation %d\n", b.start, b.index);
  row("", "initial", "final");
  for (std::size_t i = 0; i < p.parameters.size(); ++i)
    row((p.parameters[i].name + " (m)").c_str(), num(a.parameters[i]), num(b.parameters[i]));
  row(p.task == DesignTask::kTarget ? "objective (m)" : "objective (rad^2)", num(a.objective, "%.5g"),
      num(b.objective, "%.5g"));
  if (p.confirm_time_step > 0)
    row(("objective at h = " + num(p.confirm_time_step, "%.3g") + " s").c_str(), num(a.confirm_objective, "%.5g"),
        num(b.confirm_objective, "%.5g"));
  for (std::size_t k = 0; k < p.modulus_scales.size(); ++k) {
    const auto scaled = [k](const Evaluation& e) {
      return k < e.scaled.size() ? num(e.scaled[k].objective, "%.5g") + ", " +
                                       num(e.scaled[k].outcome.flip_at_landing * 180 / M_PI, "%.1f") + " deg"
                                 : std::string("not run");
    };
    row(("objective, flip at E x " + num(p.modulus_scales[k], "%g")).c_str(), scaled(a), scaled(b));
  }
  const std::vector<std::string> names = constraint_names(p.task);
  for (std::size_t i = 0; i < names.size(); ++i)
    row((names[i] + " (m)").c_str(), num(a.constraints[i], "%+.4f"), num(b.constraints[i], "%+.4f"));
  row("feasible", yes(a.feasible()), yes(b.feasible()));
  row("lifted off / landed", yes(a.outcome.lifted_off) + " / " + yes(a.outcome.landed),
      yes(b.outcome.lifted_off) + " / " + yes(b.outcome.landed));
  row("lift-off, landing (s)", num(a.outcome.lift_off_time, "%.4f") + ", " + num(a.outcome.landing_time, "%.4f"),
      num(b.outcome.lift_off_time, "%.4f") + ", " + num(b.outcome.landing_time, "%.4f"));
  row("flip at landing (deg)", num(a.outcome.flip_at_landing * 180 / M_PI, "%.1f"),
      num(b.outcome.flip_at_landing * 180 / M_PI, "%.1f"));
  row("flip at end (deg)", num(a.outcome.flip_at_end * 180 / M_PI, "%.1f"),
      num(b.outcome.flip_at_end * 180 / M_PI, "%.1f"));
  row("COM x, z at landing (m)", xz(a.outcome.com_at_landing), xz(b.outcome.com_at_landing));
  if (p.confirm_time_step > 0)
    row("... at the confirm step", xz(a.confirm_outcome.com_at_landing), xz(b.confirm_outcome.com_at_landing));
  for (std::size_t k = 0; k < p.modulus_scales.size(); ++k) {
    const auto at = [k](const Evaluation& e) {
      return k < e.scaled.size() ? xz(e.scaled[k].outcome.com_at_landing) : std::string("not run");
    };
    row(("... at E x " + num(p.modulus_scales[k], "%g")).c_str(), at(a), at(b));
  }
  row("COM x, z at end (m)", xz(a.outcome.com_at_end), xz(b.outcome.com_at_end));
  row("highest COM z (m)", num(a.outcome.com_highest.z(), "%.4f"), num(b.outcome.com_highest.z(), "%.4f"));
  if (p.task == DesignTask::kJumpOver)
    row("COM z over the wall (m)", a.crossed_wall ? num(a.z_over_wall, "%.4f") : "not crossed",
        b.crossed_wall ? num(b.z_over_wall, "%.4f") : "not crossed");
  row("upright at end", yes(a.outcome.upright), yes(b.outcome.upright));
  row("simulation (s)", num(a.seconds, "%.1f"), num(b.seconds, "%.1f"));
  std::printf("  simulations: %.1f s in total, %.1f s each on average; wall time %.1f s (%.2f min)\n", simulated,
              simulated / run.evaluations.size(), run.wall_seconds, run.wall_seconds / 60);
  if (!run.robustness.samples.empty())
    std::printf("  print variation (E +-%.0f%%, parameters +-%.2g mm): %d of %zu samples succeed (%.0f%%)\n",
                100 * p.robustness.modulus, 1e3 * p.robustness.geometry, run.robustness.successes,
                run.robustness.samples.size(), 100 * run.robustness.fraction());
  std::printf("  artifact: %s\n", out.c_str());
}

}  // namespace msfab
