#pragma once
// Implicit (trapezoidal) Newmark with Rayleigh damping, gravity and
// frictional contact against static obstacles and between bodies (thesis Eq. 4.2-4.14, 4.19,
// App. B.1). One step from (q^t, v^t):
//
//   1. b^t = h M v^t + h^2/4 F(q^t) - h^2/4 D v^t                     (4.6)
//      The damping matrix D = a M + b K_m is held fixed for the whole step
//      (the thesis evaluates it at q^{t+1} and drops dD/dq from the
//      Jacobian, B.8). With D fixed the step minimizes an incremental
//      potential, Newton is exact and the line search has a merit function;
//      the dropped term made Newton diverge on stiff, strongly damped
//      impacts. K_m is the material part of the stiffness (no geometric
//      term, clamped PSD), so D spares rigid motion of a stressed body, and
//      it is evaluated at the predicted midpoint q^t + h/2 v^t, so its
//      forces carry no torque about the step's midpoint to second order:
//      b K(q^t) lost a spinning jumper most of its angular momentum in
//      flight (docs/dynamics.md, "Damping that spares rigid motion").
//   2. continuous collision detection of each boundary node along the
//      predicted path q^t -> q^t + h v^t + h^2/2 g gathers the contact set:
//      node-obstacle contacts and, with body contact on, five-node
//      node-face contacts between and within bodies (B.5) and edge-edge
//      contacts (surface_contact.hpp)
//   3. Newton on (B.1): per iterate factor H = M + h^2/4 K + h/2 D, take
//      the free step,
//      and solve the contacts' normal and friction impulses by Gauss-Seidel
//      on the Delassus matrix (B.15-B.19; see contact_problem.hpp); a
//      backtracking line search keeps every element uninverted
//   4. nodes that still end the step inside an obstacle join the contact
//      set and the step is solved again
//   5. velocity: Newmark v = 2/h delta - v^t (complementarity), or the
//      impact projection of the velocity displacement c = 2 delta - h v^t
//      onto zero normal velocity at the contacts that carry force, in the
//      lumped-mass metric (DKE) or A = M + h^2/4 K + h/2 D (BBI). docs/dynamics.md
//      explains this reading of Eq. 4.19 / B.20.
#include <functional>
#include <memory>
#include <string>
#include <vector>

#include "dynamics/dynamics_model.hpp"
#include "fem/elastic_assembler.hpp"

namespace msfab {

class BoundarySurface;
class CholmodSolver;

struct NewmarkOptions {
  double time_step = 1e-4;
  double newton_tolerance = 1e-9;  // on the residual relative to the step's force scale
  int max_newton_iterations = 60;
  int max_contact_rounds = 6;
  // Contact candidates: nodes whose predicted path comes within this
  // fraction of the smallest element edge of an obstacle.
  double contact_margin = 0.05;
  // Reported (never enforced silently): the largest penetration tolerated
  // at the end of a step, as a fraction of the smallest element edge.
  double penetration_tolerance = 1e-3;
  // With body contact: edge-edge contacts besides the vertex-face ones, so
  // that crossing edges cannot pass through each other
  // (surface_contact.hpp).
  bool edge_contact = true;
  int gauss_seidel_sweeps = 2000;
  double gauss_seidel_tolerance = 1e-11;
};

struct Energies {
  double kinetic = 0, elastic = 0, gravity = 0;  // gravity relative to the initial state
  double total() const { return kinetic + elastic + gravity; }
};

struct StepReport {
  bool converged = false;
  std::string failure;  // why the step was not taken (try_step), when not converged
  int newton_iterations = 0;
  int contact_rounds = 0;
  int contacts = 0;         // in the contact set
  int active_contacts = 0;  // carrying a normal impulse at the end
  // The most active contacts at the end of any part of the step: where a
  // step is retaken as event substeps (dynamics_run.cpp), a touch that
  // starts and ends inside it still counts.
  int peak_active_contacts = 0;
  int gauss_seidel_sweeps = 0;
  double residual = 0;         // final relative residual
  double max_penetration = 0;  // deepest node below an obstacle surface at the end (m, >= 0)
  double seconds = 0;
};

class NewmarkIntegrator {
 public:
  NewmarkIntegrator(const DynamicsModel& model, const NewmarkOptions& options);
  ~NewmarkIntegrator();
  NewmarkIntegrator(const NewmarkIntegrator&) = delete;
  NewmarkIntegrator& operator=(const NewmarkIntegrator&) = delete;

  // InputError if sizes mismatch, a value is not finite or an element is
  // inverted.
  void set_state(const VecX& q, const VecX& v, double time = 0.0);
  // An applied force scale(t) * load besides gravity (a press ramped on
  // during the run). The trapezoidal rule takes it at both ends of a step.
  // It does no work on Energies (they hold gravity's potential only).
  void set_applied_load(const VecX& load, std::function<double(double time)> scale);
  // One time step; NumericalError with the residual history if Newton or
  // the contact solve does not converge.
  StepReport step();
  // The same step, reporting failure as solve_static and the quasistatic
  // press do: converged = false with the reason, the state unchanged (so a
  // caller may retry, e.g. with a smaller time step).
  StepReport try_step();
  // The length of the next steps (InputError unless positive and finite);
  // the run's event substeps change it around contact events.
  void set_time_step(double h);
  double time_step() const { return options_.time_step; }

  const VecX& positions() const { return q_; }
  const VecX& velocities() const { return v_; }
  double time() const { return time_; }
  Energies energies() const;
  const SpMat& mass_matrix() const { return mass_; }
  const SpMat& scalar_mass_matrix() const { return scalar_mass_; }
  const VecX& gravity_force() const { return gravity_force_; }
  const DynamicsModel& model() const { return model_; }
  const ElasticAssembler& assembler() const { return assembler_; }
  // Smallest element edge at rest (sets contact margins and tolerances).
  double element_size() const { return dx_; }
  const std::vector<int>& boundary_nodes() const { return boundary_nodes_; }

 private:
  struct Contact;
  Contact obstacle_contact(int node, int obstacle, const ContactPlane& plane) const;
  // Node-face contacts (bodies and self) whose gap at q^t + delta is below
  // `margin`, appended unless already present.
  void add_surface_contacts(const VecX& delta, double margin, std::vector<Contact>& contacts) const;
  std::vector<Contact> detect_contacts(const VecX& delta_predicted) const;
  void add_penetrating_contacts(const VecX& delta, std::vector<Contact>& contacts) const;
  // Newton on (B.1) with a fixed contact set; returns the iterations.
  int solve_step(VecX& delta, const std::vector<Contact>& contacts, VecX& impulses, StepReport& report);
  // D = sum a_e M_e + sum b_e K_e(q^t + h/2 v^t)_m and M + h/2 D for the
  // current step; K_e(q)_m is the element stiffness with dP/dF reduced to
  // its material part and clamped PSD (material/scaled_material.hpp).
  void assemble_damping(const SpMat* Kb);
  void assemble_jacobian(const SpMat& K);
  // Phi(delta) = 1/2 delta^T (M + h/2 D) delta - b^T delta + h^2/4 (E(q^t + delta) - f_g^T delta),
  // whose gradient is the residual of (B.6) with D held at q^t.
  double step_potential(const VecX& delta) const;
  StepReport take_step();  // throws NumericalError where the step cannot be taken
  void apply_fixed(VecX& x) const;
  // The unknowns the contacts touch (fixed ones left out), sorted.
  std::vector<int> contact_unknowns(const std::vector<Contact>& contacts) const;
  // G restricted to `dofs` (contact_unknowns, sorted): |dofs| x 3 contacts.
  MatX contact_columns(const std::vector<Contact>& contacts, const std::vector<int>& dofs) const;
  // W = G^T H^{-1} G from the current factorization, analyzed with the
  // contact unknowns last, and G_contact = contact_columns().
  MatX delassus_matrix(const MatX& G_contact) const;
  VecX impact_velocity(const VecX& delta, const std::vector<Contact>& contacts, const VecX& impulses);

  const DynamicsModel& model_;
  NewmarkOptions options_;
  ElasticAssembler assembler_;
  // Materials scaled by each element's b (PSD-projected), when any b > 0.
  std::unique_ptr<HexMesh> damping_mesh_;
  std::unique_ptr<ElasticAssembler> damping_assembler_;
  SpMat scalar_mass_, mass_;
  SpMat mass_in_pattern_, damping_mass_in_pattern_;  // M and sum_e a_e M_e on the stiffness pattern
  SpMat damping_, inertia_, jacobian_;
  std::vector<int> fixed_value_index_, fixed_diagonal_index_;
  std::unique_ptr<CholmodSolver> solver_;
  VecX rhs_, step_;   // the Newton system's right-hand side and solution (work vectors)
  VecX lumped_mass_;  // per node, the DKE projection's metric
  VecX gravity_force_;
  VecX applied_load_;
  std::function<double(double)> applied_scale_;
  VecX end_force_;  // gravity and the applied load at the end of the current step
  std::vector<int> boundary_nodes_;
  std::unique_ptr<BoundarySurface> surface_;  // with body contact
  std::vector<std::string> node_material_;
  double dx_ = 0;
  VecX q_, v_, q0_;
  double time_ = 0;
  VecX step_rhs_;           // b^t of the current step
  double force_scale_ = 1;  // what the current step's residual is relative to
  // The last Newton iterate's Delassus matrix, reused by BBI with the
  // factorization it came from.
  MatX delassus_;
};

}  // namespace msfab
