#include "design_artifact.hpp"

#include <cmath>
#include <cstdint>

#include "io/artifact.hpp"

namespace msfab {

namespace {
constexpr const char* kSchema = "msfab.jump_design";
constexpr int kVersion = 1;

std::vector<double> outcome_row(const JumpOutcome& o, bool crossed_wall, double z_over_wall) {
  return {double(o.lifted_off), double(o.landed),  double(o.upright),    o.lift_off_time,      o.landing_time,
          o.end_time,           o.flip_at_landing, o.flip_at_end,        o.com_at_landing.x(), o.com_at_landing.y(),
          o.com_at_landing.z(), o.com_at_end.x(),  o.com_at_end.y(),     o.com_at_end.z(),     o.com_highest.x(),
          o.com_highest.y(),    o.com_highest.z(), double(crossed_wall), z_over_wall};
}
std::vector<double> outcome_row(const Evaluation& e) { return outcome_row(e.outcome, e.crossed_wall, e.z_over_wall); }

void write_design(H5File& f, const std::string& group, const Evaluation& e) {
  f.create_group(group);
  f.write_vector(group + "/parameters", e.parameters);
  if (!e.constraints.empty()) f.write_vector(group + "/constraints", e.constraints);
  f.write_vector(group + "/outcome", outcome_row(e));
  f.write_attribute(group, "objective", e.objective);
  f.write_attribute(group, "start", static_cast<std::int32_t>(e.start));
  f.write_attribute(group, "evaluation", static_cast<std::int32_t>(e.index));
  f.write_attribute(group, "feasible", static_cast<std::int32_t>(e.feasible()));
  f.write_attribute(group, "simulated", static_cast<std::int32_t>(e.ok));
}

// A group with one row per evaluation: simulated, objective, parameters and
// outcome (the columns /evaluations and /robustness share).
void write_evaluation_table(H5File& f, const std::string& group, const std::vector<const Evaluation*>& rows) {
  const std::size_t n = rows.size(), np = rows.front()->parameters.size(), nk = outcome_columns().size();
  std::vector<std::int32_t> simulated(n);
  std::vector<double> objective(n), parameters(n * np), outcome(n * nk);
  for (std::size_t i = 0; i < n; ++i) {
    const Evaluation& e = *rows[i];
    simulated[i] = e.ok;
    objective[i] = e.objective;
    std::copy(e.parameters.begin(), e.parameters.end(), parameters.begin() + i * np);
    const std::vector<double> row = outcome_row(e);
    std::copy(row.begin(), row.end(), outcome.begin() + i * nk);
  }
  f.create_group(group);
  f.write_vector(group + "/simulated", simulated);
  f.write_vector(group + "/objective", objective);
  f.write_dataset(group + "/parameters", parameters, {hsize_t(n), hsize_t(np)});
  f.write_dataset(group + "/outcome", outcome, {hsize_t(n), hsize_t(nk)});
  f.write_attribute(group + "/outcome", "columns", format_name_list(outcome_columns()));
}

}  // namespace

std::vector<std::string> outcome_columns() {
  return {"lifted_off",    "landed",          "upright",      "lift_off_time", "landing_time",
          "end_time",      "flip_at_landing", "flip_at_end",  "com_landing_x", "com_landing_y",
          "com_landing_z", "com_end_x",       "com_end_y",    "com_end_z",     "com_highest_x",
          "com_highest_y", "com_highest_z",   "crossed_wall", "z_over_wall"};
}

void write_jump_design_artifact(const std::string& path, const DesignProblem& p, const DesignRun& run,
                                const std::string& config_text, std::uint64_t seed) {
  ArtifactWriter out(path, kSchema, kVersion, "msfab-jump-design", config_text, {}, seed);
  H5File& f = out.file();
  std::vector<std::string> names;
  std::vector<double> lower, upper, step, initial;
  for (const DesignParameter& q : p.parameters) {
    names.push_back(q.name);
    lower.push_back(q.lower);
    upper.push_back(q.upper);
    step.push_back(q.step);
    initial.push_back(q.initial);
  }
  f.write_attribute("/", "task", design_task_name(p.task));
  f.write_attribute("/", "scene", p.scene_path);
  f.write_attribute("/", "parameter_names", format_name_list(names));
  f.write_attribute("/", "constraint_names", format_name_list(constraint_names(p.task)));
  f.write_attribute("/", "outcome_columns", format_name_list(outcome_columns()));
  f.write_attribute("/", "lower", lower);
  f.write_attribute("/", "upper", upper);
  f.write_attribute("/", "step", step);
  f.write_attribute("/", "starts", static_cast<std::int32_t>(p.starts));
  f.write_attribute("/", "max_evaluations", static_cast<std::int32_t>(p.max_evaluations));
  f.write_attribute("/", "wall_seconds", run.wall_seconds);
  f.write_attribute("/", "ranks", static_cast<std::int32_t>(run.ranks));
  f.write_attribute("/", "threads", static_cast<std::int32_t>(run.threads));

  std::vector<const Evaluation*> evaluations;
  for (const Evaluation& e : run.evaluations) evaluations.push_back(&e);
  write_evaluation_table(f, "/evaluations", evaluations);
  const std::size_t n = evaluations.size(), nc = constraint_names(p.task).size();
  std::vector<std::int32_t> start(n), index(n), feasible(n);
  std::vector<double> seconds(n), constraints(n * nc);
  for (std::size_t i = 0; i < n; ++i) {
    const Evaluation& e = run.evaluations[i];
    start[i] = e.start;
    index[i] = e.index;
    feasible[i] = e.feasible();
    seconds[i] = e.seconds;
    std::copy(e.constraints.begin(), e.constraints.end(), constraints.begin() + i * nc);
  }
  f.write_vector("/evaluations/start", start);
  f.write_vector("/evaluations/index", index);
  f.write_vector("/evaluations/feasible", feasible);
  f.write_vector("/evaluations/seconds", seconds);
  f.write_attribute("/evaluations/seconds", "units", "s (wall time; the only field that varies between runs)");
  if (p.confirm_time_step > 0) {
    // The run at the confirmation step; /evaluations/objective and
    // constraints are the worse of the two steps.
    std::vector<double> confirm_objective(n), confirm_outcome;
    for (std::size_t i = 0; i < n; ++i) {
      const Evaluation& e = run.evaluations[i];
      // NaN where the run at the scene's step failed and was not repeated.
      confirm_objective[i] = e.confirmed ? e.confirm_objective : std::nan("");
      const std::vector<double> row = outcome_row(e.confirm_outcome, e.confirm_crossed_wall, e.confirm_z_over_wall);
      confirm_outcome.insert(confirm_outcome.end(), row.begin(), row.end());
    }
    f.write_attribute("/evaluations", "confirm_time_step", p.confirm_time_step);
    f.write_vector("/evaluations/confirm_objective", confirm_objective);
    f.write_dataset("/evaluations/confirm_outcome", confirm_outcome, {hsize_t(n), hsize_t(outcome_columns().size())});
    f.write_attribute("/evaluations/confirm_outcome", "columns", format_name_list(outcome_columns()));
  }
  if (!p.modulus_scales.empty()) {
    // The runs at each modulus factor; /evaluations/objective and
    // constraints are the worst of all runs. NaN where the run at the
    // scene's modulus or its confirmation failed and the factors were not
    // run.
    const std::size_t ns = p.modulus_scales.size(), nk = outcome_columns().size();
    std::vector<double> scaled_objective(n * ns, std::nan("")), scaled_outcome(n * ns * nk, std::nan(""));
    for (std::size_t i = 0; i < n; ++i)
      for (std::size_t k = 0; k < run.evaluations[i].scaled.size(); ++k) {
        const ScaledRun& r = run.evaluations[i].scaled[k];
        scaled_objective[i * ns + k] = r.objective;
        const std::vector<double> row = outcome_row(r.outcome, r.crossed_wall, r.z_over_wall);
        std::copy(row.begin(), row.end(), scaled_outcome.begin() + (i * ns + k) * nk);
      }
    f.write_attribute("/evaluations", "modulus_scales", p.modulus_scales);
    f.write_dataset("/evaluations/modulus_scale_objective", scaled_objective, {hsize_t(n), hsize_t(ns)});
    f.write_dataset("/evaluations/modulus_scale_outcome", scaled_outcome, {hsize_t(n), hsize_t(ns), hsize_t(nk)});
    f.write_attribute("/evaluations/modulus_scale_outcome", "columns", format_name_list(outcome_columns()));
  }
  if (nc > 0) {
    f.write_dataset("/evaluations/constraints", constraints, {hsize_t(n), hsize_t(nc)});
    f.write_attribute("/evaluations/constraints", "units", "m (feasible when <= 0)");
  }

  if (!run.robustness.samples.empty()) {
    const RobustnessResult& r = run.robustness;
    std::vector<const Evaluation*> samples;
    std::vector<double> scale;
    std::vector<std::int32_t> success;
    for (const RobustnessSample& sample : r.samples) {
      samples.push_back(&sample.evaluation);
      scale.push_back(sample.modulus_scale);
      success.push_back(sample.success);
    }
    write_evaluation_table(f, "/robustness", samples);
    f.write_attribute("/robustness", "modulus", p.robustness.modulus);
    f.write_attribute("/robustness", "geometry", p.robustness.geometry);
    f.write_attribute("/robustness", "success_fraction", r.fraction());
    f.write_vector("/robustness/modulus_scale", scale);
    f.write_vector("/robustness/success", success);
  }
  write_design(f, "/initial", run.evaluations[run.initial]);
  write_design(f, "/final", run.evaluations[run.final]);
  out.commit();
}

}  // namespace msfab
