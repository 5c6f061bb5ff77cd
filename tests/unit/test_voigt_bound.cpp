// The Voigt bound of the two-scale optimizer (topopt/voigt_bound.hpp): its
// conditions are exactly positive semi-definiteness of
// rho C_stiff + (1 - rho) C_soft - C for every gamut space, their gradients
// match finite differences, homogenized structures obey it, and with it no
// gamut design beats SIMP with p = 1 (the bound's own optimum).
#include <gtest/gtest.h>

#include <random>

#include "core/errors.hpp"
#include "homog/elastic_tensor.hpp"
#include "homog/periodic_homogenization.hpp"
#include "io/config.hpp"
#include "material/linear_isotropic.hpp"
#include "topopt/cell_material.hpp"
#include "topopt/topology_objective.hpp"
#include "topopt/topology_optimizers.hpp"
#include "topopt/topopt_scene.hpp"
#include "topopt/voigt_bound.hpp"

namespace msfab {
namespace {

// A level set that allows every point of the unit cube with moduli above
// 0.2: as generous as a padded gamut gets, so only the bound holds C back.
GamutLevelSet generous_gamut(int d) {
  std::vector<VecX> points;
  std::mt19937 rng(5);
  std::uniform_real_distribution<double> U(0, 1);
  while (points.size() < 4000) points.push_back(VecX::NullaryExpr(d, [&] { return U(rng); }));
  LevelSetOptions o;
  o.cells = d == 5 ? 8 : 12;
  return GamutLevelSet::from_points(points, o);
}

MatX stiff_tensor(int dim) {
  const Mat6 C = isotropic_tensor(1e6, 0.3);
  return dim == 3 ? MatX(C) : MatX(plane_block(C));
}

std::unique_ptr<CellMaterialModel> bounded_model(const std::string& space, const GamutLevelSet& ls, double soft) {
  CellMaterialSettings s;
  s.space = space;
  s.E_stiff = 1e6;
  s.level_set = &ls;
  auto model = make_cell_material_model(s);
  const MatX C = stiff_tensor(model->dimension());
  model->set_voigt_bound(C, soft * C);
  return model;
}

TEST(VoigtBound, ConditionsAreZeroOnTheBoundAndMeasureTheExcessPerMode) {
  for (int dim : {2, 3}) {
    const MatX Cs = stiff_tensor(dim);
    const VoigtBound bound(Cs, MatX::Zero(Cs.rows(), Cs.cols()), VoigtBoundModes::cubic);
    ASSERT_EQ(bound.count(), 3);
    EXPECT_LT(bound.evaluate(Cs, 1.0).cwiseAbs().maxCoeff(), 1e-12);        // the solid
    EXPECT_LT(bound.evaluate(0.5 * Cs, 0.5).cwiseAbs().maxCoeff(), 1e-12);  // SIMP p = 1
    const VecX g = bound.evaluate(0.5 * Cs, 0.4);                           // 0.1 of the solid too stiff in every mode
    for (int i = 0; i < 3; ++i) EXPECT_NEAR(g[i], 0.1, 1e-12);
  }
  const MatX Cs = stiff_tensor(2);
  const VoigtBound ortho(Cs, MatX::Zero(3, 3), VoigtBoundModes::orthotropic2d);
  EXPECT_EQ(ortho.count(), 9);  // shear, and the normal block in 8 directions
  EXPECT_LT(ortho.evaluate(0.5 * Cs, 0.5).cwiseAbs().maxCoeff(), 1e-12);
  EXPECT_LT(ortho.evaluate(Cs, 1.0).cwiseAbs().maxCoeff(), 1e-12);
}

TEST(VoigtBound, ConditionsHoldExactlyWhenTheBoundIsPositiveSemidefinite) {
  // Random materials of each space around the bound: all conditions <= 0
  // if and only if rho C_s + (1 - rho) C_w - C has no negative eigenvalue
  // (cubic: exactly; orthotropic: its normal block's form in 8 directions,
  // so a negative eigenvalue of at most tan^2(11.25 deg) of the positive
  // one passes).
  const GamutLevelSet cubic = generous_gamut(4), ortho = generous_gamut(5);
  for (const std::string space : {"cubic2d", "cubic3d", "isotropic2d", "isotropic3d", "orthotropic2d"}) {
    for (double soft : {0.0, 0.01}) {
      const auto model = bounded_model(space, space == "orthotropic2d" ? ortho : cubic, soft);
      const MatX Cs = stiff_tensor(model->dimension());
      std::mt19937 rng(3);
      std::uniform_real_distribution<double> U(0.02, 0.98);
      int inside = 0, outside = 0;
      for (int trial = 0; trial < 400; ++trial) {
        VecX p(model->parameters());
        for (int k = 0; k < p.size(); ++k) p[k] = U(rng);
        // Moduli near the top of the range, where the bound matters.
        for (int k = 0; k + 1 < p.size(); ++k) p[k] = model->names()[k].rfind("nu", 0) == 0 ? p[k] : 0.75 + 0.25 * p[k];
        MatX C;
        model->tensor(p, C);
        const double rho = p[model->density_index()];
        const MatX B = rho * Cs + (1 - rho) * soft * Cs - C;
        const Eigen::SelfAdjointEigenSolver<MatX> eig(B);
        const double lambda = eig.eigenvalues().minCoeff() / Cs.norm();
        const double worst = model->bound_constraints(p, nullptr).maxCoeff();
        if (std::abs(lambda) < 1e-9 || std::abs(worst) < 1e-9) continue;  // on the boundary
        if (lambda >= 0) {
          EXPECT_LE(worst, 0) << space << " trial " << trial << " lambda " << lambda;
        }
        if (worst <= 0 && space == "orthotropic2d") {
          // The normal block's eigenvalues (the shear mode is separate).
          const Eigen::SelfAdjointEigenSolver<Eigen::Matrix2d> normal(B.topLeftCorner<2, 2>());
          const double tan2 = std::pow(std::tan(M_PI / 16), 2);
          EXPECT_GE(normal.eigenvalues()[0], -tan2 * normal.eigenvalues()[1] - 1e-12 * Cs.norm())
              << space << " trial " << trial;
          EXPECT_GE(B(2, 2), 0) << space << " trial " << trial;
        } else if (worst <= 0) {
          EXPECT_GE(lambda, 0) << space << " trial " << trial << " g " << worst;
        }
        (lambda >= 0 ? inside : outside) += 1;
      }
      EXPECT_GT(inside, 10) << space;
      EXPECT_GT(outside, 10) << space;
    }
  }
}

TEST(VoigtBound, JacobianMatchesFiniteDifferences) {
  const GamutLevelSet cubic = generous_gamut(4), ortho = generous_gamut(5);
  for (const std::string space : {"cubic2d", "cubic3d", "isotropic2d", "isotropic3d", "orthotropic2d"}) {
    const auto model = bounded_model(space, space == "orthotropic2d" ? ortho : cubic, 0.01);
    std::mt19937 rng(9);
    std::uniform_real_distribution<double> U(0.25, 0.75);
    for (int trial = 0; trial < 4; ++trial) {
      VecX p(model->parameters());
      for (int k = 0; k < p.size(); ++k) p[k] = U(rng);
      MatX jac;
      const VecX g = model->bound_constraints(p, &jac);
      ASSERT_EQ(jac.rows(), model->bound_conditions());
      ASSERT_EQ(jac.cols(), p.size());
      for (int k = 0; k < p.size(); ++k) {
        const double h = 1e-6;
        VecX pp = p, pm = p;
        pp[k] += h, pm[k] -= h;
        const VecX fd = (model->bound_constraints(pp, nullptr) - model->bound_constraints(pm, nullptr)) / (2 * h);
        EXPECT_LT((fd - jac.col(k)).norm(), 1e-6 * (1 + fd.norm())) << space << " d g / d p" << k;
      }
    }
  }
}

TEST(VoigtBound, HomogenizedStructuresObeyIt) {
  // Random two-phase 2D cells (stiff and void, stiff and soft): their
  // plane-strain C^H satisfies the bound with the base materials' tensors.
  const auto stiff = std::make_shared<LinearIsotropic>(1e6, 0.3);
  const auto soft = std::make_shared<LinearIsotropic>(1e4, 0.45);
  const MatX Cs = stiff_tensor(2);
  std::mt19937 rng(17);
  for (const bool with_soft : {false, true}) {
    const MatX Cw = with_soft ? MatX(plane_block(isotropic_tensor(1e4, 0.45))) : MatX::Zero(3, 3);
    const VoigtBound bound(Cs, Cw, VoigtBoundModes::orthotropic2d);
    for (int trial = 0; trial < 3; ++trial) {
      VoxelGrid cell(12, 12, 1, 1.0);
      std::bernoulli_distribution solid(0.55);
      for (auto& id : cell.ids) id = solid(rng) ? 1 : (with_soft ? 2 : 0);
      const PlaneStrainResult h = homogenize_plane_strain(cell, {nullptr, stiff, soft});
      const double rho = h.full.volume_fraction[1];
      // The ersatz void (1e-6 of the stiff element) is the only slack.
      EXPECT_LE(bound.evaluate(MatX(h.C), rho).maxCoeff(), 1e-5) << "soft " << with_soft << " trial " << trial;
      EXPECT_LT(bound.evaluate(MatX(h.C), rho).maxCoeff(), -1e-3) << "a random cell is well inside the bound";
    }
  }
}

TEST(VoigtBound, BadTensorsAreInputErrors) {
  const MatX Cs = stiff_tensor(2);
  EXPECT_THROW(VoigtBound(Cs, MatX::Zero(6, 6), VoigtBoundModes::cubic), InputError);
  EXPECT_THROW(VoigtBound(-Cs, MatX::Zero(3, 3), VoigtBoundModes::cubic), InputError);
  EXPECT_THROW(VoigtBound(Cs, 2 * Cs, VoigtBoundModes::cubic), InputError);
  EXPECT_THROW(VoigtBound(stiff_tensor(3), MatX::Zero(6, 6), VoigtBoundModes::orthotropic2d), InputError);
  CellMaterialSettings s;
  s.space = "cubic2d";
  s.E_stiff = 1e6;
  const GamutLevelSet cubic = generous_gamut(4);
  s.level_set = &cubic;
  EXPECT_THROW(make_cell_material_model(s)->set_voigt_bound(stiff_tensor(3), MatX::Zero(6, 6)), InputError);
}

// The cantilever of Fig. 3-16 on a 24 x 12 grid in the generous gamut.
double cantilever_compliance(const std::string& space, bool bound, int* iterations = nullptr,
                             double* violation = nullptr) {
  const TopoptScene sc = read_topopt_scene(Config::from_string(R"(
grid: {size: [24, 12]}
space: simp2d
material: {E: 1.0e6, nu: 0.3}
supports: [{box: {min: [0, 0], max: [0, 12]}}]
loads: [{objective: compliance, forces: [{box: {min: [12, 0], max: [24, 0]}, force: [0, -1], distribute: total}]}]
filter: {radius: 1.5}
)",
                                                               "test"),
                                           0, 4);
  const GamutLevelSet cubic = generous_gamut(4);
  CellMaterialSettings ms;
  ms.space = space;
  ms.E_stiff = 1e6;
  ms.nu = 0.3;
  ms.penalty = 1;
  ms.level_set = space == "cubic2d" ? &cubic : nullptr;
  auto model = make_cell_material_model(ms);
  // The bound's solid is SIMP's: the plane-stress tensor of E0, nu.
  if (bound) model->set_voigt_bound(isotropic_voigt(2, 1e6, 0.3), MatX::Zero(3, 3));
  TopologyObjective obj(sc.setup, *model);
  MatX q0(obj.design_cells().size(), model->parameters());
  for (Eigen::Index r = 0; r < q0.rows(); ++r) q0.row(r) = model->initial_point(0.5).transpose();
  OptimizerSettings os;
  os.max_iterations = 500;
  os.log_every = 0;
  os.mass_limit = true;
  os.mass_budget = 0.5 * 24 * 12;
  const OptimizationResult r = space == "simp2d" ? optimize_oc(obj, q0, os) : optimize_in_gamut(obj, q0, os);
  if (iterations) *iterations = r.converged ? r.iterations : -1;
  if (violation) *violation = r.max_violation;
  return r.value.elastic;
}

TEST(VoigtBound, NoGamutDesignBeatsSimpWithPenaltyOne) {
  // C <= rho C_s is met with equality by SIMP p = 1 (a convex problem, so
  // OC finds its optimum), and compliance falls as C grows: with the bound
  // the gamut design cannot be stiffer. Without it the generous level set
  // lets the optimizer beat it, which is what the bound is for.
  const double simp1 = cantilever_compliance("simp2d", false);
  int iterations = 0;
  double violation = 1;
  const double bounded = cantilever_compliance("cubic2d", true, &iterations, &violation);
  const double free = cantilever_compliance("cubic2d", false);
  EXPECT_GT(iterations, 0) << "the bounded run did not converge";
  EXPECT_LE(violation, 1e-3);
  EXPECT_GE(bounded, 0.99 * simp1) << "bounded " << bounded << " SIMP p = 1 " << simp1;
  EXPECT_LT(free, 0.9 * simp1) << "free " << free << " SIMP p = 1 " << simp1;
}

}  // namespace
}  // namespace msfab
