#include "topopt/grid_elasticity.hpp"

#include <algorithm>
#include <chrono>

#include "core/errors.hpp"
#include "core/timing.hpp"
#include "solve/dirichlet_grid_multigrid.hpp"
#include "solve/sparse_ops.hpp"

namespace msfab {

namespace {}  // namespace

VoxelStiffnessField stiffness_field(const CellGrid& grid, const MatX& pairs) {
  if (grid.dimension() != 3) throw std::invalid_argument("stiffness_field: a 3D grid");
  if (pairs.rows() != grid.cells() || pairs.cols() != grid.voigt_pairs())
    throw std::invalid_argument("stiffness_field: cells x voigt_pairs");
  struct Group {
    Eigen::Index reference;                       // the column the group's weights are
    Eigen::Index peak_row;                        // where |reference| is largest
    std::vector<std::pair<int, double>> members;  // (pair, factor on the reference)
  };
  std::vector<Group> groups;
  for (int q = 0; q < pairs.cols(); ++q) {
    Eigen::Index peak_row = 0;
    const double peak = pairs.col(q).cwiseAbs().maxCoeff(&peak_row);
    if (peak == 0.0) continue;
    bool placed = false;
    for (Group& g : groups) {
      const double ratio = pairs(g.peak_row, q) / pairs(g.peak_row, g.reference);
      if ((pairs.col(q) - ratio * pairs.col(g.reference)).cwiseAbs().maxCoeff() <= 1e-13 * peak) {
        g.members.emplace_back(q, ratio);
        placed = true;
        break;
      }
    }
    if (!placed) groups.push_back({q, peak_row, {{q, 1.0}}});
  }
  VoxelStiffnessField field;
  field.nx = grid.nx(), field.ny = grid.ny(), field.nz = grid.nz();
  field.h = grid.h();
  const std::vector<MatX>& basis = grid.element_basis();
  for (const Group& g : groups) {
    Mat24 K = Mat24::Zero();
    for (const auto& [q, factor] : g.members) K += factor * basis[q];
    field.basis.push_back(K);
  }
  if (groups.empty()) {  // every cell without stiffness: keep the shapes valid
    field.basis.push_back(Mat24::Zero());
    groups.push_back({0, 0, {}});
  }
  const std::size_t G = groups.size();
  field.weights.resize(std::size_t(grid.cells()) * G);
  for (std::size_t g = 0; g < G; ++g)
    for (Eigen::Index c = 0; c < pairs.rows(); ++c)
      field.weights[std::size_t(c) * G + g] = pairs(c, groups[g].reference);
  return field;
}

GridElasticity::GridElasticity(const CellGrid& grid, std::vector<char> fixed, const std::string& solver,
                               const LinearSolverOptions& options, bool material_coarse_space)
    : grid_(grid), fixed_(std::move(fixed)), options_(options) {
  if (std::int64_t(fixed_.size()) != grid_.unknowns())
    throw std::invalid_argument("GridElasticity: one fixed flag per unknown");
  if (grid_.unknowns() > std::int64_t(1) << 30) throw InputError("grid: more than 2^30 unknowns");
  solver_name_ = solver;
  if (solver == "auto") {
    // Measured (docs/BENCHMARKS.md): at 58k unknowns the matrix-free solve
    // takes 0.2 s where CHOLMOD takes 2.5 s, and the gap grows with size.
    solver_name_ = "cholmod";
    if (grid_.dimension() == 3 && grid_.unknowns() > 30000 &&
        DirichletGridMultigrid::supports(grid_.nx(), grid_.ny(), grid_.nz()))
      solver_name_ = "matrix-free";
    else if (grid_.dimension() == 3 && grid_.unknowns() > 300000)
      solver_name_ = "pcg-mg";
  }
  if (solver_name_ == "matrix-free") {
    if (grid_.dimension() != 3) throw InputError("solver matrix-free needs a 3D grid; use cholmod in 2D");
    if (!DirichletGridMultigrid::supports(grid_.nx(), grid_.ny(), grid_.nz()))
      throw InputError("solver matrix-free needs even grid dimensions, not " + std::to_string(grid_.nx()) + " x " +
                       std::to_string(grid_.ny()) + " x " + std::to_string(grid_.nz()) + "; use pcg-mg");
    validate_linear_solver_options(options_);
    DirichletMultigridOptions mg = dirichlet_multigrid_options(options_);
    mg.material_coarse_space = material_coarse_space;
    // The solver keeps the only copy of the flags (fixed() reads it there).
    matrix_free_ = std::make_unique<DirichletGridMultigrid>(grid_.nx(), grid_.ny(), grid_.nz(), std::move(fixed_), mg);
    std::vector<char>().swap(fixed_);
    return;
  }
  if (solver_name_ == "pcg-mg") {
    if (grid_.dimension() != 3) throw InputError("solver pcg-mg needs a 3D grid; use cholmod in 2D");
    auto nodes = std::make_shared<Eigen::Matrix<double, Eigen::Dynamic, 3, Eigen::RowMajor>>(grid_.nodes(), 3);
    for (std::int64_t n = 0; n < grid_.nodes(); ++n) nodes->row(n) = grid_.node_position(n).transpose();
    options_.node_positions = nodes;
  }
  solver_ = make_linear_solver(solver_name_, options_);
  // Cells of one parity colour share no node.
  colours_.assign(grid_.dimension() == 3 ? 8 : 4, {});
  for (std::int64_t c = 0; c < grid_.cells(); ++c) {
    const auto [i, j, k] = grid_.cell_coords(c);
    colours_[(i & 1) + 2 * (j & 1) + 4 * (k & 1)].push_back(c);
  }
  build_pattern();
}

GridElasticity::~GridElasticity() = default;

const std::vector<char>& GridElasticity::fixed() const { return matrix_free_ ? matrix_free_->fixed() : fixed_; }

void GridElasticity::build_pattern() {
  const int ne = grid_.element_unknowns();
  const std::int64_t n = grid_.unknowns();
  std::vector<Eigen::Triplet<double, int>> triplets;
  triplets.reserve(std::size_t(grid_.cells()) * ne * ne / 2 + fixed_.size());
  std::vector<std::int64_t> dofs(ne);
  for (std::int64_t c = 0; c < grid_.cells(); ++c) {
    grid_.cell_unknowns(c, dofs.data());
    for (int a = 0; a < ne; ++a)
      for (int b = 0; b < ne; ++b)
        if (!fixed_[dofs[a]] && !fixed_[dofs[b]]) triplets.emplace_back(int(dofs[a]), int(dofs[b]), 0.0);
  }
  for (std::int64_t d = 0; d < n; ++d)
    if (fixed_[d]) triplets.emplace_back(int(d), int(d), 0.0);
  K_.resize(n, n);
  K_.setFromTriplets(triplets.begin(), triplets.end());
  K_.makeCompressed();
  auto slot_of = [&](std::int64_t row, std::int64_t col) {
    const int* begin = K_.innerIndexPtr() + K_.outerIndexPtr()[col];
    const int* end = K_.innerIndexPtr() + K_.outerIndexPtr()[col + 1];
    const int* it = std::lower_bound(begin, end, int(row));
    return int(it - K_.innerIndexPtr());
  };
  slot_.assign(std::size_t(grid_.cells()) * ne * ne, -1);
#pragma omp parallel for schedule(static)
  for (std::int64_t c = 0; c < grid_.cells(); ++c) {
    std::int64_t local[24];
    grid_.cell_unknowns(c, local);
    int* out = &slot_[std::size_t(c) * ne * ne];
    for (int a = 0; a < ne; ++a)
      for (int b = 0; b < ne; ++b)
        if (!fixed_[local[a]] && !fixed_[local[b]]) out[a * ne + b] = slot_of(local[b], local[a]);
  }
  fixed_slot_.clear();
  for (std::int64_t d = 0; d < n; ++d)
    if (fixed_[d]) fixed_slot_.push_back(slot_of(d, d));
}

void GridElasticity::set_stiffness(const MatX& pairs) {
  const auto t0 = std::chrono::steady_clock::now();
  if (pairs.rows() != grid_.cells() || pairs.cols() != grid_.voigt_pairs())
    throw std::invalid_argument("GridElasticity::set_stiffness: cells x voigt_pairs");
  if (matrix_free_) {
    VoxelStiffnessField field = stiffness_field(grid_, pairs);
    stats_.factorize_seconds += seconds_since(t0);  // the conversion; set_field adds the set-up
    set_field(std::move(field));
    return;
  }
  pairs_ = pairs;
  const int ne = grid_.element_unknowns(), m = grid_.voigt();
  const std::vector<MatX>& basis = grid_.element_basis();
  double* values = K_.valuePtr();
  std::fill(values, values + K_.nonZeros(), 0.0);
  for (const auto& colour : colours_) {
#pragma omp parallel for schedule(static)
    for (std::size_t idx = 0; idx < colour.size(); ++idx) {
      const std::int64_t c = colour[idx];
      MatX Ke = MatX::Zero(ne, ne);
      for (int s = 0; s < m; ++s)
        for (int t = s; t < m; ++t) {
          const int q = CellGrid::pair_index(s, t, m);
          if (pairs(c, q) != 0) Ke += pairs(c, q) * basis[q];
        }
      const int* slots = &slot_[std::size_t(c) * ne * ne];
      for (int b = 0; b < ne; ++b)
        for (int a = 0; a < ne; ++a)
          if (slots[a * ne + b] >= 0) values[slots[a * ne + b]] += Ke(a, b);
    }
  }
  // Fixed rows: a scaled identity, so an iterative solver sees a matrix of
  // uniform scale.
  double diag = 0;
  long free = 0;
  for (int col = 0; col < K_.outerSize(); ++col) {
    if (fixed_[col]) continue;
    diag += K_.coeff(col, col);
    ++free;
  }
  if (free == 0) throw InputError("every unknown of the grid is fixed: nothing to solve");
  fixed_scale_ = diag / free;
  for (int s : fixed_slot_) values[s] = fixed_scale_;
  stats_.assemble_seconds += seconds_since(t0);
  const auto t1 = std::chrono::steady_clock::now();
  if (!analyzed_) {
    solver_->analyze(K_);
    analyzed_ = true;
  }
  if (!solver_->factorize(K_))
    throw NumericalError(
        "the stiffness matrix is not positive definite: some part of the design is not held by a "
        "support, or a cell's stiffness is not positive definite");
  ++stats_.factorizations;
  stats_.factorize_seconds += seconds_since(t1);
}

void GridElasticity::set_field(VoxelStiffnessField field) {
  if (!matrix_free_) throw std::logic_error("GridElasticity::set_field: solver " + solver_name_ + " is assembled");
  if (std::abs(field.h - grid_.h()) > 1e-12 * grid_.h())
    throw std::invalid_argument("GridElasticity::set_field: the field's voxel size is not the grid's cell size");
  const auto t0 = std::chrono::steady_clock::now();
  pairs_.resize(0, 0);
  matrix_free_->set_field(std::move(field));
  fixed_scale_ = matrix_free_->fixed_scale();
  ++stats_.factorizations;
  stats_.factorize_seconds += seconds_since(t0);
}

MatX GridElasticity::element_matrix(std::int64_t cell) const {
  if (matrix_free_) return matrix_free_->field().element(cell);
  const int m = grid_.voigt();
  MatX C(m, m);
  for (int s = 0; s < m; ++s)
    for (int t = s; t < m; ++t) C(s, t) = C(t, s) = pairs_(cell, CellGrid::pair_index(s, t, m));
  return grid_.element_stiffness(C);
}

VecX GridElasticity::run_solve(VecX rhs) {
  const auto t0 = std::chrono::steady_clock::now();
  VecX x = matrix_free_ ? matrix_free_->solve(std::move(rhs)) : solver_->solve(rhs);
  ++stats_.solves;
  stats_.iterations += matrix_free_ ? matrix_free_->stats().iterations : solver_->stats().iterations;
  stats_.solve_seconds += seconds_since(t0);
  return x;
}

VecX GridElasticity::solve(VecX rhs, const VecX& prescribed) {  // rhs: the forces, made the right-hand side in place
  const std::int64_t n = grid_.unknowns();
  const std::vector<char>& fixed = this->fixed();
  for (std::int64_t d = 0; d < n; ++d)
    if (fixed[d]) rhs[d] = 0;
  if (prescribed.size() == n) {
    // Move the prescribed values to the right-hand side: rhs_f -= K_fp u_p.
    const int ne = grid_.element_unknowns();
    std::int64_t dofs[24];
    Eigen::VectorXd ue(ne);
    for (std::int64_t c = 0; c < grid_.cells(); ++c) {
      grid_.cell_unknowns(c, dofs);
      bool any = false;
      for (int a = 0; a < ne; ++a) {
        ue[a] = fixed[dofs[a]] ? prescribed[dofs[a]] : 0.0;
        any = any || ue[a] != 0;
      }
      if (!any) continue;
      const VecX r = element_matrix(c) * ue;
      for (int a = 0; a < ne; ++a)
        if (!fixed[dofs[a]]) rhs[dofs[a]] -= r[a];
    }
    for (std::int64_t d = 0; d < n; ++d)
      if (fixed[d]) rhs[d] = fixed_scale_ * prescribed[d];
  }
  return run_solve(std::move(rhs));
}

VecX GridElasticity::solve_adjoint(const VecX& rhs) {
  VecX b = rhs;
  const std::vector<char>& fixed = this->fixed();
  for (std::int64_t d = 0; d < grid_.unknowns(); ++d)
    if (fixed[d]) b[d] = 0;
  return run_solve(std::move(b));
}

MatX GridElasticity::pair_products(const VecX& a, const VecX& b) const {
  const int ne = grid_.element_unknowns(), pairs = grid_.voigt_pairs();
  const std::vector<MatX>& basis = grid_.element_basis();
  MatX out(grid_.cells(), pairs);
#pragma omp parallel for schedule(static)
  for (std::int64_t c = 0; c < grid_.cells(); ++c) {
    std::int64_t dofs[24];
    grid_.cell_unknowns(c, dofs);
    VecX ae(ne), be(ne);
    for (int i = 0; i < ne; ++i) ae[i] = a[dofs[i]], be[i] = b[dofs[i]];
    for (int q = 0; q < pairs; ++q) out(c, q) = ae.dot(basis[q] * be);
  }
  return out;
}

double GridElasticity::energy(const VecX& u) const {
  if (!matrix_free_) {
    const MatX products = pair_products(u, u);
    return 0.5 * (products.cwiseProduct(pairs_)).sum();
  }
  // 1/2 sum_e u_e^T K_e u_e from the field, cell by cell in a fixed order.
  const VoxelStiffnessField& field = matrix_free_->field();
  const int B = field.basis_size();
  return 0.5 * chunked_reduce(grid_.cells(), options_.threads, [&](Eigen::Index begin, Eigen::Index end) {
           double sum = 0;
           std::int64_t dofs[24];
           Vec24 ue;
           for (Eigen::Index c = begin; c < end; ++c) {
             grid_.cell_unknowns(c, dofs);
             for (int i = 0; i < 24; ++i) ue[i] = u[dofs[i]];
             for (int b = 0; b < B; ++b)
               if (const double w = field.weight(c, b); w != 0.0) sum += w * ue.dot(field.basis[std::size_t(b)] * ue);
           }
           return sum;
         });
}

}  // namespace msfab
