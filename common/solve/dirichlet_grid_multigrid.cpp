#include "solve/dirichlet_grid_multigrid.hpp"

#include <spdlog/spdlog.h>

#include <algorithm>
#include <array>
#include <chrono>
#include <cmath>
#include <string>
#include <utility>

#include "core/errors.hpp"
#include "core/timing.hpp"
#include "fem/element_product.hpp"
#include "solve/chebyshev_kernels.hpp"
#include "solve/component_multigrid.hpp"
#include "solve/conjugate_gradient.hpp"
#include "solve/hex_lattice.hpp"
#include "solve/material_components.hpp"
#include "solve/multigrid_solver.hpp"
#include "solve/sparse_ops.hpp"

namespace msfab {
namespace {

using namespace hex_lattice;

// Element rows per band of the matrix-free product (multiply_rows): 8, or
// fewer on a grid of few rows, so that each colour still has several bands
// (a function of the grid alone, so the order of the sums is too).
int product_band_rows(int ny) { return std::clamp(ny / 8, 1, 8); }

std::string dims_text(const int n[3]) {
  return std::to_string(n[0]) + " x " + std::to_string(n[1]) + " x " + std::to_string(n[2]);
}

// P_pos: the trilinear interpolation from a coarse element's corners to the
// corners of its fine element at position pos = pi + 2 (pj + 2 pk).
Mat24 interpolation(int pos) {
  const int p[3] = {pos & 1, pos >> 1 & 1, pos >> 2 & 1};
  Mat24 P = Mat24::Zero();
  for (int c = 0; c < 8; ++c) {
    const double xi[3] = {0.5 * (p[0] + corner_x(c)), 0.5 * (p[1] + corner_y(c)), 0.5 * (p[2] + corner_z(c))};
    for (int A = 0; A < 8; ++A) {
      const double phi =
          (corner_x(A) ? xi[0] : 1 - xi[0]) * (corner_y(A) ? xi[1] : 1 - xi[1]) * (corner_z(A) ? xi[2] : 1 - xi[2]);
      for (int d = 0; d < 3; ++d) P(3 * c + d, 3 * A + d) = phi;
    }
  }
  return P;
}

// Calls body(I, J, K) for every element of a grid of n[0] x n[1] x n[2]
// elements, one parity colour after the other (elements of one colour
// share no node, so bodies that add into their corners do not conflict),
// in parallel within a colour.
template <class Body>
void for_each_element_by_colour(const int n[3], int team, Body&& body) {
  for (int colour = 0; colour < 8; ++colour) {
    const int ci = corner_x(colour), cj = corner_y(colour), ck = corner_z(colour);
    const int hx = (n[0] - ci + 1) / 2, hy = (n[1] - cj + 1) / 2, hz = (n[2] - ck + 1) / 2;
    const std::int64_t count = std::int64_t(hx) * hy * hz;
#pragma omp parallel for schedule(static) num_threads(team)
    for (std::int64_t t = 0; t < count; ++t)
      body(ci + 2 * static_cast<int>(t % hx), cj + 2 * static_cast<int>((t / hx) % hy),
           ck + 2 * static_cast<int>(t / (std::int64_t(hx) * hy)));
  }
}

}  // namespace

bool DirichletGridMultigrid::supports(int nx, int ny, int nz) {
  for (int n : {nx, ny, nz})
    if (n < 2 || n % 2 != 0) return false;
  return true;
}

DirichletGridMultigrid::~DirichletGridMultigrid() = default;

DirichletMultigridOptions dirichlet_multigrid_options(const LinearSolverOptions& options) {
  DirichletMultigridOptions mg;
  mg.tolerance = options.pcg_tolerance, mg.max_iterations = options.pcg_max_iterations;
  mg.max_iterations_key = options.pcg_max_iterations_key;
  mg.smoother_degree = options.mg_smoother_degree, mg.coarse_unknowns = options.mg_coarse_unknowns;
  mg.threads = options.threads;
  return mg;
}

DirichletGridMultigrid::DirichletGridMultigrid(int nx, int ny, int nz, std::vector<char> fixed,
                                               const DirichletMultigridOptions& options)
    : fixed_(std::move(fixed)), options_(options) {
  fine_.n[0] = nx, fine_.n[1] = ny, fine_.n[2] = nz;
  if (!supports(nx, ny, nz))
    throw InputError("matrix-free multigrid: a " + dims_text(fine_.n) +
                     " grid cannot be coarsened (every dimension must be even)");
  if (!(options_.tolerance > 0) || options_.tolerance >= 1)
    throw InputError("matrix-free multigrid: tolerance must lie in (0, 1)");
  if (options_.max_iterations < 1) throw InputError("matrix-free multigrid: max_iterations must be >= 1");
  if (options_.smoother_degree < 1 || options_.smoother_degree > 10)
    throw InputError("matrix-free multigrid: smoother_degree must lie in 1..10");
  if (options_.grid_smoother_degree < 1 || options_.grid_smoother_degree > 10)
    throw InputError("matrix-free multigrid: grid_smoother_degree must lie in 1..10");
  const std::int64_t nodes = fine_.nodes();
  if (nodes > (std::int64_t(1) << 31) / 3) throw InputError("matrix-free multigrid: more than 2^31 unknowns");
  if (std::int64_t(fixed_.size()) != 3 * nodes)
    throw std::invalid_argument("DirichletGridMultigrid: one fixed flag per unknown");
  coarse_.n[0] = nx / 2, coarse_.n[1] = ny / 2, coarse_.n[2] = nz / 2;
  fixed_count_ = std::count_if(fixed_.begin(), fixed_.end(), [](char f) { return f != 0; });

  if (options_.material_coarse_space) return;  // set_field() numbers the nodes that touch material
  own_first_.resize(std::size_t(nodes) + 1);
  for (std::int64_t p = 0; p <= nodes; ++p) own_first_[std::size_t(p)] = static_cast<int>(p);
  number_rows(own_first_);
  // A coarse unknown is reached when some free fine unknown of the same
  // component lies within one fine spacing of its point.
  const std::int64_t coarse_nodes = coarse_.nodes();
  coarse_reached_.assign(3 * std::size_t(coarse_nodes), 0);
  for (int K = 0; K <= coarse_.n[2]; ++K)
    for (int J = 0; J <= coarse_.n[1]; ++J)
      for (int I = 0; I <= coarse_.n[0]; ++I) {
        const std::int64_t C = coarse_.node(I, J, K);
        for (int dz = -1; dz <= 1; ++dz)
          for (int dy = -1; dy <= 1; ++dy)
            for (int dx = -1; dx <= 1; ++dx) {
              const int i = 2 * I + dx, j = 2 * J + dy, k = 2 * K + dz;
              if (i < 0 || j < 0 || k < 0 || i > nx || j > ny || k > nz) continue;
              const std::uint8_t m = node_mask(fine_.node(i, j, k));
              for (int d = 0; d < 3; ++d)
                if (!(m >> d & 1)) coarse_reached_[std::size_t(3 * C + d)] = 1;
            }
      }
  build_coarse_pattern();
}

void DirichletGridMultigrid::build_coarse_pattern() {
  const int N[3] = {coarse_.n[0] + 1, coarse_.n[1] + 1, coarse_.n[2] + 1};
  const std::int64_t nodes = coarse_.nodes();
  BlockMatrix& M = coarse_blocks_;
  M.rows = static_cast<int>(nodes);
  M.row_start.assign(std::size_t(nodes) + 1, 0);
  M.column.clear();
  M.diagonal.assign(std::size_t(nodes), 0);
  coarse_slot_.assign(27 * std::size_t(nodes), -1);
  for (int k = 0; k < N[2]; ++k)
    for (int j = 0; j < N[1]; ++j)
      for (int i = 0; i < N[0]; ++i) {
        const std::int64_t p = coarse_.node(i, j, k);
        M.row_start[std::size_t(p)] = static_cast<int>(M.column.size());
        // z, y, x outermost to innermost: node indices come out ascending.
        for (int dz = -1; dz <= 1; ++dz)
          for (int dy = -1; dy <= 1; ++dy)
            for (int dx = -1; dx <= 1; ++dx) {
              if (i + dx < 0 || j + dy < 0 || k + dz < 0 || i + dx >= N[0] || j + dy >= N[1] || k + dz >= N[2])
                continue;
              coarse_slot_[27 * std::size_t(p) + offset_code(dx, dy, dz)] = static_cast<int>(M.column.size());
              M.column.push_back(static_cast<int>(coarse_.node(i + dx, j + dy, k + dz)));
            }
        M.diagonal[std::size_t(p)] = coarse_slot_[27 * std::size_t(p) + offset_code(0, 0, 0)];
      }
  M.row_start[std::size_t(nodes)] = static_cast<int>(M.column.size());
  M.values.assign(9 * M.column.size(), 0.0);
}

void DirichletGridMultigrid::set_field(VoxelStiffnessField field) {
  const auto start = std::chrono::steady_clock::now();
  validate_field(field, "matrix-free multigrid");
  if (field.nx != fine_.n[0] || field.ny != fine_.n[1] || field.nz != fine_.n[2])
    throw InputError("matrix-free multigrid: a field of " + std::to_string(field.nx) + " x " +
                     std::to_string(field.ny) + " x " + std::to_string(field.nz) + " elements for a " +
                     dims_text(fine_.n) + " grid");
  if (fixed_count_ == 3 * fine_.nodes()) throw InputError("every unknown of the grid is fixed: nothing to solve");
  field_ = std::move(field);
  has_field_ = false;
  if (options_.material_coarse_space) build_material_components();
  build_fine_smoother();
  if (options_.material_coarse_space)
    assemble_material_coarse();
  else
    assemble_coarse();
  has_field_ = true;
  stats_.analyze_seconds = seconds_since(start);
  stats_.factorize_seconds = stats_.analyze_seconds;
  stats_.positive_definite = true;
}

void DirichletGridMultigrid::number_rows(const std::vector<int>& first) {
  first_ = &first;
  const std::int64_t nodes = fine_.nodes();
  row_mask_.assign(std::size_t(rows()), 0);
  fixed_list_.clear();
  std::int64_t loose = 0;  // nodes without a row that have a free unknown
  for (std::int64_t p = 0; p < nodes; ++p) {
    const int r = row_of(p);
    bool free = false;
    for (int d = 0; d < 3; ++d) {
      if (!fixed_[std::size_t(3 * p + d)]) {
        free = true;
        continue;
      }
      if (r < 0) continue;
      row_mask_[std::size_t(r)] |= std::uint8_t(1u << d);
      fixed_list_.push_back(3 * std::int64_t(r) + d);
    }
    if (r < 0 && free) ++loose;
  }
  if (loose > 0)
    throw NumericalError("matrix-free multigrid: " + std::to_string(loose) +
                         " nodes have a diagonal stiffness block that is not positive definite (nodes that only "
                         "cells without stiffness touch)");
}

VecX DirichletGridMultigrid::gather_rows(const VecX& grid) const {
  VecX out(3 * Eigen::Index(rows()));
  chunked_for(fine_.nodes(), options_.threads, [&](Eigen::Index begin, Eigen::Index end) {
    for (Eigen::Index p = begin; p < end; ++p)
      if (const int r = row_of(p); r >= 0) out.segment<3>(3 * Eigen::Index(r)) = grid.segment<3>(3 * p);
  });
  return out;
}

void DirichletGridMultigrid::scatter_rows_into(const VecX& rows_vector, VecX& grid, double scale) const {
  chunked_for(fine_.nodes(), options_.threads, [&](Eigen::Index begin, Eigen::Index end) {
    for (Eigen::Index p = begin; p < end; ++p) {
      if (const int r = row_of(p); r >= 0)
        grid.segment<3>(3 * p) = rows_vector.segment<3>(3 * Eigen::Index(r));
      else
        grid.segment<3>(3 * p) *= scale;
    }
  });
}

VecX DirichletGridMultigrid::scatter_rows(const VecX& rows_vector, const VecX& grid, double scale) const {
  VecX out = grid;
  scatter_rows_into(rows_vector, out, scale);
  return out;
}

void DirichletGridMultigrid::build_fine_smoother() {
  const int B = field_.basis_size();
  const int nx = fine_.n[0], ny = fine_.n[1], nz = fine_.n[2];
  const std::int64_t nodes = fine_.nodes();
  const int rows = static_cast<int>(this->rows());
  // The blocks themselves are needed only here: 72 bytes per row.
  std::vector<double> diagonal(9 * std::size_t(rows), 0.0);
  // Unmasked diagonal blocks, and (sum, count) of the free unknowns' diagonal entries.
  const Eigen::Vector2d sum = chunked_reduce(nodes, options_.threads, [&](Eigen::Index begin, Eigen::Index end) {
    Eigen::Vector2d s = Eigen::Vector2d::Zero();
    for (Eigen::Index p = begin; p < end; ++p) {
      const int r = row_of(p);
      if (r < 0) continue;
      const int i = static_cast<int>(p % (nx + 1)), j = static_cast<int>((p / (nx + 1)) % (ny + 1)),
                k = static_cast<int>(p / (std::int64_t(nx + 1) * (ny + 1)));
      Mat3 D = Mat3::Zero();
      for (int a = 0; a < 8; ++a) {
        const int ei = i - corner_x(a), ej = j - corner_y(a), ek = k - corner_z(a);
        if (ei < 0 || ej < 0 || ek < 0 || ei >= nx || ej >= ny || ek >= nz) continue;
        const std::int64_t e = ei + std::int64_t(nx) * (ej + std::int64_t(ny) * ek);
        for (int b = 0; b < B; ++b)
          if (const double w = field_.weight(e, b); w != 0.0) D += w * field_.basis[b].block<3, 3>(3 * a, 3 * a);
      }
      Eigen::Map<Eigen::Matrix<double, 3, 3, Eigen::RowMajor>>(diagonal.data() + 9 * std::size_t(r)) = D;
      for (int d = 0; d < 3; ++d)
        if (!(row_mask_[std::size_t(r)] >> d & 1)) s += Eigen::Vector2d(D(d, d), 1.0);
    }
    return s;
  });
  fixed_scale_ = sum[0] / sum[1];
  if (!(fixed_scale_ > 0) || !std::isfinite(fixed_scale_))
    throw NumericalError("matrix-free multigrid: the free unknowns have no positive stiffness");
  for (std::int64_t d : fixed_list_) {
    double* m = diagonal.data() + 9 * std::size_t(d / 3);
    const int c = static_cast<int>(d % 3);
    for (int t = 0; t < 3; ++t) m[3 * c + t] = m[3 * t + c] = 0.0;
    m[4 * c] = fixed_scale_;
  }
  std::vector<double> inverse;
  const int bad = chebyshev::invert_diagonal_blocks(rows, diagonal.data(), inverse, options_.threads);
  if (bad != 0)
    throw NumericalError("matrix-free multigrid: " + std::to_string(bad) +
                         " nodes have a diagonal stiffness block that is not positive definite (nodes that only "
                         "cells without stiffness touch)");
  max_eigenvalue_ = chebyshev::estimate_max_eigenvalue(
      rows, diagonal.data(), inverse.data(),
      [this](int i, const double*, double out[3]) {
        const double* y = product_.data() + 3 * std::size_t(i);
        out[0] = y[0], out[1] = y[1], out[2] = y[2];
      },
      [this](const VecX& x) { multiply_rows(x, product_); }, options_.threads);
  if (!(max_eigenvalue_ > 0) || !std::isfinite(max_eigenvalue_))
    throw NumericalError("matrix-free multigrid: no usable eigenvalue bound for the smoother");
  std::vector<double>().swap(diagonal);
  inverse_.assign(inverse.begin(), inverse.end());
  spdlog::debug("matrix-free multigrid: largest eigenvalue of the block-Jacobi-scaled operator about {:.4g}",
                max_eigenvalue_);
}

void DirichletGridMultigrid::galerkin_tables(std::vector<Mat24>& P, std::vector<Mat24>& galerkin) const {
  const int B = field_.basis_size();
  P.resize(8);
  galerkin.resize(8 * std::size_t(B));
  for (int pos = 0; pos < 8; ++pos) {
    P[pos] = interpolation(pos);
    for (int b = 0; b < B; ++b) galerkin[std::size_t(pos) * B + b] = P[pos].transpose() * field_.basis[b] * P[pos];
  }
}

void DirichletGridMultigrid::add_voxel_galerkin(int i, int j, int k, int pos, const std::vector<Mat24>& P,
                                                const std::vector<Mat24>& galerkin, Mat24& KE) const {
  const int B = field_.basis_size();
  const std::int64_t e = fine_.element(i, j, k);
  std::uint8_t masked = 0;
  for (int a = 0; a < 8; ++a) masked |= node_mask(fine_.node(i + corner_x(a), j + corner_y(a), k + corner_z(a)));
  if (!masked) {
    for (int b = 0; b < B; ++b)
      if (const double w = field_.weight(e, b); w != 0.0) KE.noalias() += w * galerkin[std::size_t(pos) * B + b];
    return;
  }
  Mat24 Ke = field_.element(e);
  for (int a = 0; a < 8; ++a) {
    const std::uint8_t m = node_mask(fine_.node(i + corner_x(a), j + corner_y(a), k + corner_z(a)));
    for (int d = 0; d < 3; ++d)
      if (m >> d & 1) {
        Ke.row(3 * a + d).setZero();
        Ke.col(3 * a + d).setZero();
      }
  }
  KE.noalias() += P[pos].transpose() * Ke * P[pos];
}

void DirichletGridMultigrid::assemble_coarse() {
  std::vector<Mat24> P, galerkin;
  galerkin_tables(P, galerkin);
  BlockMatrix& M = coarse_blocks_;
  std::fill(M.values.begin(), M.values.end(), 0.0);
  for_each_element_by_colour(coarse_.n, resolve_thread_count(options_.threads), [&](int I, int J, int K) {
    Mat24 KE = Mat24::Zero();
    for (int pos = 0; pos < 8; ++pos) {
      const int i = 2 * I + (pos & 1), j = 2 * J + (pos >> 1 & 1), k = 2 * K + (pos >> 2 & 1);
      add_voxel_galerkin(i, j, k, pos, P, galerkin, KE);
    }
    for (int a = 0; a < 8; ++a) {
      const std::int64_t row = coarse_.node(I + corner_x(a), J + corner_y(a), K + corner_z(a));
      for (int b = 0; b < 8; ++b) {
        double* block = M.values.data() + 9 * std::size_t(coarse_slot_[27 * std::size_t(row) + corner_code(a, b)]);
        for (int r = 0; r < 3; ++r)
          for (int q = 0; q < 3; ++q) block[3 * r + q] += KE(3 * a + r, 3 * b + q);
      }
    }
  });
  // Coarse unknowns no free fine unknown interpolates have empty rows and
  // columns: a diagonal of the level's scale keeps the operator definite.
  double diagonal_sum = 0.0;
  std::int64_t reached = 0;
  for (std::size_t u = 0; u < coarse_reached_.size(); ++u)
    if (coarse_reached_[u]) {
      diagonal_sum += M.values[9 * std::size_t(M.diagonal[u / 3]) + 4 * (u % 3)];
      ++reached;
    }
  const double scale = reached > 0 ? diagonal_sum / double(reached) : 1.0;
  for (std::size_t u = 0; u < coarse_reached_.size(); ++u)
    if (!coarse_reached_[u]) M.values[9 * std::size_t(M.diagonal[u / 3]) + 4 * (u % 3)] = scale;

  if (!coarse_analyzed_) {
    coarse_matrix_ = sparse_pattern(M);
    copy_to_sparse(M, coarse_matrix_);
    LinearSolverOptions options;
    options.threads = options_.threads;
    options.mg_coarse_unknowns = options_.coarse_unknowns;
    options.mg_smoother_degree = options_.smoother_degree;
    const int NX = coarse_.n[0], NY = coarse_.n[1], NZ = coarse_.n[2];
    auto positions = std::make_shared<Eigen::Matrix<double, Eigen::Dynamic, 3, Eigen::RowMajor>>(coarse_.nodes(), 3);
    for (int k = 0; k <= NZ; ++k)
      for (int j = 0; j <= NY; ++j)
        for (int i = 0; i <= NX; ++i) positions->row(coarse_.node(i, j, k)) << i, j, k;
    options.node_positions = positions;
    coarse_solver_ = std::make_unique<MultigridSolver>(options);
    coarse_solver_->analyze(coarse_matrix_);
    coarse_analyzed_ = true;
  } else {
    copy_to_sparse(M, coarse_matrix_);
  }
  if (!coarse_solver_->factorize(coarse_matrix_))
    throw NumericalError("matrix-free multigrid: the coarse operator (" + dims_text(coarse_.n) +
                         " elements) is not positive definite: part of the body is not held by a support");
}

void DirichletGridMultigrid::build_material_components() {
  const int B = field_.basis_size();
  std::vector<char> solid(std::size_t(field_.voxels()), 0);
  for (std::int64_t e = 0; e < field_.voxels(); ++e)
    for (int b = 0; b < B && !solid[std::size_t(e)]; ++b) solid[std::size_t(e)] = field_.weight(e, b) != 0.0;
  if (!components_ || solid != components_solid_) {
    const auto start = std::chrono::steady_clock::now();
    component_solver_.reset();
    components_.reset();
    first_ = nullptr;
    components_ = std::make_shared<MaterialComponents>(fine_.n[0], fine_.n[1], fine_.n[2], solid,
                                                       std::max(1, options_.coarse_unknowns / 3), options_.threads);
    components_solid_ = std::move(solid);
    component_solver_ = std::make_unique<ComponentMultigrid>(components_, options_.smoother_degree, options_.threads,
                                                             options_.upper_level_blocks);
    std::string copies;
    for (const ComponentLevel& level : components_->levels())
      copies += (copies.empty() ? "" : ", ") + std::to_string(level.copies());
    spdlog::debug("matrix-free multigrid: node copies per level {} ({:.2f} s)", copies, seconds_since(start));
  }
  number_rows(components_->levels()[0].first);
}

void DirichletGridMultigrid::assemble_material_coarse() {
  std::vector<Mat24> P, galerkin;
  galerkin_tables(P, galerkin);
  BlockMatrix& M = component_solver_->level1();
  const std::vector<int>* upper = component_solver_->level1_upper();
  std::fill(M.values.begin(), M.values.end(), 0.0);
  const auto slot = [&M](int row, int column) {
    const auto begin = M.column.begin() + M.row_start[std::size_t(row)];
    const auto end = M.column.begin() + M.row_start[std::size_t(row) + 1];
    return static_cast<std::size_t>(std::lower_bound(begin, end, column) - M.column.begin());
  };
  // Level-1 elements of one colour share no lattice point, hence no copy.
  for_each_element_by_colour(coarse_.n, resolve_thread_count(options_.threads), [&](int I, int J, int K) {
    // Voxels whose pieces meet the element's corners in the same copies
    // share one coarse element matrix.
    std::array<int, 8> copies[8];
    Mat24 KE[8];
    int groups = 0;
    for (int pos = 0; pos < 8; ++pos) {
      const int i = 2 * I + (pos & 1), j = 2 * J + (pos >> 1 & 1), k = 2 * K + (pos >> 2 & 1);
      const std::int64_t e = fine_.element(i, j, k);
      if (!components_solid_[std::size_t(e)]) continue;
      std::array<int, 8> c;
      for (int a = 0; a < 8; ++a) c[std::size_t(a)] = components_->element_copy(i, j, k, a);
      int g = 0;
      while (g < groups && copies[g] != c) ++g;
      if (g == groups) {
        copies[g] = c;
        KE[g].setZero();
        ++groups;
      }
      add_voxel_galerkin(i, j, k, pos, P, galerkin, KE[g]);
    }
    for (int g = 0; g < groups; ++g)
      for (int a = 0; a < 8; ++a)
        for (int b = 0; b < 8; ++b) {
          const int row = copies[g][std::size_t(a)], column = copies[g][std::size_t(b)];
          // Held by its upper blocks, a block below the diagonal is its mirror's transpose.
          if (upper && column < row) continue;
          double* block = M.values.data() + stored_block(upper, static_cast<int>(slot(row, column)));
          for (int r = 0; r < 3; ++r)
            for (int q = 0; q < 3; ++q) block[3 * r + q] += KE[g](3 * a + r, 3 * b + q);
        }
  });
  if (!component_solver_->factorize())
    throw NumericalError("matrix-free multigrid: a coarse operator that follows the material (" + dims_text(coarse_.n) +
                         " elements and below) is not positive definite: part of the body "
                         "is not held by a support");
}

void DirichletGridMultigrid::multiply(const VecX& x, VecX& y) const {
  if (!has_field_) throw std::logic_error("DirichletGridMultigrid::multiply: no field set");
  VecX product;
  multiply_rows(gather_rows(x), product);
  y = scatter_rows(product, x, fixed_scale_);
}

void DirichletGridMultigrid::multiply_rows(const VecX& x, VecX& y) const {
  const int nx = fine_.n[0], ny = fine_.n[1], nz = fine_.n[2];
  const Eigen::Index n = 3 * Eigen::Index(rows());
  const int B = field_.basis_size();
  y.resize(n);
  const int team = resolve_thread_count(options_.threads);
  const ElementProductKernel product = element_product_kernel();
#pragma omp parallel num_threads(team) if (n > 3 * 4096)
  {
#pragma omp for schedule(static)
    for (Eigen::Index k = 0; k < n; ++k) y[k] = 0.0;
    const auto add_element = [&](int i, int j, int k) {
      const std::int64_t e = i + std::int64_t(nx) * (j + std::int64_t(ny) * k);
      // Void (all weights zero) adds nothing: skip its gather and scatter.
      bool has_stiffness = false;
      for (int b = 0; b < B && !has_stiffness; ++b) has_stiffness = field_.weight(e, b) != 0.0;
      if (!has_stiffness) return;
      // Every corner of a voxel with stiffness has a row.
      std::int64_t corner[8];
      Vec24 xe, ye = Vec24::Zero();
      for (int a = 0; a < 8; ++a) {
        corner[a] = row_of(fine_.node(i + corner_x(a), j + corner_y(a), k + corner_z(a)));
        xe.segment<3>(3 * a) = x.segment<3>(3 * corner[a]);
        if (const std::uint8_t m = row_mask_[std::size_t(corner[a])]; m != 0)
          for (int d = 0; d < 3; ++d)
            if (m >> d & 1) xe[3 * a + d] = 0.0;
      }
      add_voxel_product(field_, e, product, xe.data(), ye.data());
      for (int a = 0; a < 8; ++a) y.segment<3>(3 * corner[a]) += ye.segment<3>(3 * a);
    };
    // Elements in natural order (x fastest), so that neighbours share the
    // corners just read and the weights stream: by bands of
    // up to 8 element rows of one layer. Bands that differ in the
    // band's or the layer's parity share no node, so each of the four
    // colours runs its bands in parallel without conflicting additions,
    // and every entry sums its elements in the same order for any thread
    // count. (Colouring single elements by parity visited the grid eight
    // times, each time every other element: 1.4x slower on a printed
    // gripper, docs/solvers.md.)
    const int band_rows = product_band_rows(ny);
    const int bands = (ny + band_rows - 1) / band_rows;
    for (int colour = 0; colour < 4; ++colour) {
      const int cb = colour & 1, ck = colour >> 1;
      const int hb = (bands - cb + 1) / 2, hz = (nz - ck + 1) / 2;
      const int count = hb * hz;
#pragma omp for schedule(static)
      for (int t = 0; t < count; ++t) {
        const int band = cb + 2 * (t % hb), k = ck + 2 * (t / hb);
        const int j_end = std::min(ny, (band + 1) * band_rows);
        for (int j = band * band_rows; j < j_end; ++j)
          for (int i = 0; i < nx; ++i) add_element(i, j, k);
      }
    }
    // Fixed rows: s x_d (what the element sums put there is discarded).
    const std::int64_t fixed_count = static_cast<std::int64_t>(fixed_list_.size());
#pragma omp for schedule(static)
    for (std::int64_t t = 0; t < fixed_count; ++t) {
      const std::int64_t d = fixed_list_[std::size_t(t)];
      y[d] = fixed_scale_ * x[d];
    }
  }
}

void DirichletGridMultigrid::restrict_residual(const VecX& fine, VecX& coarse) const {
  if (components_) {
    const auto is_free = [this](int row, int d) { return !(row_mask_[std::size_t(row)] >> d & 1); };
    component_restrict(components_->transfers()[0], fine, is_free, coarse, options_.threads);
    return;
  }
  const int nx = fine_.n[0], ny = fine_.n[1], nz = fine_.n[2];
  const int NX = coarse_.n[0], NY = coarse_.n[1];
  const std::int64_t nodes = coarse_.nodes();
  coarse.resize(3 * nodes);
  parallel_row_ranges(static_cast<int>(nodes), resolve_thread_count(options_.threads), [&](int begin, int end) {
    for (int P = begin; P < end; ++P) {
      const int I = P % (NX + 1), J = (P / (NX + 1)) % (NY + 1), K = P / ((NX + 1) * (NY + 1));
      double sum[3] = {0, 0, 0};
      for (int dz = -1; dz <= 1; ++dz)
        for (int dy = -1; dy <= 1; ++dy)
          for (int dx = -1; dx <= 1; ++dx) {
            const int i = 2 * I + dx, j = 2 * J + dy, k = 2 * K + dz;
            if (i < 0 || j < 0 || k < 0 || i > nx || j > ny || k > nz) continue;
            const double w = (dx ? 0.5 : 1.0) * (dy ? 0.5 : 1.0) * (dz ? 0.5 : 1.0);
            const std::int64_t f = fine_.node(i, j, k);
            const std::uint8_t m = row_mask_[std::size_t(f)];  // rows are the nodes here
            for (int d = 0; d < 3; ++d)
              if (!(m >> d & 1)) sum[d] += w * fine[3 * f + d];
          }
      for (int d = 0; d < 3; ++d) coarse[3 * std::int64_t(P) + d] = sum[d];
    }
  });
}

void DirichletGridMultigrid::add_prolongation(const VecX& coarse, VecX& fine) const {
  if (components_) {
    const auto is_free = [this](int row, int d) { return !(row_mask_[std::size_t(row)] >> d & 1); };
    component_add_prolongation(components_->transfers()[0], coarse, is_free, fine, options_.threads);
    return;
  }
  const int nx = fine_.n[0], ny = fine_.n[1];
  const std::int64_t nodes = fine_.nodes();
  parallel_row_ranges(static_cast<int>(nodes), resolve_thread_count(options_.threads), [&](int begin, int end) {
    for (int p = begin; p < end; ++p) {
      const std::uint8_t m = row_mask_[std::size_t(p)];  // rows are the nodes here
      if (m == 7) continue;
      const int i = p % (nx + 1), j = (p / (nx + 1)) % (ny + 1), k = p / ((nx + 1) * (ny + 1));
      const int ox = i % 2, oy = j % 2, oz = k % 2;
      const double w = (ox ? 0.5 : 1.0) * (oy ? 0.5 : 1.0) * (oz ? 0.5 : 1.0);
      double sum[3] = {0, 0, 0};
      for (int cz = 0; cz <= oz; ++cz)
        for (int cy = 0; cy <= oy; ++cy)
          for (int cx = 0; cx <= ox; ++cx) {
            const std::int64_t C = coarse_.node(i / 2 + cx, j / 2 + cy, k / 2 + cz);
            for (int d = 0; d < 3; ++d) sum[d] += coarse[3 * C + d];
          }
      for (int d = 0; d < 3; ++d)
        if (!(m >> d & 1)) fine[3 * std::int64_t(p) + d] += w * sum[d];
    }
  });
}

void DirichletGridMultigrid::cycle(const VecX& r, VecX& z) {
  const int rows = static_cast<int>(this->rows());
  const int threads = options_.threads;
  const auto row_product = [this](int i, const double*, double out[3]) {
    const double* y = product_.data() + 3 * std::size_t(i);
    out[0] = y[0], out[1] = y[1], out[2] = y[2];
  };
  const auto apply = [this](const VecX& x) { multiply_rows(x, product_); };
  chebyshev::smooth(rows, inverse_.data(), max_eigenvalue_, options_.grid_smoother_degree, row_product, apply, r, z,
                    true, step_, next_, threads);
  apply(z);
  // r - A z into product_ itself (each row is read before it is written).
  chebyshev::residual(rows, row_product, r, z, product_, threads);
  restrict_residual(product_, coarse_rhs_);
  if (component_solver_)
    component_solver_->cycle(coarse_rhs_, coarse_solution_);
  else
    coarse_solution_ = coarse_solver_->apply_preconditioner(coarse_rhs_);
  add_prolongation(coarse_solution_, z);
  chebyshev::smooth(rows, inverse_.data(), max_eigenvalue_, options_.grid_smoother_degree, row_product, apply, r, z,
                    false, step_, next_, threads);
}

VecX DirichletGridMultigrid::apply_preconditioner(const VecX& r) {
  if (!has_field_) throw std::logic_error("DirichletGridMultigrid: no field set");
  VecX z;
  cycle(gather_rows(r), z);
  return scatter_rows(z, r, 1.0 / fixed_scale_);
}

VecX DirichletGridMultigrid::solve(VecX b) {
  if (!has_field_) throw std::logic_error("DirichletGridMultigrid::solve: no field set");
  const Eigen::Index n = 3 * Eigen::Index(fine_.nodes());
  if (b.size() != n)
    throw std::invalid_argument("DirichletGridMultigrid::solve: right-hand side has " + std::to_string(b.size()) +
                                " entries, the grid has " + std::to_string(n) + " unknowns");
  const int threads = options_.threads;
  CgSetup cg = multigrid_cg_setup([this](const VecX& x, VecX& y) { multiply_rows(x, y); },
                                  [this](const VecX& r, VecX& z) { cycle(r, z); }, options_.tolerance,
                                  options_.max_iterations, threads, "matrix-free multigrid CG");
  cg.settings.max_iterations_key = options_.max_iterations_key;
  cg.settings.progress = [](int iteration, double residual) {
    spdlog::debug("  matrix-free multigrid CG: iteration {}, relative residual {:.3g}", iteration, residual);
  };
  // Nodes without a row have every unknown fixed: their rows of A are s I,
  // so their solution is b / s. Only its non-zero entries are kept, and the
  // grid vector is released while CG runs: on a printed structure most
  // nodes have no row, and this vector would be the largest one held.
  VecX rows_b = gather_rows(b);
  std::vector<std::pair<std::int64_t, double>> outside;
  for (std::int64_t p = 0; p < fine_.nodes(); ++p)
    if (row_of(p) < 0)
      for (int d = 0; d < 3; ++d)
        if (const double v = b[3 * p + d]; v != 0.0) outside.emplace_back(3 * p + d, v / fixed_scale_);
  VecX().swap(b);
  VecX x_rows = conjugate_gradient(cg.op, cg.preconditioner, rows_b, cg.settings, stats_);
  VecX().swap(rows_b);
  VecX x = VecX::Zero(n);
  scatter_rows_into(x_rows, x, 0.0);
  for (const auto& [unknown, value] : outside) x[unknown] = value;
  return x;
}

int DirichletGridMultigrid::num_levels() const {
  if (component_solver_) return 1 + component_solver_->num_levels();
  return 1 + (coarse_solver_ ? coarse_solver_->num_levels() : 0);
}

SpMat DirichletGridMultigrid::fine_operator() const {
  const int nx = fine_.n[0], ny = fine_.n[1];
  std::vector<Eigen::Triplet<double>> triplets;
  for (std::int64_t e = 0; e < field_.voxels(); ++e) {
    const int i = static_cast<int>(e % nx), j = static_cast<int>((e / nx) % ny),
              k = static_cast<int>(e / (std::int64_t(nx) * ny));
    const Mat24 K = field_.element(e);
    std::int64_t dof[24];
    for (int a = 0; a < 8; ++a)
      for (int d = 0; d < 3; ++d)
        dof[3 * a + d] = 3 * fine_.node(i + corner_x(a), j + corner_y(a), k + corner_z(a)) + d;
    for (int r = 0; r < 24; ++r)
      for (int c = 0; c < 24; ++c)
        if (!is_fixed(dof[r]) && !is_fixed(dof[c])) triplets.emplace_back(int(dof[r]), int(dof[c]), K(r, c));
  }
  for (std::int64_t d = 0; d < 3 * fine_.nodes(); ++d)
    if (is_fixed(d)) triplets.emplace_back(int(d), int(d), fixed_scale_);
  const int n = static_cast<int>(3 * fine_.nodes());
  SpMat A(n, n);
  A.setFromTriplets(triplets.begin(), triplets.end());
  return A;
}

SpMat DirichletGridMultigrid::coarse_operator() const {
  if (!component_solver_) return coarse_matrix_;
  if (component_solver_->level_matrix(0).values.empty() || component_solver_->level1_upper())
    throw std::logic_error(
        "DirichletGridMultigrid::coarse_operator: level 1 is held by its upper blocks or was released after set-up "
        "(large grid)");
  SpMat S = sparse_pattern(component_solver_->level_matrix(0));
  copy_to_sparse(component_solver_->level_matrix(0), S);
  return S;
}

SpMat DirichletGridMultigrid::prolongation() const {
  if (components_) {
    const ComponentTransfer& t = components_->transfers()[0];
    std::vector<Eigen::Triplet<double>> triplets;
    for (std::int64_t node = 0; node < fine_.nodes(); ++node) {
      const int p = row_of(node);
      if (p < 0) continue;
      for (int s = t.parent_start[std::size_t(p)]; s < t.parent_start[std::size_t(p) + 1]; ++s)
        for (int d = 0; d < 3; ++d)
          if (!is_fixed(3 * node + d))
            triplets.emplace_back(int(3 * node + d), 3 * t.parent[std::size_t(s)] + d, t.parent_weight[std::size_t(s)]);
    }
    SpMat P(int(3 * fine_.nodes()), 3 * t.coarse_copies());
    P.setFromTriplets(triplets.begin(), triplets.end());
    return P;
  }
  const int nx = fine_.n[0], ny = fine_.n[1];
  std::vector<Eigen::Triplet<double>> triplets;
  for (std::int64_t p = 0; p < fine_.nodes(); ++p) {
    const int i = static_cast<int>(p % (nx + 1)), j = static_cast<int>((p / (nx + 1)) % (ny + 1)),
              k = static_cast<int>(p / (std::int64_t(nx + 1) * (ny + 1)));
    const int ox = i % 2, oy = j % 2, oz = k % 2;
    const double w = (ox ? 0.5 : 1.0) * (oy ? 0.5 : 1.0) * (oz ? 0.5 : 1.0);
    for (int cz = 0; cz <= oz; ++cz)
      for (int cy = 0; cy <= oy; ++cy)
        for (int cx = 0; cx <= ox; ++cx) {
          const std::int64_t C = coarse_.node(i / 2 + cx, j / 2 + cy, k / 2 + cz);
          for (int d = 0; d < 3; ++d)
            if (!is_fixed(3 * p + d)) triplets.emplace_back(int(3 * p + d), int(3 * C + d), w);
        }
  }
  SpMat P(int(3 * fine_.nodes()), int(3 * coarse_.nodes()));
  P.setFromTriplets(triplets.begin(), triplets.end());
  return P;
}

}  // namespace msfab
