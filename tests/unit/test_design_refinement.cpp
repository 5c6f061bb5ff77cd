// A two-scale design's elasticity on m^3 hexahedra per design cell
// (`elements_per_cell`, verify/design_refinement.hpp): a uniform stretch is
// exact on every mesh, so its compliance does not change with m; a bent bar's
// compliance grows with m (nested conforming meshes: the energy of the
// solution rises towards the limit), which is the locking the option
// removes; and the gradient with respect to the design cells matches
// central differences.
#include <gtest/gtest.h>

#include <random>

#include "io/config.hpp"
#include "topopt/cell_material.hpp"
#include "topopt/topopt_scene.hpp"
#include "verify/design_refinement.hpp"

namespace msfab {
namespace {

TopoptScene refined_scene(const std::string& yaml, int m) {
  TopoptScene sc = read_topopt_scene(Config::from_string(yaml, "test"), 0, 4);
  refine_fem_mesh(sc.setup, m);
  return sc;
}

// Compliance of the uniform design q (every cell E0 at rho = 1) of a scene.
double refined_compliance(const std::string& yaml, int m, const std::function<void(TopologySetup&)>& edit = {}) {
  TopoptScene sc = read_topopt_scene(Config::from_string(yaml, "test"), 0, 4);
  if (edit) edit(sc.setup);
  refine_fem_mesh(sc.setup, m);
  CellMaterialSettings ms{"simp3d", sc.E0, sc.decades, sc.nu, 3, 1e-9, nullptr};
  const auto model = make_cell_material_model(ms);
  TopologyObjective obj(sc.setup, *model);
  return obj.evaluate(MatX::Ones(Eigen::Index(obj.design_cells().size()), 1), nullptr).elastic;
}

TEST(DesignRefinement, UniformStretchIsTheSameOnEveryMesh) {
  // A 4 x 2 x 2 bar on rollers pulled by a uniform traction: the consistent
  // load of the end face (corner 1/4, edge 1/2, middle 1 of h^2 sigma).
  const char* yaml = R"(
grid: {size: [4, 2, 2]}
space: simp3d
material: {E: 1000.0, nu: 0.3}
supports:
  - {box: {min: [0, 0, 0], max: [0, 2, 2]}, fix: [x]}
  - {box: {min: [0, 0, 0], max: [4, 0, 2]}, fix: [y]}
  - {box: {min: [0, 0, 0], max: [4, 2, 0]}, fix: [z]}
loads: [{objective: compliance, forces: [{node: [4, 0, 0], force: [1, 0, 0]}]}]
)";
  const auto traction = [](TopologySetup& s) {
    VecX& f = s.loads[0].force;
    f.setZero();
    for (int j = 0; j <= 2; ++j)
      for (int k = 0; k <= 2; ++k) f[s.grid.node_index(4, j, k) * 3] = (j == 1 ? 1.0 : 0.5) * (k == 1 ? 1.0 : 0.5);
  };
  // F = 4 sigma with sigma = 1: compliance F^2 L / (E A) = 16 * 4 / (1000 * 4).
  const double exact = 16.0 * 4.0 / (1000.0 * 4.0);
  for (int m : {1, 2, 3}) EXPECT_NEAR(refined_compliance(yaml, m, traction), exact, 1e-10 * exact) << "m " << m;
}

TEST(DesignRefinement, BendingComplianceGrowsWithElementsPerCell) {
  const char* yaml = R"(
grid: {size: [6, 2, 2]}
space: simp3d
supports: [{box: {min: [0, 0, 0], max: [0, 2, 2]}}]
loads: [{objective: compliance, forces: [{box: {min: [6, 0, 0], max: [6, 2, 2]}, force: [0, 0, -1], distribute: total}]}]
)";
  const double c1 = refined_compliance(yaml, 1), c2 = refined_compliance(yaml, 2), c4 = refined_compliance(yaml, 4);
  EXPECT_GT(c2, 1.05 * c1);  // one hexahedron per cell locks
  EXPECT_GT(c4, c2);
  EXPECT_LT(c4 - c2, c2 - c1);  // converging
}

TEST(DesignRefinement, GradientMatchesFiniteDifferences) {
  const TopoptScene sc = refined_scene(R"(
grid: {size: [3, 2, 2]}
space: analytic3d
material: {E: 1.0e6, nu: 0.3}
supports: [{box: {min: [0, 0, 0], max: [0, 2, 2]}}]
loads:
  - {objective: compliance, forces: [{box: {min: [3, 0, 0], max: [3, 2, 0]}, force: [0, 0, -1], distribute: total}]}
  - objective: target
    forces: [{node: [3, 1, 2], force: [0, 1, 0]}]
    targets: [{node: [3, 2, 2], displacement: [0, 1.0e-6, 0]}]
mass: {target: 4, weight: 0.1}
filter: {radius: 1.5}
)",
                                       2);
  ASSERT_EQ(sc.setup.fem_grid.cells(), 8 * 12);
  CellMaterialSettings ms{"analytic3d", sc.E0, sc.decades, sc.nu, 3, 1e-9, nullptr};
  const auto model = make_cell_material_model(ms);
  TopologyObjective obj(sc.setup, *model);
  std::mt19937 rng(5);
  std::uniform_real_distribution<double> U(0.3, 0.7);
  MatX q(obj.design_cells().size(), model->parameters());
  for (Eigen::Index i = 0; i < q.size(); ++i) q(i % q.rows(), i / q.rows()) = U(rng);
  MatX g;
  const double S0 = obj.evaluate(q, &g).total;
  for (Eigen::Index i = 0; i < q.size(); ++i) {
    const double h = 1e-6;
    MatX qp = q, qm = q;
    qp(i % q.rows(), i / q.rows()) += h;
    qm(i % q.rows(), i / q.rows()) -= h;
    const double fd = (obj.evaluate(qp, nullptr).total - obj.evaluate(qm, nullptr).total) / (2 * h);
    EXPECT_NEAR(g(i % q.rows(), i / q.rows()), fd, 1e-4 * (std::abs(fd) + 1e-6 * std::abs(S0))) << "variable " << i;
  }
  // The design grid's displacement is the fine mesh's at the coinciding nodes.
  const VecX u = obj.grid_displacement(0);
  const CellGrid& f = obj.fem_grid();
  EXPECT_EQ(u.size(), sc.setup.grid.unknowns());
  EXPECT_EQ(u[sc.setup.grid.node_index(3, 1, 2) * 3 + 2], obj.displacements()[0][f.node_index(6, 2, 4) * 3 + 2]);
}

TEST(DesignRefinement, AnEmptyRegionSolvesAlikeWithMultigridAndCholesky) {
  // The gripper plate's scene (a forced-empty mouth) on 2^3 hexahedra per
  // cell: the nodes that only empty cells touch are held (with the family's
  // members the multigrid preconditioner met negative curvature there where
  // CHOLMOD solved; this uniform SIMP design does not), and holding them
  // leaves matrix-free multigrid and CHOLMOD in agreement on the objective
  // and its adjoint.
  const std::string yaml = R"(
grid: {size: [32, 16, 2]}
space: simp3d
domain: [{box: {min: [20, 6, 0], max: [32, 10, 2]}, role: empty}]
supports: [{box: {min: [0, 7, 0], max: [0, 9, 2]}}]
loads:
  - objective: target
    forces:
      - {box: {min: [2, 16, 0], max: [6, 16, 2]}, force: [0, -1, 0], distribute: total}
      - {box: {min: [2, 0, 0], max: [6, 0, 2]}, force: [0, 1, 0], distribute: total}
    targets:
      - {box: {min: [30, 10, 0], max: [32, 10, 2]}, displacement: [0, -0.25, 0], weight: 1}
      - {box: {min: [30, 6, 0], max: [32, 6, 2]}, displacement: [0, 0.25, 0], weight: 1}
)";
  double compliance[2];
  MatX gradient[2];
  for (int s = 0; s < 2; ++s) {
    TopoptScene sc = refined_scene(yaml, 2);
    sc.setup.solver = s == 0 ? "cholmod" : "matrix-free";
    sc.setup.solver_options.pcg_tolerance = 1e-12;
    CellMaterialSettings ms{"simp3d", sc.E0, sc.decades, sc.nu, 3, 1e-9, nullptr};
    const auto model = make_cell_material_model(ms);
    TopologyObjective obj(sc.setup, *model);
    compliance[s] = obj.evaluate(MatX::Constant(Eigen::Index(obj.design_cells().size()), 1, 0.6), &gradient[s]).elastic;
  }
  EXPECT_NEAR(compliance[1], compliance[0], 1e-7 * compliance[0]);
  EXPECT_LT((gradient[1] - gradient[0]).norm(), 1e-6 * gradient[0].norm());
}

}  // namespace
}  // namespace msfab
