#include "dynamics/dynamics_run.hpp"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <limits>
#include <sstream>

#include "core/errors.hpp"
#include "core/timing.hpp"
#include "dynamics/passenger_bodies.hpp"
#include "dynamics/quasistatic_loading.hpp"
#include "dynamics/rigid_body.hpp"
#include "dynamics/surface_contact.hpp"
#include "fem/hex_boundary.hpp"
#include "solve/newton.hpp"

namespace msfab {

namespace {

std::string format_time(double t) {
  std::ostringstream s;
  s.precision(6);
  s << t << " s";
  return s.str();
}

// Smallest clearance of the boundary nodes to the obstacles, less the
// distance each node covers in `horizon` seconds at its current speed.
double clearance(const DynamicsModel& model, const std::vector<int>& nodes, const VecX& q, const VecX& v,
                 double horizon) {
  double worst = std::numeric_limits<double>::infinity();
  for (int node : nodes)
    for (const Obstacle& o : model.obstacles)
      worst = std::min(worst,
                       signed_distance(o, q.segment<3>(3 * node), nullptr) - horizon * v.segment<3>(3 * node).norm());
  return worst;
}

class Recorder {
 public:
  Recorder(const DynamicsScene& scene, const NewmarkIntegrator& sim, Trajectory& out)
      : scene_(scene),
        sim_(sim),
        out_(out),
        body_(make_rigid_body(sim.scalar_mass_matrix(), sim.assembler().rest_positions())) {
    R0_ = project_to_rigid(body_, scene.initial_positions, scene.initial_velocities).R;
    if (scene.body_names.size() > 1) {
      // Lumped nodal masses per body, for each body's centre of mass.
      node_mass_ = VecX::Zero(scene.model.mesh.num_nodes());
      const SpMat& m = sim.scalar_mass_matrix();
      for (int j = 0; j < m.outerSize(); ++j)
        for (SpMat::InnerIterator it(m, j); it; ++it) node_mass_(it.row()) += it.value();
      node_body_.assign(scene.model.mesh.num_nodes(), 0);
      for (int e = 0; e < scene.model.mesh.num_elements(); ++e)
        for (int node : scene.model.mesh.elements[e]) node_body_[node] = scene.element_body[e];
      out.body_names = scene.body_names;
    }
  }

  void sample(SimulationPhase phase, const VecX& q, const VecX& v, const StepReport& step, double time) {
    TrajectorySample s;
    s.time = time;
    s.phase = phase;
    s.kinetic = 0.5 * v.dot(sim_.mass_matrix() * v);
    s.elastic = sim_.assembler().energy(q);
    s.gravity = -sim_.gravity_force().dot(q - sim_.assembler().rest_positions());
    const RigidState r = project_to_rigid(body_, q, v);
    s.center_of_mass = r.t;
    s.com_velocity = r.l / body_.mass;
    const Eigen::AngleAxisd rotation(r.R * R0_.transpose());
    s.rotation = rotation.angle() * rotation.axis();
    if (!node_body_.empty()) {
      std::vector<double> mass(scene_.body_names.size(), 0.0);
      s.body_center_of_mass.assign(scene_.body_names.size(), Vec3::Zero());
      for (size_t i = 0; i < node_body_.size(); ++i) {
        mass[node_body_[i]] += node_mass_(Eigen::Index(i));
        s.body_center_of_mass[node_body_[i]] += node_mass_(Eigen::Index(i)) * q.segment<3>(3 * Eigen::Index(i));
      }
      for (size_t b = 0; b < mass.size(); ++b) s.body_center_of_mass[b] /= mass[b];
    }
    s.contacts = step.contacts;
    s.active_contacts = step.peak_active_contacts;
    s.newton_iterations = step.newton_iterations;
    s.max_penetration = step.max_penetration;
    s.seconds = step.seconds;
    out_.samples.push_back(s);
    if (out_.samples.size() % scene_.output_every == 1 || scene_.output_every == 1) frame(q, v, time);
  }
  void frame(const VecX& q, const VecX& v, double time) {
    if (!out_.frames.empty() && out_.frames.back().time == time) return;
    out_.frames.push_back({time, q, v});
  }
  void event(double time, const std::string& kind, const std::string& detail) {
    out_.events.push_back({time, kind, detail});
  }
  const RigidBody& body() const { return body_; }

 private:
  const DynamicsScene& scene_;
  const NewmarkIntegrator& sim_;
  Trajectory& out_;
  RigidBody body_;
  Mat3 R0_;
  VecX node_mass_;              // lumped, with several bodies
  std::vector<int> node_body_;  // empty with one body
};

// The pluck, and the press without press.self_contact, know no contact
// between or within bodies, so a load too large for the geometry folds a
// body through itself (a pressed plate
// through the plate below it) and the dynamics would start from an
// impossible state. The boundary surface is built once per preload: the
// press that stops at touch asks about a dozen trial states.
class PreloadFoldCheck {
 public:
  PreloadFoldCheck(const DynamicsScene& scene, const NewmarkIntegrator& sim)
      : scene_(scene), surface_(hex_boundary(scene.model.mesh), sim.boundary_nodes()), dx_(sim.element_size()) {}

  // The boundary nodes of q that ended behind a face by more than 5% of an
  // element.
  std::vector<NodeFaceContact> folds(const VecX& q) const {
    return surface_.find(scene_.initial_positions, q, -0.05 * dx_, 0.25 * dx_);
  }
  bool folded(const VecX& q) const { return !folds(q).empty(); }

  // Refused, with the node that went through.
  void check(const VecX& q) const {
    const auto through = folds(q);
    if (through.empty()) return;
    const NodeFaceContact& c = through.front();
    const HexMesh& mesh = scene_.model.mesh;
    std::ostringstream msg;
    msg << (scene_.preload == Preload::kStaticPluck ? "pluck" : "press")
        << ": the preload folds the body through itself (" << through.size()
        << " boundary nodes end behind a face; node at rest (" << mesh.nodes(c.node, 0) << ", " << mesh.nodes(c.node, 1)
        << ", " << mesh.nodes(c.node, 2) << ") ends " << -c.gap_end * 1e3 << " mm deep); "
        << (scene_.preload == Preload::kQuasistaticPress
                ? "set press.self_contact (the parts then rest on each other), press.stop_at_touch, or reduce the force"
                : "the pluck has no self-contact: reduce the force");
    throw InputError(msg.str());
  }

 private:
  const DynamicsScene& scene_;
  BoundarySurface surface_;
  double dx_;
};

// The quasistatic press under `scale` times the press load (and gravity),
// always from the scene's initial state: no-slip contact makes the
// equilibrium depend on the loading path, so every scale takes the same one.
QuasistaticResult press_at(const DynamicsScene& scene, const NewmarkIntegrator& sim, const VecX& load, double scale) {
  QuasistaticOptions options;
  options.load_steps = scene.preload_steps;
  options.threads = 1;  // as the Newmark factorization: same bits for any --threads
  options.self_contact = scene.press_self_contact;
  options.edge_contact = scene.newmark.edge_contact;
  QuasistaticResult r = solve_quasistatic_loading(sim.assembler(), sim.model().obstacles,
                                                  scale * load + sim.gravity_force(), scene.initial_positions, options);
  if (!r.converged) throw NumericalError(r.failure + "\n" + format_quasistatic_history(r.history));
  return r;
}

// press.stop_at_touch: the largest fraction of the load whose equilibrium
// does not fold the body through itself, by bisection to 1% of the load
// (the pressed part then rests on, or just above, the part below it).
// Continuous in the geometry, so a design loop sees no plateau where the
// full load would have been refused.
QuasistaticResult press_until_touch(const DynamicsScene& scene, const NewmarkIntegrator& sim,
                                    const PreloadFoldCheck& fold, const VecX& load, double& scale) {
  QuasistaticResult r = press_at(scene, sim, load, 1.0);
  scale = 1.0;
  if (!fold.folded(r.x)) return r;
  double lo = 0, hi = 1;
  QuasistaticResult best = press_at(scene, sim, load, 0.0);
  if (fold.folded(best.x)) throw InputError("press: the body folds through itself under gravity alone");
  while (hi - lo > 0.01) {
    const double mid = 0.5 * (lo + hi);
    QuasistaticResult m = press_at(scene, sim, load, mid);
    if (!fold.folded(m.x)) {
      lo = mid;
      best = std::move(m);
    } else {
      hi = mid;
    }
  }
  scale = lo;
  return best;
}

// The preloaded state: the scene's initial positions, or the equilibrium
// under the pluck or press load (with gravity).
VecX preload(const DynamicsScene& scene, const NewmarkIntegrator& sim, Recorder& rec, Trajectory& out) {
  if (scene.preload == Preload::kNone || scene.preload == Preload::kDynamicPress) return scene.initial_positions;
  const auto t0 = std::chrono::steady_clock::now();
  const VecX load = region_force(scene, scene.load, scene.preload == Preload::kStaticPluck ? "pluck" : "press");
  const PreloadFoldCheck fold(scene, sim);
  VecX q;
  std::ostringstream detail;
  if (scene.preload == Preload::kStaticPluck) {
    const VecX force = load + sim.gravity_force();
    DirichletConditions bc = DirichletConditions::none(sim.model().mesh.num_dofs());
    bc.fixed = sim.model().fixed;
    if (bc.fixed.empty()) bc.fixed.assign(sim.model().mesh.num_dofs(), 0);
    const std::vector<char> passenger = passenger_bodies(scene, load);
    const std::vector<char> riding = passenger_dofs(scene, passenger);
    for (size_t i = 0; i < riding.size(); ++i) bc.fixed[i] = bc.fixed[i] || riding[i];
    bc.displacement = scene.initial_positions - sim.assembler().rest_positions();
    NewtonOptions newton;
    // The energy line search of solve_static stalls near 1e-6 on stiff rigs
    // (round-off in the energy); 1e-5 of the load is ample for a release state.
    newton.relative_tolerance = 1e-5;
    newton.load_steps = scene.preload_steps;
    newton.linear_solver = "cholmod";
    newton.linear.threads = 1;  // as the Newmark factorization: same bits for any --threads
    const NewtonResult r = solve_static(sim.assembler(), bc, force, newton, scene.initial_positions);
    if (!r.converged) throw NumericalError("pluck preload: " + r.failure + "\n" + format_history(r.history));
    std::vector<std::string> notes;
    q = carry_passengers(scene, passenger, scene.initial_positions, r.x, &notes);
    detail << "static pluck: " << r.iterations << " Newton iterations";
    for (const std::string& n : notes) detail << "; " << n;
  } else {
    double scale = 1.0;
    const QuasistaticResult r =
        scene.stop_at_touch ? press_until_touch(scene, sim, fold, load, scale) : press_at(scene, sim, load, 1.0);
    q = r.x;
    detail << "quasistatic press: " << r.iterations << " iterations, " << r.contacts.size() << " contact vertices";
    if (scene.press_self_contact) {
      const auto edge_ties = std::count_if(r.self_contacts.begin(), r.self_contacts.end(),
                                           [](const SelfContactTie& t) { return t.is_edge_pair(); });
      detail << ", " << r.self_contacts.size() << " self-contact ties (" << edge_ties << " between edges)";
    }
    if (scale < 1.0)
      detail << "; stopped at touch: " << 100 * scale << "% of the load (" << scale * scene.load.force.norm() << " N)";
  }
  fold.check(q);
  out.seconds_quasistatic = seconds_since(t0);
  rec.event(0.0, "preload", detail.str());
  StepReport none;
  rec.sample(SimulationPhase::kQuasistatic, q, VecX::Zero(q.size()), none, 0.0);
  rec.event(0.0, "release", "load removed, dynamics start from rest");
  return q;
}

// One elastic step of length h, retaken as two halves, recursively down to
// h / 2^levels, where it fails or where a contact event falls in it (the
// active contacts start or stop: a touch-down, a push-off, a lift-off).
// The impulses and the friction of the event then act over the short steps
// in which it happens instead of over a whole step. With levels = 0 it is
// sim.step(). Returns the last (sub)step's report with the Newton
// iterations, sweeps and seconds of every try, and the deepest penetration
// and most active contacts of the steps kept; `steps` counts the steps
// kept.
StepReport elastic_step(NewmarkIntegrator& sim, double h, int levels, bool active_before, std::int64_t& steps) {
  if (levels == 0) {  // no retake possible: no state to keep
    sim.set_time_step(h);
    ++steps;
    return sim.step();
  }
  const VecX q = sim.positions(), v = sim.velocities();
  const double t = sim.time();
  sim.set_time_step(h);
  const StepReport whole = sim.try_step();
  const bool event = whole.converged && (whole.active_contacts > 0) != active_before;
  if (whole.converged && !event) {
    ++steps;
    return whole;
  }
  sim.set_state(q, v, t);
  const StepReport first = elastic_step(sim, h / 2, levels - 1, active_before, steps);
  StepReport second = elastic_step(sim, h / 2, levels - 1, first.active_contacts > 0, steps);
  sim.set_time_step(h);
  for (const StepReport* r : {&whole, &first}) {
    second.newton_iterations += r->newton_iterations;
    second.contact_rounds += r->contact_rounds;
    second.gauss_seidel_sweeps += r->gauss_seidel_sweeps;
    second.seconds += r->seconds;
  }
  second.max_penetration = std::max(second.max_penetration, first.max_penetration);
  second.peak_active_contacts = std::max(second.peak_active_contacts, first.peak_active_contacts);
  return second;
}

}  // namespace

Trajectory run_dynamics_scene(const DynamicsScene& scene, const RunCallbacks& callbacks) {
  const auto t_start = std::chrono::steady_clock::now();
  Trajectory out;
  out.scene = scene.name;
  out.rest_nodes = scene.model.mesh.nodes;
  out.elements = scene.model.mesh.elements;
  out.element_tag = scene.model.mesh.element_tag;
  out.material_names.push_back("void");
  for (const SceneMaterial& m : scene.materials) out.material_names.push_back(m.name);
  out.time_step = scene.newmark.time_step;
  out.event_substeps = scene.event_substeps;
  out.impact_model = impact_model_name(scene.model.impact);
  out.obstacles = scene.model.obstacles;

  NewmarkIntegrator sim(scene.model, scene.newmark);
  Recorder rec(scene, sim, out);
  const VecX q0 = preload(scene, sim, rec, out);
  const bool from_scene = scene.preload == Preload::kNone || scene.preload == Preload::kDynamicPress;
  const VecX v0 = from_scene ? scene.initial_velocities : VecX::Zero(q0.size());
  sim.set_state(q0, v0, 0.0);
  if (scene.preload == Preload::kDynamicPress) {
    const double ramp = scene.press_ramp_time;
    sim.set_applied_load(region_force(scene, scene.load, "press"),
                         [ramp](double t) { return std::clamp(t / ramp, 0.0, 1.0); });
    std::ostringstream detail;
    detail << "dynamic press: " << scene.load.force.norm() << " N ramped on over " << ramp << " s, then held";
    rec.event(0.0, "press", detail.str());
  }
  if (from_scene) rec.sample(SimulationPhase::kElastic, q0, v0, StepReport{}, 0.0);

  const double h = scene.newmark.time_step;
  const int steps = static_cast<int>(std::ceil(scene.duration / h - 1e-9));
  const RigidBody& body = rec.body();
  const double horizon = scene.rigid.lookahead_steps * h;
  const double margin = 0.05 * sim.element_size();
  bool rigid = false, touching = false, active_before = false;
  RigidState state;
  double time = 0;
  for (int k = 1; k <= steps; ++k) {
    const auto t0 = std::chrono::steady_clock::now();
    if (rigid) {
      RigidState next = state;
      dmv_step(body, scene.model.gravity, h, &next);
      VecX q, v;
      project_to_fe(body, next, &q, &v);
      if (clearance(scene.model, sim.boundary_nodes(), q, v, horizon) > margin) {
        state = next;
        time += h;
        StepReport r;
        r.seconds = seconds_since(t0);
        out.seconds_rigid += r.seconds;
        rec.sample(SimulationPhase::kRigid, q, v, r, time);
        if (callbacks.on_step) callbacks.on_step(time, q);
        continue;
      }
      // A contact is near: back to the elastic model from the rigid state.
      project_to_fe(body, state, &q, &v);
      sim.set_state(q, v, time);
      rigid = false;
      rec.event(time, "elastic", "contact ahead: projected back to the FE model (B.23)");
    }
    const StepReport r = elastic_step(sim, h, scene.event_substeps, active_before, out.elastic_steps);
    active_before = r.active_contacts > 0;
    time = sim.time();
    out.seconds_elastic += r.seconds;
    rec.sample(SimulationPhase::kElastic, sim.positions(), sim.velocities(), r, time);
    // Contact and lift-off events: a resting body's contacts flicker between
    // carrying force and touching without force, so lift-off needs a gap.
    // A touch inside the event substeps of one step counts even where the
    // body has left again by the step's end.
    if (r.peak_active_contacts > 0 && !touching) {
      rec.event(time, "contact", std::to_string(r.peak_active_contacts) + " nodes");
      touching = true;
    } else if (r.active_contacts == 0 && touching &&
               clearance(scene.model, sim.boundary_nodes(), sim.positions(), sim.velocities(), 0.0) > margin) {
      rec.event(time, "lift-off", "");
      touching = false;
    }
    if (callbacks.on_step) callbacks.on_step(time, sim.positions());

    if (scene.rigid.enabled && !touching) {
      const TrajectorySample& e = out.samples.back();  // this step's energies
      if (e.elastic < scene.rigid.elastic_fraction * e.kinetic &&
          clearance(scene.model, sim.boundary_nodes(), sim.positions(), sim.velocities(), horizon) > margin) {
        state = project_to_rigid(body, sim.positions(), sim.velocities());
        rigid = true;
        std::ostringstream d;
        d << "elastic energy " << e.elastic << " J < " << scene.rigid.elastic_fraction << " x kinetic " << e.kinetic
          << " J: projected to a rigid body (B.22)";
        rec.event(time, "rigid", d.str());
      }
    }
  }
  if (rigid) {
    VecX q, v;
    project_to_fe(body, state, &q, &v);
    rec.frame(q, v, time);
  } else {
    rec.frame(sim.positions(), sim.velocities(), time);
  }
  rec.event(time, "end", format_time(time) + " simulated");
  out.seconds_total = seconds_since(t_start);
  return out;
}

double dynamics_peak_bytes(const DynamicsScene& scene) {
  const double elements = scene.model.mesh.num_elements();
  const double frames = std::ceil(scene.duration / scene.newmark.time_step / scene.output_every) + 2;
  return 30e3 * elements + 1e3 * std::pow(elements, 4.0 / 3.0) + frames * 2 * 8.0 * scene.model.mesh.num_dofs();
}

}  // namespace msfab
