// Structures generated at a design's targets (msfab-fill-targets): the
// coverage of a set, the grouping of uncovered cells into targets, and the
// continuous step aimed at a target a set does not hold, on 2D lattices.
#include <gtest/gtest.h>

#include <cmath>

#include "core/errors.hpp"
#include "gamut/material_space.hpp"
#include "gamut/structure_ops.hpp"
#include "homog/periodic_homogenization.hpp"
#include "mapping/mapper.hpp"
#include "mapping/target_fill.hpp"
#include "material/linear_isotropic.hpp"

namespace msfab {
namespace {

constexpr int kN = 16;
const MaterialSpace kSpace(MaterialSpaceKind::cubic2d, 1e6 / (1 - 0.09));

// A square lattice: bars of `width` voxels along both mid-lines.
std::vector<int> lattice_ids(int width) {
  VoxelGrid c(kN, kN, 1, 1.0 / kN, 0);
  for (int j = 0; j < kN; ++j)
    for (int i = 0; i < kN; ++i)
      if (std::abs(2 * i + 1 - kN) < 2 * width || std::abs(2 * j + 1 - kN) < 2 * width) c.at(i, j, 0) = 1;
  return c.ids;
}

Microstructure homogenized(const std::vector<int>& ids) {
  VoxelGrid c(kN, kN, 1, 1.0 / kN);
  c.ids = ids;
  HomogenizationOptions ho;
  ho.void_stiffness = 1e-6;
  const HomogenizationResult h = homogenize(c, {nullptr, std::make_shared<LinearIsotropic>(1e6, 0.3)}, ho);
  Microstructure m;
  m.ids = ids;
  m.C = h.C;
  m.properties = kSpace.cell_properties(h.C, h.volume_fraction[1]);
  m.unit = kSpace.normalize(m.properties);
  return m;
}

// Lattices of bar widths 1 and 5 (the set); width 3 lies between them.
MicrostructureSet lattice_set() {
  MicrostructureSet set;
  set.space = "cubic2d";
  set.property_names = kSpace.names();
  set.E_stiff = kSpace.E_stiff();
  set.decades = 4;
  set.nx = set.ny = kN, set.nz = 1;
  set.stiff = {1e6, 0.3};
  set.soft_is_void = true;
  for (int w : {1, 5}) set.items.push_back(homogenized(lattice_ids(w)));
  return set;
}

Design design_of(const std::vector<VecX>& unit_targets) {
  Design d;
  d.space = "cubic2d";
  d.property_names = kSpace.names();
  d.E_stiff = kSpace.E_stiff();
  d.dimension = 2;
  d.nx = static_cast<int>(unit_targets.size()), d.ny = 1, d.nz = 1;
  d.unit = MatX(d.nx, Eigen::Index(unit_targets.front().size()));
  d.raw = d.unit;
  for (int c = 0; c < d.nx; ++c) {
    d.unit.row(c) = unit_targets[std::size_t(c)].transpose();
    d.raw.row(c) = kSpace.denormalize(unit_targets[std::size_t(c)]).transpose();
  }
  d.roles.assign(std::size_t(d.nx), CellRole::design);
  d.phi = VecX::Zero(d.nx);
  return d;
}

CandidateOptions nearest(int k) {
  CandidateOptions o;
  o.k = k;
  return o;
}
CandidateOptions k1() { return nearest(1); }
CandidateOptions k2() { return nearest(2); }
CandidateOptions k3() { return nearest(3); }

TEST(TargetFill, CoverageIsTheSmallestGapAmongTheNearestStructures) {
  const MicrostructureSet set = lattice_set();
  const VecX middle = homogenized(lattice_ids(3)).unit;
  Design d = design_of({set.items[0].unit, middle, set.items[1].unit});
  d.roles[2] = CellRole::solid;
  const CellCoverage c = cell_coverage(d, set, k2());
  EXPECT_LT(c.gap[0], 1e-12);  // the set's own structure
  EXPECT_EQ(c.best[0], 0);
  EXPECT_EQ(c.best[2], -1);  // not a design cell
  const double to0 = relative_stiffness_gap(kSpace, set.items[0].properties, d.raw.row(1).transpose());
  const double to1 = relative_stiffness_gap(kSpace, set.items[1].properties, d.raw.row(1).transpose());
  EXPECT_DOUBLE_EQ(c.gap[1], std::min(to0, to1));
  EXPECT_GT(c.gap[1], 0.2);
  EXPECT_EQ(c.design_cells, 2);
  EXPECT_EQ(c.above(0.1), 1);
  EXPECT_DOUBLE_EQ(c.max_gap, c.gap[1]);
}

TEST(TargetFill, UncoveredCellsWithinTheRadiusShareOneTargetWorstFirst) {
  const MicrostructureSet set = lattice_set();
  const VecX middle = homogenized(lattice_ids(3)).unit;
  VecX near = middle, far = middle;
  near[1] += 0.004;
  far[0] -= 0.2;
  const Design d = design_of({near, set.items[0].unit, middle, far});
  const CellCoverage c = cell_coverage(d, set, k2());
  FillPlanOptions o;
  o.gap = 0.05;
  o.candidates.k = 2;
  o.starts = 2;
  o.cluster_radius = 0.01;
  const std::vector<FillTarget> targets = plan_targets(d, set, c, o);
  ASSERT_EQ(targets.size(), 2u);  // {middle, near} and {far}; the set's own structure is covered
  for (const FillTarget& t : targets) {
    EXPECT_GT(c.gap[std::size_t(t.cells.front())], o.gap);
    ASSERT_EQ(t.starts.size(), 2u);
    EXPECT_LE(relative_stiffness_gap(kSpace, set.items[std::size_t(t.starts[0])].properties, t.raw),
              relative_stiffness_gap(kSpace, set.items[std::size_t(t.starts[1])].properties, t.raw));
  }
  EXPECT_GE(c.gap[std::size_t(targets[0].cells.front())], c.gap[std::size_t(targets[1].cells.front())]);
  const FillTarget& pair = targets[0].cells.size() == 2 ? targets[0] : targets[1];
  ASSERT_EQ(pair.cells.size(), 2u);
  EXPECT_TRUE((pair.cells[0] == 0 && pair.cells[1] == 2) || (pair.cells[0] == 2 && pair.cells[1] == 0));
  EXPECT_LT((pair.unit - 0.5 * (near + middle)).norm(), 1e-12);
  o.max_targets = 1;
  EXPECT_EQ(plan_targets(d, set, c, o).size(), 1u);
  o.cluster_radius = 0;
  o.max_targets = 256;
  EXPECT_EQ(plan_targets(d, set, c, o).size(), 3u);
}

TEST(TargetFill, TheContinuousStepMakesAStructureNearATargetTheSetMisses) {
  // The set holds lattices of widths 1 and 5; the target is the width-3
  // lattice's stiffness. The generated structure must be far closer to it
  // than either, printable (symmetric, connected), and its stored C must
  // be its own.
  MicrostructureSet set = lattice_set();
  const Microstructure middle = homogenized(lattice_ids(3));
  const Design d = design_of({middle.unit});
  const CellCoverage before = cell_coverage(d, set, k2());
  FillPlanOptions plan;
  plan.gap = 0.05;
  plan.candidates.k = 2;
  const std::vector<FillTarget> targets = plan_targets(d, set, before, plan);
  ASSERT_EQ(targets.size(), 1u);
  ContinuousOptions o;
  o.max_iterations = 60;
  o.projection_beta = 8;
  o.threshold_levels = {0.5, 0.4, 0.45, 0.55, 0.6};
  const GeneratedStructure g = generate_at_target(set, targets[0], o, 1e-6);
  ASSERT_TRUE(g.found);
  std::printf("gap of the set %.3f, of the generated structure %.3f (from structure %d)\n", targets[0].gap, g.gap,
              g.parent);
  EXPECT_LT(g.gap, 0.5 * targets[0].gap);
  VoxelGrid cell(kN, kN, 1, 1.0 / kN);
  cell.ids = g.ids;
  EXPECT_TRUE(has_cubic_symmetry(cell));
  VoxelGrid again = cell;
  EXPECT_EQ(clean_structure(again).removed_voxels, 0);
  const Microstructure check = homogenized(g.ids);
  EXPECT_LT((check.C - g.C).norm(), 1e-8 * g.C.norm());
  EXPECT_NEAR(relative_stiffness_gap(kSpace, check.properties, targets[0].raw), g.gap, 1e-10);

  // Through a fan-out record and into the set.
  std::vector<double> row(std::size_t(generated_record_size(set)));
  write_generated_record(g, row.data());
  const GeneratedStructure back = read_generated_record(set, row.data());
  EXPECT_EQ(back.ids, g.ids);
  EXPECT_EQ(back.parent, g.parent);
  EXPECT_EQ(back.C, g.C);
  EXPECT_EQ(append_generated(set, targets, {back}, 1), 1);
  ASSERT_EQ(set.items.size(), 3u);
  EXPECT_EQ(set.items[2].step, SampleStep::targeted);
  EXPECT_EQ(set.items[2].parent, g.parent);
  EXPECT_EQ(append_generated(set, targets, {back}, 2), 0);  // already there
  const CellCoverage after = cell_coverage(d, set, k3());
  EXPECT_NEAR(after.gap[0], g.gap, 1e-12);
  EXPECT_EQ(after.best[0], 2);

  // Deterministic.
  const GeneratedStructure twice = generate_at_target(lattice_set(), targets[0], o, 1e-6);
  EXPECT_EQ(twice.ids, g.ids);
}

TEST(TargetFill, StiffnessOnlyCandidatesIgnoreTheDensity) {
  // Structure 0 has the target's moduli at twice its density, structure 1
  // the target's density with moduli 0.1 further off in the unit cube.
  MicrostructureSet set = lattice_set();
  VecX target = set.items[0].unit;
  set.items[1].unit = target;
  set.items[1].unit[0] -= 0.1;
  set.items[0].unit[3] = std::min(1.0, 2 * target[3]);
  ASSERT_GT(set.items[0].unit[3] - target[3], 0.1);
  const Design d = design_of({target});
  CandidateOptions all = k1(), stiffness = k1();
  stiffness.stiffness_only = true;
  EXPECT_EQ(design_candidates(d, set, all).structure.front(), 1);
  EXPECT_EQ(design_candidates(d, set, stiffness).structure.front(), 0);
  EXPECT_EQ(cell_coverage(d, set, stiffness).best[0], 0);
}

TEST(TargetFill, AGapBoundKeepsTheCandidatesCloseInStiffness) {
  // Lattices of widths 1, 2, 5 and a target at width 2's stiffness: with
  // max_gap the mapper keeps only the candidates within the bound, or the
  // closest when none is.
  MicrostructureSet set = lattice_set();
  set.items.push_back(homogenized(lattice_ids(2)));
  const Design d = design_of({set.items[2].unit});
  CandidateOptions o = k3();
  EXPECT_EQ(design_candidates(d, set, o).count(0), 3);
  o.max_gap = 1e-9;
  const CellCandidates tight = design_candidates(d, set, o);
  ASSERT_EQ(tight.count(0), 1);
  EXPECT_EQ(tight.structure.front(), 2);
  o.max_gap = 1e3;
  EXPECT_EQ(design_candidates(d, set, o).count(0), 3);
  set.items.pop_back();  // no structure within the bound: the closest stays
  o.max_gap = 1e-9;
  const CellCandidates closest = design_candidates(d, set, o);
  ASSERT_EQ(closest.count(0), 1);
  EXPECT_EQ(closest.structure.front(), cell_coverage(d, set, k3()).best[0]);
}

TEST(TargetFill, FaceConnectorsAreSymmetricAndHeldByTheContinuousStep) {
  VoxelGrid cell(kN, kN, 1, 1.0 / kN, 0);
  const std::vector<std::uint8_t> mask = face_connector(cell, 2, 1);
  int count = 0;
  for (std::size_t v = 0; v < mask.size(); ++v) count += mask[v], cell.ids[v] = mask[v];
  EXPECT_EQ(count, 4 * 4);  // four edges, 4 voxels each
  EXPECT_TRUE(has_cubic_symmetry(cell));
  VoxelGrid cube(8, 8, 8, 1.0 / 8, 0);
  const std::vector<std::uint8_t> mask3 = face_connector(cube, 1, 2);
  count = 0;
  for (std::size_t v = 0; v < mask3.size(); ++v) count += mask3[v], cube.ids[v] = mask3[v];
  EXPECT_EQ(count, 6 * 2 * 2 * 2);  // six faces, 2 x 2 patches 2 deep
  EXPECT_TRUE(has_cubic_symmetry(cube));
  EXPECT_THROW(face_connector(cell, 9, 1), InputError);
  EXPECT_THROW(face_connector(VoxelGrid(8, 6, 1, 0.1), 1, 1), InputError);

  // The gradient stays exact with frozen voxels, and MMA keeps them stiff.
  ContinuousOptions o;
  o.frozen_stiff = mask;
  RefinementTarget t;
  t.G = MatX(kSpace.tensor_2d(homogenized(lattice_ids(3)).properties).inverse());
  t.rho = 0.5;
  const ContinuousCellProblem problem(kN, kN, 1, 1.0 / kN, std::make_shared<LinearIsotropic>(1e6, 0.3), nullptr, t, o);
  int frozen = 0;
  for (int v = 0; v < problem.variables(); ++v) frozen += problem.frozen(v);
  EXPECT_GT(frozen, 0);
  std::vector<double> x(std::size_t(problem.variables()));
  for (std::size_t i = 0; i < x.size(); ++i)
    x[i] = problem.frozen(int(i)) ? 1.0 : 0.3 + 0.4 * std::abs(std::sin(1.3 * double(i)));
  std::vector<double> g;
  problem.objective(x, &g);
  double gmax = 0;
  for (double v : g) gmax = std::max(gmax, std::abs(v));
  for (std::size_t i = 0; i < x.size(); i += 3) {
    std::vector<double> a = x, b = x;
    a[i] += 1e-6, b[i] -= 1e-6;
    EXPECT_NEAR(g[i], (problem.objective(a, nullptr) - problem.objective(b, nullptr)) / 2e-6, 1e-5 * gmax) << i;
  }
  MicrostructureSet set = lattice_set();
  FillTarget target;
  target.unit = homogenized(lattice_ids(3)).unit;
  target.raw = kSpace.denormalize(target.unit);
  target.starts = {0};
  target.gap = 1;
  o.max_iterations = 30;
  o.projection_beta = 4;
  o.threshold_levels = {0.5, 0.4};
  const GeneratedStructure made = generate_at_target(set, target, o, 1e-6);
  ASSERT_TRUE(made.found);
  int held = 0;
  for (std::size_t v = 0; v < mask.size(); ++v) held += mask[v] && made.ids[v] == 1;
  EXPECT_EQ(held, 16);  // every connector voxel stiff
}

TEST(TargetFill, BadOptionsAreInputErrors) {
  const MicrostructureSet set = lattice_set();
  const Design d = design_of({set.items[0].unit});
  const CellCoverage c = cell_coverage(d, set, k1());
  CandidateOptions none;
  none.k = 0;
  EXPECT_THROW(cell_coverage(d, set, none), InputError);
  FillPlanOptions o;
  o.candidates.k = 2;
  o.starts = 3;
  EXPECT_THROW(plan_targets(d, set, c, o), InputError);
  o.starts = 1;
  o.gap = 0;
  EXPECT_THROW(plan_targets(d, set, c, o), InputError);
  o.gap = 0.1;
  o.cluster_radius = -1;
  EXPECT_THROW(plan_targets(d, set, c, o), InputError);
  ContinuousOptions k;
  k.threshold_levels = {};
  FillTarget t;
  t.unit = set.items[0].unit, t.raw = set.items[0].properties, t.starts = {0};
  EXPECT_THROW(generate_at_target(set, t, k, 1e-6), InputError);
  k.threshold_levels = {1.0};
  EXPECT_THROW(generate_at_target(set, t, k, 1e-6), InputError);
}

}  // namespace
}  // namespace msfab
