// Periodic homogenization (thesis §3.2): exact cases, bounds, symmetry and
// convergence under refinement.
#include <gtest/gtest.h>

#include <chrono>
#include <random>
#include <thread>

#include "core/errors.hpp"
#include "gamut/structure_ops.hpp"
#include "homog/mirror_reduction.hpp"
#include "homog/periodic_homogenization.hpp"
#include "material/linear_isotropic.hpp"

namespace msfab {
namespace {

std::vector<MaterialPtr> two_phases(double E1, double nu1, double E2, double nu2) {
  return {nullptr, std::make_shared<LinearIsotropic>(E1, nu1), std::make_shared<LinearIsotropic>(E2, nu2)};
}

// Exact effective tensor of a laminate with normal x (phases in series
// across x, in parallel along y, z): strains along the layers and the
// tractions on them are continuous. Independent of the FEM.
Mat6 laminate_x(const std::vector<Mat6>& C, const std::vector<double>& f) {
  const int N[3] = {0, 4, 5}, T[3] = {1, 2, 3};  // normal-type and tangential Voigt components
  auto sub = [](const Mat6& M, const int* r, const int* c) {
    Mat3 S;
    for (int a = 0; a < 3; ++a)
      for (int b = 0; b < 3; ++b) S(a, b) = M(r[a], c[b]);
    return S;
  };
  Mat3 A = Mat3::Zero(), B = Mat3::Zero();
  for (std::size_t p = 0; p < C.size(); ++p) {
    const Mat3 inv = sub(C[p], N, N).inverse();
    A += f[p] * inv;
    B += f[p] * inv * sub(C[p], N, T);
  }
  Mat6 Ceff = Mat6::Zero();
  for (int m = 0; m < 6; ++m) {
    Vec6 e = Vec6::Zero();
    e[m] = 1;
    Vec3 eN, eT;
    for (int a = 0; a < 3; ++a) eN[a] = e[N[a]], eT[a] = e[T[a]];
    const Vec3 sN = A.inverse() * (eN + B * eT);  // continuous tractions
    Vec6 s = Vec6::Zero();
    for (std::size_t p = 0; p < C.size(); ++p) {
      const Vec3 eNp = sub(C[p], N, N).inverse() * (sN - sub(C[p], N, T) * eT);
      const Vec3 sT = sub(C[p], T, N) * eNp + sub(C[p], T, T) * eT;
      for (int a = 0; a < 3; ++a) s[T[a]] += f[p] * sT[a];
    }
    for (int a = 0; a < 3; ++a) s[N[a]] = sN[a];
    Ceff.col(m) = s;
  }
  return Ceff;
}

VoxelGrid sphere_inclusion(int n, double radius_fraction) {
  VoxelGrid g(n, n, n, 1.0 / n, 1);
  for (int k = 0; k < n; ++k)
    for (int j = 0; j < n; ++j)
      for (int i = 0; i < n; ++i) {
        const Vec3 x = g.voxel_center(i, j, k) - Vec3(0.5, 0.5, 0.5);
        if (x.norm() < radius_fraction) g.at(i, j, k) = 2;
      }
  return g;
}

TEST(Homogenization, SmallCellsOfOneSizeGiveTheSameBitsWhateverCameBefore) {
  // Each thread keeps the symbolic analysis of the last small cell size it
  // solved directly; a cell must come out as from a thread that never
  // solved one.
  const auto pal = two_phases(1e6, 0.3, 5e4, 0.4);
  std::mt19937_64 rng(17);
  auto random_cell = [&](int nx, int void_every) {
    VoxelGrid cell(nx, 6, 6, 1e-3, 1);
    int v = 0;
    for (int& id : cell.ids) id = (void_every > 0 && ++v % void_every == 0) ? 0 : 1 + int(rng() % 2);
    return cell;
  };
  const VoxelGrid a = random_cell(6, 0), b = random_cell(6, 0), holed = random_cell(6, 7), longer = random_cell(7, 0);
  HomogenizationOptions direct;
  direct.solver = "cholmod";
  Mat6 a_fresh, holed_fresh;
  std::thread([&] { a_fresh = homogenize(a, pal, direct).C; }).join();
  std::thread([&] { holed_fresh = homogenize(holed, pal, direct).C; }).join();
  homogenize(b, pal, direct);
  homogenize(longer, pal, direct);  // another size: analyzed anew
  homogenize(b, pal, direct);
  EXPECT_EQ(homogenize(holed, pal, direct).C, holed_fresh);  // void voxels: the same pattern
  EXPECT_EQ(homogenize(a, pal, direct).C, a_fresh);
  EXPECT_GT((a_fresh - homogenize(b, pal, direct).C).norm(), 1e-3 * a_fresh.norm());
}

TEST(Homogenization, HomogeneousCellReturnsItsMaterial) {
  const auto pal = two_phases(2e6, 0.3, 1e5, 0.45);
  const VoxelGrid cell(3, 4, 2, 1e-3, 1);
  const HomogenizationResult r = homogenize(cell, pal);
  const Mat6 C0 = isotropic_tensor(2e6, 0.3);
  EXPECT_LT((r.C - C0).norm(), 1e-9 * C0.norm());
  EXPECT_LT((r.G * C0 - Mat6::Identity()).norm(), 1e-9);
  EXPECT_NEAR(r.volume_fraction[1], 1.0, 1e-15);
  EXPECT_EQ(r.pieces, 1);
  // The fluctuation vanishes: the affine field is the solution.
  for (int m = 0; m < 6; ++m) EXPECT_LT(r.fluctuation[m].cwiseAbs().maxCoeff(), 1e-12);
}

TEST(Homogenization, LaminateMatchesTheExactFormulaInEveryEntry) {
  const double E1 = 3e6, nu1 = 0.3, E2 = 2e5, nu2 = 0.45;
  const auto pal = two_phases(E1, nu1, E2, nu2);
  VoxelGrid cell(5, 2, 3, 1e-3, 1);
  for (int k = 0; k < 3; ++k)
    for (int j = 0; j < 2; ++j)
      for (int i = 3; i < 5; ++i) cell.at(i, j, k) = 2;  // 2 of 5 layers soft
  const HomogenizationResult r = homogenize(cell, pal);
  const Mat6 exact = laminate_x({isotropic_tensor(E1, nu1), isotropic_tensor(E2, nu2)}, {0.6, 0.4});
  for (int a = 0; a < 6; ++a)
    for (int b = 0; b < 6; ++b) EXPECT_NEAR(r.C(a, b), exact(a, b), 1e-9 * exact.norm()) << a << "," << b;
  // Series stiffness across the layers is below the parallel one along them.
  EXPECT_LT(r.C(0, 0), r.C(1, 1));
}

TEST(Homogenization, RandomCellsLieBetweenVoigtAndReussBounds) {
  const double E1 = 1e6, nu1 = 0.3, E2 = 5e4, nu2 = 0.4;
  const auto pal = two_phases(E1, nu1, E2, nu2);
  std::mt19937_64 rng(3);
  for (int trial = 0; trial < 3; ++trial) {
    VoxelGrid cell(6, 6, 6, 1e-3, 1);
    for (int& id : cell.ids) id = 1 + int(rng() % 2);
    const HomogenizationResult r = homogenize(cell, pal);
    const double f1 = r.volume_fraction[1], f2 = r.volume_fraction[2];
    const Mat6 C1 = isotropic_tensor(E1, nu1), C2 = isotropic_tensor(E2, nu2);
    const Mat6 voigt = f1 * C1 + f2 * C2, reuss = (f1 * C1.inverse() + f2 * C2.inverse()).inverse();
    Eigen::SelfAdjointEigenSolver<Mat6> upper(voigt - r.C), lower(r.C - reuss), self(r.C);
    EXPECT_GT(upper.eigenvalues().minCoeff(), -1e-9 * voigt.norm()) << "trial " << trial;
    EXPECT_GT(lower.eigenvalues().minCoeff(), -1e-9 * voigt.norm()) << "trial " << trial;
    EXPECT_GT(self.eigenvalues().minCoeff(), 0.0);
    // The Voigt-average bulk modulus lies between the phases' arithmetic and harmonic means.
    const double KV = (r.C.topLeftCorner<3, 3>().sum()) / 9;
    const double K1 = E1 / (3 * (1 - 2 * nu1)), K2 = E2 / (3 * (1 - 2 * nu2));
    EXPECT_LT(KV, f1 * K1 + f2 * K2);
    EXPECT_GT(KV, 1 / (f1 / K1 + f2 / K2));
  }
}

TEST(Homogenization, CubicCellGivesACubicTensorWithinHashinShtrikmanForBulk) {
  const double E1 = 1e6, nu1 = 0.3, E2 = 2e4, nu2 = 0.45;
  const auto pal = two_phases(E1, nu1, E2, nu2);
  const VoxelGrid cell = sphere_inclusion(10, 0.35);
  const HomogenizationResult r = homogenize(cell, pal);
  EXPECT_LT(cubic_deviation(r.C), 1e-9);
  const CubicModuli m = cubic_moduli(r.C);
  EXPECT_GT(m.E, 0);
  // Hashin-Shtrikman bounds on the bulk modulus (cubic symmetry suffices).
  const double f1 = r.volume_fraction[1], f2 = r.volume_fraction[2];
  const double K1 = E1 / (3 * (1 - 2 * nu1)), G1 = E1 / (2 * (1 + nu1));
  const double K2 = E2 / (3 * (1 - 2 * nu2)), G2 = E2 / (2 * (1 + nu2));
  const double K_upper = K1 + f2 / (1 / (K2 - K1) + 3 * f1 / (3 * K1 + 4 * G1));
  const double K_lower = K2 + f1 / (1 / (K1 - K2) + 3 * f2 / (3 * K2 + 4 * G2));
  const double K = (m.C11 + 2 * m.C12) / 3;
  std::printf("[homogenization] sphere: K %.4g in HS [%.4g, %.4g], E %.4g nu %.4f G' %.4f\n", K, K_lower, K_upper, m.E,
              m.nu, m.shear_ratio);
  EXPECT_GT(K, K_lower);
  EXPECT_LT(K, K_upper);
}

TEST(Homogenization, ConvergesUnderRefinementOfTheSameSphere) {
  const auto pal = two_phases(1e6, 0.3, 1e4, 0.3);
  std::vector<CubicModuli> m;
  for (int n : {6, 12, 24}) {
    const auto t0 = std::chrono::steady_clock::now();
    const HomogenizationResult r = homogenize(sphere_inclusion(n, 0.3), pal);
    m.push_back(cubic_moduli(r.C));
    std::printf("[homogenization] sphere n=%d: E %.6g nu %.6f G %.6g (%.2f s)\n", n, m.back().E, m.back().nu,
                m.back().G, std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count());
  }
  const double d1 = std::abs(m[1].E - m[0].E), d2 = std::abs(m[2].E - m[1].E);
  EXPECT_LT(d2, d1);
  EXPECT_LT(d2 / m[2].E, 0.02);
  EXPECT_LT(std::abs(m[2].G - m[1].G), std::abs(m[1].G - m[0].G));
}

TEST(Homogenization, VoidCellsAreSolvableAndPiecesAreCounted) {
  // Three orthogonal bars through the cell (cubic), void elsewhere.
  const auto pal = two_phases(1e6, 0.3, 1e6, 0.3);
  VoxelGrid cell(6, 6, 6, 1e-3, 0);
  for (int a = 0; a < 6; ++a)
    for (int b = 2; b < 4; ++b)
      for (int c = 2; c < 4; ++c) cell.at(a, b, c) = cell.at(b, a, c) = cell.at(b, c, a) = 1;
  HomogenizationResult r = homogenize(cell, pal);
  EXPECT_EQ(r.pieces, 1);
  EXPECT_LT(cubic_deviation(r.C), 1e-8);
  const CubicModuli m = cubic_moduli(r.C);
  // Stretching along a bar: close to its area fraction times E, far stiffer than shear.
  EXPECT_GT(m.E, 0.9 * (4.0 / 36) * 1e6);
  EXPECT_LT(m.E, 1.3 * (4.0 / 36) * 1e6);
  EXPECT_LT(m.shear_ratio, 0.3);  // shear bends the bars: far below isotropic (1)
  // A floating voxel is a second piece; the system stays solvable.
  cell.at(0, 0, 0) = 1;
  r = homogenize(cell, pal);
  EXPECT_EQ(r.pieces, 2);
  EXPECT_TRUE(r.C.allFinite());
}

TEST(Homogenization, BadCellsAreInputErrors) {
  const auto pal = two_phases(1e6, 0.3, 1e5, 0.3);
  EXPECT_THROW(homogenize(VoxelGrid(2, 2, 2, 1e-3, 0), pal), InputError);
  EXPECT_THROW(homogenize(VoxelGrid(2, 2, 2, 1e-3, 3), pal), InputError);
  EXPECT_THROW(homogenize(VoxelGrid(), pal), InputError);
  HomogenizationOptions o;
  o.void_stiffness = 0;
  EXPECT_THROW(homogenize(VoxelGrid(2, 2, 2, 1e-3, 1), pal, o), InputError);
}

TEST(Homogenization, PlaneStrainMatchesTheExtrudedCellAndTheExactCases) {
  const double E1 = 1e6, nu1 = 0.3, E2 = 3e4, nu2 = 0.45;
  const auto pal = two_phases(E1, nu1, E2, nu2);
  // Homogeneous: the plane-strain tensor of the material.
  const PlaneStrainResult h = homogenize_plane_strain(VoxelGrid(3, 3, 1, 1e-3, 1), pal);
  const Mat6 C3 = isotropic_tensor(E1, nu1);
  Mat3 expected;
  expected << C3(0, 0), C3(0, 1), 0, C3(1, 0), C3(1, 1), 0, 0, 0, C3(5, 5);
  EXPECT_LT((h.C - expected).norm(), 1e-9 * expected.norm());
  const PlaneModuli m = plane_moduli(h.C);
  EXPECT_NEAR(m.Ex, E1 / (1 - nu1 * nu1), 1e-6 * E1);  // plane-strain modulus
  EXPECT_NEAR(m.nu_xy, nu1 / (1 - nu1), 1e-9);
  // A random 2D pattern against the same pattern extruded 3 voxels along z.
  std::mt19937_64 rng(5);
  VoxelGrid flat(7, 5, 1, 1e-3, 1), tall(7, 5, 3, 1e-3, 1);
  for (int j = 0; j < 5; ++j)
    for (int i = 0; i < 7; ++i) {
      const int id = 1 + int(rng() % 2);
      flat.at(i, j, 0) = id;
      for (int k = 0; k < 3; ++k) tall.at(i, j, k) = id;
    }
  const PlaneStrainResult p = homogenize_plane_strain(flat, pal);
  const HomogenizationResult t = homogenize(tall, pal);
  const int in_plane[3] = {0, 1, 5};
  for (int a = 0; a < 3; ++a)
    for (int b = 0; b < 3; ++b) EXPECT_NEAR(p.C(a, b), t.C(in_plane[a], in_plane[b]), 1e-9 * p.C.norm());
  EXPECT_THROW(homogenize_plane_strain(tall, pal), InputError);
}

// A random two-phase cell invariant under the cyclic axis permutation
// (i, j, k) -> (k, i, j) only: no mirror symmetry, so it is chiral and its
// tensor is not cubic (C14-type couplings survive).
VoxelGrid cyclic_random_cell(int n, std::uint64_t seed) {
  std::mt19937_64 rng(seed);
  VoxelGrid g(n, n, n, 1.0 / n, 1);
  for (int k = 0; k < n; ++k)
    for (int j = 0; j < n; ++j)
      for (int i = 0; i < n; ++i) {
        const int id = 1 + int(rng() % 2);
        g.at(i, j, k) = g.at(k, i, j) = g.at(j, k, i) = id;  // the orbit: the last write wins for all three
      }
  return g;
}

TEST(Homogenization, CyclicSymmetryTwoSolvesEqualSixSolves) {
  // The symmetric path (two cell problems, four carried by the
  // permutation) against six separate solves: direct at 6^3, multigrid at
  // 16^3, two phases 100x apart.
  const auto pal = two_phases(1e6, 0.3, 1e4, 0.45);
  for (const std::string solver : {"cholmod", "matrix-free"}) {
    const int n = solver == "cholmod" ? 6 : 16;
    const VoxelGrid cell = cyclic_random_cell(n, 11);
    HomogenizationOptions six, two;
    six.solver = two.solver = solver;
    six.use_symmetry = false;
    six.tolerance = two.tolerance = 1e-12;
    const HomogenizationResult a = homogenize(cell, pal, six), b = homogenize(cell, pal, two);
    EXPECT_FALSE(a.symmetric_cases);
    EXPECT_TRUE(b.symmetric_cases) << solver;
    EXPECT_LT((a.C - b.C).norm(), 1e-10 * a.C.norm()) << solver;
    for (int m = 0; m < 6; ++m)
      EXPECT_LT((a.fluctuation[m] - b.fluctuation[m]).norm(), 1e-8 * a.fluctuation[m].norm() + 1e-14)
          << solver << " case " << m;
    if (solver == "matrix-free") {
      EXPECT_LT(b.iterations, 0.5 * a.iterations);
    }
    // Chiral: off-cubic couplings are present, so the test does not pass by a cubic tensor alone.
    EXPECT_GT(std::abs(a.C(0, 3)) + std::abs(a.C(3, 4)), 1e-6 * a.C(0, 0)) << solver;
  }
  // A cell that breaks the permutation in one voxel takes six solves.
  VoxelGrid broken = cyclic_random_cell(6, 11);
  broken.at(1, 2, 3) = broken.at(1, 2, 3) == 1 ? 2 : 1;
  EXPECT_FALSE(homogenize(broken, pal).symmetric_cases);
  // Non-cubic grids never take the symmetric path.
  EXPECT_FALSE(homogenize(VoxelGrid(4, 4, 6, 0.25, 1), pal).symmetric_cases);
}

// Random ids (void included when `with_void`) mirrored into the three
// reflections i -> n - 1 - i: an orthotropic gamut structure's symmetry,
// not a cubic one (the grid need not be a cube).
VoxelGrid mirrored_random_cell(int nx, int ny, int nz, std::uint64_t seed, bool with_void) {
  std::mt19937_64 rng(seed);
  VoxelGrid g(nx, ny, nz, 1.0 / nx, 1);
  for (int& id : g.ids) id = with_void ? int(rng() % 3) : 1 + int(rng() % 2);
  mirror_fundamental_domain(g, CellSymmetry::orthotropic);
  return g;
}

TEST(Homogenization, MirrorSymmetricCellsSolvedOnOneOctantMatchTheWholeCell) {
  // The octant with mirror conditions against the whole periodic cell
  // (direct, no reduction): two phases with different Poisson ratios (two
  // element bases), with and without void, a non-cubic grid, both octant
  // solvers; and a cubic cell with the cyclic reduction on top.
  const auto pal = two_phases(1e6, 0.3, 1e4, 0.45);
  struct Case {
    int nx, ny, nz;
    bool with_void, cubic;
  };
  for (const Case c : {Case{8, 12, 16, false, false}, Case{8, 12, 16, true, false}, Case{12, 12, 12, false, true}}) {
    VoxelGrid cell = mirrored_random_cell(c.nx, c.ny, c.nz, 5, c.with_void);
    if (c.cubic) mirror_fundamental_domain(cell, CellSymmetry::cubic);
    HomogenizationOptions whole;
    whole.solver = "cholmod";
    whole.use_symmetry = whole.use_mirror_symmetry = false;
    const HomogenizationResult a = homogenize(cell, pal, whole);
    EXPECT_FALSE(a.octant);
    for (const std::string solver : {"cholmod", "matrix-free"}) {
      HomogenizationOptions o;
      o.solver = solver;
      o.tolerance = 1e-12;
      const HomogenizationResult b = homogenize(cell, pal, o);
      const std::string what = solver + " " + std::to_string(c.nx) + "x" + std::to_string(c.ny) + "x" +
                               std::to_string(c.nz) + (c.with_void ? " void" : "");
      EXPECT_TRUE(b.octant) << what;
      EXPECT_EQ(b.solver, solver) << what;
      EXPECT_EQ(b.symmetric_cases, c.cubic) << what;
      EXPECT_LT(b.unknowns, a.unknowns / 6) << what;
      EXPECT_LT((a.C - b.C).norm(), 1e-10 * a.C.norm()) << what;
      for (int m = 0; m < 6; ++m)
        EXPECT_LT((a.fluctuation[m] - b.fluctuation[m]).norm(), 1e-8 * a.fluctuation[m].norm() + 1e-14)
            << what << " case " << m;
    }
    // Orthotropic: the couplings between normal and shear strains vanish.
    EXPECT_LT((a.C.topRightCorner<3, 3>().norm()), 1e-10 * a.C.norm());
  }
}

TEST(Homogenization, CellsWithoutTheThreeMirrorsUseTheWholeCell) {
  const auto pal = two_phases(1e6, 0.3, 1e4, 0.45);
  VoxelGrid broken = mirrored_random_cell(8, 8, 8, 3, false);
  broken.at(1, 2, 3) = broken.at(1, 2, 3) == 1 ? 2 : 1;
  EXPECT_FALSE(homogenize(broken, pal).octant);
  // 2D cells and odd dimensions keep the whole cell.
  EXPECT_FALSE(homogenize(mirrored_random_cell(8, 8, 1, 3, false), pal).octant);
  EXPECT_FALSE(homogenize(mirrored_random_cell(6, 6, 7, 3, false), pal).octant);
  // A material that is not mirror-symmetric (a shear-normal coupling
  // added to an isotropic element) keeps the whole cell too.
  VoxelStiffnessField field;
  field.nx = field.ny = field.nz = 4;
  field.h = 0.25;
  Mat24 K = voxel_stiffness(pal[1], 0.25);
  const Mat24 isotropic = K;
  K(0, 4) += 1e-3 * K(0, 0), K(4, 0) += 1e-3 * K(0, 0);
  field.basis = {K};
  field.weights.assign(64, 1.0);
  EXPECT_FALSE(mirror_invariant(field));
  field.basis = {isotropic};
  EXPECT_TRUE(mirror_invariant(field));
  EXPECT_TRUE(homogenize_elements(field).octant);
}

}  // namespace
}  // namespace msfab
