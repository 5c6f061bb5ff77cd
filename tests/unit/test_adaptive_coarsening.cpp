// Adaptive coarsening (docs/ddfem.md, "Adaptive coarsening"): meshes that
// mix fine voxels, level-1 and level-2 elements with hanging nodes
// constrained, the constrained assembler, and the choice of levels.
#include <gtest/gtest.h>

#include <Eigen/SparseCholesky>
#include <algorithm>
#include <cmath>
#include <random>

#include "core/errors.hpp"
#include "ddfem/adaptive_levels.hpp"
#include "ddfem/baseline_coarsening.hpp"
#include "ddfem/coarsening_error.hpp"
#include "ddfem/mixed_level_mesh.hpp"
#include "ddfem_test_blocks.hpp"
#include "fem/elastic_assembler.hpp"
#include "material/neo_hookean.hpp"
#include "solve/cholmod_solver.hpp"
#include "solve/multigrid_solver.hpp"
#include "solve/newton.hpp"

namespace msfab {
namespace {

using Rows3 = Eigen::Matrix<double, Eigen::Dynamic, 3, Eigen::RowMajor>;

// An 8 x 12 x 8 block (or another size) of two materials in an irregular
// pattern (so that level-1 and level-2 blocks mix them), with a few void
// voxels, clamped at y = 0 and pulled and sheared at y = max.
Scene two_material_block(int nx = 8, int ny = 12, int nz = 8) {
  Scene s;
  s.name = "mixed-block";
  s.grid = VoxelGrid(nx, ny, nz, 0.001, 0);
  std::mt19937 rng(3);
  for (int k = 0; k < nz; ++k)
    for (int j = 0; j < ny; ++j)
      for (int i = 0; i < nx; ++i) s.grid.at(i, j, k) = rng() % 3 == 0 ? 2 : 1;
  s.grid.at(5, 6, 2) = 0;
  s.grid.at(1, 9, 6) = 0;
  s.material_by_id = {nullptr, std::make_shared<NeoHookean>(1e5, 0.45), std::make_shared<NeoHookean>(1e6, 0.45)};
  ddfem_test::clamp_y0_load_top(s, Vec3(0.3, 0.2, -0.1));
  return s;
}

struct Grids {
  CoarseGrid level1, level2;
};

Grids grids_of(const Scene& s) {
  Grids g;
  g.level1 = coarsen_grid(s.grid);
  g.level2 = coarsen_grid(g.level1);
  return g;
}

// Levels 0, 1 and 2 side by side, so that every kind of interface occurs
// (fine next to level 2 included).
std::vector<int> patchwork_levels(const CoarseGrid& level2) {
  std::vector<int> levels(level2.num_cells());
  for (int K = 0; K < level2.nz; ++K)
    for (int J = 0; J < level2.ny; ++J)
      for (int I = 0; I < level2.nx; ++I) levels[level2.index(I, J, K)] = (I + 2 * J + K) % 3;
  return levels;
}

MixedLevelMesh naive_mixed_mesh(const Scene& s, const Grids& g, const std::vector<int>& levels) {
  return build_mixed_level_mesh(s.grid, s.material_by_id, g.level1, g.level2, levels,
                                naive_coarsening(s.material_by_id), naive_coarsening(s.material_by_id, g.level1));
}

// The coarse models a mixed mesh can hold besides the trilinear naive one:
// the enhanced element (condensed bubbles) with naive materials, and with the
// Galerkin element's points (reduced: each element on a rule of its own).
struct CoarseVariant {
  const char* name;
  bool enhanced;
  bool galerkin;
};
constexpr CoarseVariant kCoarseVariants[] = {
    {"trilinear naive", false, false}, {"enhanced naive", true, false}, {"enhanced Galerkin", true, true}};

CoarseMaterialLookup variant_lookup(const Scene& s, const CoarseVariant& v, const CoarseGrid* level1) {
  if (v.galerkin)
    return level1 ? galerkin_coarsening(s.material_by_id, *level1) : galerkin_coarsening(s.material_by_id);
  return level1 ? naive_coarsening(s.material_by_id, *level1) : naive_coarsening(s.material_by_id);
}

MixedLevelMesh variant_mixed_mesh(const Scene& s, const Grids& g, const std::vector<int>& levels,
                                  const CoarseVariant& v) {
  return build_mixed_level_mesh(s.grid, s.material_by_id, g.level1, g.level2, levels, variant_lookup(s, v, nullptr),
                                variant_lookup(s, v, &g.level1), v.enhanced);
}

TEST(AdaptiveMixedMesh, HangingNodesInterpolateRestPositionsAndRowsSumToOne) {
  const Scene s = two_material_block();
  const Grids g = grids_of(s);
  const MixedLevelMesh m = naive_mixed_mesh(s, g, patchwork_levels(g.level2));
  EXPECT_GT(m.elements_per_level[0], 0);
  EXPECT_GT(m.elements_per_level[1], 0);
  EXPECT_GT(m.elements_per_level[2], 0);
  EXPECT_GT(m.hanging_nodes, 0);
  const SpMat& T = m.constraints->node_map;
  EXPECT_LT((T * VecX::Ones(T.cols()) - VecX::Ones(T.rows())).cwiseAbs().maxCoeff(), 1e-14);
  const Rows3 interpolated = T * m.constraints->unknown_rest;
  EXPECT_LT((interpolated - Rows3(m.mesh.nodes)).cwiseAbs().maxCoeff(), 1e-15);
  // Every fine voxel is covered by exactly the volume of the elements.
  double volume = 0;
  for (int e = 0; e < m.mesh.num_elements(); ++e)
    volume += std::pow(std::ldexp(s.grid.voxel_size, m.element_level[e]), 3);
  EXPECT_GT(volume, s.grid.count_solid() * std::pow(s.grid.voxel_size, 3));
}

// Gradient and Hessian of the constrained energy E(T y) against central
// differences.
TEST(AdaptiveMixedMesh, ConstrainedGradientAndHessianMatchFiniteDifferences) {
  const Scene s = two_material_block();
  const Grids g = grids_of(s);
  const MixedLevelMesh m = naive_mixed_mesh(s, g, patchwork_levels(g.level2));
  const ElasticAssembler a(m.mesh, m.constraints);
  ASSERT_EQ(a.num_dofs(), 3 * m.num_unknown_nodes());
  std::mt19937 rng(11);
  std::uniform_real_distribution<double> u(-1e-4, 1e-4);
  VecX y = a.rest_positions();
  for (int i = 0; i < y.size(); ++i) y[i] += u(rng);
  VecX grad;
  SpMat K = a.pattern();
  const double E = a.evaluate(y, &grad, &K);
  ASSERT_TRUE(std::isfinite(E));
  const double h = 1e-8;
  VecX v(y.size());
  for (int i = 0; i < v.size(); ++i) v[i] = u(rng) * 1e4;
  const double dE = (a.energy(y + h * v) - a.energy(y - h * v)) / (2 * h);
  EXPECT_NEAR(dE, grad.dot(v), 1e-6 * std::abs(grad.dot(v)));
  VecX gp, gm;
  a.evaluate(y + h * v, &gp, nullptr);
  a.evaluate(y - h * v, &gm, nullptr);
  const VecX dg = (gp - gm) / (2 * h);
  EXPECT_LT((dg - K * v).norm(), 1e-5 * (K * v).norm());
  EXPECT_LT((SpMat(K.transpose()) - K).norm(), 1e-12 * K.norm());
}

// A homogeneous body under an affine boundary displacement stays affine: the
// hanging nodes must not add stiffness or slack at the interfaces.
TEST(AdaptiveMixedMesh, AffineDisplacementIsReproducedAcrossLevelInterfaces) {
  Scene s = two_material_block();
  for (int& id : s.grid.ids) id = id == 0 ? 0 : 1;
  s.grid.at(5, 6, 2) = 1;  // no holes: the body is a box
  s.grid.at(1, 9, 6) = 1;
  const Grids g = grids_of(s);
  for (const CoarseVariant& v : kCoarseVariants) {
    SCOPED_TRACE(v.name);
    const MixedLevelMesh m = variant_mixed_mesh(s, g, patchwork_levels(g.level2), v);
    const ElasticAssembler a(m.mesh, m.constraints);
    Mat3 strain;
    strain << 0.02, 0.005, 0, 0.005, -0.01, 0.004, 0, 0.004, 0.015;
    const NodeArray& X = m.constraints->unknown_rest;
    const Vec3 lo = m.mesh.bbox_min(), hi = m.mesh.bbox_max();
    DirichletConditions bc = DirichletConditions::none(a.num_dofs());
    for (int n = 0; n < X.rows(); ++n) {
      const Vec3 p = X.row(n).transpose();
      const bool boundary = ((p - lo).cwiseAbs().minCoeff() < 1e-12) || ((hi - p).cwiseAbs().minCoeff() < 1e-12);
      if (!boundary) continue;
      for (int c = 0; c < 3; ++c) {
        bc.fixed[3 * n + c] = 1;
        bc.displacement[3 * n + c] = (strain * p)[c];
      }
    }
    NewtonOptions opt;
    opt.linear_solver = "cholmod";
    opt.relative_tolerance = 1e-10;
    const NewtonResult r = solve_static(a, bc, VecX::Zero(a.num_dofs()), opt);
    ASSERT_TRUE(r.converged) << r.failure;
    const VecX x = a.mesh_positions(r.x);
    double worst = 0;
    for (int n = 0; n < m.mesh.num_nodes(); ++n) {
      const Vec3 p = m.mesh.nodes.row(n).transpose();
      worst = std::max(worst, (x.segment<3>(3 * n) - p - strain * p).norm());
    }
    EXPECT_LT(worst, 1e-9 * s.grid.voxel_size);
  }
}

// With every cell at level 1 (or 2) the mixed mesh is the uniform coarse
// model of build_coarse_mesh, element and materials included: the same
// solution under the scene's conditions.
TEST(AdaptiveMixedMesh, UniformLevelsSolveTheUniformCoarseModel) {
  const Scene s = two_material_block();
  const Grids g = grids_of(s);
  const VoxelMesh fine = build_voxel_mesh(s.grid, s.material_by_id);
  const StaticConditions fc = build_static_conditions(s, fine);
  NewtonOptions opt;
  opt.linear_solver = "cholmod";
  opt.relative_tolerance = 1e-10;
  for (const CoarseVariant& v : kCoarseVariants)
    for (int level : {1, 2}) {
      SCOPED_TRACE(std::string(v.name) + ", level " + std::to_string(level));
      const MixedLevelMesh m = variant_mixed_mesh(s, g, std::vector<int>(g.level2.num_cells(), level), v);
      EXPECT_EQ(m.hanging_nodes, 0);
      const CoarseGrid& grid = level == 1 ? g.level1 : g.level2;
      const VoxelMesh cm =
          build_coarse_mesh(grid, variant_lookup(s, v, level == 1 ? nullptr : &g.level1), 0, nullptr, v.enhanced);
      ASSERT_EQ(m.mesh.num_elements(), cm.mesh.num_elements());
      ASSERT_EQ(m.num_unknown_nodes(), cm.mesh.num_nodes());
      const StaticConditions cc = coarse_static_conditions(s, fine, grid, cm);
      const StaticConditions mc = mixed_static_conditions(s, fine, fc, g.level1, g.level2, m);
      EXPECT_EQ(mc.dirichlet.count_fixed(), cc.dirichlet.count_fixed());
      const ElasticAssembler ac(cm.mesh);
      const NewtonResult rc = solve_static(ac, cc.dirichlet, cc.force, opt);
      const ElasticAssembler am(m.mesh, m.constraints);
      const NewtonResult rm = solve_static(am, mc.dirichlet, mc.force, opt);
      ASSERT_TRUE(rc.converged && rm.converged);
      const VecX uc = interpolate_to_fine(s.grid, fine, grid, cm, rc.x - ac.rest_positions());
      const SpMat W = mixed_to_fine_interpolation(s.grid, fine, m);
      const VecX um = rm.x - am.rest_positions();
      VecX interpolated(fine.mesh.num_dofs());
      Eigen::Map<Rows3>(interpolated.data(), fine.mesh.num_nodes(), 3) =
          W * Eigen::Map<const Rows3>(um.data(), m.num_unknown_nodes(), 3);
      EXPECT_LT(mean_vertex_error(fine.mesh, uc, interpolated), 1e-8 * uc.cwiseAbs().maxCoeff());
      EXPECT_GT(uc.cwiseAbs().maxCoeff(), 0);
    }
}

// With every cell at level 0 (a zero budget) the mixed model is the fine
// model: same solution as the voxel mesh, and its conditions are the fine ones.
TEST(AdaptiveMixedMesh, AllFineLevelsSolveTheFineModel) {
  const Scene s = two_material_block();
  const Grids g = grids_of(s);
  const LevelChoice choice = choose_cell_levels(std::vector<CellErrorModel>(g.level2.num_cells()), {0, 0.1, 0.2}, 0.0);
  for (int l : choice.cell_level) ASSERT_EQ(l, 0);
  const MixedLevelMesh m = naive_mixed_mesh(s, g, choice.cell_level);
  EXPECT_EQ(m.hanging_nodes, 0);
  const VoxelMesh fine = build_voxel_mesh(s.grid, s.material_by_id);
  EXPECT_EQ(m.mesh.num_elements(), fine.mesh.num_elements());
  EXPECT_EQ(m.num_unknown_nodes(), fine.mesh.num_nodes());
  const StaticConditions fc = build_static_conditions(s, fine);
  const StaticConditions mc = mixed_static_conditions(s, fine, fc, g.level1, g.level2, m);
  EXPECT_EQ(mc.dirichlet.count_fixed(), fc.dirichlet.count_fixed());

  NewtonOptions opt;
  opt.linear_solver = "cholmod";
  opt.relative_tolerance = 1e-10;
  const ElasticAssembler af(fine.mesh);
  const NewtonResult rf = solve_static(af, fc.dirichlet, fc.force, opt);
  const ElasticAssembler am(m.mesh, m.constraints);
  const NewtonResult rm = solve_static(am, mc.dirichlet, mc.force, opt);
  ASSERT_TRUE(rf.converged && rm.converged);
  const SpMat W = mixed_to_fine_interpolation(s.grid, fine, m);
  const VecX um = rm.x - am.rest_positions();
  VecX interpolated(fine.mesh.num_dofs());
  Eigen::Map<Rows3>(interpolated.data(), fine.mesh.num_nodes(), 3) =
      W * Eigen::Map<const Rows3>(um.data(), m.num_unknown_nodes(), 3);
  const VecX uf = rf.x - af.rest_positions();
  EXPECT_LT(mean_vertex_error(fine.mesh, uf, interpolated), 1e-8 * uf.cwiseAbs().maxCoeff());
}

// The lattice multigrid on a mesh of three element sizes (docs/solvers.md):
// with its hanging nodes eliminated the tangent couples nodes several
// lattice steps apart, and the hierarchy is still P^T A P, symmetric, the
// same on one thread and two, and solves as CHOLMOD does, alone and in Newton.
TEST(AdaptiveMixedMesh, LatticeMultigridSolvesMixedMeshesLikeCholmod) {
  // Over 2048 unknown nodes, so that two threads split the rows. The second
  // block has void voxels at x = 0 under fine cells, so that its lowest node
  // (the lattice origin) lies one voxel in and the large elements' corners
  // sit at odd lattice coordinates: there the coarsening of equal voxels
  // would make P^T A P singular.
  struct Case {
    const char* name;
    const CoarseVariant& variant;
    bool offset;
  };
  for (const Case& test : {Case{"patchwork", kCoarseVariants[0], false}, Case{"patchwork", kCoarseVariants[2], false},
                           Case{"odd corners", kCoarseVariants[0], true}}) {
    const CoarseVariant& v = test.variant;
    SCOPED_TRACE(std::string(test.name) + ", " + v.name);
    Scene s = two_material_block(16, 32, 16);
    if (test.offset)
      for (int k = 0; k < s.grid.nz; ++k)
        for (int j = 0; j < s.grid.ny; ++j) s.grid.at(0, j, k) = 0;
    const Grids g = grids_of(s);
    std::vector<int> levels = patchwork_levels(g.level2);
    if (test.offset) {
      for (int K = 0; K < g.level2.nz; ++K)
        for (int J = 0; J < g.level2.ny; ++J) levels[g.level2.index(0, J, K)] = 0;
    }
    const VoxelMesh fine = build_voxel_mesh(s.grid, s.material_by_id);
    const StaticConditions fc = build_static_conditions(s, fine);
    const MixedLevelMesh m = variant_mixed_mesh(s, g, levels, v);
    ASSERT_GT(m.hanging_nodes, 0);
    const StaticConditions mc = mixed_static_conditions(s, fine, fc, g.level1, g.level2, m);
    const ElasticAssembler am(m.mesh, m.constraints);
    SpMat K = am.pattern();
    am.evaluate(am.rest_positions(), nullptr, &K);
    const auto positions = std::make_shared<const NodeArray>(am.unknown_rest_nodes());
    int reach = 0;
    for (int c = 0; c < K.outerSize(); ++c)
      for (SpMat::InnerIterator it(K, c); it; ++it)
        for (int a = 0; a < 3; ++a)
          reach = std::max(
              reach, static_cast<int>(std::lround(std::abs((*positions)(it.row() / 3, a) - (*positions)(c / 3, a)) /
                                                  s.grid.voxel_size)));
    EXPECT_GE(reach, 4);
    // Clamped unknowns as Newton treats them: rows and columns cleared, a
    // positive diagonal kept.
    const std::vector<char>& fixed = mc.dirichlet.fixed;
    const double diagonal = K.diagonal().mean();
    for (int c = 0; c < K.outerSize(); ++c)
      for (SpMat::InnerIterator it(K, c); it; ++it)
        if (fixed[std::size_t(c)] || fixed[std::size_t(it.row())]) it.valueRef() = it.row() == c ? diagonal : 0.0;
    std::mt19937 rng(5);
    std::uniform_real_distribution<double> noise(-1.0, 1.0);
    VecX b(K.rows());
    for (Eigen::Index i = 0; i < b.size(); ++i) b[i] = fixed[std::size_t(i)] ? 0.0 : noise(rng);
    CholmodSolver direct;
    direct.analyze(K);
    ASSERT_TRUE(direct.factorize(K));
    const VecX reference = direct.solve(b);

    VecX solutions[2];
    for (int threads : {1, 2}) {
      LinearSolverOptions options;
      options.node_positions = positions;
      options.pcg_tolerance = 1e-10;
      options.pcg_max_iterations = 300;
      options.mg_coarse_unknowns = 100;
      options.threads = threads;
      MultigridSolver solver(options);
      solver.analyze(K);
      ASSERT_TRUE(solver.factorize(K));
      ASSERT_GE(solver.num_levels(), 3);
      solutions[threads - 1] = solver.solve(b);
      EXPECT_LT(solver.stats().iterations, 100);
      EXPECT_GT(K.rows(), 3 * 2048);
      EXPECT_LT((solutions[threads - 1] - reference).norm(), 1e-8 * reference.norm());
      if (threads == 2) continue;
      for (int level = 0; level + 1 < solver.num_levels(); ++level) {
        const SpMat P = solver.prolongation(level);
        const SpMat expected = SpMat(P.transpose()) * solver.level_operator(level) * P;
        const SpMat coarse = solver.level_operator(level + 1);
        SpMat difference = coarse - expected;
        for (int c = 0; c < P.cols(); ++c)
          if (P.col(c).nonZeros() == 0) difference.coeffRef(c, c) -= 1.0;
        EXPECT_LT(difference.norm(), 1e-12 * expected.norm()) << "level " << level;
        EXPECT_EQ(SpMat(coarse - SpMat(coarse.transpose())).norm(), 0.0) << "level " << level;
        // P has full column rank, so every level is as definite as A.
        const Eigen::SimplicialLLT<SpMat> cholesky(coarse);
        EXPECT_EQ(cholesky.info(), Eigen::Success) << "level " << level + 1;
      }
      // The cycle is symmetric positive definite, so CG applies.
      VecX x(b.size()), y(b.size());
      for (Eigen::Index i = 0; i < b.size(); ++i) {
        x[i] = noise(rng);
        y[i] = noise(rng);
      }
      const VecX mx = solver.apply_preconditioner(x), my = solver.apply_preconditioner(y);
      EXPECT_GT(mx.dot(x), 0.0);
      EXPECT_LT(std::abs(mx.dot(y) - x.dot(my)), 1e-10 * std::sqrt(mx.dot(x) * my.dot(y)));
    }
    EXPECT_TRUE((solutions[0].array() == solutions[1].array()).all());
    if (v.galerkin || test.offset) continue;  // one case is enough for Newton's use of it

    NewtonOptions opt;
    opt.relative_tolerance = 1e-10;
    opt.linear_solver = "cholmod";
    const NewtonResult by_cholmod = solve_static(am, mc.dirichlet, mc.force, opt);
    opt.linear_solver = "pcg-mg";
    const NewtonResult by_multigrid = solve_static(am, mc.dirichlet, mc.force, opt);
    ASSERT_TRUE(by_cholmod.converged && by_multigrid.converged);
    const VecX u = by_cholmod.x - am.rest_positions();
    EXPECT_LT((by_multigrid.x - by_cholmod.x).norm(), 1e-6 * u.norm());
  }
}

// Loads restricted to the unknowns keep their total; the interpolation to the
// fine nodes reproduces affine fields.
TEST(AdaptiveMixedMesh, ConditionsKeepTheLoadAndInterpolationIsExactForAffineFields) {
  const Scene s = two_material_block();
  const Grids g = grids_of(s);
  const MixedLevelMesh m = naive_mixed_mesh(s, g, patchwork_levels(g.level2));
  const VoxelMesh fine = build_voxel_mesh(s.grid, s.material_by_id);
  const StaticConditions fc = build_static_conditions(s, fine);
  const StaticConditions mc = mixed_static_conditions(s, fine, fc, g.level1, g.level2, m);
  const Vec3 total = Eigen::Map<const Rows3>(mc.force.data(), m.num_unknown_nodes(), 3).colwise().sum().transpose();
  EXPECT_LT((total - Vec3(0.3, 0.2, -0.1)).norm(), 1e-12);
  // The clamped face has unknowns at y = 0 only, every one fixed.
  for (int u = 0; u < m.num_unknown_nodes(); ++u) {
    const bool on_face = std::abs(m.constraints->unknown_rest(u, 1)) < 1e-12;
    EXPECT_EQ(bool(mc.dirichlet.fixed[3 * u]), on_face) << "unknown " << u;
  }
  const SpMat W = mixed_to_fine_interpolation(s.grid, fine, m);
  Mat3 A;
  A << 1, 2, 3, -1, 0.5, 2, 0.3, -0.7, 1;
  const Rows3 field = m.constraints->unknown_rest * A.transpose();
  const Rows3 expected = fine.mesh.nodes * A.transpose();
  EXPECT_LT((Rows3(W * field) - expected).cwiseAbs().maxCoeff(), 1e-14);
}

// The warm start of a finer model from a uniform coarse solution: an affine
// displacement of the coarse nodes is reproduced at every node of the finer
// models (inside coarse cells, on their faces, and where the point's own
// cells are void).
TEST(AdaptiveMixedMesh, UniformStartReproducesAffineDisplacements) {
  const Scene s = two_material_block();
  const Grids g = grids_of(s);
  Mat3 A;
  A << 0.01, -0.02, 0.005, 0.003, 0.02, -0.01, 0.0, 0.004, -0.015;
  const Vec3 shift(1e-4, -2e-4, 3e-4);
  // Positions of the mesh's nodes moved by the affine field.
  auto affine_positions = [&](const HexMesh& mesh) {
    VecX x(mesh.num_dofs());
    for (int n = 0; n < mesh.num_nodes(); ++n) {
      const Vec3 p = mesh.nodes.row(n).transpose();
      x.segment<3>(3 * n) = p + A * p + shift;
    }
    return x;
  };
  // The largest distance of u from the affine displacement at the points.
  auto worst_affine_error = [&](const VecX& u, const NodeArray& points) {
    double worst = 0;
    for (int n = 0; n < points.rows(); ++n) {
      const Vec3 p = points.row(n).transpose();
      worst = std::max(worst, (u.segment<3>(3 * n) - A * p - shift).norm());
    }
    return worst;
  };
  const VoxelMesh level2 = build_coarse_mesh(g.level2, naive_coarsening(s.material_by_id, g.level1));
  const VoxelMesh level1 = build_coarse_mesh(g.level1, naive_coarsening(s.material_by_id));
  const VecX x2 = affine_positions(level2.mesh);
  const MixedLevelMesh m = naive_mixed_mesh(s, g, patchwork_levels(g.level2));
  for (const NodeArray* points : {&level1.mesh.nodes, &m.constraints->unknown_rest}) {
    const VecX u = uniform_displacement_at(g.level2, level2, x2, *points);
    ASSERT_EQ(u.size(), 3 * points->rows());
    EXPECT_LT(worst_affine_error(u, *points), 1e-15);
  }
  EXPECT_THROW(uniform_displacement_at(g.level1, level2, x2, level1.mesh.nodes), InputError);

  // From level 1 to level-2 elements, with the level-1 block at the origin
  // void: the level-2 element's corner there touches no level-1 element and
  // is extrapolated from a neighbour.
  Scene holed = s;
  for (int k = 0; k < 2; ++k)
    for (int j = 0; j < 2; ++j)
      for (int i = 0; i < 2; ++i) holed.grid.at(i, j, k) = 0;
  const Grids hg = grids_of(holed);
  const VoxelMesh holed1 = build_coarse_mesh(hg.level1, naive_coarsening(holed.material_by_id));
  ASSERT_LT(holed1.voxel_element[hg.level1.index(0, 0, 0)], 0);
  const VecX x1 = affine_positions(holed1.mesh);
  const MixedLevelMesh all2 = naive_mixed_mesh(holed, hg, std::vector<int>(hg.level2.num_cells(), 2));
  const NodeArray& points = all2.constraints->unknown_rest;
  ASSERT_LT(points.row(0).norm(), 1e-15);  // the corner at the origin is a node
  EXPECT_LT(worst_affine_error(uniform_displacement_at(hg.level1, holed1, x1, points), points), 1e-15);
}

TEST(AdaptiveLevels, ChoiceMeetsTheTargetAndRefinesHighEnergyCellsFirst) {
  // Four cells; the second carries most of the energy.
  std::vector<CellErrorModel> cells(4);
  const double shares[4] = {0.1, 0.6, 0.2, 0.1};
  for (int c = 0; c < 4; ++c) {
    cells[c].energy_share = shares[c];
    cells[c].elements = {64, 8, 1};
  }
  const LevelErrors e = level_errors_from_difference(0.05);
  EXPECT_DOUBLE_EQ(e[1], 0.05);
  EXPECT_DOUBLE_EQ(e[2], 0.10);
  EXPECT_NEAR(level_errors_from_difference(0.05, 2.0)[1], 0.05 / 3, 1e-15);
  // A target above the level-2 error keeps everything at level 2.
  const LevelChoice loose = choose_cell_levels(cells, e, 0.2);
  for (int l : loose.cell_level) EXPECT_EQ(l, 2);
  EXPECT_NEAR(loose.predicted_error, 0.1, 1e-15);
  int previous_elements = 4;
  for (double target : {0.09, 0.07, 0.05, 0.03, 0.01}) {
    const LevelChoice c = choose_cell_levels(cells, e, target);
    EXPECT_LE(c.predicted_error, target * (1 + 1e-9));
    EXPECT_NEAR(c.predicted_error, predicted_error(cells, e, c.cell_level), 1e-15);
    int elements = 0;
    for (int i = 0; i < 4; ++i) elements += cells[i].elements[c.cell_level[i]];
    EXPECT_GE(elements, previous_elements);
    previous_elements = elements;
    // The high-energy cell is never coarser than a low-energy one.
    for (int i : {0, 2, 3}) EXPECT_LE(c.cell_level[1], c.cell_level[i]) << "target " << target;
  }
  EXPECT_THROW(choose_cell_levels(cells, e, -1), InputError);
  EXPECT_THROW(choose_cell_levels(cells, e, NAN), InputError);
  EXPECT_THROW(level_errors_from_difference(INFINITY), InputError);
}

TEST(AdaptiveLevels, TighterTargetsRefineEveryCellOfTheLooserChoice) {
  // The a-posteriori check ranks a solve by the estimates of the solves
  // that refine it; re-choices for tightened targets must be refinements.
  std::mt19937 rng(7);
  std::uniform_real_distribution<double> u(0.01, 1.0);
  std::vector<CellErrorModel> cells(40);
  double total = 0;
  for (auto& c : cells) total += c.energy_share = u(rng), c.elements = {64, 8, 1};
  for (auto& c : cells) c.energy_share /= total;
  const LevelErrors e = level_errors_from_difference(0.02);
  std::vector<int> looser = choose_cell_levels(cells, e, 0.05).cell_level;
  for (double target : {0.03, 0.02, 0.012, 0.008, 0.004, 0.001}) {
    const std::vector<int> tighter = choose_cell_levels(cells, e, target).cell_level;
    for (size_t c = 0; c < cells.size(); ++c) EXPECT_LE(tighter[c], looser[c]) << "target " << target << " cell " << c;
    looser = tighter;
  }
}

TEST(AdaptiveLevels, ExtrapolatedEstimatesAreRaisedByTheMeasuredEstimatesOfTheirRefinements) {
  const std::vector<int> coarse = {2, 2, 1}, finer = {1, 2, 0}, elsewhere = {2, 1, 2};
  // An extrapolated 5e-3 refined by a solve measured at 6e-3: the coarser
  // solve's error is taken as at least 6e-3, and the measured solve is kept.
  std::vector<CheckedSolve> solves = {{coarse, 5e-3, false}, {finer, 6e-3, true}};
  EXPECT_DOUBLE_EQ(ranked_estimate(solves, 0), 6e-3);
  EXPECT_DOUBLE_EQ(ranked_estimate(solves, 1), 6e-3);
  EXPECT_EQ(kept_solve(solves), 1u);
  // A measured estimate below it keeps its own value.
  solves = {{coarse, 5e-3, false}, {finer, 3e-3, true}};
  EXPECT_DOUBLE_EQ(ranked_estimate(solves, 0), 5e-3);
  EXPECT_EQ(kept_solve(solves), 1u);
  // A measured solve that does not refine it (one cell coarser) says nothing about it.
  solves = {{coarse, 5e-3, false}, {elsewhere, 6e-3, true}};
  EXPECT_DOUBLE_EQ(ranked_estimate(solves, 0), 5e-3);
  EXPECT_EQ(kept_solve(solves), 0u);
  // Measured estimates are never raised; the smaller one is kept, and on
  // equal extrapolations the later (finer) solve.
  solves = {{coarse, 2e-3, true}, {finer, 4e-3, true}};
  EXPECT_DOUBLE_EQ(ranked_estimate(solves, 0), 2e-3);
  EXPECT_EQ(kept_solve(solves), 0u);
  solves = {{coarse, 4e-3, false}, {finer, 4e-3, false}};
  EXPECT_EQ(kept_solve(solves), 1u);
  EXPECT_THROW(kept_solve({}), std::invalid_argument);
  EXPECT_THROW(ranked_estimate(solves, 2), std::out_of_range);
}

TEST(AdaptiveLevels, CalibratedErrorsGiveTheMeasuredErrorSplitAsTheFieldSaysAndAskForFineCells) {
  // Four level-2 cells; the a-priori model thinks level 1 (0.03) meets the
  // target 0.05. A measured solve says otherwise.
  std::vector<CellErrorModel> cells(4);
  const double shares[4] = {0.4, 0.3, 0.2, 0.1};
  for (int c = 0; c < 4; ++c) {
    cells[c].energy_share = shares[c];
    cells[c].elements = {64, 8, 1};
  }
  const LevelErrors prior = level_errors_from_difference(0.03);
  const LevelChoice first = choose_cell_levels(cells, prior, 0.05);
  const std::vector<int> levels = {1, 1, 2, 0};
  const std::vector<double> field = {3.0, 1.0, 2.0, 50.0};  // the fine cell's is induced, left out
  const double measured = 0.08;
  const LevelErrors e = calibrated_level_errors(cells, prior, levels, field, measured);
  EXPECT_EQ(e[0], 0.0);
  // At the measured levels the calibrated model predicts the measured error,
  // split between the levels as the field's energy is.
  EXPECT_NEAR(predicted_error(cells, e, levels), measured, 1e-15);
  EXPECT_NEAR((0.4 + 0.3) * e[1] * e[1] / (0.2 * e[2] * e[2]), (3.0 + 1.0) / 2.0, 1e-12);
  EXPECT_EQ(calibrated_level_errors(cells, prior, levels, {3.0, 1.0, 2.0, 0.0}, measured), e);
  // A level without cells keeps its a-priori ratio to the measured one.
  const LevelErrors only1 = calibrated_level_errors(cells, prior, {1, 1, 1, 1}, {1, 1, 1, 1}, measured);
  EXPECT_NEAR(only1[1], measured, 1e-15);
  EXPECT_NEAR(only1[2], 2 * measured, 1e-15);
  // No field energy in a coarse cell: nothing to calibrate.
  EXPECT_EQ(calibrated_level_errors(cells, prior, levels, {0, 0, 0, 5}, measured), prior);

  // Re-chosen with the calibrated errors: level 1 (now above the target)
  // gives way to fine cells, no cell is coarsened, and the target is met.
  const LevelChoice again = refine_cell_levels(cells, e, levels, 0.05);
  EXPECT_LE(again.predicted_error, 0.05 * (1 + 1e-12));
  EXPECT_NEAR(again.predicted_error, predicted_error(cells, e, again.cell_level), 1e-15);
  int fine_from_level1 = 0;
  for (int c = 0; c < 4; ++c) {
    EXPECT_LE(again.cell_level[c], levels[c]);
    fine_from_level1 += levels[c] == 1 && again.cell_level[c] == 0;
  }
  EXPECT_GT(fine_from_level1, 0);
  for (int l : first.cell_level) EXPECT_GT(l, 0);  // what the a-priori model chose: no fine cell
  // A met target refines nothing.
  EXPECT_EQ(refine_cell_levels(cells, e, levels, measured).cell_level, levels);
  EXPECT_THROW(calibrated_level_errors(cells, prior, levels, field, NAN), InputError);
  EXPECT_THROW(calibrated_level_errors(cells, prior, {1, 1}, field, measured), InputError);
  EXPECT_THROW(refine_cell_levels(cells, e, levels, -1), InputError);
}

TEST(AdaptiveLevels, FieldEnergiesPerCellAreTheQuadraticFormOfTheTangent) {
  const Scene s = two_material_block();
  const Grids g = grids_of(s);
  const VoxelMesh fine = build_voxel_mesh(s.grid, s.material_by_id);
  const ElasticAssembler a(fine.mesh);
  const int n = fine.mesh.num_dofs();
  std::mt19937 rng(7);
  std::uniform_real_distribution<double> u(-1, 1);
  VecX state(n), field(n);
  for (int i = 0; i < n; ++i) {
    state[i] = 2e-5 * u(rng);
    field[i] = 1e-7 * u(rng);
  }
  const std::vector<double> cells = cell_field_energies(fine, g.level2, state, field);
  ASSERT_EQ(cells.size(), size_t(g.level2.num_cells()));
  SpMat K = a.pattern();
  a.evaluate(a.rest_positions() + state, nullptr, &K);
  double total = 0;
  for (double c : cells) total += c;
  const double quadratic = 0.5 * field.dot(K * field);
  EXPECT_NEAR(total, quadratic, 1e-5 * quadratic);
  // A field on the nodes of one cell's voxels only puts its energy there.
  VecX local = VecX::Zero(n);
  const auto first = g.level2.first_voxel(1);
  for (int e = 0; e < fine.mesh.num_elements(); ++e) {
    const int v = fine.element_voxel[e];
    const int i = v % s.grid.nx, j = (v / s.grid.nx) % s.grid.ny, k = v / (s.grid.nx * s.grid.ny);
    if (i < first[0] || i >= first[0] + 4 || j < first[1] || j >= first[1] + 4 || k < first[2] || k >= first[2] + 4)
      continue;
    // Interior voxels' nodes only, so that no neighbouring cell's element moves.
    if (i == first[0] || i == first[0] + 3 || j == first[1] || j == first[1] + 3 || k == first[2] || k == first[2] + 3)
      continue;
    for (int q = 0; q < 8; ++q) {
      const int node = fine.mesh.elements[e][q];
      local.segment<3>(3 * node) = field.segment<3>(3 * node);
    }
  }
  ASSERT_GT(local.norm(), 0);
  const std::vector<double> one = cell_field_energies(fine, g.level2, state, local);
  for (size_t c = 0; c < one.size(); ++c)
    if (c == 1)
      EXPECT_GT(one[c], 0);
    else
      EXPECT_EQ(one[c], 0.0) << "cell " << c;
  EXPECT_THROW(cell_field_energies(fine, g.level2, state, VecX(3)), InputError);
}

TEST(AdaptiveMixedMesh, BadLevelsAndGridsAreRefused) {
  const Scene s = two_material_block();
  const Grids g = grids_of(s);
  std::vector<int> levels(g.level2.num_cells(), 3);
  EXPECT_THROW(naive_mixed_mesh(s, g, levels), InputError);
  levels.assign(g.level2.num_cells() - 1, 0);
  EXPECT_THROW(naive_mixed_mesh(s, g, levels), InputError);
  Grids swapped{g.level2, g.level1};
  EXPECT_THROW(naive_mixed_mesh(s, swapped, std::vector<int>(g.level1.num_cells(), 0)), InputError);
}

}  // namespace
}  // namespace msfab
