// The periodic cell under finite uniaxial stress (homog/finite_strain_cell.hpp):
// gradient, Hessian and axial force against finite differences; a solid
// cell against the closed-form Neo-Hookean uniaxial stress; a frame cell at
// small strain and with a linear material against the linear C^H.
#include <gtest/gtest.h>

#include <cmath>

#include "core/errors.hpp"
#include "homog/elastic_tensor.hpp"
#include "homog/finite_strain_cell.hpp"
#include "homog/periodic_homogenization.hpp"
#include "material/linear_isotropic.hpp"
#include "material/neo_hookean.hpp"

namespace msfab {
namespace {

// Three orthogonal bars of width 2 through a 6^3 cell: cubic, one piece,
// spanning the cell periodically, and far from isotropic.
VoxelGrid frame_cell() {
  VoxelGrid g(6, 6, 6, 1.0 / 6, 0);
  auto in_bar = [](int i) { return i == 2 || i == 3; };
  for (int k = 0; k < 6; ++k)
    for (int j = 0; j < 6; ++j)
      for (int i = 0; i < 6; ++i)
        if (in_bar(i) + in_bar(j) + in_bar(k) >= 2) g.at(i, j, k) = 1;
  return g;
}

TEST(FiniteStrainCell, GradientHessianAndAxialForceMatchFiniteDifferences) {
  VoxelGrid cell = frame_cell();
  cell.at(0, 2, 2) = 2;  // a second material, and no symmetry left
  const std::vector<MaterialPtr> palette = {nullptr, std::make_shared<NeoHookean>(1.0, 0.3),
                                            std::make_shared<NeoHookean>(0.2, 0.45)};
  const PeriodicFiniteStrainCell model(cell, palette, 1);
  VecX z = model.rest();
  for (int i = 0; i < z.size(); ++i) z[i] += 0.01 * std::sin(1.7 * i + 0.3);
  const double s = 1.05;
  VecX g;
  SpMat H;
  double dE_ds = 0;
  const double E = model.energy(s, z, &g, &H, &dE_ds);
  ASSERT_TRUE(std::isfinite(E));
  const double eps = 1e-6;
  double worst_g = 0, worst_H = 0;
  const MatX Hd = MatX(H);
  for (int i = 0; i < z.size(); i += 7) {
    VecX zp = z, zm = z, gp, gm;
    zp[i] += eps, zm[i] -= eps;
    const double fd = (model.energy(s, zp, &gp, nullptr) - model.energy(s, zm, &gm, nullptr)) / (2 * eps);
    worst_g = std::max(worst_g, std::abs(fd - g[i]) / (g.cwiseAbs().maxCoeff()));
    worst_H = std::max(worst_H, ((gp - gm) / (2 * eps) - Hd.col(i)).cwiseAbs().maxCoeff() / Hd.cwiseAbs().maxCoeff());
  }
  for (int i : {static_cast<int>(z.size()) - 2, static_cast<int>(z.size()) - 1}) {  // the lateral stretches
    VecX zp = z, zm = z, gp, gm;
    zp[i] += eps, zm[i] -= eps;
    const double fd = (model.energy(s, zp, &gp, nullptr) - model.energy(s, zm, &gm, nullptr)) / (2 * eps);
    worst_g = std::max(worst_g, std::abs(fd - g[i]) / (g.cwiseAbs().maxCoeff()));
    worst_H = std::max(worst_H, ((gp - gm) / (2 * eps) - Hd.col(i)).cwiseAbs().maxCoeff() / Hd.cwiseAbs().maxCoeff());
  }
  EXPECT_LT(worst_g, 1e-7);
  EXPECT_LT(worst_H, 1e-6);
  EXPECT_LT((Hd - Hd.transpose()).cwiseAbs().maxCoeff(), 1e-12 * Hd.cwiseAbs().maxCoeff());
  const double fd_s =
      (model.energy(s + eps, z, nullptr, nullptr) - model.energy(s - eps, z, nullptr, nullptr)) / (2 * eps);
  EXPECT_NEAR(dE_ds, fd_s, 1e-7 * std::abs(fd_s));
}

// Compressible Neo-Hookean under uniaxial stress, F = diag(s, t, t):
// lateral stress zero gives mu (t^2 - 1) + lambda log(s t^2) = 0 (bisection),
// and the nominal axial stress is mu (s - 1/s) + lambda log(s t^2) / s.
TEST(FiniteStrainCell, SolidCellIsTheNeoHookeanUniaxialStress) {
  const double E = 3.0, nu = 0.35, mu = lame_mu(E, nu), lambda = lame_lambda(E, nu);
  VoxelGrid cell(3, 3, 3, 0.5, 1);
  const std::vector<MaterialPtr> palette = {nullptr, std::make_shared<NeoHookean>(E, nu)};
  const std::vector<double> strains = {0.07, -0.07, 0.02};
  const auto points = uniaxial_finite_strain(cell, palette, 2, strains);
  ASSERT_EQ(points.size(), strains.size());
  for (std::size_t p = 0; p < strains.size(); ++p) {
    const double s = 1 + strains[p];
    double lo = 0.5, hi = 1.5;
    for (int it = 0; it < 200; ++it) {
      const double t = 0.5 * (lo + hi);
      (mu * (t * t - 1) + lambda * std::log(s * t * t) > 0 ? hi : lo) = t;
    }
    const double t = 0.5 * (lo + hi);
    EXPECT_NEAR(points[p].strain, strains[p], 0);
    EXPECT_NEAR(points[p].stretch[2], s, 1e-15);
    EXPECT_NEAR(points[p].stretch[0], t, 1e-9) << strains[p];
    EXPECT_NEAR(points[p].stretch[1], t, 1e-9) << strains[p];
    EXPECT_NEAR(points[p].nominal_stress, mu * (s - 1 / s) + lambda * std::log(s * t * t) / s, 1e-8 * E);
    EXPECT_NEAR(points[p].nu[0], -(t - 1) / strains[p], 1e-7);
  }
  // Compression stiffens the lateral response of Neo-Hookean less than tension softens it: nu differs from 0.35.
  EXPECT_GT(std::abs(points[0].nu[0] - nu), 1e-3);
}

// Uniaxial stress of C^H: nu_axis,l = -S(l, axis) / S(axis, axis), E = 1 / S(axis, axis).
TEST(FiniteStrainCell, FrameAtSmallStrainAndLinearFrameAtAnyStrainMatchTheLinearCH) {
  const VoxelGrid cell = frame_cell();
  HomogenizationOptions ho;
  ho.void_stiffness = 1e-12;
  ho.solver = "cholmod";
  const double E = 1.0, nu = 0.3;
  const std::vector<MaterialPtr> neo = {nullptr, std::make_shared<NeoHookean>(E, nu)};
  const std::vector<MaterialPtr> linear = {nullptr, std::make_shared<LinearIsotropic>(E, nu)};
  const HomogenizationResult r = homogenize(cell, linear, ho);
  const Mat6 S = r.C.inverse();
  const double nu_ch = -S(1, 0) / S(0, 0), E_ch = 1 / S(0, 0);
  ASSERT_GT(nu_ch, 0.01);  // a frame: far below the solid's 0.3

  const auto small = uniaxial_finite_strain(cell, neo, 0, {1e-5, -1e-5});
  for (const auto& p : small) {
    EXPECT_NEAR(p.nu[0], nu_ch, 1e-4 * nu_ch + 1e-6) << p.strain;
    EXPECT_NEAR(p.nu[1], nu_ch, 1e-4 * nu_ch + 1e-6) << p.strain;
    EXPECT_NEAR(p.nominal_stress / p.strain, E_ch, 1e-4 * E_ch) << p.strain;
  }
  // A linear material makes the cell problem quadratic: the same ratio at 7%.
  const auto big = uniaxial_finite_strain(cell, linear, 0, {0.07, -0.07});
  for (const auto& p : big) {
    EXPECT_NEAR(p.nu[0], nu_ch, 1e-7) << p.strain;
    EXPECT_NEAR(p.nominal_stress / p.strain, E_ch, 1e-7 * E_ch) << p.strain;
  }
  // Neo-Hookean at 7% departs from the linear ratio, and by more than round-off.
  const auto neo_big = uniaxial_finite_strain(cell, neo, 0, {0.07});
  EXPECT_GT(std::abs(neo_big[0].nu[0] - nu_ch), 1e-4);
}

// A voxel that touches the frame along one edge only hinges about it at no
// energy: the Hessian is singular there and the solver shifts it. The
// dangling voxel only follows its edge's stretch, so the frame's response
// moves by a few 1e-5.
TEST(FiniteStrainCell, HingedVoxelIsShiftedAndBarelyMovesTheFrame) {
  const VoxelGrid frame = frame_cell();
  VoxelGrid hinged = frame;
  ASSERT_EQ(hinged.at(2, 2, 0), 1);
  hinged.at(1, 1, 0) = 1;  // shares the z-edge at (2, 2) with the z bar, nothing else
  const std::vector<MaterialPtr> palette = {nullptr, std::make_shared<NeoHookean>(1.0, 0.3)};
  const auto plain = uniaxial_finite_strain(frame, palette, 0, {0.03});
  const auto with_hinge = uniaxial_finite_strain(hinged, palette, 0, {0.03});
  EXPECT_EQ(plain[0].shifted_factorizations, 0);
  EXPECT_GT(with_hinge[0].shifted_factorizations, 0);
  EXPECT_NEAR(with_hinge[0].nu[0], plain[0].nu[0], 1e-4 * plain[0].nu[0]);
  EXPECT_NEAR(with_hinge[0].nominal_stress, plain[0].nominal_stress, 1e-4 * plain[0].nominal_stress);
}

TEST(FiniteStrainCell, RefusesFloatingPiecesVoidAndFlatCells) {
  const std::vector<MaterialPtr> palette = {nullptr, std::make_shared<NeoHookean>(1.0, 0.3)};
  VoxelGrid two(6, 6, 6, 1.0, 0);
  two.at(0, 0, 0) = 1, two.at(3, 3, 3) = 1;
  EXPECT_THROW(PeriodicFiniteStrainCell(two, palette, 0), InputError);
  EXPECT_THROW(PeriodicFiniteStrainCell(VoxelGrid(4, 4, 4, 1.0, 0), palette, 0), InputError);
  EXPECT_THROW(PeriodicFiniteStrainCell(VoxelGrid(4, 4, 1, 1.0, 1), palette, 0), InputError);
  EXPECT_THROW(uniaxial_finite_strain(VoxelGrid(4, 4, 4, 1.0, 1), palette, 0, {0.0}), InputError);
  // One piece that does not reach its periodic copies carries no macroscopic stress.
  VoxelGrid island(6, 6, 6, 1.0, 0);
  island.at(2, 2, 2) = island.at(3, 2, 2) = 1;
  EXPECT_THROW(PeriodicFiniteStrainCell(island, palette, 0), InputError);
  // Plates spanning x and y only (a layer of voxels at k = 0..1 with nothing above).
  VoxelGrid plate(4, 4, 4, 1.0, 0);
  for (int j = 0; j < 4; ++j)
    for (int i = 0; i < 4; ++i) plate.at(i, j, 0) = plate.at(i, j, 1) = 1;
  EXPECT_THROW(PeriodicFiniteStrainCell(plate, palette, 0), InputError);
}

}  // namespace
}  // namespace msfab
