// Coarse spaces that follow the material (solve/material_components.hpp,
// solve/component_multigrid.hpp): copies per piece across a gap, a
// partition of unity on every piece at every level, nested pieces, the
// lattice hierarchy on a solid box, level 1 as the Galerkin product, and
// the matrix-free CG on a structure with gaps against a direct solve, in
// fewer iterations than the lattice coarse space, for any thread count;
// levels held by their upper blocks (the large grids' path) give the same
// Galerkin products and the same solve.
#include <gtest/gtest.h>

#include <Eigen/SparseCholesky>
#include <algorithm>
#include <random>

#include "core/errors.hpp"
#include "fem/voxel_stiffness_field.hpp"
#include "homog/periodic_homogenization.hpp"
#include "material/linear_isotropic.hpp"
#include "solve/chebyshev_smoother.hpp"
#include "solve/component_multigrid.hpp"
#include "solve/dirichlet_grid_multigrid.hpp"
#include "solve/material_components.hpp"

namespace msfab {
namespace {

std::int64_t voxel_of(int nx, int ny, int i, int j, int k) { return i + std::int64_t(nx) * (j + std::int64_t(ny) * k); }
std::int64_t components_node_of(int nx, int ny, int i, int j, int k) {
  return i + std::int64_t(nx + 1) * (j + std::int64_t(ny + 1) * k);
}

// A comb: a solid back plate at x < 2 and teeth along x, one voxel thick
// in y with one-voxel gaps between them, so that every coarse hat function
// at a gap spans two teeth that move apart freely.
std::vector<char> comb(int nx, int ny, int nz) {
  std::vector<char> solid(std::size_t(nx) * ny * nz, 0);
  for (int k = 0; k < nz; ++k)
    for (int j = 0; j < ny; ++j)
      for (int i = 0; i < nx; ++i) solid[std::size_t(voxel_of(nx, ny, i, j, k))] = (i < 2 || j % 2 == 0);
  return solid;
}

VoxelStiffnessField field_of(int nx, int ny, int nz, const std::vector<char>& solid) {
  VoxelStiffnessField f;
  f.nx = nx, f.ny = ny, f.nz = nz, f.h = 1.0 / nx;
  f.basis = {voxel_stiffness(std::make_shared<LinearIsotropic>(1.0, 0.3), f.h)};
  f.weights.resize(std::size_t(f.voxels()));
  for (std::int64_t v = 0; v < f.voxels(); ++v) f.weights[std::size_t(v)] = solid[std::size_t(v)] ? 1.0 : 0.0;
  return f;
}

// Whether node (i, j, k) is a corner of a solid voxel.
bool touches_material(int nx, int ny, int nz, const std::vector<char>& solid, int i, int j, int k) {
  for (int dz = -1; dz <= 0; ++dz)
    for (int dy = -1; dy <= 0; ++dy)
      for (int dx = -1; dx <= 0; ++dx) {
        const int vi = i + dx, vj = j + dy, vk = k + dz;
        if (vi >= 0 && vj >= 0 && vk >= 0 && vi < nx && vj < ny && vk < nz &&
            solid[std::size_t(voxel_of(nx, ny, vi, vj, vk))])
          return true;
      }
  return false;
}

// Nodes at x = 0 clamped, nodes that touch no solid voxel fixed (void
// carries no unknowns, as in msfab-verify-map).
std::vector<char> clamped_without_void(int nx, int ny, int nz, const std::vector<char>& solid) {
  std::vector<char> fixed(3 * std::size_t(nx + 1) * (ny + 1) * (nz + 1), 0);
  for (int k = 0; k <= nz; ++k)
    for (int j = 0; j <= ny; ++j)
      for (int i = 0; i <= nx; ++i) {
        if (i == 0 || !touches_material(nx, ny, nz, solid, i, j, k))
          for (int d = 0; d < 3; ++d) fixed[3 * std::size_t(components_node_of(nx, ny, i, j, k)) + d] = 1;
      }
  return fixed;
}

// Per row of a transfer with parents: the weights sum to 1.
void expect_partition_of_unity(const ComponentTransfer& t, const ComponentLevel& fine) {
  int rows_with_parents = 0;
  for (int f = 0; f < t.fine_rows(); ++f) {
    if (fine.representative[std::size_t(f)] < 0) {
      EXPECT_EQ(t.parent_start[std::size_t(f) + 1], t.parent_start[std::size_t(f)]);
      continue;
    }
    double sum = 0.0;
    for (int s = t.parent_start[std::size_t(f)]; s < t.parent_start[std::size_t(f) + 1]; ++s)
      sum += t.parent_weight[std::size_t(s)];
    EXPECT_NEAR(sum, 1.0, 1e-15) << "row " << f;
    ++rows_with_parents;
  }
  EXPECT_GT(rows_with_parents, 0);
}

TEST(MaterialComponents, CopiesPerPieceAndPartitionOfUnityAtEveryLevel) {
  const int nx = 16, ny = 8, nz = 4;
  const std::vector<char> solid = comb(nx, ny, nz);
  const MaterialComponents components(nx, ny, nz, solid, 10, 1);
  const auto& levels = components.levels();
  ASSERT_GE(levels.size(), 3u);
  // Level 1 at the gap between teeth j = 2 and j = 4 (lattice point y = 2,
  // y = 3 the gap), away from the back plate: two pieces, two copies.
  const ComponentLevel& level1 = levels[1];
  const std::int64_t gap = level1.point(6, 1, 1);
  EXPECT_EQ(level1.first[std::size_t(gap) + 1] - level1.first[std::size_t(gap)], 2);
  // Over the back plate the teeth join: one copy.
  const std::int64_t plate = level1.point(0, 1, 1);
  EXPECT_EQ(level1.first[std::size_t(plate) + 1] - level1.first[std::size_t(plate)], 1);
  for (std::size_t l = 0; l + 1 < levels.size(); ++l) expect_partition_of_unity(components.transfers()[l], levels[l]);
  // Each copy's piece lies in exactly one piece of a coarser point: one
  // parent per coarse lattice point.
  for (std::size_t l = 1; l + 1 < levels.size(); ++l) {
    const ComponentTransfer& t = components.transfers()[l];
    const ComponentLevel& coarse = levels[l + 1];
    for (int f = 0; f < t.fine_rows(); ++f) {
      std::vector<std::int64_t> points;
      for (int s = t.parent_start[std::size_t(f)]; s < t.parent_start[std::size_t(f) + 1]; ++s) {
        const int C = t.parent[std::size_t(s)];
        points.push_back(std::upper_bound(coarse.first.begin(), coarse.first.end(), C) - coarse.first.begin() - 1);
      }
      std::sort(points.begin(), points.end());
      EXPECT_EQ(std::adjacent_find(points.begin(), points.end()), points.end()) << "level " << l << " copy " << f;
    }
  }
}

// The fine level carries rows only for nodes that touch material; a node
// that only void touches must be fixed, and its solution is b / s.
TEST(MaterialComponents, OnlyNodesThatTouchMaterialCarryRows) {
  const int nx = 12, ny = 8, nz = 4;
  std::vector<char> solid = comb(nx, ny, nz);
  for (int k = 0; k < nz; ++k)  // cut every tooth short: void at the far end
    for (int j = 0; j < ny; ++j)
      for (int i = nx - 3; i < nx; ++i) solid[std::size_t(voxel_of(nx, ny, i, j, k))] = 0;
  std::vector<char> fixed = clamped_without_void(nx, ny, nz, solid);
  std::int64_t touching = 0;
  for (int k = 0; k <= nz; ++k)
    for (int j = 0; j <= ny; ++j)
      for (int i = 0; i <= nx; ++i) touching += touches_material(nx, ny, nz, solid, i, j, k);
  DirichletMultigridOptions options;
  options.material_coarse_space = true;
  options.coarse_unknowns = 30;
  options.tolerance = 1e-10;
  DirichletGridMultigrid mg(nx, ny, nz, fixed, options);
  mg.set_field(field_of(nx, ny, nz, solid));
  EXPECT_EQ(mg.rows(), touching);
  EXPECT_LT(touching, std::int64_t(nx + 1) * (ny + 1) * (nz + 1));
  // Against a direct solve of the whole grid, fixed values prescribed
  // through b = s u on every fixed unknown, void nodes included.
  VecX b = VecX::Zero(3 * std::int64_t(nx + 1) * (ny + 1) * (nz + 1));
  for (Eigen::Index d = 0; d < b.size(); ++d)
    b[d] = fixed[std::size_t(d)] ? mg.fixed_scale() * 1e-3 * double(d % 7) : 1e-4;
  const VecX x = mg.solve(b);
  Eigen::SimplicialLDLT<SpMat> direct(mg.fine_operator());
  ASSERT_EQ(direct.info(), Eigen::Success);
  const VecX reference = direct.solve(b);
  EXPECT_LT((x - reference).norm(), 1e-8 * reference.norm());
  VecX y;
  mg.multiply(x, y);
  EXPECT_LT((y - mg.fine_operator() * x).norm(), 1e-12 * y.norm());
  // A node that only void touches left free: refused.
  for (std::size_t d = 0; d < fixed.size(); ++d)
    if (fixed[d] && d / 3 % std::size_t(nx + 1) == std::size_t(nx)) {
      fixed[d] = 0;
      break;
    }
  DirichletGridMultigrid loose(nx, ny, nz, fixed, options);
  EXPECT_THROW(loose.set_field(field_of(nx, ny, nz, solid)), NumericalError);
}

TEST(MaterialComponents, SolidBoxHasOneCopyPerLatticePoint) {
  const int nx = 8, ny = 6, nz = 4;
  const MaterialComponents components(nx, ny, nz, std::vector<char>(std::size_t(nx) * ny * nz, 1), 1, 1);
  for (const ComponentLevel& level : components.levels()) EXPECT_EQ(level.copies(), level.num_points());
  EXPECT_EQ(components.levels()[1].points[0], 5);
  EXPECT_EQ(components.levels()[1].points[1], 4);
  EXPECT_EQ(components.levels()[2].points[1], 3);  // level-1 points 0..3: 0, 2 and 4 (covers 3)
  EXPECT_THROW(MaterialComponents(5, 4, 4, std::vector<char>(80, 1), 1, 1), InputError);
}

TEST(MaterialComponents, LevelOneIsTheGalerkinProductOfThePieces) {
  const int nx = 12, ny = 8, nz = 4;
  const std::vector<char> solid = comb(nx, ny, nz);
  DirichletMultigridOptions options;
  options.material_coarse_space = true;
  options.coarse_unknowns = 30;
  DirichletGridMultigrid mg(nx, ny, nz, clamped_without_void(nx, ny, nz, solid), options);
  mg.set_field(field_of(nx, ny, nz, solid));
  const SpMat A = mg.fine_operator(), P = mg.prolongation(), Ac = mg.coarse_operator();
  const MatX reference = MatX(SpMat(P.transpose()) * A * P);
  MatX difference = MatX(Ac) - reference;
  // Unknowns P does not reach (clamped) hold a diagonal on the level.
  for (Eigen::Index u = 0; u < Ac.rows(); ++u)
    if (reference.row(u).norm() == 0.0) difference(u, u) = 0.0;
  EXPECT_LT(difference.norm(), 1e-12 * reference.norm());
  EXPECT_GE(mg.num_levels(), 3);
}

TEST(MaterialComponents, CombSolvesLikeADirectSolverInFewerIterations) {
  const int nx = 24, ny = 16, nz = 4;
  const std::vector<char> solid = comb(nx, ny, nz);
  const std::vector<char> fixed = clamped_without_void(nx, ny, nz, solid);
  VecX b = VecX::Zero(3 * std::int64_t(nx + 1) * (ny + 1) * (nz + 1));
  for (int k = 0; k <= nz; ++k)  // the teeth's tips pushed sideways
    for (int j = 0; j <= ny; ++j) {
      const std::int64_t d = 3 * components_node_of(nx, ny, nx, j, k) + 1;
      if (!fixed[std::size_t(d)]) b[d] = 1e-3;
    }
  int iterations[2];
  VecX solution[2];
  for (int material = 0; material < 2; ++material) {
    DirichletMultigridOptions options;
    options.tolerance = 1e-10;
    options.coarse_unknowns = 60;
    options.material_coarse_space = material == 1;
    DirichletGridMultigrid mg(nx, ny, nz, fixed, options);
    mg.set_field(field_of(nx, ny, nz, solid));
    solution[material] = mg.solve(b);
    iterations[material] = mg.stats().iterations;
    const SpMat A = mg.fine_operator();
    Eigen::SimplicialLDLT<SpMat> direct(A);
    ASSERT_EQ(direct.info(), Eigen::Success);
    const VecX reference = direct.solve(b);
    EXPECT_LT((solution[material] - reference).norm(), 1e-7 * reference.norm());
  }
  EXPECT_LT(iterations[1], iterations[0]);
  // Thread count does not change a bit of the result.
  DirichletMultigridOptions options;
  options.tolerance = 1e-10;
  options.coarse_unknowns = 60;
  options.material_coarse_space = true;
  options.threads = 1;
  DirichletGridMultigrid one(nx, ny, nz, fixed, options);
  one.set_field(field_of(nx, ny, nz, solid));
  options.threads = 3;
  DirichletGridMultigrid three(nx, ny, nz, fixed, options);
  three.set_field(field_of(nx, ny, nz, solid));
  const VecX x1 = one.solve(b), x3 = three.solve(b);
  EXPECT_EQ((x1 - x3).cwiseAbs().maxCoeff(), 0.0);
}

// An exactly symmetric operator on level 1's pattern in full storage:
// random blocks, each block below the diagonal written as its mirror's
// transpose, dominant diagonal blocks, every seventh copy's diagonal block
// empty (a copy no free unknown reaches) and component 1 of every fifth
// copy decoupled (its row and column cleared but for the diagonal).
BlockMatrix symmetric_level1(const MaterialComponents& components) {
  BlockMatrix M = level1_element_pattern(components, 1);
  M.values.assign(9 * std::size_t(M.num_blocks()), 0.0);
  const auto slot_of = [&M](int i, int j) {
    const auto begin = M.column.begin() + M.row_start[std::size_t(i)];
    const auto end = M.column.begin() + M.row_start[std::size_t(i) + 1];
    return static_cast<std::size_t>(std::lower_bound(begin, end, j) - M.column.begin());
  };
  std::mt19937 rng(5);
  std::uniform_real_distribution<double> value(-1.0, 1.0);
  for (int i = 0; i < M.rows; ++i)
    for (int slot = M.diagonal[std::size_t(i)]; slot < M.row_start[std::size_t(i) + 1]; ++slot) {
      const int j = M.column[std::size_t(slot)];
      double* block = M.values.data() + 9 * std::size_t(slot);
      for (int e = 0; e < 9; ++e) block[e] = value(rng);
      if (j == i) {
        for (int r = 0; r < 3; ++r)
          for (int q = 0; q < r; ++q) block[3 * r + q] = block[3 * q + r];
        for (int d = 0; d < 3; ++d) block[4 * d] += 60.0;
        if (i % 7 == 3) std::fill(block, block + 9, 0.0);
      }
      for (int r = 0; r < 3; ++r)
        for (int q = 0; q < 3; ++q) {
          if ((i % 5 == 0 && r == 1 && !(j == i && q == 1)) || (j % 5 == 0 && q == 1 && !(j == i && r == 1)))
            block[3 * r + q] = 0.0;
          M.values[9 * slot_of(j, i) + 3 * std::size_t(q) + std::size_t(r)] = block[3 * r + q];
        }
    }
  return M;
}

TEST(MaterialComponents, UpperHeldLevelOneGivesTheSameBitsAsFullStorage) {
  const int nx = 12, ny = 8, nz = 4;
  const MaterialComponents components(nx, ny, nz, comb(nx, ny, nz), 10, 1);
  ASSERT_GE(components.levels().size(), 3u);
  BlockMatrix full = symmetric_level1(components);
  // The same operator by its upper blocks.
  const std::vector<int> upper = upper_block_numbering(full, 2);
  BlockMatrix held = full;
  held.values.assign(9 * upper_block_count(full), 0.0);
  for (int i = 0; i < full.rows; ++i)
    for (int slot = full.diagonal[std::size_t(i)]; slot < full.row_start[std::size_t(i) + 1]; ++slot)
      std::copy_n(full.values.data() + 9 * std::size_t(slot), 9,
                  held.values.data() + 9 * std::size_t(upper[std::size_t(slot)]));
  EXPECT_LT(held.values.size(), full.values.size() * 6 / 10);
  double block[9];  // a block below the diagonal reads as its stored self
  for (int i = 0; i < full.rows; ++i)
    for (int slot = full.row_start[std::size_t(i)]; slot < full.row_start[std::size_t(i) + 1]; ++slot) {
      read_block(held, &upper, i, slot, block);
      ASSERT_TRUE(std::equal(block, block + 9, full.values.data() + 9 * std::size_t(slot)));
    }

  fill_empty_diagonal(full);
  fill_empty_diagonal(held, &upper);
  const std::vector<char> decoupled = decoupled_unknowns(full, 2);
  EXPECT_GT(std::count(decoupled.begin(), decoupled.end(), char(1)), 0);
  EXPECT_EQ(decoupled_unknowns(held, 2, &upper), decoupled);
  BlockMatrix coarse_full, coarse_held;
  component_galerkin_product(full, decoupled, components.transfers()[1], coarse_full, 2);
  component_galerkin_product(held, decoupled, components.transfers()[1], coarse_held, 2, &upper);
  EXPECT_EQ(coarse_held.column, coarse_full.column);
  EXPECT_EQ(coarse_held.values, coarse_full.values);  // bit for bit

  // The smoother from either storage: the same operator, bit for bit.
  ChebyshevSmoother from_full, from_held;
  ASSERT_TRUE(from_full.setup(full, 2, 2, SmootherValues::single_upper));
  ASSERT_TRUE(from_held.setup(held, 2, 2, SmootherValues::single_upper, &upper));
  EXPECT_EQ(from_held.max_eigenvalue(), from_full.max_eigenvalue());
  const VecX x = VecX::LinSpaced(full.unknowns(), -1.0, 2.0), b = VecX::Zero(full.unknowns());
  VecX r_full, r_held;
  from_full.residual(b, x, r_full);
  from_held.residual(b, x, r_held);
  EXPECT_EQ((r_full - r_held).cwiseAbs().maxCoeff(), 0.0);
  // Handed over instead of copied: the same operator, the numbering gone.
  ChebyshevSmoother from_taken;
  std::vector<int> taken = upper;
  ASSERT_TRUE(from_taken.setup(held, 2, 2, std::move(taken)));
  EXPECT_TRUE(taken.empty());
  EXPECT_EQ(from_taken.max_eigenvalue(), from_full.max_eigenvalue());
  VecX r_taken;
  from_taken.residual(b, x, r_taken);
  EXPECT_EQ((r_full - r_taken).cwiseAbs().maxCoeff(), 0.0);
  // A set-up that fails (a diagonal block not positive definite) leaves the
  // numbering with the caller.
  BlockMatrix broken = held;
  double* diagonal = broken.values.data() + 9 * std::size_t(upper[std::size_t(broken.diagonal[0])]);
  std::fill(diagonal, diagonal + 9, 0.0);
  diagonal[0] = diagonal[4] = diagonal[8] = -1.0;
  std::vector<int> kept = upper;
  ChebyshevSmoother from_broken;
  EXPECT_FALSE(from_broken.setup(broken, 2, 2, std::move(kept)));
  EXPECT_EQ(kept, upper);
  EXPECT_THROW(from_held.setup(held, 2, 2, SmootherValues::single, &upper), std::logic_error);
}

TEST(MaterialComponents, UpperHeldLevelsSolveLikeFullOnes) {
  const int nx = 24, ny = 16, nz = 4;
  const std::vector<char> solid = comb(nx, ny, nz);
  const std::vector<char> fixed = clamped_without_void(nx, ny, nz, solid);
  VecX b = VecX::Zero(3 * std::int64_t(nx + 1) * (ny + 1) * (nz + 1));
  for (int k = 0; k <= nz; ++k)
    for (int j = 0; j <= ny; ++j) {
      const std::int64_t d = 3 * components_node_of(nx, ny, nx, j, k) + 1;
      if (!fixed[std::size_t(d)]) b[d] = 1e-3;
    }
  const auto solve = [&](int upper_level_blocks, int threads, int* iterations) {
    DirichletMultigridOptions options;
    options.tolerance = 1e-10;
    options.coarse_unknowns = 60;
    options.material_coarse_space = true;
    options.upper_level_blocks = upper_level_blocks;
    options.threads = threads;
    DirichletGridMultigrid mg(nx, ny, nz, fixed, options);
    mg.set_field(field_of(nx, ny, nz, solid));
    const VecX first = mg.solve(b);
    if (iterations) *iterations = mg.stats().iterations;
    EXPECT_GE(mg.num_levels(), 4);
    if (upper_level_blocks == 0) {  // level 1 held by its upper blocks, then released
      EXPECT_THROW(mg.coarse_operator(), std::logic_error);
    }
    // A new field on the same material rebuilds level 1 from its released values.
    mg.set_field(field_of(nx, ny, nz, solid));
    const VecX again = mg.solve(b);
    EXPECT_EQ((again - first).cwiseAbs().maxCoeff(), 0.0);
    return first;
  };
  int full_iterations = 0, upper_iterations = 0;
  const VecX full = solve(kUpperLevelBlocks, 2, &full_iterations);
  const VecX upper = solve(0, 2, &upper_iterations);
  // Every level held by its upper blocks (level 1 in double from assembly,
  // every smoother in single precision): a preconditioner that differs by
  // rounding, the same solution to CG's tolerance in about as many
  // iterations (on this comb, whose CG takes over a hundred iterations, the
  // smoothers' rounding alone moves the count by about 10%).
  EXPECT_LT((upper - full).norm(), 1e-7 * full.norm());
  EXPECT_LE(std::abs(upper_iterations - full_iterations), full_iterations / 8);
  EXPECT_EQ((solve(0, 1, nullptr) - solve(0, 3, nullptr)).cwiseAbs().maxCoeff(), 0.0);
}

}  // namespace
}  // namespace msfab
