#include "dynamics/newmark_integrator.hpp"

#include <algorithm>
#include <array>
#include <chrono>
#include <cmath>
#include <limits>
#include <map>
#include <sstream>

#include "core/errors.hpp"
#include "core/timing.hpp"
#include "dynamics/contact_problem.hpp"
#include "dynamics/mass_matrix.hpp"
#include "dynamics/surface_contact.hpp"
#include "fem/hex_boundary.hpp"
#include "material/scaled_material.hpp"
#include "solve/cholmod_solver.hpp"
#include "solve/regularized_step.hpp"

namespace msfab {

// A contact row of G (B.5): a boundary node against an obstacle's face
// plane, a node against a boundary face (weights w of the face's closest
// point) or an edge against an edge (weights of the two closest points).
// Its relative position is sum_i c_i x_i over its nodes, with coefficients
// c = (1) for an obstacle, (1, -w_0, .., -w_3) for a face and
// (1 - alpha, alpha, beta - 1, -beta) for two edges; a force f on it pushes
// node i by c_i f.
struct NewmarkIntegrator::Contact {
  // What touches what: (node, obstacle index), (node, obstacles.size() +
  // boundary face) or (-1 - edge a, -1 - edge b); unique per contact.
  std::pair<int, int> key;
  int count = 1;
  std::array<int, 5> nodes{};
  std::array<double, 5> coefficient{};
  double gap0 = 0;  // n . relative position at q^t
  Mat3 frame;       // columns: normal, tangent 1, tangent 2
  double mu = 0;

  bool on_obstacle() const { return key.first >= 0 && count == 1; }
  Vec3 relative(const VecX& x) const {
    Vec3 r = Vec3::Zero();
    for (int i = 0; i < count; ++i) r += coefficient[i] * x.segment<3>(3 * nodes[i]);
    return r;
  }
  // out += G_k f, each node's share divided by scale(node).
  template <class Scale>
  void scatter(const Vec3& f, VecX& out, Scale scale) const {
    for (int i = 0; i < count; ++i) out.segment<3>(3 * nodes[i]) += coefficient[i] * f / scale(nodes[i]);
  }
  void scatter(const Vec3& f, VecX& out) const {
    scatter(f, out, [](int) { return 1.0; });
  }
};

namespace {

// Newton accepts a stalled residual within this factor of its tolerance
// (solve_step).
constexpr double kStallFactor = 100;

// Node-face pairs count only for nodes starting no deeper than this
// fraction of an element behind the face (surface_contact.hpp).
constexpr double kSurfaceDepthLimit = 0.25;

double smallest_edge(const HexMesh& mesh) {
  double h = std::numeric_limits<double>::infinity();
  for (int e = 0; e < mesh.num_elements(); ++e) {
    const hex8::NodeMatrix X = mesh.element_rest_positions(e);
    for (int i = 0; i < 8; ++i)
      for (int bit = 1; bit < 8; bit <<= 1)
        if (!(i & bit)) h = std::min(h, (X.row(i) - X.row(i | bit)).norm());
  }
  return h;
}

// The mesh with every element's materials scaled by its own factor.
HexMesh scale_materials(const HexMesh& mesh, const std::vector<double>& factor) {
  HexMesh scaled = mesh;
  scaled.materials.clear();
  scaled.element_material.assign(mesh.num_elements(), 0);
  std::map<std::pair<int, double>, int> index;
  for (int e = 0; e < mesh.num_elements(); ++e) {
    const int base = mesh.element_material[e];
    const auto [it, inserted] = index.try_emplace({base, factor[e]}, static_cast<int>(scaled.materials.size()));
    if (inserted) {
      QuadratureMaterials q;
      q.rule = mesh.materials[base].rule;
      for (const auto& m : mesh.materials[base].at_point)
        q.at_point.push_back(m ? std::make_shared<ScaledMaterial>(m, factor[e], ScaledTangent::material_psd) : nullptr);
      scaled.materials.push_back(std::move(q));
    }
    scaled.element_material[e] = it->second;
  }
  return scaled;
}

}  // namespace

NewmarkIntegrator::NewmarkIntegrator(const DynamicsModel& model, const NewmarkOptions& options)
    : model_(model), options_(options), assembler_((validate_dynamics_model(model), model.mesh)) {
  set_time_step(options.time_step);
  const HexMesh& mesh = model.mesh;
  const int n = mesh.num_dofs();

  if (std::any_of(model.damping_b.begin(), model.damping_b.end(), [](double b) { return b > 0; })) {
    damping_mesh_ = std::make_unique<HexMesh>(scale_materials(mesh, model.damping_b));
    damping_assembler_ = std::make_unique<ElasticAssembler>(*damping_mesh_);
  }

  scalar_mass_ = msfab::scalar_mass_matrix(mesh, model.density);
  mass_ = expand_to_dofs(scalar_mass_);
  const SpMat pattern = assembler_.pattern();
  mass_in_pattern_ = pattern + mass_;
  std::vector<double> rho_a(mesh.num_elements());
  for (int e = 0; e < mesh.num_elements(); ++e) rho_a[e] = model.density[e] * model.damping_a[e];
  damping_mass_in_pattern_ = pattern + expand_to_dofs(weighted_mass_matrix(mesh, rho_a));
  if (mass_in_pattern_.nonZeros() != pattern.nonZeros() || damping_mass_in_pattern_.nonZeros() != pattern.nonZeros())
    throw std::logic_error("mass matrix pattern is not contained in the stiffness pattern");
  jacobian_ = mass_in_pattern_;

  const std::vector<char> fixed = model.fixed.empty() ? std::vector<char>(n, 0) : model.fixed;
  for (int j = 0; j < n; ++j)
    for (int k = jacobian_.outerIndexPtr()[j]; k < jacobian_.outerIndexPtr()[j + 1]; ++k) {
      const int i = jacobian_.innerIndexPtr()[k];
      if (fixed[i] || fixed[j]) (i == j ? fixed_diagonal_index_ : fixed_value_index_).push_back(k);
    }

  VecX g(n);
  for (int i = 0; i < mesh.num_nodes(); ++i) g.segment<3>(3 * i) = model.gravity;
  gravity_force_ = mass_ * g;
  apply_fixed(gravity_force_);

  for (int node : hex_boundary(mesh).nodes)
    if (!(fixed[3 * node] && fixed[3 * node + 1] && fixed[3 * node + 2])) boundary_nodes_.push_back(node);
  node_material_.assign(mesh.num_nodes(), std::string());
  for (int e = 0; e < mesh.num_elements(); ++e)
    for (int node : mesh.elements[e])
      if (node_material_[node].empty()) node_material_[node] = model.element_material_name[e];
  dx_ = smallest_edge(mesh);
  if (model.contact && model.body_contact)
    surface_ = std::make_unique<BoundarySurface>(hex_boundary(mesh), boundary_nodes_);

  // The factorization runs on one thread. A step's Jacobian is small enough
  // that threaded BLAS gains nothing (the 432-element plant: 48 ms per step
  // either way, 86-274 ms with CHOLMOD's own four threads on two cores),
  // and threaded BLAS changes the round-off with the thread count, which
  // would make runs differ between thread counts.
  LinearSolverOptions solver_options;
  solver_options.threads = 1;
  solver_ = std::make_unique<CholmodSolver>(solver_options);
  solver_->analyze(jacobian_);
  lumped_mass_ = VecX::Zero(mesh.num_nodes());
  for (int j = 0; j < scalar_mass_.outerSize(); ++j)
    for (SpMat::InnerIterator it(scalar_mass_, j); it; ++it) lumped_mass_(it.row()) += it.value();
  q_ = assembler_.rest_positions();
  v_ = VecX::Zero(n);
}

NewmarkIntegrator::~NewmarkIntegrator() = default;

void NewmarkIntegrator::set_time_step(double h) {
  if (!(h > 0) || !std::isfinite(h))
    throw InputError("dynamics: time_step must be positive (got " + std::to_string(h) + ")");
  options_.time_step = h;
}

void NewmarkIntegrator::apply_fixed(VecX& x) const {
  if (model_.fixed.empty()) return;
  for (int i = 0; i < x.size(); ++i)
    if (model_.fixed[i]) x(i) = 0;
}

void NewmarkIntegrator::set_state(const VecX& q, const VecX& v, double time) {
  const int n = model_.mesh.num_dofs();
  if (q.size() != n || v.size() != n)
    throw InputError("dynamics: state has " + std::to_string(q.size()) + " positions and " + std::to_string(v.size()) +
                     " velocities for " + std::to_string(n) + " DOFs");
  if (!q.allFinite() || !v.allFinite()) throw InputError("dynamics: initial state is not finite");
  if (!std::isfinite(assembler_.energy(q))) throw InputError("dynamics: an element is inverted in the initial state");
  q_ = q;
  v_ = v;
  apply_fixed(v_);
  time_ = time;
}

Energies NewmarkIntegrator::energies() const {
  Energies e;
  e.kinetic = 0.5 * v_.dot(mass_ * v_);
  e.elastic = assembler_.energy(q_);
  e.gravity = -gravity_force_.dot(q_ - assembler_.rest_positions());
  return e;
}

void NewmarkIntegrator::assemble_damping(const SpMat* Kb) {
  damping_ = damping_mass_in_pattern_;
  double* d = damping_.valuePtr();
  const Eigen::Index nnz = damping_.nonZeros();
  if (Kb) {
    const double* kb = Kb->valuePtr();
    for (Eigen::Index i = 0; i < nnz; ++i) d[i] += kb[i];
  }
  // M + h/2 D, the constant part of this step's Jacobian.
  const double h = options_.time_step;
  inertia_ = mass_in_pattern_;
  double* m = inertia_.valuePtr();
  for (Eigen::Index i = 0; i < nnz; ++i) m[i] += h / 2 * d[i];
}

void NewmarkIntegrator::assemble_jacobian(const SpMat& K) {
  const double h = options_.time_step;
  const double* m = inertia_.valuePtr();
  const double* k = K.valuePtr();
  double* H = jacobian_.valuePtr();
  const Eigen::Index nnz = jacobian_.nonZeros();
  for (Eigen::Index i = 0; i < nnz; ++i) H[i] = m[i] + h * h / 4 * k[i];
  for (int i : fixed_value_index_) H[i] = 0;
  for (int i : fixed_diagonal_index_) H[i] = 1;
}

NewmarkIntegrator::Contact NewmarkIntegrator::obstacle_contact(int node, int obstacle,
                                                               const ContactPlane& plane) const {
  Contact c;
  c.key = {node, obstacle};
  c.nodes[0] = node;
  c.coefficient[0] = 1;
  c.gap0 = plane.gap(q_.segment<3>(3 * node));
  c.frame = contact_frame(plane.normal);
  c.mu = model_.friction ? model_.friction_table.mu(node_material_[node], model_.obstacles[obstacle].surface) : 0.0;
  return c;
}

void NewmarkIntegrator::add_surface_contacts(const VecX& delta, double margin, std::vector<Contact>& contacts) const {
  if (!surface_) return;
  std::vector<std::pair<int, int>> present;
  for (const Contact& c : contacts) present.push_back(c.key);
  std::sort(present.begin(), present.end());
  auto absent = [&](const std::pair<int, int>& key) {
    return !std::binary_search(present.begin(), present.end(), key);
  };
  auto material = [&](int face) { return model_.element_material_name[surface_->boundary().face_element[face]]; };
  auto friction = [&](const std::string& a, const std::string& b) {
    return model_.friction ? model_.friction_table.mu_between(a, b) : 0.0;
  };
  const int first_face = static_cast<int>(model_.obstacles.size());
  const HexBoundary& boundary = surface_->boundary();
  const VecX end = q_ + delta;
  for (const NodeFaceContact& f : surface_->find(q_, end, margin, kSurfaceDepthLimit * dx_)) {
    Contact c;
    c.key = {f.node, first_face + f.face};
    if (!absent(c.key)) continue;
    c.count = 5;
    c.nodes[0] = f.node;
    c.coefficient[0] = 1;
    for (int i = 0; i < 4; ++i) {
      c.nodes[1 + i] = boundary.faces[f.face][i];
      c.coefficient[1 + i] = -f.weights[i];
    }
    c.gap0 = f.gap_start;
    c.frame = contact_frame(f.normal);
    c.mu = friction(node_material_[f.node], material(f.face));
    contacts.push_back(c);
  }
  if (!options_.edge_contact) return;
  const auto& edges = surface_->edges();
  for (const EdgeEdgeContact& e : surface_->find_edges(q_, end, margin, kSurfaceDepthLimit * dx_)) {
    Contact c;
    c.key = {-1 - e.edge_a, -1 - e.edge_b};
    if (!absent(c.key)) continue;
    c.count = 4;
    const auto& a = edges[e.edge_a].nodes;
    const auto& b = edges[e.edge_b].nodes;
    c.nodes = {a[0], a[1], b[0], b[1], 0};
    c.coefficient = {1 - e.alpha, e.alpha, e.beta - 1, -e.beta, 0};
    c.gap0 = e.gap_start;
    c.frame = contact_frame(e.normal);
    c.mu = friction(material(edges[e.edge_a].faces.front()), material(edges[e.edge_b].faces.front()));
    contacts.push_back(c);
  }
}

std::vector<NewmarkIntegrator::Contact> NewmarkIntegrator::detect_contacts(const VecX& delta_predicted) const {
  std::vector<Contact> contacts;
  if (!model_.contact) return contacts;
  const double margin = options_.contact_margin * dx_;
  for (int node : boundary_nodes_) {
    const Vec3 x0 = q_.segment<3>(3 * node);
    const Vec3 x1 = x0 + delta_predicted.segment<3>(3 * node);
    for (int o = 0; o < static_cast<int>(model_.obstacles.size()); ++o)
      if (const auto plane = first_contact(model_.obstacles[o], x0, x1, margin))
        contacts.push_back(obstacle_contact(node, o, *plane));
  }
  add_surface_contacts(delta_predicted, margin, contacts);
  return contacts;
}

void NewmarkIntegrator::add_penetrating_contacts(const VecX& delta, std::vector<Contact>& contacts) const {
  const double tolerance = options_.penetration_tolerance * dx_;
  std::vector<std::pair<int, int>> present;
  for (const Contact& c : contacts) present.push_back(c.key);
  std::sort(present.begin(), present.end());
  for (int node : boundary_nodes_) {
    const Vec3 x0 = q_.segment<3>(3 * node);
    const Vec3 x1 = x0 + delta.segment<3>(3 * node);
    for (int o = 0; o < static_cast<int>(model_.obstacles.size()); ++o) {
      if (std::binary_search(present.begin(), present.end(), std::make_pair(node, o))) continue;
      if (signed_distance(model_.obstacles[o], x1, nullptr) >= -tolerance) continue;
      ContactPlane plane;
      if (auto hit = first_contact(model_.obstacles[o], x0, x1, 0.0)) {
        plane = *hit;
      } else {
        signed_distance(model_.obstacles[o], x1, &plane);
      }
      contacts.push_back(obstacle_contact(node, o, plane));
    }
  }
  add_surface_contacts(delta, -tolerance, contacts);
}

double NewmarkIntegrator::step_potential(const VecX& delta) const {
  const double h = options_.time_step;
  const double elastic = assembler_.energy(q_ + delta);
  if (!std::isfinite(elastic)) return elastic;
  return 0.5 * delta.dot(inertia_ * delta) - step_rhs_.dot(delta) + h * h / 4 * (elastic - end_force_.dot(delta));
}

void NewmarkIntegrator::set_applied_load(const VecX& load, std::function<double(double)> scale) {
  if (load.size() != model_.mesh.num_dofs() || !load.allFinite())
    throw std::invalid_argument("NewmarkIntegrator::set_applied_load: load does not match the mesh or is not finite");
  applied_load_ = load;
  apply_fixed(applied_load_);
  applied_scale_ = std::move(scale);
}

StepReport NewmarkIntegrator::step() {
  StepReport report = try_step();
  if (!report.converged) throw NumericalError(report.failure);
  return report;
}

StepReport NewmarkIntegrator::try_step() {
  // The state (q, v, t) changes only when a step is taken, so a step that
  // fails leaves the integrator where it was, ready for another try.
  try {
    StepReport report = take_step();
    report.converged = true;
    return report;
  } catch (const NumericalError& e) {
    StepReport report;
    report.failure = e.what();
    return report;
  }
}

StepReport NewmarkIntegrator::take_step() {
  const auto t0 = std::chrono::steady_clock::now();
  StepReport report;
  const double h = options_.time_step;
  const int n = model_.mesh.num_dofs();

  // b^t (Eq. 4.6).
  VecX grad_t(n);
  assembler_.evaluate(q_, &grad_t, nullptr);
  SpMat Kb_t;
  if (damping_assembler_) {
    Kb_t = damping_assembler_->pattern();
    // At the predicted midpoint: D's forces are torque-free about the
    // configuration it is evaluated at, and the step's angular momentum
    // balance is taken about the midpoint. Held at q^t, the lever arms are
    // off by delta/2 and a ringing, spinning body loses spin at first order.
    // Where the prediction inverts an element its energy is not finite
    // (or NaN where b = 0) and q^t is used.
    if (!std::isfinite(damping_assembler_->evaluate(q_ + 0.5 * h * v_, nullptr, &Kb_t)))
      damping_assembler_->evaluate(q_, nullptr, &Kb_t);
  }
  assemble_damping(damping_assembler_ ? &Kb_t : nullptr);
  VecX force_t = gravity_force_ - grad_t;
  end_force_ = gravity_force_;
  if (applied_scale_) {
    force_t += applied_scale_(time_) * applied_load_;
    end_force_ += applied_scale_(time_ + h) * applied_load_;
  }
  // With D held fixed, the -h^2/4 D v^t of b^t cancels against the same
  // term of the end-of-step damping force h^2/4 D (2/h delta - v^t), whose
  // remaining h/2 D delta lives in inertia_.
  step_rhs_ = h * (mass_ * v_) + h * h / 4 * force_t;
  apply_fixed(step_rhs_);
  force_scale_ = std::max({(mass_ * v_).norm() * h, h * h / 4 * end_force_.norm(), h * h / 4 * grad_t.norm(), 1e-300});

  // Predicted path for collision detection: free flight under gravity.
  VecX delta = h * v_;
  for (int i = 0; i < model_.mesh.num_nodes(); ++i) delta.segment<3>(3 * i) += 0.5 * h * h * model_.gravity;
  apply_fixed(delta);
  std::vector<Contact> contacts = detect_contacts(delta);
  if (!std::isfinite(assembler_.energy(q_ + delta))) delta.setZero();

  VecX impulses;
  for (int round = 1;; ++round) {
    VecX warm = VecX::Zero(3 * static_cast<Eigen::Index>(contacts.size()));
    warm.head(std::min(warm.size(), impulses.size())) = impulses.head(std::min(warm.size(), impulses.size()));
    impulses = warm;
    report.newton_iterations += solve_step(delta, contacts, impulses, report);
    report.contact_rounds = round;
    if (!model_.contact) break;
    const size_t before = contacts.size();
    add_penetrating_contacts(delta, contacts);
    if (contacts.size() == before) break;
    if (round == options_.max_contact_rounds)
      throw NumericalError("dynamics: step at t = " + std::to_string(time_) +
                           " s still finds new penetrating nodes after " + std::to_string(round) +
                           " contact rounds; reduce the time step");
  }

  const VecX v_new = impact_velocity(delta, contacts, impulses);
  report.contacts = static_cast<int>(contacts.size());
  for (size_t k = 0; k < contacts.size(); ++k) {
    if (impulses(3 * k) > 0) ++report.active_contacts;
    if (!contacts[k].on_obstacle())
      report.max_penetration = std::max(
          report.max_penetration, -(contacts[k].gap0 + contacts[k].frame.col(0).dot(contacts[k].relative(delta))));
  }
  report.peak_active_contacts = report.active_contacts;
  q_ += delta;
  v_ = v_new;
  time_ += h;
  for (int node : boundary_nodes_)
    for (const Obstacle& o : model_.obstacles)
      if (model_.contact)
        report.max_penetration =
            std::max(report.max_penetration, -signed_distance(o, q_.segment<3>(3 * node), nullptr));
  report.seconds = seconds_since(t0);
  return report;
}

int NewmarkIntegrator::solve_step(VecX& delta, const std::vector<Contact>& contacts, VecX& impulses,
                                  StepReport& report) {
  const double h = options_.time_step;
  const int n = model_.mesh.num_dofs();
  const int m = static_cast<int>(contacts.size());
  SpMat K = assembler_.pattern();
  VecX grad(n), f(n);
  std::vector<double> history;
  double last_step = std::numeric_limits<double>::infinity();

  auto contact_force = [&](const VecX& p) {
    VecX Gp = VecX::Zero(n);
    for (int k = 0; k < m; ++k) contacts[k].scatter(contacts[k].frame * p.segment<3>(3 * k), Gp);
    apply_fixed(Gp);
    return Gp;
  };

  // The contact unknowns go last in the factorization, so that the
  // Delassus matrix comes from the factor's trailing block (one dense solve
  // on them) instead of one sparse solve per contact column; a resting
  // plate has hundreds of contacts (solve/cholmod_solver.hpp).
  const std::vector<int> contact_dofs = contact_unknowns(contacts);
  if (contact_dofs != solver_->last_unknowns()) {
    if (contact_dofs.empty())
      solver_->analyze(jacobian_);
    else
      solver_->analyze_with_last(jacobian_, contact_dofs);
  }
  const MatX G_contact = contact_columns(contacts, contact_dofs);

  for (int it = 1; it <= options_.max_newton_iterations; ++it) {
    const VecX x = q_ + delta;
    assembler_.evaluate(x, &grad, &K);
    f = inertia_ * delta - step_rhs_ + h * h / 4 * (grad - end_force_);
    apply_fixed(f);
    const double residual = (f - contact_force(impulses)).norm() / force_scale_;
    history.push_back(residual);
    report.residual = residual;
    if (it > 1 && (residual <= options_.newton_tolerance || last_step <= 1e-13 * dx_)) return it - 1;
    // The contact impulses come from Gauss-Seidel, whose accuracy on a
    // large, nearly redundant contact set (a plate resting on a plate:
    // node-face and edge-edge rows along the same normals) sets a floor
    // under the residual. Within kStallFactor of the tolerance, a residual
    // that has not fallen by 10% over five iterations is at that floor.
    const size_t c = history.size();
    if (c > 5 && residual <= kStallFactor * options_.newton_tolerance && residual > 0.9 * history[c - 6]) return it - 1;

    assemble_jacobian(K);
    // The inertia term keeps the Jacobian far from singular, so the shift
    // starts lower than the static solver's and goes up to the diagonal.
    RegularizationSchedule schedule;
    schedule.first_shift = 1e-10;
    const RegularizedStep newton_step = solve_regularized_step(
        *solver_, jacobian_, jacobian_.diagonal().cwiseAbs().maxCoeff(), [&](double, VecX& b) { b = f; },
        [](VecX&) { return true; }, rhs_, step_, "dynamics: ", schedule);
    if (!newton_step.ok)
      throw NumericalError("dynamics: the Newmark Jacobian is not positive definite at t = " + std::to_string(time_) +
                           " s; reduce the time step");
    const VecX delta_free = delta - step_;
    VecX candidate = delta_free;
    if (m > 0) {
      ContactProblem problem;
      problem.h = h;
      problem.W = delassus_matrix(G_contact);
      problem.u_free.resize(3 * m);
      problem.tangential_velocity_start.resize(2 * m);
      for (int k = 0; k < m; ++k) {
        const Contact& ct = contacts[k];
        const Mat3& F = ct.frame;
        problem.u_free.segment<3>(3 * k) = F.transpose() * ct.relative(delta_free);
        problem.gap0.push_back(ct.gap0);
        problem.mu.push_back(ct.mu);
        problem.tangential_velocity_start.segment<2>(2 * k) = F.rightCols<2>().transpose() * ct.relative(v_);
      }
      // Symmetrize against round-off so Gauss-Seidel sees one matrix.
      problem.W = 0.5 * (problem.W + problem.W.transpose()).eval();
      ContactSolveOptions gs;
      gs.max_sweeps = options_.gauss_seidel_sweeps;
      gs.tolerance = options_.gauss_seidel_tolerance;
      const ContactSolveResult solved = solve_contact_problem(problem, impulses, gs);
      report.gauss_seidel_sweeps += solved.sweeps;
      if (!solved.converged && solved.max_change > 1e-2)
        throw NumericalError("dynamics: contact Gauss-Seidel did not converge at t = " + std::to_string(time_) +
                             " s (" + std::to_string(m) + " contacts, last relative change " +
                             std::to_string(solved.max_change) + ")");
      impulses = solved.p;
      delassus_ = std::move(problem.W);
      candidate += solver_->solve(contact_force(impulses));
    }
    // Backtracking on the step's incremental potential (Armijo) when the
    // direction descends it, which the frictionless contact step from an
    // admissible iterate always does; otherwise only until no element is
    // inverted. The contact constraints are linear in delta, so every point
    // between two admissible iterates is admissible too.
    VecX step = candidate - delta;
    const double phi0 = step_potential(delta);
    const double slope = f.dot(step);
    double phi = step_potential(delta + step);
    for (int ls = 0; ls < 40; ++ls) {
      const bool finite = std::isfinite(phi);
      if (finite && (slope >= 0 || phi <= phi0 + 1e-4 * slope * std::pow(0.5, ls) || ls > 30)) break;
      step *= 0.5;
      phi = step_potential(delta + step);
    }
    if (!std::isfinite(phi))
      throw NumericalError("dynamics: no uninverted step at t = " + std::to_string(time_) + " s; reduce the time step");
    delta += step;
    last_step = step.cwiseAbs().maxCoeff();
  }
  std::ostringstream msg;
  msg << "dynamics: Newton did not converge in " << options_.max_newton_iterations << " iterations at t = " << time_
      << " s (" << m << " contacts); relative residuals:";
  for (size_t i = 0; i < history.size(); ++i)
    if (i < 5 || i + 5 >= history.size()) msg << ' ' << history[i];
  throw NumericalError(msg.str());
}

std::vector<int> NewmarkIntegrator::contact_unknowns(const std::vector<Contact>& contacts) const {
  std::vector<int> dofs;
  for (const Contact& ct : contacts)
    for (int i = 0; i < ct.count; ++i)
      for (int a = 0; a < 3; ++a) {
        const int dof = 3 * ct.nodes[i] + a;
        if (model_.fixed.empty() || !model_.fixed[dof]) dofs.push_back(dof);
      }
  std::sort(dofs.begin(), dofs.end());
  dofs.erase(std::unique(dofs.begin(), dofs.end()), dofs.end());
  return dofs;
}

MatX NewmarkIntegrator::contact_columns(const std::vector<Contact>& contacts, const std::vector<int>& dofs) const {
  const int m = static_cast<int>(contacts.size());
  MatX G = MatX::Zero(static_cast<Eigen::Index>(dofs.size()), 3 * m);
  for (int k = 0; k < m; ++k) {
    const Contact& ct = contacts[k];
    for (int i = 0; i < ct.count; ++i)
      for (int a = 0; a < 3; ++a) {
        const auto r = std::lower_bound(dofs.begin(), dofs.end(), 3 * ct.nodes[i] + a);
        if (r == dofs.end() || *r != 3 * ct.nodes[i] + a) continue;  // a fixed unknown
        for (int c = 0; c < 3; ++c) G(r - dofs.begin(), 3 * k + c) += ct.coefficient[i] * ct.frame(a, c);
      }
  }
  return G;
}

MatX NewmarkIntegrator::delassus_matrix(const MatX& G_contact) const {
  // W = (L_ll^{-1} G_C)^T (L_ll^{-1} G_C).
  const Eigen::Index cols = G_contact.cols();
  if (G_contact.rows() == 0) return MatX::Zero(cols, cols);
  const MatX X = solver_->trailing_factor().triangularView<Eigen::Lower>().solve(G_contact);
  MatX W = MatX::Zero(cols, cols);
  W.selfadjointView<Eigen::Lower>().rankUpdate(X.transpose());
  return W.selfadjointView<Eigen::Lower>();
}

VecX NewmarkIntegrator::impact_velocity(const VecX& delta, const std::vector<Contact>& contacts, const VecX& impulses) {
  const double h = options_.time_step;
  const VecX c = 2.0 * delta - h * v_;
  if (model_.impact == ImpactModel::kComplementarity) return c / h;
  std::vector<int> active;
  for (size_t k = 0; k < contacts.size(); ++k)
    if (impulses(3 * k) > 0) active.push_back(static_cast<int>(k));
  if (active.empty()) return c / h;
  const int a = static_cast<int>(active.size());
  // Y = A^{-1} N_a with A = H (BBI, with the last Newton iterate's
  // factorization and Delassus matrix) or A = M (DKE).
  MatX Y;
  MatX S(a, a);
  if (model_.impact == ImpactModel::kBbi) {
    for (int i = 0; i < a; ++i)
      for (int j = 0; j < a; ++j) S(i, j) = delassus_(3 * active[i], 3 * active[j]);
  } else {
    // DKE: the L2 projection with the lumped (row-sum) mass, which is
    // nodewise: each force-carrying node loses its normal velocity and
    // nothing else changes.
    Y = MatX::Zero(c.size(), a);
    S.setZero();
    for (int j = 0; j < a; ++j) {
      const Contact& ct = contacts[active[j]];
      VecX column = VecX::Zero(c.size());
      ct.scatter(ct.frame.col(0), column, [&](int node) { return lumped_mass_(node); });
      apply_fixed(column);
      Y.col(j) = column;
    }
    for (int i = 0; i < a; ++i)
      for (int j = 0; j < a; ++j) {
        const Contact& ci = contacts[active[i]];
        S(i, j) = ci.frame.col(0).dot(ci.relative(Y.col(j)));
      }
  }
  VecX normal_c(a);
  for (int i = 0; i < a; ++i) {
    const Contact& ct = contacts[active[i]];
    normal_c(i) = ct.frame.col(0).dot(ct.relative(c));
  }
  // Zero normal velocity at every force-carrying contact, nearest to c in
  // the chosen metric: d = c + Y mu with N_a^T d = 0.
  const VecX mu = S.ldlt().solve(-normal_c);
  VecX d = c;
  if (model_.impact == ImpactModel::kBbi) {  // H^{-1} N_a mu, one solve
    VecX N_mu = VecX::Zero(c.size());
    for (int j = 0; j < a; ++j) contacts[active[j]].scatter(mu(j) * contacts[active[j]].frame.col(0), N_mu);
    apply_fixed(N_mu);
    d += solver_->solve(N_mu);
  } else {
    d += Y * mu;
  }
  apply_fixed(d);
  return d / h;
}

}  // namespace msfab
