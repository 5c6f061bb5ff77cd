// Designs written by hand (msfab-assign): the patterns cell by cell, roles
// respected, the design's targets equal to the structures' properties, and
// the mapper with one candidate giving back exactly the assigned structures
// with zero distance and zero property gap.
#include <gtest/gtest.h>

#include <map>
#include <random>

#include "core/errors.hpp"
#include "mapping/cell_pattern.hpp"
#include "mapping/mapper.hpp"

namespace msfab {
namespace {

// Structures of 4^3 random voxels with distinct random properties.
MicrostructureSet small_set(int structures, unsigned seed) {
  std::mt19937 rng(seed);
  std::uniform_real_distribution<double> u(0.05, 0.95);
  MicrostructureSet set;
  set.space = "cubic3d";
  set.property_names = {"E", "nu", "G", "rho"};
  set.E_stiff = 1e6;
  set.nx = set.ny = set.nz = 4;
  set.stiff = {1e6, 0.3};
  for (int s = 0; s < structures; ++s) {
    Microstructure m;
    m.ids.resize(64);
    for (int& v : m.ids) v = int(rng() % 2u);
    m.unit = VecX(4);
    for (int j = 0; j < 4; ++j) m.unit[j] = u(rng);
    m.properties = VecX(4);
    m.properties << 1e6 * m.unit[0], m.unit[1] * 0.5, 1e6 * m.unit[2], m.unit[3];
    set.items.push_back(m);
  }
  return set;
}

TEST(CellPattern, UniformFillsEveryDesignCellAndSkipsForcedOnes) {
  const CellGrid grid(3, 3, 2, 2, 1.0);
  std::vector<CellRole> roles(std::size_t(grid.cells()), CellRole::design);
  roles[1] = CellRole::empty, roles[5] = CellRole::solid;
  CellPattern p;
  p.structures = {7};
  const auto s = pattern_structures(grid, roles, p);
  for (std::int64_t c = 0; c < grid.cells(); ++c)
    EXPECT_EQ(s[std::size_t(c)], roles[std::size_t(c)] == CellRole::design ? 7 : -1) << c;
}

TEST(CellPattern, LayersCycleAlongTheirAxisWithTheirThickness) {
  const CellGrid grid(3, 2, 3, 6, 1.0);
  const std::vector<CellRole> roles(std::size_t(grid.cells()), CellRole::design);
  CellPattern p;
  p.kind = PatternKind::layers;
  p.structures = {4, 9, 2};
  p.axis = 2, p.thickness = 2;
  const auto s = pattern_structures(grid, roles, p);
  for (std::int64_t c = 0; c < grid.cells(); ++c) {
    const int k = grid.cell_coords(c)[2];
    EXPECT_EQ(s[std::size_t(c)], p.structures[std::size_t((k / 2) % 3)]) << c;
  }
  p.axis = 0, p.thickness = 1;
  const auto sx = pattern_structures(grid, roles, p);
  for (std::int64_t c = 0; c < grid.cells(); ++c)
    EXPECT_EQ(sx[std::size_t(c)], p.structures[std::size_t(grid.cell_coords(c)[0] % 3)]) << c;
}

TEST(CellPattern, RandomDependsOnTheSeedOnlyAndUsesEveryStructure) {
  const CellGrid grid(3, 8, 8, 8, 1.0);
  const std::vector<CellRole> roles(std::size_t(grid.cells()), CellRole::design);
  CellPattern p;
  p.kind = PatternKind::random;
  p.structures = {3, 1, 8};
  p.seed = 11;
  const auto a = pattern_structures(grid, roles, p), b = pattern_structures(grid, roles, p);
  EXPECT_EQ(a, b);
  std::map<int, int> counts;
  for (int v : a) ++counts[v];
  ASSERT_EQ(counts.size(), 3u);
  for (const auto& [structure, n] : counts) EXPECT_GT(n, 512 / 3 - 60) << structure;  // about a third each
  p.seed = 12;
  EXPECT_NE(pattern_structures(grid, roles, p), a);
}

TEST(CellPattern, RefusesInvalidPatterns) {
  const CellGrid grid(3, 2, 2, 2, 1.0);
  const std::vector<CellRole> roles(std::size_t(grid.cells()), CellRole::design);
  CellPattern p;
  EXPECT_THROW(pattern_structures(grid, roles, p), std::invalid_argument);  // no structures
  p.structures = {1, 2};
  EXPECT_THROW(pattern_structures(grid, roles, p), std::invalid_argument);  // uniform with two
  p.kind = PatternKind::layers, p.axis = 3;
  EXPECT_THROW(pattern_structures(grid, roles, p), std::invalid_argument);
  p.axis = 0, p.thickness = 0;
  EXPECT_THROW(pattern_structures(grid, roles, p), std::invalid_argument);
}

TEST(CellPattern, MapperWithOneCandidateReturnsTheAssignedStructures) {
  const MicrostructureSet set = small_set(12, 5);
  const CellGrid grid(3, 4, 3, 2, 0.5);
  std::vector<CellRole> roles(std::size_t(grid.cells()), CellRole::design);
  roles[0] = CellRole::solid, roles[3] = CellRole::empty;
  for (PatternKind kind : {PatternKind::uniform, PatternKind::layers, PatternKind::random}) {
    CellPattern p;
    p.kind = kind;
    p.structures = kind == PatternKind::uniform ? std::vector<std::int32_t>{6} : std::vector<std::int32_t>{2, 10, 6};
    p.axis = 1, p.seed = 3;
    const auto assigned = pattern_structures(grid, roles, p);
    const Design design = assigned_design(grid, roles, assigned, set, "set.h5");
    EXPECT_EQ(design.nx, 4);
    EXPECT_DOUBLE_EQ(design.cell_size, 0.5);
    EXPECT_DOUBLE_EQ(design.raw(0, 3), 1.0);  // forced solid: density 1
    check_mapping_inputs(design, "design.h5", set, "set.h5");
    MapperOptions options;
    options.candidates.k = 1;
    options.half_shift = false;
    const CellCandidates candidates = design_candidates(design, set, options.candidates);
    MismatchProblem problem = mismatch_problem(design, set, candidates, options.half_shift);
    problem.randomize(1);
    const DescentReport report = problem.descend();
    const MappedDesign mapped = mapped_design(design, set, candidates, problem, report, options);
    for (std::int64_t c = 0; c < grid.cells(); ++c) {
      EXPECT_EQ(mapped.structure[std::size_t(c)], assigned[std::size_t(c)]) << c;
      if (roles[std::size_t(c)] != CellRole::design) continue;
      EXPECT_EQ(design.unit.row(c), set.items[std::size_t(assigned[std::size_t(c)])].unit.transpose());
      EXPECT_DOUBLE_EQ(mapped.distance[std::size_t(c)], 0.0);
      ASSERT_FALSE(mapped.property_gap.empty());
      EXPECT_DOUBLE_EQ(mapped.property_gap[std::size_t(c)], 0.0);
    }
  }
}

TEST(CellPattern, BadInputNamesTheSet) {
  const MicrostructureSet set = small_set(3, 2);
  const CellGrid grid3(3, 2, 2, 2, 1.0), grid2(2, 2, 2, 1, 1.0);
  const std::vector<CellRole> roles3(8, CellRole::design), roles2(4, CellRole::design);
  try {
    assigned_design(grid3, roles3, std::vector<std::int32_t>(8, 3), set, "my.set.h5");
    FAIL() << "index outside the set accepted";
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find("my.set.h5: structure 3 requested, the set holds 3"), std::string::npos)
        << e.what();
  }
  EXPECT_THROW(assigned_design(grid2, roles2, std::vector<std::int32_t>(4, 0), set, "my.set.h5"), InputError);
}

}  // namespace
}  // namespace msfab
