// DDFEM online coarsening: coarse grid, baseline coarsenings, error metric.
#include <gtest/gtest.h>

#include <Eigen/Geometry>
#include <cmath>
#include <cstdio>
#include <map>
#include <random>

#include "core/errors.hpp"
#include "ddfem/baseline_coarsening.hpp"
#include "ddfem/coarse_grid.hpp"
#include "ddfem/coarsening_error.hpp"
#include "ddfem/galerkin_quadrature.hpp"
#include "ddfem_test_blocks.hpp"
#include "fem/elastic_assembler.hpp"
#include "homog/elastic_tensor.hpp"
#include "homog/periodic_homogenization.hpp"
#include "material/neo_hookean.hpp"
#include "material/voigt.hpp"
#include "scene/scene.hpp"
#include "solve/newton.hpp"

using namespace msfab;

namespace {

std::vector<MaterialPtr> soft_stiff_palette() {
  return {nullptr, std::make_shared<NeoHookean>(1e5, 0.45), std::make_shared<NeoHookean>(1e7, 0.45)};
}

const ChildIds& children_of(const CoarseGrid& c, int I, int J, int K) {
  const int comb = c.cell_combination[c.index(I, J, K)];
  EXPECT_GE(comb, 0);
  return c.combinations.at(comb);
}

VecX random_positions(const HexMesh& mesh, double amplitude, unsigned seed) {
  std::mt19937 rng(seed);
  std::uniform_real_distribution<double> u(-amplitude, amplitude);
  VecX x(mesh.num_dofs());
  for (int n = 0; n < mesh.num_nodes(); ++n)
    for (int a = 0; a < 3; ++a) x[3 * n + a] = mesh.nodes(n, a) + u(rng);
  return x;
}

// Energy and gradient of two meshes with identical nodes must agree.
void expect_same_mechanics(const HexMesh& a, const HexMesh& b, double amplitude) {
  ASSERT_EQ(a.num_nodes(), b.num_nodes());
  ASSERT_EQ(a.num_elements(), b.num_elements());
  EXPECT_EQ((a.nodes - b.nodes).cwiseAbs().maxCoeff(), 0.0);
  ElasticAssembler aa(a), ab(b);
  const VecX x = random_positions(a, amplitude, 7);
  VecX ga, gb;
  const double ea = aa.evaluate(x, &ga, nullptr), eb = ab.evaluate(x, &gb, nullptr);
  ASSERT_TRUE(std::isfinite(ea));
  EXPECT_GT(ea, 0);
  EXPECT_NEAR(ea, eb, 1e-12 * std::abs(ea));
  EXPECT_LE((ga - gb).norm(), 1e-12 * ga.norm());
}

}  // namespace

TEST(DdfemCoarsenGrid, BlocksHaveHex8ChildOrder) {
  VoxelGrid g(4, 6, 2, 0.1);
  for (size_t v = 0; v < g.size(); ++v) g.ids[v] = static_cast<int>(v) + 1;  // every voxel distinct
  const CoarseGrid c = coarsen_grid(g);
  EXPECT_EQ(c.level, 1);
  EXPECT_EQ(c.nx, 2);
  EXPECT_EQ(c.ny, 3);
  EXPECT_EQ(c.nz, 1);
  EXPECT_DOUBLE_EQ(c.cell_size, 0.2);
  EXPECT_EQ(c.num_elements(), 6);
  EXPECT_EQ(c.combinations.size(), 6u);
  const ChildIds& c000 = children_of(c, 0, 0, 0);
  EXPECT_EQ(c000[0], g.at(0, 0, 0));
  EXPECT_EQ(c000[1], g.at(0, 0, 1));  // dk -> bit 0
  EXPECT_EQ(c000[2], g.at(0, 1, 0));  // dj -> bit 1
  EXPECT_EQ(c000[4], g.at(1, 0, 0));  // di -> bit 2
  EXPECT_EQ(c000[7], g.at(1, 1, 1));
  const ChildIds& c120 = children_of(c, 1, 2, 0);
  EXPECT_EQ(c120[5], g.at(3, 4, 1));
  EXPECT_EQ(c120[6], g.at(3, 5, 0));
  EXPECT_EQ(c120[3], g.at(2, 5, 1));
}

TEST(DdfemCoarsenGrid, OddSizesArePaddedWithVoidAndVoidBlocksDropped) {
  VoxelGrid g(5, 3, 1, 1.0, 1);
  g.at(4, 2, 0) = 2;
  const CoarseGrid c = coarsen_grid(g);
  EXPECT_EQ(c.nx, 3);
  EXPECT_EQ(c.ny, 2);
  EXPECT_EQ(c.nz, 1);
  const ChildIds& corner = children_of(c, 2, 1, 0);
  EXPECT_EQ(corner, (ChildIds{2, 0, 0, 0, 0, 0, 0, 0}));
  EXPECT_EQ(children_of(c, 0, 0, 0), (ChildIds{1, 0, 1, 0, 1, 0, 1, 0}));

  // Voxels only in x < 2 of a 6 x 2 x 2 grid: two of three blocks are void.
  VoxelGrid h(6, 2, 2, 1.0, 0);
  for (int j = 0; j < 2; ++j)
    for (int k = 0; k < 2; ++k) h.at(0, j, k) = h.at(1, j, k) = 1;
  h.at(5, 1, 1) = 0;
  const CoarseGrid ch = coarsen_grid(h);
  EXPECT_EQ(ch.num_cells(), 3);
  EXPECT_EQ(ch.num_elements(), 1);
  EXPECT_EQ(ch.cell_combination[1], -1);
  EXPECT_EQ(ch.cell_combination[2], -1);
  const VoxelMesh m = build_coarse_mesh(ch, naive_coarsening(soft_stiff_palette()));
  EXPECT_EQ(m.mesh.num_elements(), 1);
  EXPECT_EQ(m.mesh.num_nodes(), 8);

  EXPECT_THROW(coarsen_grid(VoxelGrid(2, 2, 2, 1.0, 0)), InputError);
}

TEST(DdfemCoarsenGrid, IdenticalBlocksShareOneMaterialEntry) {
  VoxelGrid g(8, 8, 4, 0.05, 1);
  for (int j = 0; j < 8; ++j)
    for (int i = 0; i < 8; ++i) g.at(i, j, 3) = 2;  // a stiff top layer, one voxel thick
  const CoarseGrid c = coarsen_grid(g);
  CoarseMeshStats stats;
  int calls = 0;
  auto naive = naive_coarsening(soft_stiff_palette());
  const VoxelMesh m = build_coarse_mesh(
      c,
      [&](const ChildIds& ids) {
        ++calls;
        return naive(ids);
      },
      0, &stats);
  EXPECT_EQ(stats.elements, 32);
  EXPECT_EQ(stats.distinct_combinations, 2);  // all-soft blocks and soft/stiff blocks
  EXPECT_EQ(calls, 2);
  EXPECT_EQ(m.mesh.materials.size(), 2u);
  EXPECT_EQ(m.mesh.geometries.size(), 1u);
  EXPECT_EQ(m.mesh.geometries[0].size(), 8);
  double vol = 0;
  for (double w : m.mesh.geometries[0].weight) vol += w;
  EXPECT_NEAR(vol, std::pow(0.1, 3), 1e-15);

  const CoarseGrid c2 = coarsen_grid(c);
  EXPECT_EQ(c2.level, 2);
  EXPECT_EQ(c2.fine_per_cell(), 4);
  EXPECT_EQ(c2.nx, 2);
  EXPECT_EQ(c2.nz, 1);
  EXPECT_DOUBLE_EQ(c2.cell_size, 0.2);
  ASSERT_EQ(c2.combinations.size(), 1u);
  // Children of a level-2 cell are level-1 combinations (index + 1).
  const ChildIds& l2 = c2.combinations[0];
  for (int q = 0; q < 8; ++q) EXPECT_EQ(c.combinations[l2[q] - 1][q & 1 ? 1 : 0], (q & 1) ? 2 : 1);
  const VoxelMesh m2 = build_coarse_mesh(c2, naive_coarsening(soft_stiff_palette(), c));
  EXPECT_EQ(m2.mesh.geometries[0].size(), 64);
  EXPECT_EQ(m2.mesh.materials[0].at_point.size(), 64u);
  // Point (a, b, c) of the 4-point rule lies in fine voxel (a, b, c) of the block: c = 3 is the stiff layer.
  EXPECT_EQ(m2.mesh.materials[0].at_point[(1 * 4 + 2) * 4 + 3]->shear_modulus(), lame_mu(1e7, 0.45));
  EXPECT_EQ(m2.mesh.materials[0].at_point[(1 * 4 + 2) * 4 + 2]->shear_modulus(), lame_mu(1e5, 0.45));
}

TEST(DdfemCoarsenBaselines, NaiveHomogeneousEqualsVoxelMeshOfDoubleSize) {
  const auto palette = soft_stiff_palette();
  VoxelGrid fine(4, 6, 4, 0.05, 2);
  fine.origin = Vec3(0.3, -0.1, 0.2);
  VoxelGrid ref(2, 3, 2, 0.1, 2);
  ref.origin = fine.origin;
  // One void 2x2x2 block, one block with a single void voxel (filled by the naive rule).
  for (int q = 0; q < 8; ++q) fine.at(2 + (q >> 2 & 1), 4 + (q >> 1 & 1), (q & 1)) = 0;
  ref.at(1, 2, 0) = 0;
  fine.at(0, 0, 0) = 0;
  const CoarseGrid c = coarsen_grid(fine);
  const VoxelMesh coarse = build_coarse_mesh(c, naive_coarsening(palette));
  const VoxelMesh reference = build_voxel_mesh(ref, palette);
  expect_same_mechanics(coarse.mesh, reference.mesh, 0.01);

  // Level 2 against a voxel mesh of 4h integrated with the same 4-point rule.
  VoxelGrid fine2(8, 8, 4, 0.05, 1);
  const CoarseGrid c1 = coarsen_grid(fine2);
  const VoxelMesh coarse2 = build_coarse_mesh(coarsen_grid(c1), naive_coarsening(palette, c1));
  VoxelMesh reference2 = build_voxel_mesh(VoxelGrid(2, 2, 1, 0.2, 1), palette);
  hex8::NodeMatrix cube;
  for (int q = 0; q < 8; ++q) cube.row(q) = 0.2 * Vec3(q >> 2 & 1, q >> 1 & 1, q & 1).transpose();
  reference2.mesh.geometries[0] = hex8::element_geometry(cube, hex8::gauss_rule(4));
  expect_same_mechanics(coarse2.mesh, reference2.mesh, 0.02);
}

TEST(DdfemCoarsenBaselines, AveragedUsesVolumeMeanOfLameParameters) {
  const auto palette = soft_stiff_palette();
  const double mu1 = lame_mu(1e5, 0.45), mu2 = lame_mu(1e7, 0.45);
  const double la1 = lame_lambda(1e5, 0.45), la2 = lame_lambda(1e7, 0.45);
  const auto averaged = averaged_coarsening(palette);
  const QuadratureMaterials half = averaged(ChildIds{1, 1, 1, 1, 2, 2, 2, 2});
  ASSERT_EQ(half.at_point.size(), 1u);
  EXPECT_NEAR(half.at(0)->shear_modulus(), 0.5 * (mu1 + mu2), 1e-9 * mu2);
  EXPECT_NEAR(half.at(0)->lame_lambda(), 0.5 * (la1 + la2), 1e-9 * la2);
  // Void counts as zero stiffness.
  const QuadratureMaterials mostly_void = averaged(ChildIds{0, 0, 2, 0, 0, 0, 0, 0});
  EXPECT_NEAR(mostly_void.at(0)->shear_modulus(), mu2 / 8, 1e-9 * mu2);
  EXPECT_NEAR(mostly_void.at(0)->lame_lambda(), la2 / 8, 1e-9 * la2);
  EXPECT_THROW(averaged(ChildIds{3, 1, 1, 1, 1, 1, 1, 1}), InputError);

  // Naive: a void child takes the softest of its nearest solid children
  // (children 1, 2, 4 share a face with child 0).
  const auto naive = naive_coarsening(palette);
  const ChildIds ids{0, 2, 1, 2, 2, 2, 2, 2};
  const QuadratureMaterials n = naive(ids);
  ASSERT_EQ(n.at_point.size(), 8u);
  EXPECT_EQ(n.at_point[0], palette[1]);
  for (int q = 1; q < 8; ++q) EXPECT_EQ(n.at_point[q], palette[ids[q]]);
  // Child 7 (corner opposite child 0) is void: its nearest solid children are 3, 5, 6.
  const QuadratureMaterials m = naive(ChildIds{1, 1, 1, 2, 1, 2, 2, 0});
  EXPECT_EQ(m.at_point[7], palette[2]);
}

// The Galerkin element is the fine mesh restricted to the coarse field: its
// energy and gradient are the fine ones of the interpolated field (the
// gradient through the transpose of the interpolation), on a random
// three-phase grid with void, at both levels; naive coarsening is not.
TEST(DdfemCoarsenBaselines, GalerkinElementIsTheFineEnergyOfTheInterpolatedField) {
  const auto palette = soft_stiff_palette();
  for (int level : {1, 2}) {
    VoxelGrid grid(level == 1 ? 4 : 8, 6, 4, 0.1, 1);
    std::mt19937 rng(3 + level);
    std::uniform_int_distribution<int> draw(0, 5);  // void one time in six, soft and stiff alike
    for (int k = 0; k < grid.nz; ++k)
      for (int j = 0; j < grid.ny; ++j)
        for (int i = 0; i < grid.nx; ++i) {
          const int v = draw(rng);
          grid.at(i, j, k) = v == 0 ? 0 : (v < 3 ? 1 : 2);
        }
    const VoxelMesh fine = build_voxel_mesh(grid, palette);
    const CoarseGrid l1 = coarsen_grid(grid);
    const CoarseGrid c = level == 1 ? l1 : coarsen_grid(l1);
    const hex8::QuadratureRule rule = hex8::composite_gauss_rule(c.fine_per_cell(), 2);
    ASSERT_EQ(rule.size(), level == 1 ? 64 : 512);
    const VoxelMesh galerkin = build_coarse_mesh(
        c, level == 1 ? galerkin_coarsening(palette, false) : galerkin_coarsening(palette, l1, false));
    const VoxelMesh naive =
        build_coarse_mesh(c, level == 1 ? naive_coarsening(palette) : naive_coarsening(palette, l1));

    const VecX xc = random_positions(galerkin.mesh, 0.004, 11);
    VecX u_coarse(xc.size());
    for (int n = 0; n < galerkin.mesh.num_nodes(); ++n)
      for (int a = 0; a < 3; ++a) u_coarse[3 * n + a] = xc[3 * n + a] - galerkin.mesh.nodes(n, a);
    const VecX u_fine = interpolate_to_fine(grid, fine, c, galerkin, u_coarse);
    VecX xf(u_fine.size());
    for (int n = 0; n < fine.mesh.num_nodes(); ++n)
      for (int a = 0; a < 3; ++a) xf[3 * n + a] = fine.mesh.nodes(n, a) + u_fine[3 * n + a];

    VecX gc, gf;
    const double ec = ElasticAssembler(galerkin.mesh).evaluate(xc, &gc, nullptr);
    const double ef = ElasticAssembler(fine.mesh).evaluate(xf, &gf, nullptr);
    ASSERT_GT(ef, 0);
    EXPECT_NEAR(ec, ef, 1e-11 * ef) << "level " << level;
    const SpMat P = coarse_to_fine_interpolation(grid, fine, c, galerkin);
    VecX restricted = VecX::Zero(gc.size());
    for (int a = 0; a < 3; ++a) {
      VecX ga(fine.mesh.num_nodes());
      for (int n = 0; n < fine.mesh.num_nodes(); ++n) ga[n] = gf[3 * n + a];
      const VecX ra = P.transpose() * ga;
      for (int m = 0; m < galerkin.mesh.num_nodes(); ++m) restricted[3 * m + a] = ra[m];
    }
    EXPECT_LE((restricted - gc).norm(), 1e-10 * gc.norm()) << "level " << level;
    // Naive coarsening puts each voxel's stiffness at one point: not the same energy.
    EXPECT_GT(std::abs(ElasticAssembler(naive.mesh).energy(xc) - ef), 1e-3 * ef) << "level " << level;
  }
}

// The reduced Galerkin element keeps, per material of the block, at most
// 23 of the composite rule's points (at level 2 under a third of them): its
// tangent at rest is the full
// element's (the stiffness monomials are integrated exactly), trilinear and
// with bubbles, at both levels, on a random three-phase grid with void; at
// a finite deformation the energy differs by the quadrature error only.
TEST(DdfemCoarsenBaselines, ReducedGalerkinElementKeepsTheStiffnessOnFewerPoints) {
  EXPECT_EQ(hex_stiffness_monomials().size(), 23u);
  const auto palette = soft_stiff_palette();
  for (int level : {1, 2})
    for (bool enhanced : {false, true}) {
      VoxelGrid grid(level == 1 ? 4 : 8, 8, 4, 0.1, 1);
      std::mt19937 rng(5 + level);
      std::uniform_int_distribution<int> draw(0, 5);
      for (int k = 0; k < grid.nz; ++k)
        for (int j = 0; j < grid.ny; ++j)
          for (int i = 0; i < grid.nx; ++i) {
            const int v = draw(rng);
            grid.at(i, j, k) = v == 0 ? 0 : (v < 3 ? 1 : 2);
          }
      const CoarseGrid l1 = coarsen_grid(grid);
      const CoarseGrid c = level == 1 ? l1 : coarsen_grid(l1);
      const VoxelMesh full = build_coarse_mesh(
          c, level == 1 ? galerkin_coarsening(palette, false) : galerkin_coarsening(palette, l1, false), 0, nullptr,
          enhanced);
      const VoxelMesh reduced = build_coarse_mesh(
          c, level == 1 ? galerkin_coarsening(palette) : galerkin_coarsening(palette, l1), 0, nullptr, enhanced);
      ASSERT_EQ(full.mesh.num_elements(), reduced.mesh.num_elements());
      size_t full_points = 0, reduced_points = 0;
      for (int e = 0; e < full.mesh.num_elements(); ++e) {
        const QuadratureMaterials& m = reduced.mesh.materials[reduced.mesh.element_material[e]];
        ASSERT_TRUE(m.rule);
        std::map<const Material*, int> per_material;
        for (const MaterialPtr& p : m.at_point) {
          ASSERT_TRUE(p);  // void points are dropped
          ++per_material[p.get()];
        }
        for (const auto& [material, count] : per_material) EXPECT_LE(count, 23);
        for (double w : m.rule->weights) EXPECT_GT(w, 0);
        reduced_points += m.at_point.size();
        full_points += full.mesh.materials[full.mesh.element_material[e]].at_point.size();
      }
      // Level 1: a material in one or two voxels keeps all their points (8
      // per voxel integrate the 23 monomials exactly and no fewer of them do).
      EXPECT_LT((level == 2 ? 3 : 1) * reduced_points, full_points) << "level " << level;

      const ElasticAssembler af(full.mesh), ar(reduced.mesh);
      VecX rest(full.mesh.num_dofs());
      for (int n = 0; n < full.mesh.num_nodes(); ++n) rest.segment<3>(3 * n) = full.mesh.nodes.row(n).transpose();
      SpMat Kf = af.pattern(), Kr = ar.pattern();
      VecX gf, gr;
      af.evaluate(rest, &gf, &Kf);
      ar.evaluate(rest, &gr, &Kr);
      const double scale = MatX(Kf).norm();
      EXPECT_LE(MatX(Kf - Kr).norm(), 1e-10 * scale) << "level " << level << (enhanced ? " enhanced" : "");
      // A finite deformation (strains of a few per cent): close, not equal.
      const VecX x = random_positions(full.mesh, 0.004, 11);
      const double ef = af.energy(x), er = ar.energy(x);
      ASSERT_GT(ef, 0);
      EXPECT_NEAR(er, ef, 2e-2 * ef) << "level " << level << (enhanced ? " enhanced" : "");
      EXPECT_GT(std::abs(er - ef), 1e-14 * ef);  // the reduction is not the full rule in disguise
    }
}

TEST(DdfemCoarsenBaselines, HomogenizedElementHasTheBlockStiffnessAtSmallStrain) {
  const auto palette = soft_stiff_palette();
  const auto homogenized = homogenized_coarsening(palette);
  const Eigen::Matrix<double, 6, 9> B = voigt_strain_operator();
  // A homogeneous block: exactly its palette material (no anisotropic part).
  const QuadratureMaterials same = homogenized(ChildIds{2, 2, 2, 2, 2, 2, 2, 2});
  ASSERT_EQ(same.at_point.size(), 1u);
  EXPECT_NEAR(same.at(0)->shear_modulus(), palette[2]->shear_modulus(), 1e-8 * palette[2]->shear_modulus());
  EXPECT_LE((same.at(0)->stress_derivative(Mat3::Identity()) - palette[2]->stress_derivative(Mat3::Identity())).norm(),
            1e-8 * palette[2]->stress_derivative(Mat3::Identity()).norm());
  // Layers normal to x (children 0-3 soft, 4-7 stiff): the tangent at rest
  // is B^T C^H B, with the laminate's series modulus across the layers and
  // the parallel one along them.
  const QuadratureMaterials layered = homogenized(ChildIds{1, 1, 1, 1, 2, 2, 2, 2});
  VoxelGrid cell(2, 2, 2, 1.0, 1);
  for (int q = 4; q < 8; ++q) cell.at(1, q >> 1 & 1, q & 1) = 2;
  HomogenizationOptions options;
  options.solver = "cholmod";
  // Material Voigt order (xx, yy, zz, xy, yz, zx), checked on the physics:
  const Mat6 C = to_material_voigt_order(homogenize(cell, palette, options).C);
  EXPECT_LE((layered.at(0)->stress_derivative(Mat3::Identity()) - B.transpose() * C * B).norm(), 1e-8 * C.norm());
  const double mu1 = palette[1]->shear_modulus(), mu2 = palette[2]->shear_modulus();
  EXPECT_NEAR(C(4, 4), 0.5 * (mu1 + mu2), 1e-6 * mu2);            // yz, in the layer plane: parallel
  EXPECT_NEAR(C(3, 3), 2 * mu1 * mu2 / (mu1 + mu2), 1e-6 * mu1);  // xy, across the layers: series
  EXPECT_NEAR(C(5, 5), C(3, 3), 1e-9 * mu1);                      // zx, likewise
  // Pure shear yz stores the parallel modulus in the element's energy.
  Mat3 F = Mat3::Identity();
  F(1, 2) = 1e-4;
  EXPECT_NEAR(layered.at(0)->energy(F), 0.5 * C(4, 4) * 1e-8, 1e-3 * C(4, 4) * 1e-8);
  // Rotations store no energy; a block with void falls back to naive.
  const Mat3 R = Eigen::AngleAxisd(0.9, Vec3(1, -1, 2).normalized()).toRotationMatrix();
  EXPECT_LE(layered.at(0)->energy(R), 1e-12 * mu2);
  EXPECT_EQ(homogenized(ChildIds{0, 2, 1, 2, 2, 2, 2, 2}).at_point.size(), 8u);
  EXPECT_THROW(homogenized(ChildIds{3, 1, 1, 1, 1, 1, 1, 1}), InputError);
}

namespace {

struct ErrorFixture {
  VoxelGrid grid;
  VoxelMesh fine;
  CoarseGrid coarse;
  VoxelMesh coarse_mesh;
};

ErrorFixture make_error_fixture(int nx, int ny, int nz, int levels) {
  ErrorFixture f;
  f.grid = VoxelGrid(nx, ny, nz, 0.1, 1);
  f.grid.origin = Vec3(-0.2, 0.1, 0.05);
  f.grid.at(0, 0, 0) = 0;
  f.grid.at(nx - 1, ny - 1, 0) = 2;
  const auto palette = soft_stiff_palette();
  f.fine = build_voxel_mesh(f.grid, palette);
  f.coarse = coarsen_grid(f.grid);
  if (levels == 2) {
    const CoarseGrid l1 = f.coarse;
    f.coarse = coarsen_grid(l1);
    f.coarse_mesh = build_coarse_mesh(f.coarse, averaged_coarsening(palette, l1));
  } else {
    f.coarse_mesh = build_coarse_mesh(f.coarse, averaged_coarsening(palette));
  }
  return f;
}

VecX affine_field(const HexMesh& mesh, const Mat3& A, const Vec3& b) {
  VecX u(mesh.num_dofs());
  for (int n = 0; n < mesh.num_nodes(); ++n) u.segment<3>(3 * n) = A * mesh.nodes.row(n).transpose() + b;
  return u;
}

}  // namespace

TEST(DdfemCoarsenError, AffineFieldsInterpolateExactly) {
  Mat3 A;
  A << 0.1, -0.2, 0.05, 0.3, 0.02, -0.1, 0.07, 0.11, -0.3;
  const Vec3 b(0.01, -0.02, 0.03);
  for (const auto& [dims, levels] :
       std::vector<std::pair<std::array<int, 3>, int>>{{{4, 6, 4}, 1}, {{5, 6, 3}, 1}, {{8, 7, 4}, 2}}) {
    const ErrorFixture f = make_error_fixture(dims[0], dims[1], dims[2], levels);
    const VecX uf = affine_field(f.fine.mesh, A, b), uc = affine_field(f.coarse_mesh.mesh, A, b);
    const VecX interp = interpolate_to_fine(f.grid, f.fine, f.coarse, f.coarse_mesh, uc);
    EXPECT_LE((interp - uf).cwiseAbs().maxCoeff(), 1e-14) << dims[0] << "x" << dims[1] << "x" << dims[2];
    EXPECT_LE(mean_vertex_error(f.grid, f.fine, uf, f.coarse, f.coarse_mesh, uc), 1e-14);
  }
}

TEST(DdfemCoarsenError, ConstantOffsetGivesItsLengthOverLongestDimension) {
  const ErrorFixture f = make_error_fixture(4, 6, 4, 1);
  const Vec3 d(0.003, -0.004, 0.012);  // |d| = 0.013
  const VecX uc = affine_field(f.coarse_mesh.mesh, Mat3::Zero(), d);
  const VecX uf = VecX::Zero(f.fine.mesh.num_dofs());
  EXPECT_NEAR(mean_vertex_error(f.grid, f.fine, uf, f.coarse, f.coarse_mesh, uc), 0.013 / 0.6, 1e-15);
  // The interpolation and the metric refuse a coarse grid of another fine grid.
  VoxelGrid other = f.grid;
  other.voxel_size = 0.2;
  EXPECT_THROW(mean_vertex_error(other, f.fine, uf, f.coarse, f.coarse_mesh, uc), InputError);
  EXPECT_THROW(mean_vertex_error(f.grid, f.fine, uf, f.coarse, f.coarse_mesh, uc.head(6)), InputError);
}

TEST(DdfemCoarsenError, FloorOfARepresentableFieldIsZero) {
  Mat3 A;
  A << 0.1, -0.2, 0.05, 0.3, 0.02, -0.1, 0.07, 0.11, -0.3;
  for (int levels : {1, 2}) {
    const ErrorFixture f = make_error_fixture(8, 6, 4, levels);
    const VecX uc = affine_field(f.coarse_mesh.mesh, A, Vec3(0.01, 0, -0.02));
    const VecX uf = interpolate_to_fine(f.grid, f.fine, f.coarse, f.coarse_mesh, uc);
    const CoarseErrorFloor floor = coarse_error_floor(f.grid, f.fine, uf, f.coarse, f.coarse_mesh);
    EXPECT_LE(floor.error, 1e-12);
    EXPECT_LE(floor.lower_bound, floor.error);
  }
}

TEST(DdfemCoarsenError, FloorIsTheMinimumOverCoarseFields) {
  // A field no coarse mesh represents: smooth plus voxel-scale wiggles.
  const ErrorFixture f = make_error_fixture(8, 6, 6, 1);
  std::mt19937 rng(5);
  std::normal_distribution<double> noise(0.0, 1.0);
  VecX uf(f.fine.mesh.num_dofs());
  for (int n = 0; n < f.fine.mesh.num_nodes(); ++n) {
    const Vec3 x = f.fine.mesh.nodes.row(n).transpose();
    uf.segment<3>(3 * n) = Vec3(std::sin(4 * x[1]), x[0] * x[2], std::cos(3 * x[0])) * 0.01 +
                           0.002 * Vec3(noise(rng), noise(rng), noise(rng));
  }
  const CoarseErrorFloor floor = coarse_error_floor(f.grid, f.fine, uf, f.coarse, f.coarse_mesh);
  ASSERT_EQ(floor.coarse_displacement.size(), f.coarse_mesh.mesh.num_dofs());
  // The returned field has the returned error.
  EXPECT_NEAR(mean_vertex_error(f.grid, f.fine, uf, f.coarse, f.coarse_mesh, floor.coarse_displacement), floor.error,
              1e-12 * floor.error);
  // Certified to the requested gap, and the certificate is below every coarse field's error.
  EXPECT_LE(floor.lower_bound, floor.error);
  EXPECT_GE(floor.lower_bound, (1 - 1e-3) * floor.error);
  std::uniform_int_distribution<int> pick(0, int(floor.coarse_displacement.size()) - 1);
  for (int trial = 0; trial < 50; ++trial) {
    VecX uc = floor.coarse_displacement;
    for (int k = 0; k < 3; ++k) uc[pick(rng)] += 1e-4 * noise(rng);
    EXPECT_GE(mean_vertex_error(f.grid, f.fine, uf, f.coarse, f.coarse_mesh, uc), floor.lower_bound);
  }
  // Least squares alone (one iteration) is not the minimum of a mean of norms.
  CoarseErrorFloorOptions one;
  one.max_iterations = 1;
  const CoarseErrorFloor least_squares = coarse_error_floor(f.grid, f.fine, uf, f.coarse, f.coarse_mesh, one);
  EXPECT_GT(least_squares.error, floor.error);
  EXPECT_THROW(coarse_error_floor(f.grid, f.fine, uf.head(9), f.coarse, f.coarse_mesh), InputError);
}

namespace {

// 4 x 16 x 4 bar along y, soft/stiff layers two voxels thick, clamped at
// y = 0, total force at the far end.
Scene layered_bar(bool aligned) {
  Scene s;
  s.name = "layered-bar";
  s.grid = VoxelGrid(4, 16, 4, 0.01, 0);
  for (int k = 0; k < 4; ++k)
    for (int j = 0; j < 16; ++j)
      for (int i = 0; i < 4; ++i) {
        const int layer = aligned ? j / 2 : (j + 1) / 2;  // offset: every block straddles two layers
        s.grid.at(i, j, k) = layer % 2 == 0 ? 1 : 2;
      }
  s.material_by_id = soft_stiff_palette();
  ddfem_test::clamp_y0_load_top(s, Vec3(0.2, 0, 0));
  return s;
}

struct Solved {
  VecX u;
  int dofs = 0;
};

Solved solve(const VoxelMesh& vm, const StaticConditions& sc) {
  ElasticAssembler asmb(vm.mesh);
  NewtonOptions opt;
  opt.linear_solver = "cholmod";
  const NewtonResult r = solve_static(asmb, sc.dirichlet, sc.force, opt);
  EXPECT_TRUE(r.converged) << r.failure;
  return {r.x - asmb.rest_positions(), vm.mesh.num_dofs()};
}

}  // namespace

TEST(DdfemCoarsenEndToEnd, LayeredBarNaiveAndAveragedAgainstFine) {
  for (bool aligned : {false, true}) {
    const Scene s = layered_bar(aligned);
    const VoxelMesh fine = build_voxel_mesh(s.grid, s.material_by_id);
    const Solved uf = solve(fine, build_static_conditions(s, fine));
    const CoarseGrid c = coarsen_grid(s.grid);
    double err[2];
    const char* names[2] = {"naive", "averaged"};
    for (int b = 0; b < 2; ++b) {
      CoarseMeshStats stats;
      const VoxelMesh cm = build_coarse_mesh(
          c, b == 0 ? naive_coarsening(s.material_by_id) : averaged_coarsening(s.material_by_id), 0, &stats);
      const StaticConditions sc = coarse_static_conditions(s, fine, c, cm);
      // Restriction keeps the total load; the clamp covers the coarse ymin face (3 x 3 nodes).
      EXPECT_NEAR(sc.force.reshaped(3, cm.mesh.num_nodes()).rowwise().sum()(0), 0.2, 1e-14);
      EXPECT_EQ(sc.dirichlet.count_fixed(), 27);
      const Solved ucs = solve(cm, sc);
      EXPECT_LT(ucs.dofs, uf.dofs / 4);
      err[b] = mean_vertex_error(s.grid, fine, uf.u, c, cm, ucs.u);
      EXPECT_TRUE(std::isfinite(err[b]));
      EXPECT_GT(err[b], 0);
      // Both baselines are stiffer than the fine model (§2.5.2).
      EXPECT_LT(ucs.u.maxCoeff(), uf.u.maxCoeff());
      std::printf(
          "layered bar (%s layers): %s error %.3e, fine max ux %.3e m, coarse max ux %.3e m, coarse %d DOFs vs fine "
          "%d, "
          "coarsening %.2e s (grid) + %.2e s (mesh), %d combinations\n",
          aligned ? "aligned" : "offset", names[b], err[b], uf.u.maxCoeff(), ucs.u.maxCoeff(), ucs.dofs, uf.dofs,
          c.seconds, stats.seconds, stats.distinct_combinations);
    }
    // No coarse model does better than the best trilinear fit of the fine field.
    const CoarseErrorFloor floor =
        coarse_error_floor(s.grid, fine, uf.u, c, build_coarse_mesh(c, naive_coarsening(s.material_by_id)));
    EXPECT_LE(floor.lower_bound, floor.error);
    EXPECT_LE(floor.error, std::min(err[0], err[1]));
    EXPECT_GT(floor.lower_bound, 0.05 * floor.error);  // a certificate that says something
    std::printf(
        "layered bar (%s layers): best possible error on the coarse mesh %.3e (certified >= %.3e, %d iterations)\n",
        aligned ? "aligned" : "offset", floor.error, floor.lower_bound, floor.iterations);
    if (aligned) {
      // Homogeneous blocks: both baselines are the exact material layout.
      EXPECT_NEAR(err[0], err[1], 1e-9 * err[0]);
    } else {
      EXPECT_GT(std::abs(err[0] - err[1]), 1e-3 * err[0]);
    }
  }
}
