#pragma once
// Quasistatic loading against static obstacles (thesis App. B.3, Eq. B.24):
// the equilibrium of an elastic mesh under external loads with unilateral,
// no-slip (infinite friction) vertex contact.
//
// Newton-Raphson on K(q) delta = F_ext - grad E(q), with every active
// contact vertex held where it touched (all three components: no slip).
// A projected line search halves the step while a free vertex would
// penetrate an obstacle deeper than penetration_tolerance * dx (dx: the
// characteristic rest element size) or an element would invert. After each
// step the active set is updated: an active vertex whose reaction pulls it
// off the obstacle (reaction . n < 0) is released, and a free vertex that
// penetrates is projected back onto the obstacle face and becomes active.
// The load is applied in increments (continuation); a failing increment is
// halved. With self_contact, boundary nodes that reach a face of the mesh
// are tied to it in the same way (self_contact_ties.hpp).
#include <string>
#include <vector>

#include "dynamics/obstacles.hpp"
#include "dynamics/self_contact_ties.hpp"
#include "fem/elastic_assembler.hpp"
#include "solve/newton.hpp"

namespace msfab {

struct QuasistaticOptions {
  // Convergence: ||free residual|| <= relative_tolerance * force scale (the
  // applied load and the contact reactions), with an unchanged active set.
  double relative_tolerance = 1e-9;
  int max_iterations = 60;    // per load increment, counted from the last change of the active set
  int load_steps = 4;         // initial number of equal load increments
  int max_step_halvings = 6;  // adaptive cuts of a failing increment
  double armijo = 1e-4;
  int max_line_search = 40;
  // Depth a free vertex may reach inside an obstacle within one step, in
  // units of dx (B.3 uses 1e-2); also the largest penetration accepted in
  // the initial state (such vertices are projected onto the surface).
  double penetration_tolerance = 1e-2;
  // A vertex of the initial state within this distance (units of dx) of an
  // obstacle counts as touching it and starts active.
  double touch_tolerance = 1e-6;
  // Contact of the mesh with itself and between its bodies: a boundary node
  // that reaches a boundary face is tied to it without slip
  // (self_contact_ties.hpp), as the obstacles hold vertices.
  bool self_contact = false;
  // With self_contact: boundary edges that cross are tied at their closest
  // points too (self_contact_ties.hpp).
  bool edge_contact = true;
  // Threads of the linear solver; 0 uses the OpenMP default. Assembly always
  // follows the OpenMP default (set by the stage).
  int threads = 0;
};

// One vertex held by an obstacle.
struct ContactVertex {
  int node = 0;
  int obstacle = 0;  // index into the obstacle list
  // Face it rests on (admissible side normal . x >= offset); on an edge or
  // corner, the touching face that pushes hardest.
  ContactPlane plane;
  Vec3 reaction = Vec3::Zero();  // force the obstacle exerts on the vertex
};

struct QuasistaticIteration {
  int load_step = 0;
  double load_factor = 0;
  int iteration = 0;
  double residual = 0;     // ||free residual|| / force scale
  double energy = 0;       // total potential E(q) - F . (q - X)
  double step_length = 0;  // accepted line-search step (0 when none taken)
  double shift = 0;        // diagonal regularization of the Newton system
  int active = 0;          // active vertices (obstacle and self-contact) after this iteration's release
  int released = 0;        // vertices released at the start of this iteration
  int activated = 0;       // free vertices projected and activated after the step
};

struct QuasistaticResult {
  bool converged = false;
  std::string failure;                        // why it stopped, when not converged
  VecX x;                                     // equilibrium positions (3N, node-major)
  std::vector<ContactVertex> contacts;        // active vertices, ascending node order
  std::vector<SelfContactTie> self_contacts;  // nodes tied to faces and crossing edges tied together, with their forces
  int iterations = 0;                         // Newton steps taken, all increments
  int load_steps = 0;                         // increments attempted (including cut ones)
  double elastic_energy = 0;                  // E(x)
  double characteristic_size = 0;             // dx used for the tolerances
  std::vector<QuasistaticIteration> history;
};

// Solves B.24 for the mesh of `assembler` under the external nodal forces
// `force` (3N, full load; e.g. a load region plus gravity), starting from
// x0 (3N; rest positions when empty), which must not penetrate an obstacle
// deeper than penetration_tolerance * dx.
// Throws InputError for mismatched sizes, non-finite values, invalid
// options or obstacles, an inverted or penetrating initial state. Never
// throws when no equilibrium is found, as solve_static: the result says
// converged = false with the reason, the history and the positions of the
// last converged load factor, and callers decide.
QuasistaticResult solve_quasistatic_loading(const ElasticAssembler& assembler, const std::vector<Obstacle>& obstacles,
                                            const VecX& force, const VecX& x0 = VecX(),
                                            const QuasistaticOptions& options = {});

// Mean rest edge length of the mesh's hexahedra.
double characteristic_element_size(const HexMesh& mesh);

// The contact vertices of `result` as Dirichlet conditions of solve_static
// (fixed where they are), for re-solving or checking with a fixed active set.
DirichletConditions contact_dirichlet(const QuasistaticResult& result, const VecX& rest_positions);

// The history as readable text, for error messages.
std::string format_quasistatic_history(const std::vector<QuasistaticIteration>& history, size_t max_lines = 30);

}  // namespace msfab
