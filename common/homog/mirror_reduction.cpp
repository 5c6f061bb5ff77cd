#include "homog/mirror_reduction.hpp"

#include <algorithm>
#include <cmath>

#include "core/errors.hpp"
#include "homog/elastic_tensor.hpp"
#include "solve/cholmod_solver.hpp"
#include "solve/conjugate_gradient.hpp"
#include "solve/dirichlet_grid_multigrid.hpp"

namespace msfab {
namespace {

// Corner a of a voxel sits at offset (a>>2&1, a>>1&1, a&1): axis d is bit 2 - d.
int corner_bit(int d) { return 1 << (2 - d); }

// Parity s_md of strain case m under the reflection of axis d: -1 when the
// reflection flips the unit strain's sign (a shear whose axes contain d).
int parity(int m, int d) {
  if (m < 3) return 1;
  const int p = m == 3 ? 1 : 0, q = m == 5 ? 1 : 2;  // yz, xz, xy
  return (d == p || d == q) ? -1 : 1;
}

// The octant's nodes: (n/2 + 1) per axis, node i + (hx + 1) (j + (hy + 1) k).
struct Octant {
  int h[3];
  std::int64_t nodes() const { return std::int64_t(h[0] + 1) * (h[1] + 1) * (h[2] + 1); }
  std::int64_t node(int i, int j, int k) const { return i + std::int64_t(h[0] + 1) * (j + std::int64_t(h[1] + 1) * k); }
  std::int64_t voxels() const { return std::int64_t(h[0]) * h[1] * h[2]; }
};

// Per octant unknown: 1 where the parity of case m pins it (module comment).
std::vector<char> pinned_unknowns(const Octant& o, int m) {
  std::vector<char> fixed(3 * std::size_t(o.nodes()), 0);
  for (int k = 0; k <= o.h[2]; ++k)
    for (int j = 0; j <= o.h[1]; ++j)
      for (int i = 0; i <= o.h[0]; ++i) {
        const int at[3] = {i, j, k};
        const std::int64_t p = o.node(i, j, k);
        for (int d = 0; d < 3; ++d) {
          if (at[d] != 0 && at[d] != o.h[d]) continue;
          for (int r = 0; r < 3; ++r)
            if ((parity(m, d) == 1) == (r == d)) fixed[3 * p + r] = 1;
        }
      }
  return fixed;
}

// Octant voxel (i, j, k) is voxel (i, j, k) of the cell.
VoxelStiffnessField octant_field(const VoxelStiffnessField& f, const Octant& o) {
  VoxelStiffnessField out;
  out.nx = o.h[0], out.ny = o.h[1], out.nz = o.h[2], out.h = f.h;
  out.basis = f.basis;
  const int B = f.basis_size();
  out.weights.resize(std::size_t(o.voxels()) * B);
  std::size_t w = 0;
  for (int k = 0; k < o.h[2]; ++k)
    for (int j = 0; j < o.h[1]; ++j)
      for (int i = 0; i < o.h[0]; ++i) {
        const std::int64_t v = i + std::int64_t(f.nx) * (j + std::int64_t(f.ny) * k);
        for (int b = 0; b < B; ++b) out.weights[w++] = f.weight(v, b);
      }
  return out;
}

// -sum_v K_v u^m over the octant's voxels (the affine corner displacements
// of strain m), pinned unknowns zeroed. One pass in voxel order:
// deterministic.
VecX octant_load(const VoxelStiffnessField& f, const Octant& o, int m, const std::vector<char>& fixed) {
  Vec6 e = Vec6::Zero();
  e[m] = 1;
  const Mat3 eps = strain_tensor(e);
  Eigen::Matrix<double, 24, 1> affine;
  for (int a = 0; a < 8; ++a) affine.segment<3>(3 * a) = eps * (f.h * Vec3(a >> 2 & 1, a >> 1 & 1, a & 1));
  std::vector<Eigen::Matrix<double, 24, 1>> basis_load(f.basis.size());
  for (std::size_t b = 0; b < f.basis.size(); ++b) basis_load[b] = -(f.basis[b] * affine);
  VecX load = VecX::Zero(3 * o.nodes());
  std::int64_t v = 0;
  for (int k = 0; k < o.h[2]; ++k)
    for (int j = 0; j < o.h[1]; ++j)
      for (int i = 0; i < o.h[0]; ++i, ++v)
        for (int b = 0; b < f.basis_size(); ++b) {
          const double w = f.weight(v, b);
          if (w == 0.0) continue;
          for (int a = 0; a < 8; ++a)
            load.segment<3>(3 * o.node(i + (a >> 2 & 1), j + (a >> 1 & 1), k + (a & 1))) +=
                w * basis_load[b].segment<3>(3 * a);
        }
  for (std::size_t d = 0; d < fixed.size(); ++d)
    if (fixed[d]) load[d] = 0.0;
  return load;
}

// The octant's stiffness on its free unknowns, assembled and factorized.
class OctantCholesky {
 public:
  OctantCholesky(const VoxelStiffnessField& f, const Octant& o, const std::vector<char>& fixed)
      : index_(fixed.size(), -1) {
    for (std::size_t d = 0; d < fixed.size(); ++d)
      if (!fixed[d]) index_[d] = free_++;
    std::vector<Eigen::Triplet<double>> triplets;
    triplets.reserve(std::size_t(o.voxels()) * 300);
    std::int64_t v = 0;
    int dof[24];
    for (int k = 0; k < o.h[2]; ++k)
      for (int j = 0; j < o.h[1]; ++j)
        for (int i = 0; i < o.h[0]; ++i, ++v) {
          for (int a = 0; a < 8; ++a) {
            const std::int64_t p = o.node(i + (a >> 2 & 1), j + (a >> 1 & 1), k + (a & 1));
            for (int r = 0; r < 3; ++r) dof[3 * a + r] = index_[3 * p + r];
          }
          const Mat24 K = f.element(v);
          for (int c = 0; c < 24; ++c)
            for (int r = c; r < 24; ++r)  // lower triangle: CHOLMOD reads one half
              if (dof[r] >= 0 && dof[c] >= 0)
                triplets.emplace_back(std::max(dof[r], dof[c]), std::min(dof[r], dof[c]), K(r, c));
        }
    SpMat lower(free_, free_);
    lower.setFromTriplets(triplets.begin(), triplets.end());
    // The solver factors the lower triangle and checks its residual with the whole matrix.
    A_ = lower.selfadjointView<Eigen::Lower>();
    LinearSolverOptions options;
    options.threads = 1;  // C^H must not depend on the thread count
    solver_ = std::make_unique<CholmodSolver>(options);
    solver_->analyze(A_);
    if (!solver_->factorize(A_))
      throw NumericalError("homogenization: the octant's stiffness matrix is not positive definite");
  }
  VecX solve(const VecX& load) const {
    VecX b(free_);
    for (std::size_t d = 0; d < index_.size(); ++d)
      if (index_[d] >= 0) b[index_[d]] = load[d];
    const VecX x = solver_->solve(b);
    VecX out = VecX::Zero(load.size());
    for (std::size_t d = 0; d < index_.size(); ++d)
      if (index_[d] >= 0) out[d] = x[index_[d]];
    return out;
  }
  int unknowns() const { return free_; }

 private:
  std::vector<int> index_;
  int free_ = 0;
  SpMat A_;  // the solver keeps a pointer to it
  std::unique_ptr<CholmodSolver> solver_;
};

// chi on the full lattice from the octant's: node i > n/2 is the mirror
// image of node n - i, and each reflection carries the parity factor
// s_md R_d (component d changes sign under R_d).
VecX unfold(const VoxelStiffnessField& f, const Octant& o, int m, const VecX& chi) {
  const int n[3] = {f.nx, f.ny, f.nz};
  VecX full(3 * f.voxels());
  std::int64_t p = 0;
  for (int k = 0; k < n[2]; ++k)
    for (int j = 0; j < n[1]; ++j)
      for (int i = 0; i < n[0]; ++i, ++p) {
        const int at[3] = {i, j, k};
        int folded[3];
        double sign[3] = {1, 1, 1};
        for (int d = 0; d < 3; ++d) {
          const bool image = at[d] > o.h[d];
          folded[d] = image ? n[d] - at[d] : at[d];
          if (!image) continue;
          for (int r = 0; r < 3; ++r) sign[r] *= parity(m, d) * (r == d ? -1 : 1);
        }
        const std::int64_t q = o.node(folded[0], folded[1], folded[2]);
        for (int r = 0; r < 3; ++r) full[3 * p + r] = sign[r] * chi[3 * q + r];
      }
  return full;
}

// Cases that share their pins: the normal ones (0, 1, 2), each shear alone.
int pin_group(int m) { return m < 3 ? 0 : m; }

}  // namespace

bool mirror_invariant(const VoxelStiffnessField& f) {
  const int n[3] = {f.nx, f.ny, f.nz};
  for (int d = 0; d < 3; ++d) {
    if (n[d] < 2 || n[d] % 2 != 0) return false;
    VoxelSymmetry mirror{{}, {0, 1, 2}, {1, 1, 1}};
    for (int a = 0; a < 8; ++a) mirror.corner[a] = a ^ corner_bit(d);
    mirror.sign[d] = -1;
    if (!basis_invariant(f, mirror)) return false;
  }
  for (std::int64_t v = 0; v < f.voxels(); ++v) {
    const int at[3] = {static_cast<int>(v % n[0]), static_cast<int>((v / n[0]) % n[1]),
                       static_cast<int>(v / (std::int64_t(n[0]) * n[1]))};
    for (int d = 0; d < 3; ++d) {
      int image[3] = {at[0], at[1], at[2]};
      image[d] = n[d] - 1 - at[d];
      if (!same_weights(f, v, image[0] + std::int64_t(n[0]) * (image[1] + std::int64_t(n[1]) * image[2]))) return false;
    }
  }
  return true;
}

std::string octant_solver(const VoxelStiffnessField& f, const std::string& option) {
  const bool grid = DirichletGridMultigrid::supports(f.nx / 2, f.ny / 2, f.nz / 2);
  if (option == "cholmod") return option;
  if (option == "matrix-free") return grid ? option : "cholmod";
  if (option == "auto") return grid && f.voxels() / 8 > kAutoOctantMultigridVoxels ? "matrix-free" : "cholmod";
  throw InputError("homogenization: unknown solver '" + option + "' (choose auto, direct or multigrid)");
}

OctantSolveReport solve_on_octant(const VoxelStiffnessField& field, const std::vector<int>& cases,
                                  const OctantSolverOptions& options, std::array<VecX, 6>& fluctuation) {
  if (!mirror_invariant(field)) throw InputError("homogenization: the cell is not mirror-symmetric");
  const Octant o{{field.nx / 2, field.ny / 2, field.nz / 2}};
  OctantSolveReport report;
  report.solver = octant_solver(field, options.solver);
  const VoxelStiffnessField octant = octant_field(field, o);
  for (int group : {0, 3, 4, 5}) {
    std::vector<int> members;
    for (int m : cases)
      if (pin_group(m) == group) members.push_back(m);
    if (members.empty()) continue;
    const std::vector<char> fixed = pinned_unknowns(o, group);
    if (report.solver == "cholmod") {
      const OctantCholesky cholesky(octant, o, fixed);
      report.unknowns = std::max<std::int64_t>(report.unknowns, cholesky.unknowns());
      for (int m : members) fluctuation[m] = unfold(field, o, m, cholesky.solve(octant_load(octant, o, m, fixed)));
    } else {
      DirichletMultigridOptions mg;
      copy_cg_limits(options, mg);
      mg.smoother_degree = options.smoother_degree;
      // A cell problem takes 10-50 CG iterations per set-up, too few to repay
      // factoring a 3000-unknown first coarse level (half the time at 32^3).
      mg.coarse_unknowns = 300;
      DirichletGridMultigrid solver(o.h[0], o.h[1], o.h[2], fixed, mg);
      solver.set_field(octant);
      report.unknowns = std::max<std::int64_t>(
          report.unknowns, std::int64_t(fixed.size()) - std::count(fixed.begin(), fixed.end(), char(1)));
      for (int m : members) {
        // Pinned rows of the grid operator read s x_d = b_d: zero loads keep them zero.
        fluctuation[m] = unfold(field, o, m, solver.solve(octant_load(octant, o, m, fixed)));
        report.iterations += solver.stats().iterations;
      }
    }
  }
  return report;
}

}  // namespace msfab
