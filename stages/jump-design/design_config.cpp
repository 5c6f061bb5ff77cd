#include "design_config.hpp"

#include <cmath>

#include "core/errors.hpp"

namespace msfab {

const char* design_task_name(DesignTask task) {
  switch (task) {
    case DesignTask::kFlip: return "flip";
    case DesignTask::kTarget: return "target";
    case DesignTask::kJumpOnto: return "jump-onto";
    case DesignTask::kJumpOver: return "jump-over";
  }
  return "?";
}

std::vector<std::string> constraint_names(DesignTask task) {
  switch (task) {
    case DesignTask::kJumpOnto: return {"x_wall - x_c", "z_wall - z_c"};
    case DesignTask::kJumpOver: return {"x_wall - x_c", "z_wall - z_over_wall"};
    default: return {};
  }
}

namespace {

DesignTask parse_task(const Config& c) {
  const std::string t = c.one_of("task", {"flip", "target", "jump-onto", "jump-over"});
  if (t == "flip") return DesignTask::kFlip;
  if (t == "target") return DesignTask::kTarget;
  if (t == "jump-onto") return DesignTask::kJumpOnto;
  return DesignTask::kJumpOver;
}

void read_measure(const Config& c, DesignProblem& p) {
  if (!c.has("measure")) return;
  const Config s = c.child("measure");
  JumpMeasureOptions& m = p.measure;
  p.body = s.get_or("body", "");
  p.settle = s.get_or<double>("settle", p.settle);
  if (!(p.settle >= 0)) s.fail("settle", "must be >= 0 (s)");
  if (s.has("confirm_time_step"))
    p.confirm_time_step = s.require_positive<double>("confirm_time_step", "time step (s)");
  if (s.has("modulus_scales")) {
    p.modulus_scales = s.get<std::vector<double>>("modulus_scales");
    if (p.modulus_scales.empty() || p.modulus_scales.size() > 8)
      s.fail("modulus_scales", "needs 1 to 8 factors of the modulus");
    for (std::size_t i = 0; i < p.modulus_scales.size(); ++i) {
      const double f = p.modulus_scales[i];
      if (!(f > 0) || !(f <= 10)) s.fail("modulus_scales", "factor " + std::to_string(f) + " is not in (0, 10]");
      if (f == 1) s.fail("modulus_scales", "factor 1 is the scene's own modulus, which every evaluation runs anyway");
      for (std::size_t j = 0; j < i; ++j)
        if (p.modulus_scales[j] == f) s.fail("modulus_scales", "factor " + std::to_string(f) + " is listed twice");
    }
  }
  const std::string axis = s.get_or("flip_axis", "y");
  if (axis != "x" && axis != "y" && axis != "z") s.fail("flip_axis", "must be x, y or z");
  m.flip_axis = axis[0] - 'x';
  m.min_flight = s.get_or<double>("min_flight", m.min_flight);
  if (!(m.min_flight >= 0)) s.fail("min_flight", "must be >= 0 (s)");
  if (s.has("upright_tolerance_deg"))
    m.upright_tolerance = s.require_range<double>("upright_tolerance_deg", 0.0, 180.0, Bounds::OpenClosed) * M_PI / 180;
}

void read_optimizer(const Config& c, DesignProblem& p) {
  if (!c.has("optimizer")) return;
  const Config o = c.child("optimizer");
  p.max_evaluations = o.get_or<int>("max_evaluations", p.max_evaluations);
  if (p.max_evaluations < 1 || p.max_evaluations > 10000) o.fail("max_evaluations", "must be in [1, 10000]");
  p.starts = o.get_or<int>("starts", p.starts);
  if (p.starts < 1 || p.starts > 1000) o.fail("starts", "must be in [1, 1000]");
  p.spread = o.get_or<double>("spread", p.spread);
  if (!(p.spread >= 0)) o.fail("spread", "must be >= 0 (initial steps)");
  if (o.has("start_points"))
    p.space_filling_starts = o.one_of("start_points", {"around_initial", "space_filling"}) == "space_filling";
  p.xtol = o.get_or<double>("xtol", p.xtol);
  if (!(p.xtol > 0) || !(p.xtol < 1)) o.fail("xtol", "must be in (0, 1) (normalized parameters)");
  p.stop_below = o.get_or<double>("stop_below", p.stop_below);
  if (!(p.stop_below >= 0)) o.fail("stop_below", "must be >= 0");
  p.length_scale = o.get_or<double>("length_scale", p.length_scale);
  if (!(p.length_scale > 0)) o.fail("length_scale", "must be positive (m)");
}

void read_robustness(const Config& c, RobustnessCheck& r) {
  if (!c.has("robustness")) return;
  const Config s = c.child("robustness");
  r.samples = s.get_or<int>("samples", r.samples);
  if (r.samples < 0 || r.samples > 100000) s.fail("samples", "must be in [0, 100000]");
  r.modulus = s.get_or<double>("modulus", r.modulus);
  if (!(r.modulus >= 0) || !(r.modulus < 1)) s.fail("modulus", "must be in [0, 1) (relative variation of E)");
  r.geometry = s.get_or<double>("geometry", r.geometry);
  if (!(r.geometry >= 0)) s.fail("geometry", "must be >= 0 (m, variation of every design parameter)");
  r.target_distance = s.get_or<double>("target_distance", r.target_distance);
  if (!(r.target_distance > 0)) s.fail("target_distance", "must be positive (m)");
}

}  // namespace

DesignProblem read_design_problem(const Config& c) {
  DesignProblem p;
  p.config_source = c.source();
  p.scene_path = c.get_path("scene");
  p.scene_set = c.get_or<std::vector<std::string>>("scene_set", {});
  Config scene = Config::load_file(p.scene_path);
  scene.apply_overrides(p.scene_set);
  if (!scene.has("parameters")) c.fail("scene", "the scene has no `parameters` section to design with");
  const Config scene_parameters = scene.child("parameters");

  for (const Config& d : c.children("parameters")) {
    DesignParameter q;
    q.name = d.get<std::string>("name");
    if (!scene_parameters.has(q.name)) {
      std::string known;
      for (const std::string& k : scene_parameters.keys()) known += (known.empty() ? "" : ", ") + k;
      d.fail("name", "'" + q.name + "' is not a parameter of " + p.scene_path + " (its parameters: " + known + ")");
    }
    q.initial = scene_parameters.require_finite(q.name, "parameter value");
    q.reference = q.initial;
    if (scene.has("reference_parameters") && scene.child("reference_parameters").has(q.name))
      q.reference = scene.child("reference_parameters").require_finite(q.name, "reference value");
    q.lower = d.require_finite("lower");
    q.upper = d.require_finite("upper");
    if (!(q.lower < q.upper)) d.fail("upper", "must exceed lower (" + std::to_string(q.lower) + ")");
    if (q.initial < q.lower || q.initial > q.upper)
      d.fail("name", "the initial design " + q.name + " = " + std::to_string(q.initial) +
                         " (from the scene) lies outside [" + std::to_string(q.lower) + ", " + std::to_string(q.upper) +
                         "]");
    q.step = d.require_positive<double>("step", "initial step");
    if (q.step > q.upper - q.lower) d.fail("step", "must not exceed upper - lower");
    for (const DesignParameter& other : p.parameters)
      if (other.name == q.name) d.fail("name", "parameter '" + q.name + "' is listed twice");
    p.parameters.push_back(q);
  }
  if (p.parameters.empty()) c.fail("parameters", "needs at least one design parameter");

  p.task = parse_task(c);
  if (p.task == DesignTask::kTarget) {
    p.target_x = c.require_finite("target_x", "target position (m)");
  } else {
    p.target_flip = c.get_or<double>("target_flip_deg", 0.0) * M_PI / 180;  // finite: the reader refuses others
  }
  if (p.task == DesignTask::kJumpOnto || p.task == DesignTask::kJumpOver) {
    p.obstacle = c.get<std::string>("obstacle");
    p.clearance = c.get_or<double>("clearance", 0.0);
  }
  read_measure(c, p);
  read_optimizer(c, p);
  read_robustness(c, p.robustness);
  return p;
}

}  // namespace msfab
