#include "dynamics/quasistatic_loading.hpp"

#include <spdlog/spdlog.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <memory>
#include <sstream>

#include "core/errors.hpp"
#include "solve/cholmod_solver.hpp"
#include "solve/regularized_step.hpp"

namespace msfab {
namespace {

// Total iterations of one load increment, in units of max_iterations (see
// the iteration limit in newton_at).
constexpr int kActiveSetRounds = 10;

constexpr int kFree = -1;

// Contact state per node: the obstacle holding it (kFree if none) and the
// face it rests on.
struct ActiveSet {
  std::vector<int> obstacle;
  std::vector<ContactPlane> plane;
  int count() const {
    return static_cast<int>(std::count_if(obstacle.begin(), obstacle.end(), [](int o) { return o != kFree; }));
  }
};

// The obstacle the point is deepest in (or nearest to), its signed distance
// and face plane.
struct Nearest {
  int obstacle = kFree;
  double distance = 0;
  ContactPlane plane;
};
Nearest nearest_obstacle(const std::vector<Obstacle>& obstacles, const Vec3& x) {
  Nearest best;
  for (size_t o = 0; o < obstacles.size(); ++o) {
    ContactPlane p;
    const double d = signed_distance(obstacles[o], x, &p);
    if (best.obstacle == kFree || d < best.distance) best = {static_cast<int>(o), d, p};
  }
  return best;
}

// Faces of the obstacles the point touches (within tol): one for a face,
// two on an edge, three at a corner; more where obstacles meet.
std::vector<std::pair<int, ContactPlane>> touching_faces(const std::vector<Obstacle>& obstacles, const Vec3& x,
                                                         double tol) {
  std::vector<std::pair<int, ContactPlane>> faces;
  for (size_t o = 0; o < obstacles.size(); ++o) {
    const Obstacle& ob = obstacles[o];
    ContactPlane nearest;
    if (std::abs(signed_distance(ob, x, &nearest)) > tol) continue;
    if (ob.kind == Obstacle::Kind::kGround) {
      faces.emplace_back(static_cast<int>(o), nearest);
      continue;
    }
    for (int a = 0; a < 3; ++a) {
      ContactPlane lower{-Vec3::Unit(a), -ob.lo(a)}, upper{Vec3::Unit(a), ob.hi(a)};
      if (lower.gap(x) >= -tol) faces.emplace_back(static_cast<int>(o), lower);
      if (upper.gap(x) >= -tol) faces.emplace_back(static_cast<int>(o), upper);
    }
  }
  return faces;
}

// Does the segment x0 -> x1 reach deeper than `depth` into the obstacle? The
// segment test catches a step that would tunnel through a thin box.
bool penetrates(const Obstacle& o, const Vec3& x0, const Vec3& x1, double depth) {
  if (signed_distance(o, x1, nullptr) < -depth) return true;
  if (o.kind == Obstacle::Kind::kBox && ((o.hi - o.lo).array() > 2 * depth).all())
    return first_contact(o, x0, x1, -depth).has_value();
  return false;
}

void validate(const ElasticAssembler& assembler, const std::vector<Obstacle>& obstacles, const VecX& force,
              const VecX& x0, const QuasistaticOptions& opt) {
  const int n = assembler.mesh().num_dofs();
  auto fail = [](const std::string& what) { throw InputError("quasistatic loading: " + what); };
  if (force.size() != n)
    fail("external force has " + std::to_string(force.size()) + " entries, the mesh has " + std::to_string(n) +
         " DOFs");
  if (!force.allFinite()) fail("external force has non-finite entries");
  if (x0.size() != 0 && x0.size() != n)
    fail("initial positions have " + std::to_string(x0.size()) + " entries, the mesh has " + std::to_string(n) +
         " DOFs");
  if (x0.size() != 0 && !x0.allFinite()) fail("initial positions have non-finite entries");
  for (const Obstacle& o : obstacles) {
    if (o.kind == Obstacle::Kind::kGround && !std::isfinite(o.ground_z))
      fail("obstacle '" + o.name + "': ground height is not finite");
    if (o.kind == Obstacle::Kind::kBox && !(o.lo.allFinite() && o.hi.allFinite() && (o.lo.array() < o.hi.array()).all()))
      fail("obstacle '" + o.name + "': box needs finite corners with lo < hi");
  }
  if (!(opt.relative_tolerance > 0)) fail("option relative_tolerance must be > 0");
  if (opt.max_iterations < 1) fail("option max_iterations must be >= 1");
  if (opt.load_steps < 1) fail("option load_steps must be >= 1");
  if (opt.max_step_halvings < 0) fail("option max_step_halvings must be >= 0");
  if (opt.max_line_search < 1) fail("option max_line_search must be >= 1");
  if (!(opt.armijo >= 0 && opt.armijo < 0.5)) fail("option armijo must be in [0, 0.5)");
  if (!(opt.penetration_tolerance > 0)) fail("option penetration_tolerance must be > 0");
  if (!(opt.touch_tolerance >= 0 && opt.touch_tolerance <= opt.penetration_tolerance))
    fail("option touch_tolerance must be in [0, penetration_tolerance]");
  if (opt.threads < 0) fail("option threads must be >= 0");
}

}  // namespace

double characteristic_element_size(const HexMesh& mesh) {
  if (mesh.num_elements() == 0) return 0;
  double sum = 0;
  for (int e = 0; e < mesh.num_elements(); ++e) {
    const hex8::NodeMatrix X = mesh.element_rest_positions(e);
    // Edges join corners whose natural coordinates differ in one bit.
    for (int i = 0; i < hex8::kNodes; ++i)
      for (int bit = 1; bit < hex8::kNodes; bit <<= 1)
        if (!(i & bit)) sum += (X.row(i) - X.row(i | bit)).norm();
  }
  return sum / (12.0 * mesh.num_elements());
}

DirichletConditions contact_dirichlet(const QuasistaticResult& result, const VecX& rest_positions) {
  DirichletConditions dc = DirichletConditions::none(static_cast<int>(rest_positions.size()));
  for (const ContactVertex& c : result.contacts)
    for (int a = 0; a < 3; ++a) {
      const int d = 3 * c.node + a;
      dc.fixed[d] = 1;
      dc.displacement[d] = result.x[d] - rest_positions[d];
    }
  return dc;
}

std::string format_quasistatic_history(const std::vector<QuasistaticIteration>& history, size_t max_lines) {
  std::ostringstream out;
  out << "  step  load    iter  residual    energy         alpha      shift     active  -rel  +act\n";
  const size_t first = history.size() > max_lines ? history.size() - max_lines : 0;
  if (first > 0) out << "  ... (" << first << " earlier iterations)\n";
  char line[200];
  for (size_t i = first; i < history.size(); ++i) {
    const auto& h = history[i];
    std::snprintf(line, sizeof line, "  %4d  %.4f  %4d  %.4e  % .6e  %.3e  %.2e  %6d  %4d  %4d\n", h.load_step,
                  h.load_factor, h.iteration, h.residual, h.energy, h.step_length, h.shift, h.active, h.released,
                  h.activated);
    out << line;
  }
  return out.str();
}

QuasistaticResult solve_quasistatic_loading(const ElasticAssembler& assembler, const std::vector<Obstacle>& obstacles,
                                            const VecX& force, const VecX& x0, const QuasistaticOptions& opt) {
  validate(assembler, obstacles, force, x0, opt);
  const HexMesh& mesh = assembler.mesh();
  const int n = mesh.num_dofs(), nodes = mesh.num_nodes();
  const VecX X = assembler.rest_positions();
  const double dx = characteristic_element_size(mesh);
  const double max_depth = opt.penetration_tolerance * dx;
  const double touch = std::max(opt.touch_tolerance, 1e-12) * dx;
  const double length_scale = (mesh.bbox_max() - mesh.bbox_min()).norm();

  QuasistaticResult result;
  result.characteristic_size = dx;
  VecX& q = result.x;
  q = x0.size() == n ? x0 : X;

  // Initial active set: every vertex touching an obstacle, the slightly
  // penetrating ones projected onto the face they are in.
  ActiveSet active{std::vector<int>(nodes, kFree), std::vector<ContactPlane>(nodes)};
  for (int i = 0; i < nodes; ++i) {
    const Nearest c = nearest_obstacle(obstacles, q.segment<3>(3 * i));
    if (c.obstacle == kFree || c.distance > touch) continue;
    if (c.distance < -max_depth) {
      std::ostringstream msg;
      msg << "quasistatic loading: initial positions: node " << i << " lies " << -c.distance
          << " m inside obstacle '" << obstacles[c.obstacle].name << "' (tolerance " << max_depth
          << " m = penetration_tolerance * element size)";
      throw InputError(msg.str());
    }
    if (c.distance < 0) q.segment<3>(3 * i) -= c.distance * c.plane.normal;
    active.obstacle[i] = c.obstacle;
    active.plane[i] = c.plane;
  }
  if (!std::isfinite(assembler.energy(q)))
    throw InputError("quasistatic loading: initial positions invert an element (det F <= 0)");

  SpMat K = assembler.pattern();
  LinearSolverOptions linear;
  linear.threads = opt.threads;
  CholmodSolver solver(linear);
  solver.analyze(K);

  std::unique_ptr<SelfContactTies> ties;
  if (opt.self_contact) ties = std::make_unique<SelfContactTies>(mesh);
  // A node starting deeper than this behind a face is on its far side, not
  // touching it (surface_contact.hpp).
  const double tie_depth_limit = 0.25 * dx;
  int analyzed = -1;  // the ties' version whose reduced pattern the solver holds (-1: K's own)
  auto tied = [&](int d) { return ties && ties->is_slave(d / 3); };
  auto reduced_gradient = [&](const VecX& grad) { return ties ? ties->reduce(grad) : grad; };
  // Nodes touching a face at the start are tied from the start, as
  // vertices touching an obstacle start active.
  if (ties) {
    ties->activate(q, q, touch, tie_depth_limit, [&](int node) { return active.obstacle[node] != kFree; });
    if (!std::isfinite(assembler.energy(q)))
      throw InputError("quasistatic loading: initial positions: putting touching nodes onto faces inverts an element");
  }

  VecX g(n), g_trial(n), rhs(n), step(n), trial(n), r(n);
  std::vector<char> fixed(n, 0), held(n, 0);
  auto update_fixed = [&]() {
    for (int i = 0; i < nodes; ++i) fixed[3 * i] = fixed[3 * i + 1] = fixed[3 * i + 2] = active.obstacle[i] != kFree;
  };

  // Newton at load factor s from the current state; true on convergence.
  auto newton_at = [&](double s, int load_step, std::string& why) -> bool {
    const VecX fs = s * force;
    int activated = 0;  // free vertices made active after the previous step
    std::vector<double> recent;  // residuals since the active set last changed
    // The iteration limit counts Newton iterations at a settled active set:
    // a contact front that peels or spreads moves by a row of vertices per
    // iteration, so on a fine mesh the active set alone can take more than
    // max_iterations updates (the 0.5 mm flipper lifting its base: 60). A
    // hard cap of kActiveSetRounds times the limit stops a cycling set.
    int last_change = 0;
    const int hard_cap = kActiveSetRounds * opt.max_iterations;
    for (int it = 0;; ++it) {
      const double E = assembler.evaluate(q, &g, &K);
      if (!std::isfinite(E)) {
        why = "the configuration is inverted (an element has det F <= 0)";
        return false;
      }
      g -= fs;  // gradient of the total potential; at an active vertex the reaction
      const double potential = E - fs.dot(q - X);
      update_fixed();
      double diag = 0, reaction_sq = 0;
      int free_dofs = 0;
      for (int d = 0; d < n; ++d) {
        if (fixed[d] || tied(d)) {
          reaction_sq += g[d] * g[d];
        } else {
          diag += std::abs(K.coeff(d, d));
          ++free_dofs;
        }
      }
      diag = free_dofs ? diag / free_dofs : 1.0;
      // Rounding level of the energy: a diagonal stiffness entry times dx^2
      // is about the energy of one element at unit strain.
      const double noise_floor = 1e-13 * diag * dx * dx * nodes;
      const double scale = std::max({fs.norm(), std::sqrt(reaction_sq), 1e-12 * diag * length_scale});

      // Release vertices the obstacle would have to pull on. On an edge or
      // corner the obstacle can push along any face normal there, so a
      // vertex goes only if its reaction pulls away from all of them; the
      // face pushing hardest is the one reported.
      int released = 0;
      for (int i = 0; i < nodes; ++i) {
        if (active.obstacle[i] == kFree) continue;
        const Vec3 reaction = g.segment<3>(3 * i);
        double push = active.plane[i].normal.dot(reaction);
        for (const auto& [o, face] : touching_faces(obstacles, q.segment<3>(3 * i), touch)) {
          const double p = face.normal.dot(reaction);
          if (p > push) push = p, active.obstacle[i] = o, active.plane[i] = face;
        }
        if (push < -opt.relative_tolerance * scale) {
          active.obstacle[i] = kFree;
          ++released;
        }
      }
      if (ties) released += ties->release(q, g, opt.relative_tolerance * scale);
      if (released) update_fixed();
      r = reduced_gradient(g);
      double free_sq = 0;
      for (int d = 0; d < n; ++d) {
        held[d] = fixed[d] || tied(d);
        if (!held[d]) free_sq += r[d] * r[d];
      }

      QuasistaticIteration rec;
      rec.load_step = load_step;
      rec.load_factor = s;
      rec.iteration = it;
      rec.residual = std::sqrt(free_sq) / scale;
      rec.energy = potential;
      rec.active = active.count() + (ties ? static_cast<int>(ties->ties().size()) : 0);
      rec.released = released;
      // Converged at the tolerance, or at the round-off floor: with the
      // active set settled, a residual within 1000x the tolerance that has
      // not fallen by 10% over the last 5 iterations (a small load
      // increment on a fine mesh stalls near 1e-7 of its own force).
      recent.push_back(rec.residual);
      const size_t c = recent.size();
      const bool stalled = c > 5 && rec.residual <= 1e3 * opt.relative_tolerance && rec.residual > 0.9 * recent[c - 6];
      if (released == 0 && activated == 0 && (rec.residual <= opt.relative_tolerance || stalled)) {
        result.history.push_back(rec);
        return true;
      }
      if (released || activated) {
        recent.clear();
        last_change = it;
      }
      if (it - last_change == opt.max_iterations || it == hard_cap) {
        result.history.push_back(rec);
        why = "no convergence in " + std::to_string(it) + " iterations (" + std::to_string(it - last_change) +
              " since the active set last changed; limits " + std::to_string(opt.max_iterations) + " and " +
              std::to_string(hard_cap) + ")";
        return false;
      }

      // Newton step with the active vertices fixed where they are and the
      // tied ones following their faces; an indefinite Hessian (or a
      // non-descent step) gets a growing shift.
      SpMat reduced;
      SpMat& system = ties && !ties->empty() ? (reduced = ties->reduce(K)) : K;
      constrain_matrix(system, held, diag);
      const int pattern = &system == &K ? -1 : ties->version();
      if (pattern != analyzed) {
        solver.analyze(system);
        analyzed = pattern;
      }
      const RegularizedStep regularized = solve_regularized_step(
          solver, system, diag,
          [&](double, VecX& b) {
            for (int d = 0; d < n; ++d) b[d] = held[d] ? 0.0 : -r[d];
          },
          [&](VecX& s) {
            for (int d = 0; d < n; ++d)
              if (held[d]) s[d] = 0;
            if (ties) ties->expand(s);
            return g.dot(s) < 0 || free_sq == 0;
          },
          rhs, step, "quasistatic: ");
      rec.shift = regularized.shift;
      if (!regularized.ok) {
        result.history.push_back(rec);
        why = "the Newton system could not be solved even with regularization";
        return false;
      }

      // Projected line search: halve while a free vertex would go deeper
      // than max_depth into an obstacle, an element would invert, or the
      // potential does not decrease enough.
      const double slope = g.dot(step);
      double alpha = 1;
      bool accepted = false;
      for (int ls = 0; ls < opt.max_line_search; ++ls, alpha *= 0.5) {
        trial = q + alpha * step;
        bool too_deep = false;
        for (int i = 0; i < nodes && !too_deep; ++i) {
          if (active.obstacle[i] != kFree) continue;
          for (const Obstacle& o : obstacles)
            if (penetrates(o, q.segment<3>(3 * i), trial.segment<3>(3 * i), max_depth)) {
              too_deep = true;
              break;
            }
        }
        if (too_deep || (ties && ties->penetrates(q, trial, max_depth, tie_depth_limit))) continue;
        const double Et = assembler.energy(trial);
        if (!std::isfinite(Et)) continue;
        const double pt = Et - fs.dot(trial - X);
        if (pt <= potential + opt.armijo * alpha * slope) {
          accepted = true;
          break;
        }
        // Close to equilibrium the decrease drowns in the rounding of the
        // energy sum; there a step that lowers the free residual is taken.
        if (std::abs(pt - potential) <= noise_floor) {
          assembler.evaluate(trial, &g_trial, nullptr);
          g_trial -= fs;
          const VecX r_trial = reduced_gradient(g_trial);
          double trial_sq = 0;
          for (int d = 0; d < n; ++d)
            if (!held[d]) trial_sq += r_trial[d] * r_trial[d];
          if (trial_sq < free_sq) {
            accepted = true;
            break;
          }
        }
      }
      if (!accepted) {
        result.history.push_back(rec);
        why = "the projected line search found no admissible decrease";
        return false;
      }

      // Free vertices that went into an obstacle: back onto its face, held.
      // (A tied node follows its face and is left to it.)
      activated = 0;
      for (int i = 0; i < nodes; ++i) {
        if (active.obstacle[i] != kFree || tied(3 * i)) continue;
        for (int round = 0; round < 4; ++round) {  // a corner may need one projection per face
          const Nearest c = nearest_obstacle(obstacles, trial.segment<3>(3 * i));
          if (c.obstacle == kFree || c.distance >= 0) break;
          trial.segment<3>(3 * i) -= c.distance * c.plane.normal;
          if (active.obstacle[i] == kFree) ++activated;
          active.obstacle[i] = c.obstacle;
          active.plane[i] = c.plane;
        }
      }
      // Free nodes that went behind a face of the mesh: onto it, tied.
      if (ties)
        activated += ties->activate(q, trial, 0.0, tie_depth_limit, [&](int node) { return active.obstacle[node] != kFree; });
      if (activated && !std::isfinite(assembler.energy(trial))) {
        result.history.push_back(rec);
        why = "projecting penetrating vertices onto the obstacles (or faces) inverted an element";
        return false;
      }
      rec.step_length = alpha;
      rec.activated = activated;
      result.history.push_back(rec);
      spdlog::debug("quasistatic load {:.4f} iter {:2d} residual {:.3e} alpha {:.3g} active {} (-{} +{})", s, it,
                    rec.residual, alpha, rec.active, released, activated);
      q = trial;
      ++result.iterations;
    }
    return false;
  };

  // Load continuation with adaptive halving of failing increments.
  const int steps = opt.load_steps;
  double s_done = 0, ds = 1.0 / steps;
  int halvings = 0, load_step = 0;
  while (s_done < 1.0 - 1e-12) {
    const double s = std::min(1.0, s_done + ds);
    const VecX q_saved = q;
    const ActiveSet active_saved = active;
    const std::vector<SelfContactTie> ties_saved = ties ? ties->ties() : std::vector<SelfContactTie>();
    std::string why;
    ++load_step;
    if (newton_at(s, load_step, why)) {
      s_done = s;
      if (halvings > 0) ds = std::min(2 * ds, 1.0 / steps);
      halvings = 0;
      continue;
    }
    q = q_saved;
    active = active_saved;
    if (ties) ties->assign(ties_saved);
    if (halvings >= opt.max_step_halvings) {
      std::ostringstream msg;
      msg << "quasistatic loading failed at load factor " << s << " after " << halvings
          << " load-step halvings: " << why << "\n"
          << format_quasistatic_history(result.history);
      throw NumericalError(msg.str());
    }
    spdlog::debug("quasistatic load factor {:.4f} failed ({}); halving the increment", s, why);
    ds *= 0.5;
    ++halvings;
  }

  // Reactions from the converged state (g was evaluated there last).
  result.load_steps = load_step;
  result.elastic_energy = assembler.energy(q);
  for (int i = 0; i < nodes; ++i) {
    if (active.obstacle[i] == kFree) continue;
    ContactVertex c;
    c.node = i;
    c.obstacle = active.obstacle[i];
    c.plane = active.plane[i];
    c.reaction = g.segment<3>(3 * i);
    result.contacts.push_back(c);
  }
  if (ties) {
    ties->record_reactions(g);
    result.self_contacts = ties->ties();
  }
  return result;
}

}  // namespace msfab
