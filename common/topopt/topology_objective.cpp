#include "topopt/topology_objective.hpp"

#include "core/errors.hpp"

namespace msfab {

namespace {
void upper_triangle(const MatX& C, int m, double* out) {
  for (int s = 0; s < m; ++s)
    for (int t = s; t < m; ++t) out[CellGrid::pair_index(s, t, m)] = C(s, t);
}
}  // namespace

TopologyObjective::TopologyObjective(TopologySetup setup, const CellMaterialModel& model)
    : setup_(std::move(setup)), model_(model) {
  const CellGrid& g = setup_.grid;
  const int m = setup_.elements_per_cell;
  if (m < 1) throw std::invalid_argument("TopologyObjective: elements_per_cell must be >= 1");
  if (m > 1) {
    const CellGrid& f = setup_.fem_grid;
    if (f.dimension() != g.dimension() || f.nx() != m * g.nx() || f.ny() != m * g.ny() ||
        f.nz() != (g.dimension() == 3 ? m * g.nz() : 1))
      throw std::invalid_argument("TopologyObjective: fem_grid must have elements_per_cell times the grid's cells");
    fem_parent_.resize(std::size_t(f.cells()));
    for (std::int64_t c = 0; c < f.cells(); ++c) {
      const auto [i, j, k] = f.cell_coords(c);
      fem_parent_[std::size_t(c)] = g.cell_index(i / m, j / m, k / m);
    }
  }
  const std::int64_t n = fem_grid().unknowns();
  if (model.dimension() != g.dimension())
    throw InputError("material space " + model.space() + " is " + std::to_string(model.dimension()) +
                     "D but the grid is " + std::to_string(g.dimension()) + "D");
  if (std::int64_t(setup_.roles.size()) != g.cells() || std::int64_t(setup_.fixed.size()) != n)
    throw std::invalid_argument("TopologyObjective: roles per cell and fixed flags per unknown");
  if (setup_.loads.empty()) throw InputError("no load case: the objective needs at least one");
  for (const LoadCase& l : setup_.loads) {
    if (l.force.size() != n) throw std::invalid_argument("TopologyObjective: force per unknown");
    if (l.objective == ElasticObjective::compliance && l.prescribed.size() == n) {
      for (std::int64_t d = 0; d < n; ++d)
        if (setup_.fixed[d] && l.prescribed[d] != 0)
          throw InputError("load case '" + l.name +
                           "': minimum compliance needs force loads; with a prescribed displacement u^T K u grows "
                           "with stiffness (use a target-deformation objective)");
    }
    if (l.objective == ElasticObjective::target && (l.target.size() != n || l.target_weight.size() != n))
      throw std::invalid_argument("TopologyObjective: target and weights per unknown");
  }
  for (std::int64_t c = 0; c < g.cells(); ++c)
    if (setup_.roles[c] == CellRole::design) design_cells_.push_back(c);
  if (design_cells_.empty()) throw InputError("the design domain has no design cell");
  filter_ = CellFilter(g, design_cells_, setup_.filter_radius);
  hold_void_nodes();
  fem_ = std::make_unique<GridElasticity>(fem_grid(), setup_.fixed, setup_.solver, setup_.solver_options);
}

MatX TopologyObjective::physical(const MatX& q) const {
  MatX p = filter_.apply(q);
  if (model_.derives_density()) {
    const int rho = model_.density_index();
#pragma omp parallel for schedule(static)
    for (Eigen::Index r = 0; r < p.rows(); ++r) p(r, rho) = model_.density(p.row(r).transpose(), nullptr);
  }
  return p;
}

MatX TopologyObjective::to_variables(const MatX& p, MatX grad_p) const {
  if (model_.derives_density()) {
    const int rho = model_.density_index();
#pragma omp parallel for schedule(static)
    for (Eigen::Index r = 0; r < p.rows(); ++r) {
      VecX dr;
      model_.density(p.row(r).transpose(), &dr);
      const double through = grad_p(r, rho);
      grad_p(r, rho) = 0;
      grad_p.row(r) += through * dr.transpose();
    }
  }
  return filter_.apply_transpose(grad_p);
}

MatX TopologyObjective::mass_gradient(const MatX& q) const {
  MatX grad_p = MatX::Zero(q.rows(), q.cols());
  grad_p.col(model_.density_index()).setConstant(setup_.grid.cell_volume());
  return to_variables(physical(q), std::move(grad_p));
}

double TopologyObjective::mass(const MatX& q) const {
  const MatX p = physical(q);
  const int rho = model_.density_index();
  double total = p.col(rho).sum();
  for (CellRole r : setup_.roles) total += r == CellRole::solid ? 1.0 : 0.0;
  return total * setup_.grid.cell_volume();
}

ObjectiveValue TopologyObjective::evaluate(const MatX& q, MatX* gradient) {
  const int d = model_.parameters();
  const Eigen::Index rows = Eigen::Index(design_cells_.size());
  if (q.rows() != rows || q.cols() != d) throw std::invalid_argument("TopologyObjective::evaluate: q shape");
  // A gradient asked for at the point of the last evaluation (Ipopt's
  // eval_f then eval_grad_f) reuses its solves.
  if (!(has_state_ && q == last_q_)) compute_state(q);
  if (gradient) *gradient = gradient_from_state();
  return value_;
}

MatX TopologyObjective::cell_pairs(const MatX& p) const {
  const CellGrid& g = setup_.grid;
  const int m = g.voigt(), npairs = g.voigt_pairs();
  const Eigen::Index rows = Eigen::Index(design_cells_.size());
  MatX pairs(g.cells(), npairs);
  Eigen::Matrix<double, 1, Eigen::Dynamic> solid(npairs), empty(npairs);
  upper_triangle(setup_.solid_C, m, solid.data());
  upper_triangle(setup_.empty_C, m, empty.data());
  for (std::int64_t c = 0; c < g.cells(); ++c)
    if (setup_.roles[c] != CellRole::design) pairs.row(c) = setup_.roles[c] == CellRole::solid ? solid : empty;
  bool finite = true;
#pragma omp parallel for schedule(static) reduction(&& : finite)
  for (Eigen::Index r = 0; r < rows; ++r) {
    MatX C;
    model_.tensor(p.row(r).transpose(), C);
    finite = finite && C.allFinite();
    Eigen::Matrix<double, 1, Eigen::Dynamic> row(npairs);
    upper_triangle(C, m, row.data());
    pairs.row(design_cells_[r]) = row;
  }
  if (!finite) throw NumericalError("a cell's stiffness is not finite (parameters at a singular point of the space)");
  return pairs;
}

void TopologyObjective::compute_state(const MatX& q) {
  const CellGrid& g = setup_.grid;
  const int npairs = g.voigt_pairs();
  const Eigen::Index rows = Eigen::Index(design_cells_.size());
  has_state_ = false;
  last_q_ = q;
  p_ = physical(q);
  const MatX pairs = cell_pairs(p_);
  if (fem_parent_.empty()) {
    fem_->set_stiffness(pairs);
  } else {
    MatX fine(fem_grid().cells(), npairs);
    for (std::size_t f = 0; f < fem_parent_.size(); ++f) fine.row(Eigen::Index(f)) = pairs.row(fem_parent_[f]);
    fem_->set_stiffness(fine);
  }
  const MatX& p = p_;

  // Elasticity terms.
  ObjectiveValue value;
  u_.clear();
  for (const LoadCase& l : setup_.loads) {
    const VecX u = fem_->solve(l.force, l.prescribed);
    double J = 0;
    if (l.objective == ElasticObjective::compliance) {
      J = u.dot(l.force);  // = u^T K u at equilibrium with zero prescribed values
    } else {
      J = (l.target_weight.array() * (u - l.target).array().square()).sum();
    }
    value.per_load.push_back(J);
    value.elastic += l.weight * J;
    u_.push_back(u);
  }

  // Mass terms (Eq. 3.7 and the local targets).
  const int rho = model_.density_index();
  const double V = g.cell_volume();
  const MassTerms& mt = setup_.mass;
  if (mt.total_weight > 0) {
    const double excess = mass(q) - mt.total_target;
    value.mass += mt.total_weight * excess * excess;
  }
  if (mt.local_weight > 0) {
    for (Eigen::Index r = 0; r < rows; ++r) {
      const double diff = p(r, rho) - mt.local_target[design_cells_[r]];
      value.mass += mt.local_weight * diff * diff * V;
    }
  }
  value.total = value.elastic + value.mass;
  value_ = value;
  has_state_ = true;
}

MatX TopologyObjective::gradient_from_state() {
  const CellGrid& g = setup_.grid;
  const int m = g.voigt(), npairs = g.voigt_pairs(), d = model_.parameters();
  const Eigen::Index rows = Eigen::Index(design_cells_.size());
  const MatX& p = p_;
  // dS/dC per FEM cell and pair by the adjoint method.
  MatX dS_dC = MatX::Zero(fem_grid().cells(), npairs);
  for (std::size_t i = 0; i < setup_.loads.size(); ++i) {
    const LoadCase& l = setup_.loads[i];
    const VecX& u = u_[i];
    if (l.objective == ElasticObjective::compliance) {
      // Adjoint lambda = 2u: dJ/dC = u^T B u - 2 u^T B u.
      dS_dC -= l.weight * fem_->pair_products(u, u);
    } else {
      const VecX lambda = fem_->solve_adjoint(2 * l.target_weight.cwiseProduct(u - l.target));
      dS_dC -= l.weight * fem_->pair_products(lambda, u);
    }
  }
  if (!fem_parent_.empty()) {  // a design cell's stiffness acts in all its FEM cells
    MatX per_cell = MatX::Zero(g.cells(), npairs);
    for (std::size_t f = 0; f < fem_parent_.size(); ++f) per_cell.row(fem_parent_[f]) += dS_dC.row(Eigen::Index(f));
    dS_dC = std::move(per_cell);
  }
  const int rho = model_.density_index();
  const double V = g.cell_volume();
  const MassTerms& mt = setup_.mass;
  MatX grad_p = MatX::Zero(rows, d);
  if (mt.total_weight > 0) grad_p.col(rho).array() += 2 * mt.total_weight * (mass(last_q_) - mt.total_target) * V;
  if (mt.local_weight > 0)
    for (Eigen::Index r = 0; r < rows; ++r)
      grad_p(r, rho) += 2 * mt.local_weight * (p(r, rho) - mt.local_target[design_cells_[r]]) * V;
  {
#pragma omp parallel for schedule(static)
    for (Eigen::Index r = 0; r < rows; ++r) {
      MatX C;
      std::vector<MatX> dC;
      model_.tensor(p.row(r).transpose(), C, &dC);
      const std::int64_t c = design_cells_[r];
      for (int k = 0; k < d; ++k) {
        double s = 0;
        for (int a = 0; a < m; ++a)
          for (int b = a; b < m; ++b) s += dC[k](a, b) * dS_dC(c, CellGrid::pair_index(a, b, m));
        grad_p(r, k) += s;
      }
    }
  }
  return to_variables(p, std::move(grad_p));
}

void TopologyObjective::hold_void_nodes() {
  const CellGrid& f = fem_grid();
  const int dim = f.dimension();
  std::vector<char> touched(std::size_t(f.nodes()), 0);
  for (std::int64_t c = 0; c < f.cells(); ++c) {
    const std::int64_t parent = fem_parent_.empty() ? c : fem_parent_[std::size_t(c)];
    if (setup_.roles[std::size_t(parent)] == CellRole::empty) continue;
    const auto nodes = f.cell_nodes(c);
    for (int k = 0; k < f.corners(); ++k) touched[std::size_t(nodes[std::size_t(k)])] = 1;
  }
  for (std::int64_t node = 0; node < f.nodes(); ++node)
    if (!touched[std::size_t(node)])
      for (int c = 0; c < dim; ++c) setup_.fixed[std::size_t(node * dim + c)] = 1;
}

VecX TopologyObjective::grid_displacement(std::size_t l) const {
  const VecX& u = u_.at(l);
  const int m = setup_.elements_per_cell;
  if (m == 1) return u;
  const CellGrid& g = setup_.grid;
  const CellGrid& f = fem_grid();
  const int dim = g.dimension();
  VecX out(g.unknowns());
  for (std::int64_t node = 0; node < g.nodes(); ++node) {
    const auto [i, j, k] = g.node_coords(node);
    const std::int64_t fine = f.node_index(m * i, m * j, dim == 3 ? m * k : 0);
    for (int c = 0; c < dim; ++c) out[node * dim + c] = u[fine * dim + c];
  }
  return out;
}

}  // namespace msfab
