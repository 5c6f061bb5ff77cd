#include "homog/periodic_homogenization.hpp"

#include <algorithm>
#include <array>
#include <chrono>
#include <cmath>
#include <memory>
#include <numeric>
#include <sstream>

#include "core/errors.hpp"
#include "fem/hex_element.hpp"
#include "homog/mirror_reduction.hpp"
#include "solve/cholmod_solver.hpp"
#include "solve/conjugate_gradient.hpp"
#include "solve/periodic_grid_multigrid.hpp"

namespace msfab {
namespace {

int find_root(std::vector<int>& parent, int v) {
  while (parent[v] != v) v = parent[v] = parent[parent[v]];
  return v;
}

}  // namespace

int count_periodic_pieces(const VoxelGrid& cell) {
  const int nx = cell.nx, ny = cell.ny, nz = cell.nz;
  std::vector<int> parent(cell.size());
  std::iota(parent.begin(), parent.end(), 0);
  for (int k = 0; k < nz; ++k)
    for (int j = 0; j < ny; ++j)
      for (int i = 0; i < nx; ++i) {
        if (cell.at(i, j, k) == 0) continue;
        const int v = static_cast<int>(cell.index(i, j, k));
        for (int dk = -1; dk <= 1; ++dk)
          for (int dj = -1; dj <= 1; ++dj)
            for (int di = -1; di <= 1; ++di) {
              const int w = static_cast<int>(
                  cell.index(wrap_periodic(i + di, nx), wrap_periodic(j + dj, ny), wrap_periodic(k + dk, nz)));
              if (cell.ids[w] != 0) parent[find_root(parent, v)] = find_root(parent, w);
            }
      }
  int pieces = 0;
  for (std::size_t v = 0; v < cell.size(); ++v)
    if (cell.ids[v] != 0 && find_root(parent, static_cast<int>(v)) == static_cast<int>(v)) ++pieces;
  return pieces;
}

HomogenizationResult homogenize(const VoxelGrid& cell, const std::vector<MaterialPtr>& palette,
                                const HomogenizationOptions& options) {
  const int nx = cell.nx, ny = cell.ny, nz = cell.nz;
  if (nx < 1 || ny < 1 || nz < 1 || cell.size() != std::size_t(nx) * ny * nz)
    throw InputError("homogenization: the cell has no voxels");
  if (!(options.void_stiffness > 0)) throw InputError("homogenization: void_stiffness must be > 0");
  std::vector<double> fraction(palette.size(), 0.0);
  for (int id : cell.ids) {
    if (id < 0 || id >= static_cast<int>(palette.size()) || (id > 0 && !palette[id])) {
      std::ostringstream os;
      os << "homogenization: voxel material id " << id << " is not in the palette (ids 1.." << palette.size() - 1
         << ", 0 = void)";
      throw InputError(os.str());
    }
    fraction[id] += 1.0 / cell.size();
  }
  if (fraction[0] >= 1.0) throw InputError("homogenization: the cell is all void");

  // Element stiffness per palette id (at rest); void: a fraction of the
  // stiffest. One basis matrix per id, weights one-hot.
  VoxelStiffnessField field;
  field.nx = nx, field.ny = ny, field.nz = nz, field.h = cell.voxel_size;
  field.basis.assign(palette.size(), Mat24::Zero());
  int stiffest = -1;
  for (std::size_t id = 1; id < palette.size(); ++id) {
    if (!palette[id] || fraction[id] == 0) continue;
    field.basis[id] = voxel_stiffness(palette[id], cell.voxel_size);
    if (stiffest < 0 || palette[id]->shear_modulus() > palette[stiffest]->shear_modulus())
      stiffest = static_cast<int>(id);
  }
  field.basis[0] = options.void_stiffness * field.basis[stiffest];
  field.weights.assign(cell.size() * palette.size(), 0.0);
  for (std::size_t v = 0; v < cell.size(); ++v) field.weights[v * palette.size() + cell.ids[v]] = 1.0;
  HomogenizationResult out = homogenize_elements(field, options);
  out.volume_fraction = fraction;
  out.pieces = count_periodic_pieces(cell);
  return out;
}

Mat24 voxel_stiffness(const MaterialPtr& material, double h) {
  const hex8::NodeMatrix X = voxel_corners(h);
  const hex8::ElementGeometry geo = hex8::element_geometry(X, hex8::gauss_rule(2));
  Mat24 K = Mat24::Zero();
  hex_evaluate(geo, QuadratureMaterials{{material}}, X, nullptr, &K);
  return K;
}

hex8::NodeMatrix voxel_corners(double h) {
  hex8::NodeMatrix X;
  for (int a = 0; a < 8; ++a) X.row(a) = h * Vec3(a >> 2 & 1, a >> 1 & 1, a & 1).transpose();
  return X;
}

Eigen::Matrix<double, 24, 6> total_element_displacements(const HomogenizationResult& r, int nx, int ny, int nz,
                                                         double h, std::int64_t voxel) {
  const hex8::NodeMatrix X = voxel_corners(h);
  const int i = static_cast<int>(voxel % nx), j = static_cast<int>((voxel / nx) % ny),
            k = static_cast<int>(voxel / (std::int64_t(nx) * ny));
  Eigen::Matrix<double, 24, 6> U;
  for (int m = 0; m < 6; ++m) {
    Vec6 e = Vec6::Zero();
    e[m] = 1;
    const Mat3 eps = strain_tensor(e);
    for (int a = 0; a < 8; ++a) {
      const std::int64_t q =
          wrap_periodic(i + (a >> 2 & 1), nx) +
          nx * (wrap_periodic(j + (a >> 1 & 1), ny) + std::int64_t(ny) * wrap_periodic(k + (a & 1), nz));
      U.col(m).segment<3>(3 * a) = eps * X.row(a).transpose() + r.fluctuation[m].segment<3>(3 * q);
    }
  }
  return U;
}

std::string homogenization_solver(int nx, int ny, int nz, const std::string& option) {
  if (option == "cholmod") return option;
  if (option == "matrix-free") {
    if (!PeriodicGridMultigrid::supports(nx, ny, nz))
      throw InputError("homogenization: solver matrix-free needs every cell dimension even and at least 4, got " +
                       std::to_string(nx) + " x " + std::to_string(ny) + " x " + std::to_string(nz));
    return option;
  }
  if (option == "auto")
    return PeriodicGridMultigrid::supports(nx, ny, nz) && std::int64_t(nx) * ny * nz >= kAutoMultigridVoxels
               ? "matrix-free"
               : "cholmod";
  throw InputError("homogenization: unknown solver '" + option + "' (choose auto, cholmod or matrix-free)");
}

double homogenization_peak_bytes(int nx, int ny, int nz, const std::string& option) {
  const double n = double(nx) * ny * nz;
  if (nz == 1) return 24e3 * n;
  return homogenization_solver(nx, ny, nz, option) == "cholmod" ? 3.3e3 * std::pow(n, 4.0 / 3.0) : 1.3e3 * n;
}

namespace {

// -K u^m gathered per node (3 rows per node, one column per unit strain):
// each node sums the loads of its 8 elements, so the result does not depend
// on the thread count.
Eigen::MatrixXd strain_loads(const VoxelStiffnessField& field) {
  const int nx = field.nx, ny = field.ny, nz = field.nz;
  const hex8::NodeMatrix X = voxel_corners(field.h);
  // Affine corner displacements of a voxel for each unit strain (the same
  // for every voxel up to a rigid translation, which K_e ignores).
  Eigen::Matrix<double, 24, 6> UA;
  for (int m = 0; m < 6; ++m) {
    Vec6 e = Vec6::Zero();
    e[m] = 1;
    const Mat3 eps = strain_tensor(e);
    for (int a = 0; a < 8; ++a) UA.col(m).segment<3>(3 * a) = eps * X.row(a).transpose();
  }
  std::vector<Eigen::Matrix<double, 24, 6>> basis_loads(field.basis.size());
  for (std::size_t b = 0; b < field.basis.size(); ++b) basis_loads[b] = -(field.basis[b] * UA);
  const std::int64_t nodes = field.voxels();
  Eigen::MatrixXd B = Eigen::MatrixXd::Zero(3 * nodes, 6);
#pragma omp parallel for schedule(static)
  for (std::int64_t p = 0; p < nodes; ++p) {
    const int i = static_cast<int>(p % nx), j = static_cast<int>((p / nx) % ny),
              k = static_cast<int>(p / (std::int64_t(nx) * ny));
    for (int a = 0; a < 8; ++a) {  // p is corner a of element (i, j, k) - offset(a)
      const std::int64_t e =
          wrap_periodic(i - (a >> 2 & 1), nx) +
          nx * (wrap_periodic(j - (a >> 1 & 1), ny) + std::int64_t(ny) * wrap_periodic(k - (a & 1), nz));
      for (int b = 0; b < field.basis_size(); ++b)
        if (const double w = field.weight(e, b); w != 0.0)
          B.middleRows<3>(3 * p) += w * basis_loads[b].middleRows<3>(3 * a);
    }
  }
  return B;
}

// Cells up to this many voxels keep their symbolic analysis per thread.
// Small cells (DDFEM blocks, the windows of the checked lookup) are
// homogenized by the thousand, all of one size, and the pattern of K is
// that of the size alone (every element's entries are assembled, void ones
// as zeros); the METIS ordering, which runs one at a time process-wide,
// was then a third of each homogenization and serialized the threads.
// The ordering of a pattern does not depend on when it is computed, so
// the results are the same bits.
constexpr std::int64_t kCachedAnalysisVoxels = 12 * 12 * 12;

// One BLAS thread for the cells' factorizations: a multithreaded
// supernodal factorization rounds differently per thread count, and C^H
// must not depend on it.
LinearSolverOptions cell_solver_options() {
  LinearSolverOptions options;
  options.threads = 1;
  return options;
}

// The calling thread's kept solver analyzed for A, the stiffness of a small
// nx x ny x nz cell (analyzed now if the size is new to the thread), or
// null for a cell above kCachedAnalysisVoxels, whose factor is not kept.
CholmodSolver* kept_analyzed_solver(const SpMat& A, int nx, int ny, int nz) {
  if (std::int64_t(nx) * ny * nz > kCachedAnalysisVoxels) return nullptr;
  struct Kept {
    std::array<int, 3> size{-1, -1, -1};
    std::unique_ptr<CholmodSolver> solver;
  };
  thread_local Kept kept;
  const std::array<int, 3> size{nx, ny, nz};
  if (!kept.solver || kept.size != size) {
    kept.solver = std::make_unique<CholmodSolver>(cell_solver_options());
    kept.size = {-1, -1, -1};  // an analysis that throws keeps no size
    kept.solver->analyze(A);
    kept.size = size;
  }
  return kept.solver.get();
}

// The direct solver: K assembled with node 0 pinned (it removes the
// translations), factorized once, six solves.
void solve_direct(const VoxelStiffnessField& field, const Eigen::MatrixXd& loads, HomogenizationResult& out,
                  const std::vector<int>& cases) {
  const int nx = field.nx, ny = field.ny, nz = field.nz;
  const std::int64_t N = field.voxels();
  auto node = [&](int i, int j, int k) -> std::int64_t {
    return wrap_periodic(i, nx) + nx * (wrap_periodic(j, ny) + std::int64_t(ny) * wrap_periodic(k, nz));
  };
  out.unknowns = 3 * N - 3;
  // Assemble node by node (each column gathers its 8 elements): deterministic for any thread count.
  std::vector<std::vector<Eigen::Triplet<double>>> per_node(N);
#pragma omp parallel for schedule(static)
  for (std::int64_t p = 0; p < N; ++p) {
    const int i = static_cast<int>(p % nx), j = static_cast<int>((p / nx) % ny),
              k = static_cast<int>(p / (std::int64_t(nx) * ny));
    auto& trip = per_node[p];
    if (p == 0) continue;
    for (int a = 0; a < 8; ++a) {  // p is node a of element e = (i, j, k) - offset(a)
      const int ei = i - (a >> 2 & 1), ej = j - (a >> 1 & 1), ek = k - (a & 1);
      const Mat24 K = field.element(node(ei, ej, ek));
      for (int b = 0; b < 8; ++b) {
        const std::int64_t q = node(ei + (b >> 2 & 1), ej + (b >> 1 & 1), ek + (b & 1));
        if (q == 0) continue;
        for (int r = 0; r < 3; ++r)
          for (int c = 0; c < 3; ++c)
            trip.emplace_back(static_cast<int>(3 * q + r - 3), static_cast<int>(3 * p + c - 3),
                              K(3 * b + r, 3 * a + c));
      }
    }
  }
  std::vector<Eigen::Triplet<double>> all;
  for (auto& t : per_node) all.insert(all.end(), t.begin(), t.end()), std::vector<Eigen::Triplet<double>>().swap(t);
  SpMat A(out.unknowns, out.unknowns);
  A.setFromTriplets(all.begin(), all.end());
  std::vector<Eigen::Triplet<double>>().swap(all);
  std::unique_ptr<CholmodSolver> own;
  CholmodSolver* kept = kept_analyzed_solver(A, nx, ny, nz);
  if (!kept) {
    own = std::make_unique<CholmodSolver>(cell_solver_options());
    own->analyze(A);
  }
  CholmodSolver& solver = kept ? *kept : *own;
  if (!solver.factorize(A))
    throw NumericalError("homogenization: the cell's stiffness matrix is not positive definite");
  for (int m : cases) {
    const VecX x = solver.solve(loads.col(m).tail(3 * N - 3));
    out.fluctuation[m] = VecX::Zero(3 * N);
    out.fluctuation[m].tail(3 * N - 3) = x;
  }
}

// The cyclic permutation P: position (x, y, z) -> (z, x, y), so P e_x = e_y,
// P e_y = e_z, P e_z = e_x; a displacement's component r moves to r + 1.
int cyclic_corner(int a) {  // corner offset (ox, oy, oz) -> (oz, ox, oy)
  const int ox = a >> 2 & 1, oy = a >> 1 & 1, oz = a & 1;
  return oz << 2 | ox << 1 | oy;
}

// Strain case m -> the case P carries it to: xx -> yy -> zz, yz -> xz -> xy.
constexpr int kCyclicCase[6] = {1, 2, 0, 4, 5, 3};

// chi_{P eps P^T}(node sigma(p)) = P chi_eps(node p), sigma(i, j, k) = (k, i, j).
VecX permute_fluctuation(const VecX& chi, int n) {
  VecX out(chi.size());
  const std::int64_t nodes = std::int64_t(n) * n * n;
  for (std::int64_t p = 0; p < nodes; ++p) {
    const int i = static_cast<int>(p % n), j = static_cast<int>((p / n) % n),
              k = static_cast<int>(p / (std::int64_t(n) * n));
    const std::int64_t q = k + n * (i + std::int64_t(n) * j);
    for (int r = 0; r < 3; ++r) out[3 * q + (r + 1) % 3] = chi[3 * p + r];
  }
  return out;
}

void solve_multigrid(const VoxelStiffnessField& field, const Eigen::MatrixXd& loads,
                     const HomogenizationOptions& options, HomogenizationResult& out, const std::vector<int>& cases) {
  PeriodicMultigridOptions mg;
  copy_cg_limits(options, mg);
  mg.smoother_degree = options.multigrid_smoother_degree;
  mg.coarsest_nodes = options.multigrid_coarsest_nodes;
  PeriodicGridMultigrid solver(field, mg);
  out.unknowns = 3 * field.voxels();
  for (int m : cases) {
    VecX x = solver.solve(loads.col(m));
    // The same gauge as the direct solver: zero at node 0.
    const Vec3 shift = x.head<3>();
    for (std::int64_t p = 0; p < field.voxels(); ++p) x.segment<3>(3 * p) -= shift;
    out.fluctuation[m] = std::move(x);
    out.iterations += solver.stats().iterations;
  }
}

}  // namespace

bool cyclic_invariant(const VoxelStiffnessField& f) {
  const int n = f.nx;
  if (f.ny != n || f.nz != n || n < 2) return false;
  VoxelSymmetry cyclic{{}, {1, 2, 0}, {1, 1, 1}};
  for (int a = 0; a < 8; ++a) cyclic.corner[a] = cyclic_corner(a);
  if (!basis_invariant(f, cyclic)) return false;
  for (std::int64_t v = 0; v < f.voxels(); ++v) {
    const int i = static_cast<int>(v % n), j = static_cast<int>((v / n) % n),
              k = static_cast<int>(v / (std::int64_t(n) * n));
    if (!same_weights(f, v, k + n * (i + std::int64_t(n) * j))) return false;
  }
  return true;
}

HomogenizationResult homogenize_elements(const VoxelStiffnessField& field, const HomogenizationOptions& options) {
  const auto t0 = std::chrono::steady_clock::now();
  validate_field(field, "homogenization");
  if (!(options.tolerance > 0) || options.tolerance >= 1)
    throw InputError("homogenization: tolerance must lie in (0, 1)");
  if (options.max_iterations < 1) throw InputError("homogenization: max_iterations must be at least 1");
  const int nx = field.nx, ny = field.ny, nz = field.nz;
  const double h = field.h;
  const std::int64_t cells = field.voxels();
  HomogenizationResult out;
  out.solver = homogenization_solver(nx, ny, nz, options.solver);
  const bool symmetric = options.use_symmetry && cyclic_invariant(field);
  const std::vector<int> cases = symmetric ? std::vector<int>{0, 3} : std::vector<int>{0, 1, 2, 3, 4, 5};
  out.octant = options.use_mirror_symmetry && mirror_invariant(field);
  if (out.octant) {
    OctantSolverOptions octant;
    octant.solver = options.solver;
    copy_cg_limits(options, octant);
    octant.smoother_degree = options.multigrid_smoother_degree;
    const OctantSolveReport report = solve_on_octant(field, cases, octant, out.fluctuation);
    out.solver = report.solver;
    out.unknowns = report.unknowns;
    out.iterations = report.iterations;
  } else if (const Eigen::MatrixXd loads = strain_loads(field); out.solver == "cholmod") {
    solve_direct(field, loads, out, cases);
  } else {
    solve_multigrid(field, loads, options, out, cases);
  }
  if (symmetric)
    for (int m : {0, 3})
      for (int step = 0, from = m; step < 2; ++step, from = kCyclicCase[from])
        out.fluctuation[kCyclicCase[from]] = permute_fluctuation(out.fluctuation[from], nx);
  out.symmetric_cases = symmetric;
  // C^H from the element energies of the total fields, summed per element
  // first and then in element order (deterministic).
  std::vector<Mat6> contribution(cells);
#pragma omp parallel for schedule(static)
  for (std::int64_t v = 0; v < cells; ++v) {
    const Eigen::Matrix<double, 24, 6> U = total_element_displacements(out, nx, ny, nz, h, v);
    contribution[v] = U.transpose() * field.element(v) * U;
  }
  for (const Mat6& c : contribution) out.C += c;
  out.C /= double(cells) * h * h * h;
  out.C = 0.5 * (out.C + out.C.transpose());
  out.G = out.C.inverse();
  out.seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  return out;
}

PlaneStrainResult homogenize_plane_strain(const VoxelGrid& cell, const std::vector<MaterialPtr>& palette,
                                          const HomogenizationOptions& options) {
  if (cell.nz != 1)
    throw InputError("homogenization: a 2D (plane strain) cell has one voxel along z, this one has " +
                     std::to_string(cell.nz));
  PlaneStrainResult r;
  r.full = homogenize(cell, palette, options);
  r.C = plane_block(r.full.C);
  r.G = r.C.inverse();
  return r;
}

PlaneModuli plane_moduli(const Mat3& C) {
  const Mat3 S = C.inverse();
  PlaneModuli m;
  m.Ex = 1 / S(0, 0);
  m.Ey = 1 / S(1, 1);
  m.nu_xy = -S(0, 1) / S(0, 0);
  m.G = 1 / S(2, 2);
  return m;
}

}  // namespace msfab
