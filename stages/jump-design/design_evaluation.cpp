#include "design_evaluation.hpp"

#include <spdlog/spdlog.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>

#include "core/errors.hpp"
#include "dynamics/dynamics_run.hpp"
#include "dynamics/dynamics_scene.hpp"
#include "jump_observer.hpp"

namespace msfab {

bool Evaluation::feasible(double tolerance) const {
  if (!ok) return false;
  for (double g : constraints)
    if (g > tolerance) return false;
  return true;
}

double Evaluation::violation() const {
  double v = 0;
  for (double g : constraints) v += std::max(0.0, g);
  return v;
}

bool Evaluation::landed_in_every_run() const {
  if (!ok || !outcome.landed || (confirmed && !confirm_outcome.landed)) return false;
  for (const ScaledRun& r : scaled)
    if (!r.outcome.landed) return false;
  return true;
}

// Row layout: start, index, ok, objective, seconds, elements, crossed_wall,
// z_over_wall, confirmed, confirm_objective, confirm_crossed_wall,
// confirm_z_over_wall, then the parameters, the constraints, the jump
// outcome and the confirmation's outcome (kOutcomeSize numbers each, in the
// order of pack_outcome), then one block per modulus factor: ran, ok,
// objective, crossed_wall, z_over_wall, constraints, outcome (zeros where
// it did not run).
namespace {

constexpr int kHeader = 12;
constexpr int kOutcomeSize = 17;
constexpr int kScaledHeader = 5;

int scaled_block_size(const DesignProblem& p) {
  return kScaledHeader + static_cast<int>(constraint_names(p.task).size()) + kOutcomeSize;
}

void pack_outcome(const JumpOutcome& o, double* r) {
  const double v[kOutcomeSize] = {double(o.lifted_off), double(o.landed),     double(o.upright),    o.lift_off_time,
                                  o.landing_time,       o.end_time,           o.flip_at_landing,    o.flip_at_end,
                                  o.com_at_landing.x(), o.com_at_landing.y(), o.com_at_landing.z(), o.com_at_end.x(),
                                  o.com_at_end.y(),     o.com_at_end.z(),     o.com_highest.x(),    o.com_highest.y(),
                                  o.com_highest.z()};
  std::copy(v, v + kOutcomeSize, r);
}

JumpOutcome unpack_outcome(const double* r) {
  JumpOutcome o;
  o.lifted_off = r[0] != 0;
  o.landed = r[1] != 0;
  o.upright = r[2] != 0;
  o.lift_off_time = r[3];
  o.landing_time = r[4];
  o.end_time = r[5];
  o.flip_at_landing = r[6];
  o.flip_at_end = r[7];
  o.com_at_landing = Vec3(r[8], r[9], r[10]);
  o.com_at_end = Vec3(r[11], r[12], r[13]);
  o.com_highest = Vec3(r[14], r[15], r[16]);
  return o;
}

}  // namespace

int evaluation_record_size(const DesignProblem& p) {
  return kHeader + static_cast<int>(p.parameters.size() + constraint_names(p.task).size()) + 2 * kOutcomeSize +
         static_cast<int>(p.modulus_scales.size()) * scaled_block_size(p);
}

void pack_evaluation(const DesignProblem& problem, const Evaluation& e, double* r) {
  if (e.scaled.size() > problem.modulus_scales.size())
    throw NumericalError("pack_evaluation: more modulus-scaled runs than measure.modulus_scales lists");
  r[0] = e.start;
  r[1] = e.index;
  r[2] = e.ok ? 1 : 0;
  r[3] = e.objective;
  r[4] = e.seconds;
  r[5] = e.elements;
  r[6] = e.crossed_wall ? 1 : 0;
  r[7] = e.z_over_wall;
  r[8] = e.confirmed ? 1 : 0;
  r[9] = e.confirm_objective;
  r[10] = e.confirm_crossed_wall ? 1 : 0;
  r[11] = e.confirm_z_over_wall;
  double* p = r + kHeader;
  for (double x : e.parameters) *p++ = x;
  for (double g : e.constraints) *p++ = g;
  pack_outcome(e.outcome, p);
  pack_outcome(e.confirm_outcome, p + kOutcomeSize);
  p += 2 * kOutcomeSize;
  const int block = scaled_block_size(problem);
  std::fill(p, p + problem.modulus_scales.size() * block, 0.0);
  for (const ScaledRun& s : e.scaled) {
    p[0] = 1;
    p[1] = s.ok ? 1 : 0;
    p[2] = s.objective;
    p[3] = s.crossed_wall ? 1 : 0;
    p[4] = s.z_over_wall;
    std::copy(s.constraints.begin(), s.constraints.end(), p + kScaledHeader);
    pack_outcome(s.outcome, p + kScaledHeader + s.constraints.size());
    p += block;
  }
}

Evaluation unpack_evaluation(const DesignProblem& problem, const double* r) {
  Evaluation e;
  e.start = static_cast<int>(r[0]);
  e.index = static_cast<int>(r[1]);
  e.ok = r[2] != 0;
  e.objective = r[3];
  e.seconds = r[4];
  e.elements = static_cast<int>(r[5]);
  e.crossed_wall = r[6] != 0;
  e.z_over_wall = r[7];
  e.confirmed = r[8] != 0;
  e.confirm_objective = r[9];
  e.confirm_crossed_wall = r[10] != 0;
  e.confirm_z_over_wall = r[11];
  const double* p = r + kHeader;
  e.parameters.assign(p, p + problem.parameters.size());
  p += problem.parameters.size();
  const std::size_t nc = constraint_names(problem.task).size();
  e.constraints.assign(p, p + nc);
  e.outcome = unpack_outcome(p + nc);
  e.confirm_outcome = unpack_outcome(p + nc + kOutcomeSize);
  p += nc + 2 * kOutcomeSize;
  for (double factor : problem.modulus_scales) {
    if (p[0] == 0) break;
    ScaledRun s;
    s.modulus_scale = factor;
    s.ok = p[1] != 0;
    s.objective = p[2];
    s.crossed_wall = p[3] != 0;
    s.z_over_wall = p[4];
    s.constraints.assign(p + kScaledHeader, p + kScaledHeader + nc);
    s.outcome = unpack_outcome(p + kScaledHeader + nc);
    e.scaled.push_back(std::move(s));
    p += scaled_block_size(problem);
  }
  return e;
}

namespace {

std::string number_text(double x) {
  char buf[40];
  std::snprintf(buf, sizeof buf, "%.17g", x);
  return buf;
}

// The scene at `values`, meshed at the reference values (the scene's
// reference_parameters, else the initial design), with every modulus
// times `modulus_scale` (on top of the scene's own) and run at `time_step`
// (0: the scene's).
DynamicsScene build_scene(const DesignProblem& problem, const std::vector<double>& values, double modulus_scale = 1.0,
                          double time_step = 0) {
  Config scene = Config::load_file(problem.scene_path);
  scene.apply_overrides(problem.scene_set);
  if (time_step > 0) scene.apply_override("simulation.time_step=" + number_text(time_step));
  if (modulus_scale != 1.0) {
    const double own = scene.has("modulus_scale") ? scene.get<double>("modulus_scale") : 1.0;
    scene.apply_override("modulus_scale=" + number_text(own * modulus_scale));
  }
  for (std::size_t i = 0; i < problem.parameters.size(); ++i) {
    const DesignParameter& q = problem.parameters[i];
    scene.apply_override("parameters." + q.name + "=" + number_text(values[i]));
    scene.apply_override("reference_parameters." + q.name + "=" + number_text(q.reference));
  }
  DynamicsScene s = read_dynamics_scene(scene);
  scene.check_no_unknown_keys();
  return s;
}

}  // namespace

DesignEvaluator::DesignEvaluator(const DesignProblem& problem) : problem_(problem) {
  std::vector<double> initial;
  for (const DesignParameter& q : problem.parameters) initial.push_back(q.initial);
  const DynamicsScene scene = build_scene(problem, initial);
  elements_ = scene.model.mesh.num_elements();
  peak_bytes_ = dynamics_peak_bytes(scene);
  // Every corner of the bounds must give a valid scene (box faces in the
  // same order as at the initial design), so that bad bounds stop the run
  // here rather than as failed evaluations later; with faces linear in the
  // parameters the corners cover the whole box.
  const std::size_t n = problem.parameters.size();
  if (n <= 10)
    for (unsigned corner = 0; corner < (1u << n); ++corner) {
      std::vector<double> values(n);
      std::string where;
      for (std::size_t i = 0; i < n; ++i) {
        const DesignParameter& q = problem.parameters[i];
        values[i] = (corner >> i & 1) ? q.upper : q.lower;
        where += (where.empty() ? "" : ", ") + q.name + " = " + number_text(values[i]);
      }
      try {
        build_scene(problem, values);
      } catch (const InputError& e) {
        throw InputError(problem.config_source + ": parameters: at the corner of the bounds (" + where +
                         ") the scene is invalid: " + e.what());
      }
    }
  if (problem.confirm_time_step > 0) {
    if (problem.confirm_time_step == scene.newmark.time_step)
      throw InputError(problem.config_source + ": measure.confirm_time_step = " +
                       number_text(problem.confirm_time_step) + " s is the scene's own time step: nothing to confirm");
    try {
      build_scene(problem, initial, 1.0, problem.confirm_time_step);
    } catch (const InputError& e) {
      throw InputError(problem.config_source +
                       ": measure.confirm_time_step: the scene at that step is invalid: " + e.what());
    }
  }
  if (scene.preload == Preload::kNone)
    spdlog::warn("scene {} has no preload (press or pluck); the design loop runs it as it is", problem.scene_path);
  if (!problem.body.empty() &&
      std::find(scene.body_names.begin(), scene.body_names.end(), problem.body) == scene.body_names.end())
    throw InputError(problem.config_source + ": measure.body = " + problem.body + ": the scene " + problem.scene_path +
                     " has no body of that name");
  if (!problem.obstacle.empty()) {
    for (const Obstacle& o : scene.model.obstacles)
      if (o.name == problem.obstacle) obstacle_ = o, has_obstacle_ = true;
    if (!has_obstacle_ || obstacle_.kind != Obstacle::Kind::kBox)
      throw InputError(problem.config_source + ": obstacle = " + problem.obstacle + ": the scene " +
                       problem.scene_path + " has no box obstacle of that name");
  }
}

Trajectory DesignEvaluator::run_trajectory(const std::vector<double>& values, double until) const {
  DynamicsScene scene = build_scene(problem_, values);
  scene.duration = std::min(scene.duration, until);
  return run_dynamics_scene(scene);
}

Evaluation DesignEvaluator::simulate(const std::vector<double>& values, double modulus_scale, double time_step) const {
  Evaluation e;
  e.parameters = values;
  e.elements = elements_;
  const std::size_t nc = constraint_names(problem_.task).size();
  try {
    const DynamicsScene scene = build_scene(problem_, values, modulus_scale, time_step);
    // The observer stops the run shortly after the landing (jump_observer.hpp).
    JumpObserver observer(scene, {problem_.measure.min_flight, problem_.settle, 0.01, problem_.body});
    RunCallbacks callbacks;
    callbacks.on_step = [&](double time, const VecX& q) { observer.on_step(time, q); };
    try {
      run_dynamics_scene(scene, callbacks);
    } catch (const JumpOver&) {
    }
    const Trajectory& t = observer.trajectory();
    e.outcome = measure_jump(t, problem_.measure);
    e.ok = true;
    if (has_obstacle_) {
      const double middle = 0.5 * (obstacle_.lo.x() + obstacle_.hi.x());
      e.crossed_wall = com_height_at_x(t, middle, e.z_over_wall);
      // Never over the wall: count it as passing at the wall's foot, so the
      // clearance constraint is violated too.
      if (!e.crossed_wall) e.z_over_wall = obstacle_.lo.z();
    }
  } catch (const std::exception& ex) {
    spdlog::warn("simulation of ({}) failed ({}); penalty values", fmt::join(values, ", "), ex.what());
  }
  if (!e.ok) {
    e.objective = kFailedObjective;
    e.constraints.assign(nc, kFailedConstraint);
    return e;
  }
  const JumpOutcome& o = e.outcome;
  // Flip: the turn itself is the goal (a backflip is -2 pi, not 0).
  // Jump-onto / jump-over: landing upright after any number of turns.
  const double turn = o.flip_at_landing - problem_.target_flip;
  const double miss = problem_.task == DesignTask::kFlip ? turn : std::remainder(turn, 2 * M_PI);
  const double z_top = obstacle_.hi.z() + problem_.clearance;
  switch (problem_.task) {
    case DesignTask::kFlip: e.objective = miss * miss; break;
    case DesignTask::kTarget: e.objective = std::abs(o.com_at_landing.x() - problem_.target_x); break;
    case DesignTask::kJumpOnto:
      e.objective = miss * miss;
      e.constraints = {obstacle_.lo.x() - o.com_at_landing.x(), z_top - o.com_at_landing.z()};
      break;
    case DesignTask::kJumpOver:
      e.objective = miss * miss;
      e.constraints = {obstacle_.hi.x() - o.com_at_landing.x(), z_top - e.z_over_wall};
      break;
  }
  return e;
}

Evaluation DesignEvaluator::evaluate(const std::vector<double>& values, int start, int index, double modulus_scale,
                                     bool with_modulus_scales) const {
  const auto t0 = std::chrono::steady_clock::now();
  Evaluation e = simulate(values, modulus_scale, 0);
  // The worst of all runs counts: the objective, each constraint, and a
  // failure of any run fails the evaluation.
  const auto fold = [&e](const Evaluation& other) {
    e.ok = e.ok && other.ok;
    e.objective = std::max(e.objective, other.objective);
    for (std::size_t i = 0; i < e.constraints.size(); ++i)
      e.constraints[i] = std::max(e.constraints[i], other.constraints[i]);
  };
  const bool first_ok = e.ok;
  if (first_ok && problem_.confirm_time_step > 0) {
    const Evaluation c = simulate(values, modulus_scale, problem_.confirm_time_step);
    e.confirmed = true;
    e.confirm_objective = c.objective;
    e.confirm_outcome = c.outcome;
    e.confirm_crossed_wall = c.crossed_wall;
    e.confirm_z_over_wall = c.z_over_wall;
    fold(c);
  }
  // A failed run already fails the evaluation: no factor can change that.
  if (e.ok && with_modulus_scales)
    for (double factor : problem_.modulus_scales) {
      const Evaluation c = simulate(values, modulus_scale * factor, 0);
      e.scaled.push_back({factor, c.ok, c.objective, c.constraints, c.outcome, c.crossed_wall, c.z_over_wall});
      fold(c);
    }
  e.start = start;
  e.index = index;
  e.seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  return e;
}

}  // namespace msfab
