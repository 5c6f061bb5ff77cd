#include "solve/periodic_grid_multigrid.hpp"

#include <spdlog/spdlog.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <string>
#include <utility>

#include "core/errors.hpp"
#include "core/timing.hpp"
#include "fem/element_product.hpp"
#include "solve/block_matrix.hpp"
#include "solve/chebyshev_kernels.hpp"
#include "solve/chebyshev_smoother.hpp"
#include "solve/conjugate_gradient.hpp"
#include "solve/hex_lattice.hpp"
#include "solve/multigrid_cycle.hpp"
#include "solve/sparse_ops.hpp"

namespace msfab {
namespace {

// Coarse levels are small: smoothing them harder and visiting them twice (a
// W-cycle below the finest level) costs little and keeps the high-contrast
// coarse operators from slowing CG down.
using namespace multigrid_cycle;

using namespace hex_lattice;

std::string dims_text(const std::array<int, 3>& n) {
  return std::to_string(n[0]) + " x " + std::to_string(n[1]) + " x " + std::to_string(n[2]);
}

// x -= its mean, per displacement component.
void project_zero_mean(VecX& x, int threads) {
  const Eigen::Index nodes = x.size() / 3;
  if (nodes == 0) return;
  const Vec3 sum = chunked_reduce(nodes, threads, [&](Eigen::Index begin, Eigen::Index end) {
    Vec3 s = Vec3::Zero();
    for (Eigen::Index i = begin; i < end; ++i) s += x.segment<3>(3 * i);
    return s;
  });
  const Vec3 mean = sum / double(nodes);
  chunked_for(nodes, threads, [&](Eigen::Index begin, Eigen::Index end) {
    for (Eigen::Index i = begin; i < end; ++i) x.segment<3>(3 * i) -= mean;
  });
}

}  // namespace

struct PeriodicGridMultigrid::Level {
  std::array<int, 3> n{0, 0, 0};  // nodes = elements per axis
  int scale = 1;                  // voxels per element edge
  bool coarsest = false;
  BlockMatrix matrix;     // assembled operator (levels between the finest and the coarsest)
  std::vector<int> slot;  // 27 per node: slot of the block at each lattice offset
  ChebyshevSmoother smoother;
  VecX rhs, solution, residual;  // cycle workspace

  int nodes() const { return n[0] * n[1] * n[2]; }
  int node(int i, int j, int k) const {
    return wrap_periodic(i, n[0]) + n[0] * (wrap_periodic(j, n[1]) + n[1] * wrap_periodic(k, n[2]));
  }
  std::array<int, 3> coords(int p) const { return {p % n[0], (p / n[0]) % n[1], p / (n[0] * n[1])}; }
};

bool PeriodicGridMultigrid::supports(int nx, int ny, int nz) {
  for (int n : {nx, ny, nz})
    if (n < 4 || n % 2 != 0) return false;
  return true;
}

PeriodicGridMultigrid::~PeriodicGridMultigrid() = default;

PeriodicGridMultigrid::PeriodicGridMultigrid(VoxelStiffnessField field, const PeriodicMultigridOptions& options)
    : field_(std::move(field)), options_(options), single_precision_smoothers_(options.single_precision_smoothers) {
  const auto start = std::chrono::steady_clock::now();
  validate_field(field_, "periodic multigrid");
  if (!(options_.tolerance > 0) || options_.tolerance >= 1)
    throw InputError("periodic multigrid: tolerance must lie in (0, 1)");
  if (options_.max_iterations < 1) throw InputError("periodic multigrid: max_iterations must be >= 1");
  if (options_.smoother_degree < 1 || options_.smoother_degree > 10)
    throw InputError("periodic multigrid: smoother_degree must lie in 1..10");
  if (options_.coarsest_nodes < 8) throw InputError("periodic multigrid: coarsest_nodes must be >= 8");
  if (!supports(field_.nx, field_.ny, field_.nz))
    throw InputError("periodic multigrid: a " + dims_text({field_.nx, field_.ny, field_.nz}) +
                     " grid cannot be coarsened (every dimension must be even and at least 4)");

  // The hierarchy: always one coarsening, then more while the level is large and can be halved.
  auto level0 = std::make_unique<Level>();
  level0->n = {field_.nx, field_.ny, field_.nz};
  levels_.push_back(std::move(level0));
  for (;;) {
    const Level& last = *levels_.back();
    if (levels_.size() > 1 && (last.nodes() <= options_.coarsest_nodes || !supports(last.n[0], last.n[1], last.n[2])))
      break;
    auto next = std::make_unique<Level>();
    next->n = {last.n[0] / 2, last.n[1] / 2, last.n[2] / 2};
    next->scale = 2 * last.scale;
    levels_.push_back(std::move(next));
  }
  levels_.back()->coarsest = true;

  // Finest level: diagonal blocks, Chebyshev bound.
  const int B = field_.basis_size();
  const Level& fine = *levels_.front();
  const int nodes = fine.nodes();
  fine_diagonal_.assign(9 * std::size_t(nodes), 0.0);
  chunked_for(nodes, options_.threads, [&](Eigen::Index begin, Eigen::Index end) {
    for (Eigen::Index p = begin; p < end; ++p) {
      const auto c = fine.coords(static_cast<int>(p));
      Mat3 D = Mat3::Zero();
      for (int a = 0; a < 8; ++a) {
        const int e = fine.node(c[0] - corner_x(a), c[1] - corner_y(a), c[2] - corner_z(a));
        for (int b = 0; b < B; ++b)
          if (const double w = field_.weight(e, b); w != 0.0) D += w * field_.basis[b].block<3, 3>(3 * a, 3 * a);
      }
      Eigen::Map<Eigen::Matrix<double, 3, 3, Eigen::RowMajor>>(fine_diagonal_.data() + 9 * p) = D;
    }
  });
  if (chebyshev::invert_diagonal_blocks(nodes, fine_diagonal_.data(), fine_inverse_, options_.threads) != 0)
    throw NumericalError("periodic multigrid: a node's diagonal stiffness block is not positive definite");
  fine_max_eigenvalue_ = chebyshev::estimate_max_eigenvalue(
      nodes, fine_diagonal_.data(), fine_inverse_.data(), fine_rows(),
      [this](const VecX& x) { multiply(x, fine_product_); }, options_.threads);
  if (!(fine_max_eigenvalue_ > 0) || !std::isfinite(fine_max_eigenvalue_))
    throw NumericalError("periodic multigrid: no usable eigenvalue bound for the smoother");

  for (std::size_t l = 1; l < levels_.size(); ++l) build_level(l);
  stats_.analyze_seconds = seconds_since(start);
  stats_.positive_definite = true;
}

void PeriodicGridMultigrid::build_level(std::size_t l) {
  Level& level = *levels_[l];
  const int B = field_.basis_size();
  const int s = level.scale;
  // Q[pos][b] = P_pos^T K_b P_pos for every voxel position pos inside a coarse element.
  std::vector<Mat24> galerkin(std::size_t(s) * s * s * B);
#pragma omp parallel for schedule(static) num_threads(resolve_thread_count(options_.threads))
  for (int pos = 0; pos < s * s * s; ++pos) {
    const int pi = pos % s, pj = (pos / s) % s, pk = pos / (s * s);
    Mat24 P = Mat24::Zero();
    for (int c = 0; c < 8; ++c) {
      const double xi[3] = {double(pi + corner_x(c)) / s, double(pj + corner_y(c)) / s, double(pk + corner_z(c)) / s};
      for (int A = 0; A < 8; ++A) {
        const double phi =
            (corner_x(A) ? xi[0] : 1 - xi[0]) * (corner_y(A) ? xi[1] : 1 - xi[1]) * (corner_z(A) ? xi[2] : 1 - xi[2]);
        for (int d = 0; d < 3; ++d) P(3 * c + d, 3 * A + d) = phi;
      }
    }
    for (int b = 0; b < B; ++b) galerkin[std::size_t(pos) * B + b] = P.transpose() * field_.basis[b] * P;
  }

  const int nodes = level.nodes();
  if (level.coarsest) {
    // Small: assemble by triplets (duplicates add, which also handles a
    // dimension of 2, where a node is its own neighbour on both sides).
    std::vector<Eigen::Triplet<double>> triplets;
    triplets.reserve(std::size_t(nodes) * 576);
    for (int e = 0; e < nodes; ++e) {
      const Mat24 K = coarse_element(l, e, galerkin);
      const auto c = level.coords(e);
      int corner_node[8];
      for (int a = 0; a < 8; ++a)
        corner_node[a] = level.node(c[0] + corner_x(a), c[1] + corner_y(a), c[2] + corner_z(a));
      for (int a = 0; a < 8; ++a)
        for (int b = 0; b < 8; ++b)
          for (int r = 0; r < 3; ++r)
            for (int q = 0; q < 3; ++q)
              triplets.emplace_back(3 * corner_node[a] + r, 3 * corner_node[b] + q, K(3 * a + r, 3 * b + q));
    }
    const int N = 3 * nodes;
    coarsest_full_.resize(N, N);
    coarsest_full_.setFromTriplets(triplets.begin(), triplets.end());
    const SpMat pinned = coarsest_full_.block(3, 3, N - 3, N - 3);
    coarse_solver_.compute(pinned);
    if (coarse_solver_.info() != Eigen::Success)
      throw NumericalError("periodic multigrid: the coarsest operator (" + dims_text(level.n) +
                           ") is not positive definite; the cell's solid may not be connected");
    return;
  }

  // Block pattern: the 27 lattice neighbours of each node, in ascending order.
  BlockMatrix& M = level.matrix;
  M.rows = nodes;
  M.row_start.resize(std::size_t(nodes) + 1);
  M.column.resize(27 * std::size_t(nodes));
  M.diagonal.resize(nodes);
  level.slot.resize(27 * std::size_t(nodes));
  for (int p = 0; p < nodes; ++p) {
    M.row_start[p] = 27 * p;
    const auto c = level.coords(p);
    std::array<std::pair<int, int>, 27> neighbours;  // (node, code)
    for (int dz = -1; dz <= 1; ++dz)
      for (int dy = -1; dy <= 1; ++dy)
        for (int dx = -1; dx <= 1; ++dx)
          neighbours[offset_code(dx, dy, dz)] = {level.node(c[0] + dx, c[1] + dy, c[2] + dz), offset_code(dx, dy, dz)};
    std::sort(neighbours.begin(), neighbours.end());
    for (int t = 0; t < 27; ++t) {
      M.column[27 * std::size_t(p) + t] = neighbours[t].first;
      level.slot[27 * std::size_t(p) + neighbours[t].second] = 27 * p + t;
    }
    M.diagonal[p] = level.slot[27 * std::size_t(p) + offset_code(0, 0, 0)];
  }
  M.row_start[nodes] = 27 * nodes;
  M.values.assign(9 * std::size_t(M.num_blocks()), 0.0);
  // Scatter element matrices colour by colour: elements of one parity share
  // no node (dimensions are even), so a colour adds without conflicts and
  // the order of additions is fixed.
  const int half = nodes / 8;
  for (int colour = 0; colour < 8; ++colour) {
#pragma omp parallel for schedule(static) num_threads(resolve_thread_count(options_.threads))
    for (int t = 0; t < half; ++t) {
      const int hx = level.n[0] / 2, hy = level.n[1] / 2;
      const int i = 2 * (t % hx) + corner_x(colour), j = 2 * ((t / hx) % hy) + corner_y(colour),
                k = 2 * (t / (hx * hy)) + corner_z(colour);
      const int e = level.node(i, j, k);
      const Mat24 K = coarse_element(l, e, galerkin);
      for (int a = 0; a < 8; ++a) {
        const int row = level.node(i + corner_x(a), j + corner_y(a), k + corner_z(a));
        for (int b = 0; b < 8; ++b) {
          double* block = M.values.data() + 9 * std::size_t(level.slot[27 * std::size_t(row) + corner_code(a, b)]);
          for (int r = 0; r < 3; ++r)
            for (int q = 0; q < 3; ++q) block[3 * r + q] += K(3 * a + r, 3 * b + q);
        }
      }
    }
  }
  if (!level.smoother.setup(M, kCoarseDegreeFactor * options_.smoother_degree, options_.threads,
                            single_precision_smoothers_ ? SmootherValues::single : SmootherValues::double_values))
    throw NumericalError("periodic multigrid: a diagonal block of level " + std::to_string(l) + " (" +
                         dims_text(level.n) + ") is not positive definite");
}

Mat24 PeriodicGridMultigrid::coarse_element(std::size_t l, std::int64_t element,
                                            const std::vector<Mat24>& galerkin) const {
  const Level& level = *levels_[l];
  const int s = level.scale, B = field_.basis_size();
  const auto c = level.coords(static_cast<int>(element));
  Mat24 K = Mat24::Zero();
  for (int pk = 0; pk < s; ++pk)
    for (int pj = 0; pj < s; ++pj)
      for (int pi = 0; pi < s; ++pi) {
        const std::int64_t v =
            (s * c[0] + pi) + std::int64_t(field_.nx) * ((s * c[1] + pj) + std::int64_t(field_.ny) * (s * c[2] + pk));
        const std::size_t pos = std::size_t(pi + s * (pj + s * pk));
        for (int b = 0; b < B; ++b)
          if (const double w = field_.weight(v, b); w != 0.0) K.noalias() += w * galerkin[pos * B + b];
      }
  return K;
}

void PeriodicGridMultigrid::multiply(const VecX& x, VecX& y) const {
  const int nx = field_.nx, ny = field_.ny, nz = field_.nz;
  const Eigen::Index n = 3 * Eigen::Index(nx) * ny * nz;
  const int hy = ny / 2, rows = hy * (nz / 2);
  y.resize(n);
  const int team = resolve_thread_count(options_.threads);
  const ElementProductKernel product = element_product_kernel();
#pragma omp parallel num_threads(team) if (n > 3 * 4096)
  {
#pragma omp for schedule(static)
    for (Eigen::Index k = 0; k < n; ++k) y[k] = 0.0;
    // Voxels in natural order (x fastest), a row of the grid at a time:
    // rows whose j or k parity differ share no node (the dimensions are
    // even, so also across the periodic wrap), so each of the four colours
    // runs its rows in parallel, and every entry sums its voxels in the
    // same order for any thread count. (Single voxels coloured by parity
    // swept the grid eight times; docs/solvers.md.)
    for (int colour = 0; colour < 4; ++colour) {
      const int cj = colour & 1, ck = colour >> 1;
#pragma omp for schedule(static)
      for (int t = 0; t < rows; ++t) {
        const int j = 2 * (t % hy) + cj, k = 2 * (t / hy) + ck;
        const int j1 = j + 1 == ny ? 0 : j + 1, k1 = k + 1 == nz ? 0 : k + 1;
        for (int i = 0; i < nx; ++i) {
          const int xs[2] = {i, i + 1 == nx ? 0 : i + 1}, ys[2] = {j, j1}, zs[2] = {k, k1};
          int corner[8];
          for (int a = 0; a < 8; ++a) corner[a] = xs[corner_x(a)] + nx * (ys[corner_y(a)] + ny * zs[corner_z(a)]);
          Eigen::Matrix<double, 24, 1> xe, ye = Eigen::Matrix<double, 24, 1>::Zero();
          for (int a = 0; a < 8; ++a) xe.segment<3>(3 * a) = x.segment<3>(3 * Eigen::Index(corner[a]));
          const std::int64_t e = i + std::int64_t(nx) * (j + std::int64_t(ny) * k);
          add_voxel_product(field_, e, product, xe.data(), ye.data());
          for (int a = 0; a < 8; ++a) y.segment<3>(3 * Eigen::Index(corner[a])) += ye.segment<3>(3 * a);
        }
      }
    }
  }
}

void PeriodicGridMultigrid::cycle(std::size_t index, const VecX& rhs, VecX& solution) {
  // The periodic grid levels: the finest matrix-free (K x applied whole
  // before each smoothing pass and read back by rows), the others
  // assembled; full-weighting transfers on the periodic lattice; the
  // coarsest solved with its first node pinned, on zero-mean vectors.
  struct Levels : multigrid_cycle::SmoothedLevels<decltype(levels_)> {
    PeriodicGridMultigrid& s;
    int threads = s.options_.threads;
    int team = resolve_thread_count(threads);
    bool is_coarsest(std::size_t i) const { return s.levels_[i]->coarsest; }
    void solve_coarsest(std::size_t, const VecX& b, VecX& x) {
      VecX r = b;
      project_zero_mean(r, threads);
      const Eigen::Index N = r.size();
      x.resize(N);
      x.head<3>().setZero();
      x.tail(N - 3) = s.coarse_solver_.solve(r.tail(N - 3));
      project_zero_mean(x, threads);
    }
    void apply_fine(const VecX& x) { s.multiply(x, s.fine_product_); }
    void smooth(std::size_t i, const VecX& b, VecX& x, bool zero_start) {
      if (i == 0)
        chebyshev::smooth(
            s.levels_[0]->nodes(), s.fine_inverse_.data(), s.fine_max_eigenvalue_, s.options_.smoother_degree,
            s.fine_rows(), [this](const VecX& y) { apply_fine(y); }, b, x, zero_start, s.step_, s.next_, threads);
      else
        SmoothedLevels::smooth(i, b, x, zero_start);
    }
    void residual(std::size_t i, const VecX& b, const VecX& x, VecX& r) {
      if (i == 0) {
        apply_fine(x);
        chebyshev::residual(s.levels_[0]->nodes(), s.fine_rows(), b, x, r, threads);
      } else {
        SmoothedLevels::residual(i, b, x, r);
      }
    }
    // Restriction P^T r: each coarse node gathers the fine nodes within one
    // fine spacing of its point, weight 1 or 1/2 per axis.
    void restrict_to_coarse(std::size_t i, const VecX& r, VecX& coarse_rhs) {
      const Level& level = *s.levels_[i];
      const Level& coarse = *s.levels_[i + 1];
      coarse_rhs.resize(3 * Eigen::Index(coarse.nodes()));
      parallel_row_ranges(coarse.nodes(), team, [&](int begin, int end) {
        for (int P = begin; P < end; ++P) {
          const auto C = coarse.coords(P);
          Vec3 sum = Vec3::Zero();
          for (int dz = -1; dz <= 1; ++dz)
            for (int dy = -1; dy <= 1; ++dy)
              for (int dx = -1; dx <= 1; ++dx) {
                const double w = (dx ? 0.5 : 1.0) * (dy ? 0.5 : 1.0) * (dz ? 0.5 : 1.0);
                sum += w * r.segment<3>(3 * level.node(2 * C[0] + dx, 2 * C[1] + dy, 2 * C[2] + dz));
              }
          coarse_rhs.segment<3>(3 * P) = sum;
        }
      });
    }
    // Prolongation x += P x_c: a fine node interpolates the coarse nodes of
    // its enclosing coarse cell (1, 2, 4 or 8 of them).
    void add_prolongation(std::size_t i, const VecX& coarse_x, VecX& x) {
      const Level& level = *s.levels_[i];
      const Level& coarse = *s.levels_[i + 1];
      parallel_row_ranges(level.nodes(), team, [&](int begin, int end) {
        for (int p = begin; p < end; ++p) {
          const auto f = level.coords(p);
          Vec3 sum = Vec3::Zero();
          const int ox = f[0] % 2, oy = f[1] % 2, oz = f[2] % 2;
          const double w = (ox ? 0.5 : 1.0) * (oy ? 0.5 : 1.0) * (oz ? 0.5 : 1.0);
          for (int cz = 0; cz <= oz; ++cz)
            for (int cy = 0; cy <= oy; ++cy)
              for (int cx = 0; cx <= ox; ++cx)
                sum += coarse_x.segment<3>(3 * coarse.node(f[0] / 2 + cx, f[1] / 2 + cy, f[2] / 2 + cz));
          x.segment<3>(3 * p) += w * sum;
        }
      });
    }
  } levels{{levels_}, *this};
  multigrid_cycle::cycle(levels, index, rhs, solution);
}

VecX PeriodicGridMultigrid::apply_preconditioner(const VecX& r) {
  VecX z;
  cycle(0, r, z);
  project_zero_mean(z, options_.threads);
  return z;
}

VecX PeriodicGridMultigrid::solve(const VecX& b) {
  const Eigen::Index n = 3 * Eigen::Index(levels_.front()->nodes());
  if (b.size() != n)
    throw std::invalid_argument("PeriodicGridMultigrid::solve: right-hand side has " + std::to_string(b.size()) +
                                " entries, the grid has " + std::to_string(n) + " unknowns");
  VecX consistent = b;
  project_zero_mean(consistent, options_.threads);
  try {
    return solve_cg(consistent);
  } catch (const NumericalError& e) {
    if (stats_.positive_definite || !single_precision_smoothers_) throw;
    // The fine operator is exact (double, matrix-free), so an indefinite
    // preconditioner comes from the rounded coarse operators.
    spdlog::warn(
        "periodic multigrid: the preconditioner is indefinite with single-precision smoothers ({}); "
        "retrying with double precision",
        e.what());
    single_precision_smoothers_ = false;
    for (std::size_t l = 1; l < levels_.size(); ++l)
      if (!levels_[l]->coarsest) build_level(l);
    stats_.positive_definite = true;
    return solve_cg(consistent);
  }
}

VecX PeriodicGridMultigrid::solve_cg(const VecX& consistent) {
  const int threads = options_.threads;
  CgSetup cg = multigrid_cg_setup([this](const VecX& x, VecX& y) { multiply(x, y); },
                                  [this, threads](const VecX& r, VecX& z) {
                                    cycle(0, r, z);
                                    project_zero_mean(z, threads);
                                  },
                                  options_.tolerance, options_.max_iterations, threads, "periodic multigrid CG");
  cg.settings.max_iterations_key = options_.max_iterations_key;
  VecX x = conjugate_gradient(cg.op, cg.preconditioner, consistent, cg.settings, stats_);
  project_zero_mean(x, threads);
  return x;
}

std::array<int, 3> PeriodicGridMultigrid::level_dims(int level) const { return levels_.at(level)->n; }

SpMat PeriodicGridMultigrid::level_operator(int l) const {
  const Level& level = *levels_.at(l);
  if (level.coarsest) return coarsest_full_;
  if (l > 0) {
    SpMat S = sparse_pattern(level.matrix);
    copy_to_sparse(level.matrix, S);
    return S;
  }
  std::vector<Eigen::Triplet<double>> triplets;
  for (int e = 0; e < level.nodes(); ++e) {
    const Mat24 K = field_.element(e);
    const auto c = level.coords(e);
    for (int a = 0; a < 8; ++a)
      for (int b = 0; b < 8; ++b) {
        const int p = level.node(c[0] + corner_x(a), c[1] + corner_y(a), c[2] + corner_z(a));
        const int q = level.node(c[0] + corner_x(b), c[1] + corner_y(b), c[2] + corner_z(b));
        for (int r = 0; r < 3; ++r)
          for (int t = 0; t < 3; ++t) triplets.emplace_back(3 * p + r, 3 * q + t, K(3 * a + r, 3 * b + t));
      }
  }
  SpMat S(3 * level.nodes(), 3 * level.nodes());
  S.setFromTriplets(triplets.begin(), triplets.end());
  return S;
}

SpMat PeriodicGridMultigrid::prolongation(int l) const {
  const Level& fine = *levels_.at(l);
  if (fine.coarsest)
    throw std::invalid_argument("PeriodicGridMultigrid::prolongation: level " + std::to_string(l) + " is the coarsest");
  const Level& coarse = *levels_.at(l + 1);
  std::vector<Eigen::Triplet<double>> triplets;
  for (int p = 0; p < fine.nodes(); ++p) {
    const auto f = fine.coords(p);
    const int ox = f[0] % 2, oy = f[1] % 2, oz = f[2] % 2;
    const double w = (ox ? 0.5 : 1.0) * (oy ? 0.5 : 1.0) * (oz ? 0.5 : 1.0);
    for (int cz = 0; cz <= oz; ++cz)
      for (int cy = 0; cy <= oy; ++cy)
        for (int cx = 0; cx <= ox; ++cx) {
          const int P = coarse.node(f[0] / 2 + cx, f[1] / 2 + cy, f[2] / 2 + cz);
          for (int d = 0; d < 3; ++d) triplets.emplace_back(3 * p + d, 3 * P + d, w);
        }
  }
  SpMat S(3 * fine.nodes(), 3 * coarse.nodes());
  S.setFromTriplets(triplets.begin(), triplets.end());
  return S;
}

}  // namespace msfab
