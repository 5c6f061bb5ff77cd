#include "dynamics/quasistatic_loading.hpp"

#include <spdlog/spdlog.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <memory>
#include <sstream>

#include "core/errors.hpp"
#include "solve/cholmod_solver.hpp"
#include "solve/load_continuation.hpp"
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
    if (o.kind == Obstacle::Kind::kBox &&
        !(o.lo.allFinite() && o.hi.allFinite() && (o.lo.array() < o.hi.array()).all()))
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

// One quasistatic press: the state (positions, contacts, ties) and the
// steps of its Newton iteration at a load factor.
class Press {
 public:
  Press(const ElasticAssembler& assembler, const std::vector<Obstacle>& obstacles, const VecX& force, const VecX& x0,
        const QuasistaticOptions& opt)
      : assembler_(assembler),
        obstacles_(obstacles),
        force_(force),
        opt_(opt),
        mesh_(assembler.mesh()),
        n_(mesh_.num_dofs()),
        nodes_(mesh_.num_nodes()),
        X_(assembler.rest_positions()),
        dx_(characteristic_element_size(mesh_)),
        max_depth_(opt.penetration_tolerance * dx_),
        touch_(std::max(opt.touch_tolerance, 1e-12) * dx_),
        length_scale_((mesh_.bbox_max() - mesh_.bbox_min()).norm()),
        // A node starting deeper than this behind a face is on its far
        // side, not touching it (surface_contact.hpp).
        tie_depth_limit_(0.25 * dx_),
        active_{std::vector<int>(nodes_, kFree), std::vector<ContactPlane>(nodes_)},
        g_(n_),
        g_trial_(n_),
        rhs_(n_),
        step_(n_),
        trial_(n_),
        r_(n_),
        fixed_(n_, 0),
        held_(n_, 0) {
    result_.characteristic_size = dx_;
    result_.x = x0.size() == n_ ? x0 : X_;
  }

  // The contacts at the start, the solver's pattern and the ties.
  void start();
  // Newton at load factor s from the current state; true on convergence,
  // else `why` says what failed.
  bool newton_at(double s, int load_step, std::string& why);

  struct Saved {
    VecX q;
    ActiveSet active;
    std::vector<SelfContactTie> ties;
  };
  Saved save() const { return {result_.x, active_, ties_ ? ties_->ties() : std::vector<SelfContactTie>()}; }
  void restore(const Saved& saved) {
    result_.x = saved.q;
    active_ = saved.active;
    if (ties_) ties_->assign(saved.ties);
  }

  const QuasistaticResult& result() const { return result_; }
  // The result with the reactions of the converged state.
  QuasistaticResult finish(int load_steps);

 private:
  // The scales of one iterate: the mean free diagonal stiffness, the
  // residual's reference and the energy's rounding level.
  struct Scales {
    double diag = 1, scale = 0, noise_floor = 0;
  };

  VecX& q() { return result_.x; }
  bool tied(int d) const { return ties_ && ties_->is_slave(d / 3); }
  VecX reduced_gradient(const VecX& grad) const { return ties_ ? ties_->reduce(grad) : grad; }
  void update_fixed() {
    for (int i = 0; i < nodes_; ++i)
      fixed_[3 * i] = fixed_[3 * i + 1] = fixed_[3 * i + 2] = active_.obstacle[i] != kFree;
  }
  Scales scales(const VecX& fs) const;
  int release_pulling_contacts(double scale);
  double free_residual_squared();
  RegularizedStep newton_step(double diag, double free_sq);
  bool line_search(const VecX& fs, double potential, double free_sq, double noise_floor, double& alpha);
  int project_penetrations();

  const ElasticAssembler& assembler_;
  const std::vector<Obstacle>& obstacles_;
  const VecX& force_;
  const QuasistaticOptions& opt_;
  const HexMesh& mesh_;
  const int n_, nodes_;
  const VecX X_;
  const double dx_, max_depth_, touch_, length_scale_, tie_depth_limit_;

  QuasistaticResult result_;
  ActiveSet active_;
  SpMat K_;
  std::unique_ptr<CholmodSolver> solver_;
  std::unique_ptr<SelfContactTies> ties_;
  int analyzed_ = -1;  // the ties' version whose reduced pattern the solver holds (-1: K's own)
  VecX g_, g_trial_, rhs_, step_, trial_, r_;
  std::vector<char> fixed_, held_;
};

void Press::start() {
  // Initial active set: every vertex touching an obstacle, the slightly
  // penetrating ones projected onto the face they are in.
  for (int i = 0; i < nodes_; ++i) {
    const Nearest c = nearest_obstacle(obstacles_, q().segment<3>(3 * i));
    if (c.obstacle == kFree || c.distance > touch_) continue;
    if (c.distance < -max_depth_) {
      std::ostringstream msg;
      msg << "quasistatic loading: initial positions: node " << i << " lies " << -c.distance << " m inside obstacle '"
          << obstacles_[c.obstacle].name << "' (tolerance " << max_depth_
          << " m = penetration_tolerance * element size)";
      throw InputError(msg.str());
    }
    if (c.distance < 0) q().segment<3>(3 * i) -= c.distance * c.plane.normal;
    active_.obstacle[i] = c.obstacle;
    active_.plane[i] = c.plane;
  }
  if (!std::isfinite(assembler_.energy(q())))
    throw InputError("quasistatic loading: initial positions invert an element (det F <= 0)");

  K_ = assembler_.pattern();
  LinearSolverOptions linear;
  linear.threads = opt_.threads;
  solver_ = std::make_unique<CholmodSolver>(linear);
  solver_->analyze(K_);

  if (opt_.self_contact) ties_ = std::make_unique<SelfContactTies>(mesh_, opt_.edge_contact);
  // Nodes touching a face at the start are tied from the start, as
  // vertices touching an obstacle start active.
  if (ties_) {
    ties_->activate(q(), q(), touch_, tie_depth_limit_, [&](int node) { return active_.obstacle[node] != kFree; });
    if (!std::isfinite(assembler_.energy(q())))
      throw InputError("quasistatic loading: initial positions: putting touching nodes onto faces inverts an element");
  }
}

Press::Scales Press::scales(const VecX& fs) const {
  Scales out;
  double diag = 0, reaction_sq = 0;
  int free_dofs = 0;
  for (int d = 0; d < n_; ++d) {
    if (fixed_[d] || tied(d)) {
      reaction_sq += g_[d] * g_[d];
    } else {
      diag += std::abs(K_.coeff(d, d));
      ++free_dofs;
    }
  }
  out.diag = free_dofs ? diag / free_dofs : 1.0;
  // Rounding level of the energy: a diagonal stiffness entry times dx^2
  // is about the energy of one element at unit strain.
  out.noise_floor = 1e-13 * out.diag * dx_ * dx_ * nodes_;
  out.scale = std::max({fs.norm(), std::sqrt(reaction_sq), 1e-12 * out.diag * length_scale_});
  return out;
}

// Releases vertices the obstacle would have to pull on. On an edge or
// corner the obstacle can push along any face normal there, so a vertex
// goes only if its reaction pulls away from all of them; the face pushing
// hardest is the one kept. Ties release the same way.
int Press::release_pulling_contacts(double scale) {
  int released = 0;
  for (int i = 0; i < nodes_; ++i) {
    if (active_.obstacle[i] == kFree) continue;
    const Vec3 reaction = g_.segment<3>(3 * i);
    double push = active_.plane[i].normal.dot(reaction);
    for (const auto& [o, face] : touching_faces(obstacles_, q().segment<3>(3 * i), touch_)) {
      const double p = face.normal.dot(reaction);
      if (p > push) push = p, active_.obstacle[i] = o, active_.plane[i] = face;
    }
    if (push < -opt_.relative_tolerance * scale) {
      active_.obstacle[i] = kFree;
      ++released;
    }
  }
  if (ties_) released += ties_->release(q(), g_, opt_.relative_tolerance * scale);
  if (released) update_fixed();
  return released;
}

// The gradient on the unknowns that move freely (held: in contact or tied),
// reduced onto the ties' masters; returns its squared norm.
double Press::free_residual_squared() {
  r_ = reduced_gradient(g_);
  double free_sq = 0;
  for (int d = 0; d < n_; ++d) {
    held_[d] = fixed_[d] || tied(d);
    if (!held_[d]) free_sq += r_[d] * r_[d];
  }
  return free_sq;
}

// The Newton step with the active vertices fixed where they are and the
// tied ones following their faces; an indefinite Hessian (or a non-descent
// step) gets a growing shift.
RegularizedStep Press::newton_step(double diag, double free_sq) {
  SpMat reduced;
  SpMat& system = ties_ && !ties_->empty() ? (reduced = ties_->reduce(K_)) : K_;
  constrain_matrix(system, held_, diag);
  const int pattern = &system == &K_ ? -1 : ties_->version();
  if (pattern != analyzed_) {
    solver_->analyze(system);
    analyzed_ = pattern;
  }
  return solve_regularized_step(
      *solver_, system, diag,
      [&](double, VecX& b) {
        for (int d = 0; d < n_; ++d) b[d] = held_[d] ? 0.0 : -r_[d];
      },
      [&](VecX& s) {
        for (int d = 0; d < n_; ++d)
          if (held_[d]) s[d] = 0;
        if (ties_) ties_->expand(s);
        return g_.dot(s) < 0 || free_sq == 0;
      },
      rhs_, step_, "quasistatic: ");
}

// Projected line search into trial_: halves while a free vertex would go
// deeper than max_depth into an obstacle, an element would invert, or the
// potential does not decrease enough.
bool Press::line_search(const VecX& fs, double potential, double free_sq, double noise_floor, double& alpha) {
  const double slope = g_.dot(step_);
  alpha = 1;
  for (int ls = 0; ls < opt_.max_line_search; ++ls, alpha *= 0.5) {
    trial_ = q() + alpha * step_;
    bool too_deep = false;
    for (int i = 0; i < nodes_ && !too_deep; ++i) {
      if (active_.obstacle[i] != kFree) continue;
      for (const Obstacle& o : obstacles_)
        if (penetrates(o, q().segment<3>(3 * i), trial_.segment<3>(3 * i), max_depth_)) {
          too_deep = true;
          break;
        }
    }
    if (too_deep || (ties_ && ties_->penetrates(q(), trial_, max_depth_, tie_depth_limit_))) continue;
    const double Et = assembler_.energy(trial_);
    if (!std::isfinite(Et)) continue;
    const double pt = Et - fs.dot(trial_ - X_);
    if (pt <= potential + opt_.armijo * alpha * slope) return true;
    // Close to equilibrium the decrease drowns in the rounding of the
    // energy sum; there a step that lowers the free residual is taken.
    if (std::abs(pt - potential) <= noise_floor) {
      assembler_.evaluate(trial_, &g_trial_, nullptr);
      g_trial_ -= fs;
      const VecX r_trial = reduced_gradient(g_trial_);
      double trial_sq = 0;
      for (int d = 0; d < n_; ++d)
        if (!held_[d]) trial_sq += r_trial[d] * r_trial[d];
      if (trial_sq < free_sq) return true;
    }
  }
  return false;
}

// Free vertices of trial_ that went into an obstacle: back onto its face,
// held; free nodes that went behind a face of the mesh: onto it, tied (a
// tied node follows its face and is left to it). Returns how many.
int Press::project_penetrations() {
  int activated = 0;
  for (int i = 0; i < nodes_; ++i) {
    if (active_.obstacle[i] != kFree || tied(3 * i)) continue;
    for (int round = 0; round < 4; ++round) {  // a corner may need one projection per face
      const Nearest c = nearest_obstacle(obstacles_, trial_.segment<3>(3 * i));
      if (c.obstacle == kFree || c.distance >= 0) break;
      trial_.segment<3>(3 * i) -= c.distance * c.plane.normal;
      if (active_.obstacle[i] == kFree) ++activated;
      active_.obstacle[i] = c.obstacle;
      active_.plane[i] = c.plane;
    }
  }
  if (ties_)
    activated +=
        ties_->activate(q(), trial_, 0.0, tie_depth_limit_, [&](int node) { return active_.obstacle[node] != kFree; });
  return activated;
}

bool Press::newton_at(double s, int load_step, std::string& why) {
  const VecX fs = s * force_;
  int activated = 0;           // free vertices made active after the previous step
  std::vector<double> recent;  // residuals since the active set last changed
  // The iteration limit counts Newton iterations at a settled active set:
  // a contact front that peels or spreads moves by a row of vertices per
  // iteration, so on a fine mesh the active set alone can take more than
  // max_iterations updates (the 0.5 mm flipper lifting its base: 60). A
  // hard cap of kActiveSetRounds times the limit stops a cycling set.
  int last_change = 0;
  const int hard_cap = kActiveSetRounds * opt_.max_iterations;
  for (int it = 0;; ++it) {
    const double E = assembler_.evaluate(q(), &g_, &K_);
    if (!std::isfinite(E)) {
      why = "the configuration is inverted (an element has det F <= 0)";
      return false;
    }
    g_ -= fs;  // gradient of the total potential; at an active vertex the reaction
    const double potential = E - fs.dot(q() - X_);
    update_fixed();
    const Scales sc = scales(fs);
    const int released = release_pulling_contacts(sc.scale);
    const double free_sq = free_residual_squared();

    QuasistaticIteration rec;
    rec.load_step = load_step;
    rec.load_factor = s;
    rec.iteration = it;
    rec.residual = std::sqrt(free_sq) / sc.scale;
    rec.energy = potential;
    rec.active = active_.count() + (ties_ ? static_cast<int>(ties_->ties().size()) : 0);
    rec.released = released;
    // Converged at the tolerance, or at the round-off floor: with the
    // active set settled, a residual within 1000x the tolerance that has
    // not fallen by 10% over the last 5 iterations (a small load
    // increment on a fine mesh stalls near 1e-7 of its own force).
    recent.push_back(rec.residual);
    const size_t c = recent.size();
    const bool stalled = c > 5 && rec.residual <= 1e3 * opt_.relative_tolerance && rec.residual > 0.9 * recent[c - 6];
    if (released == 0 && activated == 0 && (rec.residual <= opt_.relative_tolerance || stalled)) {
      result_.history.push_back(rec);
      return true;
    }
    if (released || activated) {
      recent.clear();
      last_change = it;
    }
    if (it - last_change == opt_.max_iterations || it == hard_cap) {
      result_.history.push_back(rec);
      why = "no convergence in " + std::to_string(it) + " iterations (" + std::to_string(it - last_change) +
            " since the active set last changed; limits " + std::to_string(opt_.max_iterations) + " and " +
            std::to_string(hard_cap) + ")";
      return false;
    }

    const RegularizedStep regularized = newton_step(sc.diag, free_sq);
    rec.shift = regularized.shift;
    if (!regularized.ok) {
      result_.history.push_back(rec);
      why = "the Newton system could not be solved even with regularization";
      return false;
    }
    double alpha = 1;
    if (!line_search(fs, potential, free_sq, sc.noise_floor, alpha)) {
      result_.history.push_back(rec);
      why = "the projected line search found no admissible decrease";
      return false;
    }
    activated = project_penetrations();
    if (activated && !std::isfinite(assembler_.energy(trial_))) {
      result_.history.push_back(rec);
      why = "projecting penetrating vertices onto the obstacles (or faces) inverted an element";
      return false;
    }
    rec.step_length = alpha;
    rec.activated = activated;
    result_.history.push_back(rec);
    spdlog::debug("quasistatic load {:.4f} iter {:2d} residual {:.3e} alpha {:.3g} active {} (-{} +{})", s, it,
                  rec.residual, alpha, rec.active, released, activated);
    q() = trial_;
    ++result_.iterations;
  }
  return false;
}

QuasistaticResult Press::finish(int load_steps) {
  // Reactions from the converged state (g was evaluated there last).
  result_.load_steps = load_steps;
  result_.elastic_energy = assembler_.energy(q());
  for (int i = 0; i < nodes_; ++i) {
    if (active_.obstacle[i] == kFree) continue;
    ContactVertex c;
    c.node = i;
    c.obstacle = active_.obstacle[i];
    c.plane = active_.plane[i];
    c.reaction = g_.segment<3>(3 * i);
    result_.contacts.push_back(c);
  }
  if (ties_) {
    ties_->record_reactions(g_);
    result_.self_contacts = ties_->ties();
  }
  return result_;
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
  return format_iteration_table(
      history, max_lines, "  step  load    iter  residual    energy         alpha      shift     active  -rel  +act\n",
      [](const QuasistaticIteration& h) {
        char contact[64];
        std::snprintf(contact, sizeof contact, "  %6d  %4d  %4d\n", h.active, h.released, h.activated);
        return newton_iteration_columns(h) + contact;
      });
}

QuasistaticResult solve_quasistatic_loading(const ElasticAssembler& assembler, const std::vector<Obstacle>& obstacles,
                                            const VecX& force, const VecX& x0, const QuasistaticOptions& opt) {
  validate(assembler, obstacles, force, x0, opt);
  Press press(assembler, obstacles, force, x0, opt);
  press.start();

  // Load continuation with adaptive halving of failing increments.
  Press::Saved saved;
  LoadContinuation continuation;
  continuation.steps = opt.load_steps;
  continuation.max_halvings = opt.max_step_halvings;
  continuation.solve_at = [&](double s, int load_step, std::string& why) { return press.newton_at(s, load_step, why); };
  continuation.save = [&] { saved = press.save(); };
  continuation.restore = [&] { press.restore(saved); };
  continuation.on_halving = [](double s, const std::string& why) {
    spdlog::debug("quasistatic load factor {:.4f} failed ({}); halving the increment", s, why);
  };
  const LoadContinuationResult loaded = continue_load(continuation);
  if (!loaded.converged) {
    QuasistaticResult failed = press.result();  // restored to the last converged load factor
    failed.load_steps = loaded.load_steps;
    std::ostringstream why;
    why << "quasistatic loading failed at load factor " << loaded.failed_at << " after " << loaded.halvings
        << " load-step halvings: " << loaded.why;
    failed.failure = why.str();
    return failed;
  }
  QuasistaticResult done = press.finish(loaded.load_steps);
  done.converged = true;
  return done;
}

}  // namespace msfab
