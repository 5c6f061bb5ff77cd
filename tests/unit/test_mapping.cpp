// The microstructure mapper (thesis §3.5): mismatch of hand-built cells,
// the half-shifted exemplar, candidates against brute force, the greedy
// descent's monotonicity and local minimum, determinism across thread
// counts, the voxel / STL exports against a direct assembly, bad inputs.
#include <gtest/gtest.h>
#include <omp.h>
#include <unistd.h>

#include <cmath>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <functional>
#include <random>

#include "core/errors.hpp"
#include "gamut/microstructure_set.hpp"
#include "io/hdf5_file.hpp"
#include "mapping/mapper.hpp"
#include "mapping/voxel_model.hpp"

namespace msfab {
namespace {
namespace fs = std::filesystem;

fs::path mapping_scratch(const std::string& name) {
  const fs::path dir = fs::temp_directory_path() / ("msfab_mapping_" + std::to_string(::getpid()));
  fs::create_directories(dir);
  return dir / name;
}

std::vector<int> mapping_random_ids(std::mt19937& rng, std::size_t n, int max_id) {
  std::vector<int> ids(n);
  for (int& v : ids) v = int(rng() % unsigned(max_id + 1));
  return ids;
}

// A set of random structures with random unit properties in 3 dimensions.
MicrostructureSet random_set(int structures, int vx, int vy, int vz, unsigned seed, bool soft = true) {
  std::mt19937 rng(seed);
  std::uniform_real_distribution<double> u(0, 1);
  MicrostructureSet set;
  set.space = vz == 1 ? "cubic2d" : "cubic3d";
  set.property_names = {"E", "nu", "G"};
  set.E_stiff = 1e6;
  set.nx = vx, set.ny = vy, set.nz = vz;
  set.stiff = {1e6, 0.3};
  set.soft = {1e4, 0.45};
  set.soft_is_void = !soft;
  for (int s = 0; s < structures; ++s) {
    Microstructure m;
    m.ids = mapping_random_ids(rng, std::size_t(vx) * vy * vz, soft ? 2 : 1);
    m.unit = VecX(3);
    for (int j = 0; j < 3; ++j) m.unit[j] = u(rng);
    m.properties = m.unit * 1e5;
    set.items.push_back(m);
  }
  return set;
}

// A design over the set's space with random targets; every 7th cell forced
// empty and every 11th forced solid.
Design mapping_random_design(const MicrostructureSet& set, int nx, int ny, int nz, unsigned seed) {
  std::mt19937 rng(seed);
  std::uniform_real_distribution<double> u(0, 1);
  Design d;
  d.space = set.space;
  d.property_names = set.property_names;
  d.E_stiff = set.E_stiff;
  d.dimension = set.nz == 1 ? 2 : 3;
  d.nx = nx, d.ny = ny, d.nz = nz;
  d.cell_size = 0.01;
  const std::int64_t n = d.cells();
  d.unit = MatX(n, 3);
  for (Eigen::Index c = 0; c < n; ++c)
    for (int j = 0; j < 3; ++j) d.unit(c, j) = u(rng);
  d.raw = d.unit * 1e5;
  d.roles.assign(std::size_t(n), CellRole::design);
  for (std::int64_t c = 0; c < n; ++c) {
    if (c % 7 == 3) d.roles[std::size_t(c)] = CellRole::empty;
    if (c % 11 == 5) d.roles[std::size_t(c)] = CellRole::solid;
  }
  d.phi = VecX::Zero(n);
  return d;
}

// Total mismatch counted directly from the voxels of the assembled model:
// every differing pair across a cell face, counted once per cell (twice).
std::int64_t brute_total(const VoxelModel& model) {
  const std::int64_t NX = model.nx(), NY = model.ny(), NZ = model.nz();
  const MappedDesign& m = model.mapping();
  std::vector<std::vector<int>> layers(static_cast<std::size_t>(NZ));
  for (std::int64_t z = 0; z < NZ; ++z) model.layer(z, layers[std::size_t(z)]);
  auto id = [&](std::int64_t x, std::int64_t y, std::int64_t z) {
    return layers[std::size_t(z)][std::size_t(x + NX * y)];
  };
  std::int64_t pairs = 0;
  for (std::int64_t z = 0; z < NZ; ++z)
    for (std::int64_t y = 0; y < NY; ++y)
      for (std::int64_t x = 0; x < NX; ++x) {
        if ((x + 1) % m.vx == 0 && x + 1 < NX && id(x, y, z) != id(x + 1, y, z)) ++pairs;
        if ((y + 1) % m.vy == 0 && y + 1 < NY && id(x, y, z) != id(x, y + 1, z)) ++pairs;
        if (m.dimension == 3 && (z + 1) % m.vz == 0 && z + 1 < NZ && id(x, y, z) != id(x, y, z + 1)) ++pairs;
      }
  return 2 * pairs;
}

MapperOptions default_options(int k = 4, bool half_shift = true) {
  MapperOptions o;
  o.candidates.k = k;
  o.half_shift = half_shift;
  return o;
}

struct MapperRun {
  CellCandidates candidates;
  MappedDesign mapped;
  DescentReport report;
};

MapperRun run_mapper(const Design& d, const MicrostructureSet& set, const MapperOptions& options, std::uint64_t seed) {
  MapperRun r;
  r.candidates = design_candidates(d, set, options.candidates);
  MismatchProblem problem = mismatch_problem(d, set, r.candidates, options.half_shift);
  problem.randomize(seed);
  r.report = problem.descend();
  r.mapped = mapped_design(d, set, r.candidates, problem, r.report, options);
  return r;
}

// --- mismatch of hand-built cells --------------------------------------------

// 4 x 4 cells: rows alternate 0, 1, 0, 1 along y (each row constant in x).
std::vector<int> stripes() {
  std::vector<int> ids(16);
  for (int y = 0; y < 4; ++y)
    for (int x = 0; x < 4; ++x) ids[x + 4 * y] = y % 2;
  return ids;
}

std::vector<int> complement(std::vector<int> ids) {
  for (int& v : ids) v = 1 - v;
  return ids;
}

MismatchProblem two_cells(const FaceGrid& grid, const std::vector<int>& a, const std::vector<int>& b, int vz = 1) {
  FaceTable table(4, 4, vz, grid.dimension);
  const int ea = table.add(a), eb = table.add(b);
  return MismatchProblem(grid, std::move(table), {0, 1, 2}, {ea, eb});
}

TEST(Mapping, IdenticalStructuresAcrossAFaceDoNotMismatch) {
  // Along x the stripes continue across the face: nothing differs.
  MismatchProblem same = two_cells({2, 2, 1, 1}, stripes(), stripes());
  EXPECT_EQ(same.energy(0), 0);
  EXPECT_EQ(same.energy(1), 0);
  EXPECT_EQ(same.total(), 0);
  // The complement differs at every one of the 4 voxel pairs of the face,
  // counted once for each cell.
  MismatchProblem opposite = two_cells({2, 2, 1, 1}, stripes(), complement(stripes()));
  EXPECT_EQ(opposite.energy(0), 4);
  EXPECT_EQ(opposite.energy(1), 4);
  EXPECT_EQ(opposite.total(), 8);
  // Along y the top row (y = 3: id 1) meets the bottom row (y = 0: id 0) of
  // the same structure: the full face differs; with the complement above,
  // 1 meets 1 and nothing differs.
  MismatchProblem stacked = two_cells({2, 1, 2, 1}, stripes(), stripes());
  EXPECT_EQ(stacked.total(), 8);
  MismatchProblem stacked_complement = two_cells({2, 1, 2, 1}, stripes(), complement(stripes()));
  EXPECT_EQ(stacked_complement.total(), 0);
}

TEST(Mapping, MismatchAcrossZAndAgainstForcedCells) {
  // 3D, 4 x 4 x 2 voxels: layer z = 0 void, z = 1 solid. Stacked along z the
  // solid top meets the void bottom: 16 pairs, I = 32.
  std::vector<int> layered(32, 0);
  std::fill(layered.begin() + 16, layered.end(), 1);
  MismatchProblem stacked = two_cells({3, 1, 1, 2}, layered, layered, 2);
  EXPECT_EQ(stacked.energy(0), 16);
  EXPECT_EQ(stacked.total(), 32);
  // Side by side along x: every pair matches.
  MismatchProblem side = two_cells({3, 2, 1, 1}, layered, layered, 2);
  EXPECT_EQ(side.total(), 0);
  // A solid structure next to a forced empty cell mismatches on the whole
  // face, next to a forced solid one nowhere.
  FaceTable table(4, 4, 1, 2);
  const int empty = table.add_uniform(0), solid = table.add_uniform(1), full = table.add(std::vector<int>(16, 1));
  MismatchProblem p({2, 3, 1, 1}, std::move(table), {0, 1, 2, 3}, {empty, full, solid});
  EXPECT_EQ(p.energy(0), 4);
  EXPECT_EQ(p.energy(1), 4);
  EXPECT_EQ(p.energy(2), 0);
  EXPECT_EQ(p.total(), 8);
}

TEST(Mapping, FaceMismatchCountsEveryDifferingPair) {
  // Faces of 1 to 40 voxels (the word-wise count and its tail), ids 0..255.
  std::mt19937 rng(17);
  for (int vy = 1; vy <= 40; vy += 3) {
    FaceTable table(3, vy, 1, 2);
    std::vector<int> a(std::size_t(3) * vy), b(a.size());
    for (std::size_t i = 0; i < a.size(); ++i) {
      a[i] = int(rng() % 4 == 0 ? rng() % 256 : 1);
      b[i] = int(rng() % 4 == 0 ? rng() % 256 : 1);
    }
    const int ea = table.add(a), eb = table.add(b);
    std::int64_t expected = 0;
    for (int y = 0; y < vy; ++y) expected += a[std::size_t(2 + 3 * y)] != b[std::size_t(3 * y)];
    EXPECT_EQ(table.mismatch(ea, eb, 0), expected) << vy;
    std::int64_t stacked = 0;  // a's top row against its own bottom row
    for (int x = 0; x < 3; ++x) stacked += a[std::size_t(x + 3 * (vy - 1))] != a[std::size_t(x)];
    EXPECT_EQ(table.mismatch(ea, ea, 1), stacked);
  }
}

// --- the half-shifted exemplar ---------------------------------------------

TEST(Mapping, HalfShiftIsThePeriodicTranslateByHalfACell) {
  std::mt19937 rng(5);
  const int nx = 5, ny = 4, nz = 3;  // odd sizes round down: shift (2, 2, 1)
  const std::vector<int> ids = mapping_random_ids(rng, std::size_t(nx) * ny * nz, 2);
  const std::vector<int> shifted = half_shifted(ids, nx, ny, nz);
  for (int z = 0; z < nz; ++z)
    for (int y = 0; y < ny; ++y)
      for (int x = 0; x < nx; ++x)
        ASSERT_EQ(shifted[x + nx * (y + ny * z)], ids[(x + 2) % nx + nx * ((y + 2) % ny + ny * ((z + 1) % nz))]);
  // Translating by a whole period changes nothing; half of an even cell
  // twice is a whole period.
  EXPECT_EQ(periodic_shift(ids, nx, ny, nz, nx, -ny, 2 * nz), ids);
  const std::vector<int> even = mapping_random_ids(rng, 4 * 4 * 2, 1);
  EXPECT_EQ(half_shifted(half_shifted(even, 4, 4, 2), 4, 4, 2), even);
  EXPECT_NE(half_shifted(even, 4, 4, 2), even);
  // Its lower x face is the original's column x = nx / 2.
  FaceTable table(nx, ny, nz, 3);
  const int e = table.add(shifted);
  for (int z = 0; z < nz; ++z)
    for (int y = 0; y < ny; ++y)
      EXPECT_EQ(table.face(e, 0)[y + ny * z], ids[2 + nx * ((y + 2) % ny + ny * ((z + 1) % nz))]);
  // A 2D cell (nz = 1) is not shifted along z.
  const std::vector<int> flat = mapping_random_ids(rng, 4 * 6, 1);
  EXPECT_EQ(half_shifted(flat, 4, 6, 1), periodic_shift(flat, 4, 6, 1, 2, 3, 0));
}

// --- candidates ----------------------------------------------------------------

TEST(Mapping, CandidatesAreTheTrueNearestWithTiesByIndex) {
  std::mt19937 rng(11);
  // Coordinates on a coarse lattice, with duplicated points: many ties.
  MatX points(400, 4);
  for (Eigen::Index i = 0; i < points.rows(); ++i)
    for (int j = 0; j < 4; ++j) points(i, j) = (i % 5 == 4) ? points(i - 1, j) : double(rng() % 6) / 5.0;
  const KdTree tree(points);
  std::uniform_real_distribution<double> u(-0.1, 1.1);
  for (int q = 0; q < 150; ++q) {
    double target[4];
    for (double& t : target) t = q % 3 == 0 ? double(rng() % 6) / 5.0 : u(rng);
    for (int k : {1, 3, 16, 500}) {
      const auto fast = tree.nearest(target, k), slow = brute_force_nearest(points, target, k);
      ASSERT_EQ(fast.size(), std::min<std::size_t>(std::size_t(k), 400));
      ASSERT_EQ(fast.size(), slow.size());
      for (std::size_t i = 0; i < fast.size(); ++i) {
        ASSERT_EQ(fast[i].index, slow[i].index) << "query " << q << " k " << k << " rank " << i;
        ASSERT_EQ(fast[i].distance2, slow[i].distance2);
      }
    }
    const auto ball = tree.within(target, 0.3), ball_slow = brute_force_within(points, target, 0.3);
    ASSERT_EQ(ball.size(), ball_slow.size());
    for (std::size_t i = 0; i < ball.size(); ++i) ASSERT_EQ(ball[i].index, ball_slow[i].index);
  }

  // Per cell: the k nearest, united with the ball, nearest first, no repeats.
  MatX targets(60, 4);
  for (Eigen::Index c = 0; c < targets.rows(); ++c)
    for (int j = 0; j < 4; ++j) targets(c, j) = u(rng);
  std::vector<bool> wanted(60, true);
  wanted[7] = false;
  const CellCandidates cand = find_candidates(targets, wanted, points, {5, 0.25});
  EXPECT_EQ(cand.count(7), 0);
  for (Eigen::Index c = 0; c < 60; ++c) {
    if (c == 7) continue;
    const VecX t = targets.row(c).transpose();
    std::vector<Neighbour> expected = brute_force_within(points, t.data(), 0.25);
    if (expected.size() < 5) expected = brute_force_nearest(points, t.data(), 5);
    ASSERT_EQ(cand.count(c), std::int64_t(expected.size())) << "cell " << c;
    for (std::size_t i = 0; i < expected.size(); ++i) {
      ASSERT_EQ(cand.structure[std::size_t(cand.offsets[c]) + i], expected[i].index);
      ASSERT_DOUBLE_EQ(cand.distance[std::size_t(cand.offsets[c]) + i], std::sqrt(expected[i].distance2));
    }
  }
}

// --- the greedy descent --------------------------------------------------------

void expect_descent_to_local_minimum(const FaceGrid& grid, int vx, int vy, int vz, unsigned seed) {
  std::mt19937 rng(seed);
  FaceTable table(vx, vy, vz, grid.dimension);
  const int empty = table.add_uniform(0);
  for (int s = 0; s < 20; ++s) table.add(mapping_random_ids(rng, std::size_t(vx) * vy * vz, 2));
  std::vector<std::int64_t> offsets{0};
  std::vector<std::int32_t> options;
  for (std::int64_t c = 0; c < grid.cells(); ++c) {
    const int count = c % 9 == 4 ? 1 : 2 + int(rng() % 5);
    for (int o = 0; o < count; ++o) options.push_back(c % 9 == 4 ? empty : 1 + int(rng() % 20));
    offsets.push_back(std::int64_t(options.size()));
  }
  MismatchProblem p(grid, table, offsets, options);
  p.randomize(seed);
  const std::int64_t initial = p.total();
  const DescentReport r = p.descend();
  EXPECT_EQ(r.initial, initial);
  ASSERT_EQ(r.history.size(), std::size_t(r.moves) + 1);
  ASSERT_EQ(r.changed.size(), r.history.size());
  EXPECT_EQ(r.history.front(), initial);
  EXPECT_GT(r.moves, 0);
  for (std::size_t i = 1; i < r.history.size(); ++i) ASSERT_LT(r.history[i], r.history[i - 1]) << "move " << i;
  EXPECT_EQ(r.history.back(), r.final);
  // The cached energies agree with a recount from scratch.
  MismatchProblem fresh = p;
  fresh.recompute_energies();
  EXPECT_EQ(fresh.total(), r.final);
  for (std::int64_t c = 0; c < grid.cells(); ++c) ASSERT_EQ(fresh.energy(c), p.energy(c));
  // A local minimum: no single-cell change lowers the total, recounted in full.
  for (std::int64_t c = 0; c < grid.cells(); ++c)
    for (int o = 0; o < p.option_count(c); ++o) {
      MismatchProblem changed = p;
      changed.assign(c, o);
      changed.recompute_energies();
      ASSERT_GE(changed.total(), r.final) << "cell " << c << " option " << o;
      ASSERT_EQ(changed.total() - r.final, 2 * (p.energy_with(c, o) - p.energy(c)));
    }
}

TEST(Mapping, GreedyNeverIncreasesAndEndsInALocalMinimum) {
  expect_descent_to_local_minimum({2, 7, 6, 1}, 4, 3, 1, 1);
  expect_descent_to_local_minimum({3, 4, 3, 3}, 3, 2, 2, 2);
}

// A void-pair cost c: every cell's energy is 16 mismatching pairs + round(16 c)
// pairs void on both sides, counted here voxel by voxel from the face
// table; the face-pair totals partition every face; the descent ends in a
// local minimum of that energy; c = 0 is the plain mismatch.
TEST(Mapping, VoidPairCostCountsPairsVoidOnBothSides) {
  const FaceGrid grid{3, 4, 3, 2};
  std::mt19937 rng(11);
  const int vx = 5, vy = 3, vz = 2;  // faces of 6, 10 and 15 voxels: the eight-at-a-time loop and its tail
  FaceTable table(vx, vy, vz, 3);
  for (int s = 0; s < 9; ++s) table.add(mapping_random_ids(rng, std::size_t(vx) * vy * vz, 2));
  table.add_uniform(0);
  std::vector<std::int64_t> offsets{0};
  std::vector<std::int32_t> options;
  for (std::int64_t c = 0; c < grid.cells(); ++c) {
    const int count = 1 + int(rng() % 4);
    for (int o = 0; o < count; ++o) options.push_back(int(rng() % 10));
    offsets.push_back(std::int64_t(options.size()));
  }
  // Pairs between lower's upper face and upper's lower face, voxel by voxel.
  auto count_pairs = [&](int lower, int upper, int axis, bool want_void) {
    const std::uint8_t* a = table.face(lower, 2 * axis + 1);
    const std::uint8_t* b = table.face(upper, 2 * axis);
    std::int64_t n = 0;
    for (int k = 0; k < table.face_size(axis); ++k) n += want_void ? (a[k] == 0 && b[k] == 0) : a[k] != b[k];
    return n;
  };
  for (int lower = 0; lower < table.entries(); ++lower)
    for (int upper = 0; upper < table.entries(); ++upper)
      for (int axis = 0; axis < 3; ++axis) {
        ASSERT_EQ(table.void_pairs(lower, upper, axis), count_pairs(lower, upper, axis, true));
        ASSERT_EQ(table.mismatch(lower, upper, axis), count_pairs(lower, upper, axis, false));
      }

  MismatchProblem p(grid, table, offsets, options, 0.3);  // round(16 * 0.3) = 5
  p.randomize(2);
  auto brute_energy = [&](const MismatchProblem& q, std::int64_t cell, int option) {
    std::int64_t e = 0;
    for (int f = 0; f < grid.faces(); ++f) {
      const std::int64_t n = grid.neighbour(cell, f);
      if (n < 0) continue;
      const int mine = q.entry(cell, option), theirs = q.entry(n, q.choice()[std::size_t(n)]);
      const int lower = f % 2 == 1 ? mine : theirs, upper = f % 2 == 1 ? theirs : mine;
      e += 16 * count_pairs(lower, upper, f / 2, false) + 5 * count_pairs(lower, upper, f / 2, true);
    }
    return e;
  };
  for (std::int64_t c = 0; c < grid.cells(); ++c)
    for (int o = 0; o < p.option_count(c); ++o) ASSERT_EQ(p.energy_with(c, o), brute_energy(p, c, o));
  const DescentReport r = p.descend();
  for (std::size_t i = 1; i < r.history.size(); ++i) ASSERT_LT(r.history[i], r.history[i - 1]);
  for (std::int64_t c = 0; c < grid.cells(); ++c) {
    ASSERT_EQ(p.energy(c), brute_energy(p, c, p.choice()[std::size_t(c)]));
    for (int o = 0; o < p.option_count(c); ++o) ASSERT_GE(p.energy_with(c, o), p.energy(c));
  }
  // Every face pair is counted once and falls in exactly one class.
  const MismatchProblem::FacePairs pairs = p.face_pairs();
  std::int64_t all = 0, differ = 0, both_void = 0;
  for (std::int64_t c = 0; c < grid.cells(); ++c)
    for (int axis = 0; axis < 3; ++axis) {
      const std::int64_t n = grid.neighbour(c, 2 * axis + 1);
      if (n < 0) continue;
      const int lower = p.entry(c, p.choice()[std::size_t(c)]), upper = p.entry(n, p.choice()[std::size_t(n)]);
      all += table.face_size(axis);
      differ += count_pairs(lower, upper, axis, false);
      both_void += count_pairs(lower, upper, axis, true);
    }
  EXPECT_EQ(pairs.mismatch, differ);
  EXPECT_EQ(pairs.both_void, both_void);
  EXPECT_EQ(pairs.mismatch + pairs.both_void + pairs.contact, all);
  EXPECT_GT(pairs.contact, 0);

  MismatchProblem plain(grid, table, offsets, options);
  plain.randomize(2);
  EXPECT_EQ(plain.total(), 2 * plain.face_pairs().mismatch);
  EXPECT_THROW(MismatchProblem(grid, table, offsets, options, 1.5), std::invalid_argument);
  EXPECT_THROW(MismatchProblem(grid, table, offsets, options, -0.1), std::invalid_argument);
}

// Several starts keep the lowest local minimum: start 0 is the plain
// random descent, start 1 the nearest option everywhere, the problem ends
// at the kept start's choice; on two uniform fills whose only zero-mismatch
// states are "all one fill", the nearest start finds zero.
TEST(Mapping, MultiStartKeepsTheLowestLocalMinimum) {
  const FaceGrid grid{3, 5, 4, 3};
  std::mt19937 rng(7);
  FaceTable table(3, 3, 2, 3);
  for (int s = 0; s < 12; ++s) table.add(mapping_random_ids(rng, 18, 2));
  std::vector<std::int64_t> offsets{0};
  std::vector<std::int32_t> options;
  for (std::int64_t c = 0; c < grid.cells(); ++c) {
    const int count = 1 + int(rng() % 4);
    for (int o = 0; o < count; ++o) options.push_back(int(rng() % 12));
    offsets.push_back(std::int64_t(options.size()));
  }
  const MismatchProblem problem(grid, table, offsets, options);
  MismatchProblem plain = problem, nearest = problem, multi = problem;
  plain.randomize(3);
  const DescentReport plain_report = plain.descend();
  nearest.start_nearest();
  const DescentReport nearest_report = nearest.descend();
  const MultiStartReport r = descend_from_starts(multi, 3, 6);
  ASSERT_EQ(r.finals.size(), 6u);
  EXPECT_EQ(r.finals[0], plain_report.final);
  EXPECT_EQ(r.finals[1], nearest_report.final);
  const auto lowest = std::min_element(r.finals.begin(), r.finals.end());
  EXPECT_EQ(r.kept_start, int(lowest - r.finals.begin()));
  EXPECT_EQ(r.kept.final, *lowest);
  EXPECT_LE(r.kept.final, plain_report.final);
  EXPECT_GT(*std::max_element(r.finals.begin(), r.finals.end()), *lowest) << "the starts should differ here";
  // The problem holds the kept choice: its energies recounted give the kept total.
  MismatchProblem fresh = multi;
  fresh.recompute_energies();
  EXPECT_EQ(fresh.total(), r.kept.final);
  for (std::int64_t c = 0; c < grid.cells(); ++c) ASSERT_EQ(fresh.energy(c), multi.energy(c));
  // One start is the plain descent.
  MismatchProblem single = problem;
  EXPECT_EQ(descend_from_starts(single, 3, 1).kept.final, plain_report.final);
  EXPECT_EQ(single.choice(), plain.choice());

  FaceTable fills(2, 2, 2, 3);
  const int zero = fills.add_uniform(0), one = fills.add_uniform(1);
  std::vector<std::int64_t> two_offsets{0};
  std::vector<std::int32_t> two_options;
  for (std::int64_t c = 0; c < grid.cells(); ++c) {
    two_options.push_back(zero), two_options.push_back(one);
    two_offsets.push_back(std::int64_t(two_options.size()));
  }
  MismatchProblem two(grid, fills, two_offsets, two_options);
  const MultiStartReport t = descend_from_starts(two, 1, 2);
  EXPECT_EQ(t.finals[1], 0);
  EXPECT_EQ(t.kept.final, 0);
  EXPECT_EQ(two.total(), 0);
}

TEST(Mapping, SameSeedSameMappingOnAnyThreadCount) {
  const MicrostructureSet set = random_set(60, 4, 4, 1, 3);
  const Design d = mapping_random_design(set, 9, 7, 1, 4);
  const int saved = omp_get_max_threads();
  omp_set_num_threads(1);
  const MapperRun one = run_mapper(d, set, default_options(6), 42);
  omp_set_num_threads(3);
  const MapperRun three = run_mapper(d, set, default_options(6), 42);
  const MapperRun other_seed = run_mapper(d, set, default_options(6), 43);
  omp_set_num_threads(saved);
  EXPECT_EQ(one.candidates.structure, three.candidates.structure);
  EXPECT_EQ(one.mapped.structure, three.mapped.structure);
  EXPECT_EQ(one.mapped.shift, three.mapped.shift);
  EXPECT_EQ(one.report.history, three.report.history);
  EXPECT_EQ(one.report.changed, three.report.changed);
  EXPECT_NE(one.report.history.front(), other_seed.report.history.front());
  EXPECT_LT(one.report.final, one.report.initial);
}

TEST(Mapping, MappedDesignMatchesTheVoxelsAndTheTargets) {
  const MicrostructureSet set = random_set(40, 3, 3, 2, 7);
  const Design d = mapping_random_design(set, 4, 3, 3, 8);
  const MapperRun r = run_mapper(d, set, default_options(5), 9);
  const MappedDesign& m = r.mapped;
  // The final mismatch is what the assembled voxels show.
  const VoxelModel model(m, set);
  EXPECT_EQ(brute_total(model), r.report.final);
  std::int64_t sum = 0;
  for (std::int64_t e : m.mismatch) sum += e;
  EXPECT_EQ(sum, r.report.final);
  for (std::int64_t c = 0; c < d.cells(); ++c) {
    if (d.roles[std::size_t(c)] != CellRole::design) {
      EXPECT_EQ(m.structure[std::size_t(c)], -1);
      continue;
    }
    const int s = m.structure[std::size_t(c)];
    ASSERT_GE(s, 0);
    EXPECT_NEAR(m.distance[std::size_t(c)], (set.items[std::size_t(s)].unit - d.unit.row(c).transpose()).norm(), 1e-12);
    EXPECT_EQ(m.candidates[std::size_t(c)], 5);
  }
  // Without the variants, no cell takes a shifted exemplar.
  const MapperRun plain = run_mapper(d, set, default_options(5, false), 9);
  for (std::uint8_t s : plain.mapped.shift) EXPECT_EQ(s, 0);
  // A structure exactly at the target, with k = 1, is the one taken.
  Design exact = d;
  for (std::int64_t c = 0; c < d.cells(); ++c) exact.unit.row(c) = set.items[std::size_t(c % 40)].unit.transpose();
  const MapperRun nearest = run_mapper(exact, set, default_options(1, false), 1);
  for (std::int64_t c = 0; c < d.cells(); ++c)
    if (d.roles[std::size_t(c)] == CellRole::design) {
      EXPECT_EQ(nearest.mapped.structure[std::size_t(c)], c % 40);
      EXPECT_EQ(nearest.mapped.distance[std::size_t(c)], 0.0);
    }

  // The artifact reads back as written.
  const std::string path = mapping_scratch("m.mapped.h5").string();
  write_mapped_artifact(path, m, "test", "", {}, 9);
  const MappedDesign back = read_mapped_artifact(path);
  EXPECT_EQ(back.structure, m.structure);
  EXPECT_EQ(back.shift, m.shift);
  EXPECT_EQ(back.distance, m.distance);
  EXPECT_EQ(back.property_gap, m.property_gap);
  EXPECT_EQ(back.mismatch, m.mismatch);
  EXPECT_EQ(back.history, m.history);
  EXPECT_EQ(back.history_cell, m.history_cell);
  EXPECT_EQ(back.roles, m.roles);
  EXPECT_EQ(back.nx, 4);
  EXPECT_EQ(back.vz, 2);
  EXPECT_EQ(back.k, 5);
  EXPECT_EQ(back.tiling, 1);
  MappedDesign tiled = m;
  tiled.tiling = 3;
  write_mapped_artifact(path, tiled, "test", "", {}, 9);
  EXPECT_EQ(read_mapped_artifact(path).tiling, 3);
}

// A cubic3d set and design with physical properties (E, nu, G, rho), so
// that the property gap (a relative difference of stiffness tensors) is
// defined: zero for a structure exactly at its cell's target, and relative
// in the Frobenius norm of C.
TEST(Mapping, PropertyGapIsZeroAtTheTargetAndRelativeInTheNormOfC) {
  const MaterialSpace space(MaterialSpaceKind::cubic3d, 1e6);
  std::mt19937 rng(31);
  std::uniform_real_distribution<double> u(0, 1);
  auto physical = [&] {
    VecX raw(4);
    raw << 1e6 * std::pow(10.0, -2 * u(rng)), 0.4 * u(rng), 1e6 * std::pow(10.0, -2.5 * u(rng)), 0.1 + 0.9 * u(rng);
    return raw;
  };
  MicrostructureSet set = random_set(30, 2, 2, 2, 32, false);
  set.property_names = {"E", "nu", "G", "rho"};
  for (Microstructure& m : set.items) {
    m.properties = physical();
    m.unit = space.normalize(m.properties);
  }
  Design d = mapping_random_design(set, 3, 3, 2, 33);
  d.unit = MatX(d.cells(), 4);
  d.raw = MatX(d.cells(), 4);
  for (std::int64_t c = 0; c < d.cells(); ++c) {
    d.raw.row(c) = physical().transpose();
    d.unit.row(c) = space.normalize(d.raw.row(c).transpose()).transpose();
  }
  const MapperRun r = run_mapper(d, set, default_options(3), 4);
  double mean = 0, largest = 0;
  for (std::int64_t c = 0; c < d.cells(); ++c) {
    const double gap = r.mapped.property_gap[std::size_t(c)];
    if (d.roles[std::size_t(c)] != CellRole::design) {
      EXPECT_EQ(gap, 0.0);
      continue;
    }
    const Mat6 target = space.tensor_3d(d.raw.row(c).transpose());
    const Mat6 chosen = space.tensor_3d(set.items[std::size_t(r.mapped.structure[std::size_t(c)])].properties);
    EXPECT_NEAR(gap, (chosen - target).norm() / target.norm(), 1e-12 * (1 + gap));
    mean += gap;
    largest = std::max(largest, gap);
  }
  const DistanceSummary summary = summarize_distances(r.candidates, r.mapped, 0.1);
  EXPECT_NEAR(summary.mean_gap, mean / double(summary.design_cells), 1e-12);
  EXPECT_EQ(summary.max_gap, largest);
  EXPECT_GT(largest, 0.0);
  // Targets on the samples themselves, one candidate: gap zero everywhere.
  Design exact = d;
  for (std::int64_t c = 0; c < d.cells(); ++c) {
    exact.raw.row(c) = set.items[std::size_t(c % 30)].properties.transpose();
    exact.unit.row(c) = set.items[std::size_t(c % 30)].unit.transpose();
  }
  const MapperRun on_samples = run_mapper(exact, set, default_options(1, false), 1);
  for (double gap : on_samples.mapped.property_gap) EXPECT_EQ(gap, 0.0);
  // Twice E and G at the same nu: twice C.
  VecX target(4), doubled(4);
  target << 2e5, 0.25, 7e4, 0.5;
  doubled << 4e5, 0.25, 1.4e5, 0.5;
  EXPECT_NEAR(relative_stiffness_gap(space, doubled, target), 1.0, 1e-12);
  EXPECT_NEAR(relative_stiffness_gap(space, target, doubled), 0.5, 1e-12);
}

// --- exports ---------------------------------------------------------------------

// A hand-made mapping of 3 x 2 x 2 cells of 4 x 3 x 2 voxels: all roles, both
// exemplars.
struct SmallModel {
  MicrostructureSet set = random_set(5, 4, 3, 2, 21);
  MappedDesign m;
  SmallModel() {
    m.space = set.space;
    m.property_names = set.property_names;
    m.dimension = 3;
    m.nx = 3, m.ny = 2, m.nz = 2;
    m.cell_size = 0.012;
    m.vx = 4, m.vy = 3, m.vz = 2;
    const std::size_t n = 12;
    m.roles.assign(n, CellRole::design);
    m.roles[4] = CellRole::empty;
    m.roles[9] = CellRole::solid;
    for (std::size_t c = 0; c < n; ++c) {
      m.structure.push_back(m.roles[c] == CellRole::design ? std::int32_t(c % 5) : -1);
      m.shift.push_back(std::uint8_t(c % 2));
    }
    m.distance.assign(n, 0.0);
    m.candidates.assign(n, 1);
    m.mismatch.assign(n, 0);
    m.history = {0};
    m.history_cell = {-1};
  }
  // The voxel (X, Y, Z) assembled directly from the cells.
  int id(std::int64_t X, std::int64_t Y, std::int64_t Z) const {
    const std::size_t c = std::size_t(X / 4 + 3 * (Y / 3 + 2 * (Z / 2)));
    if (m.roles[c] == CellRole::empty) return 0;
    if (m.roles[c] == CellRole::solid) return 1;
    const std::vector<int>& s = set.items[std::size_t(m.structure[c])].ids;
    const std::vector<int> cell = m.shift[c] ? half_shifted(s, 4, 3, 2) : s;
    return cell[std::size_t(X % 4 + 4 * (Y % 3 + 3 * (Z % 2)))];
  }
};

// A cell tiled t times holds t^3 copies of its structure (same exemplar):
// voxel (X, Y, Z) is the untiled model's voxel of the same cell at the
// position within one copy.
TEST(Mapping, TiledCellsRepeatTheirStructure) {
  for (int t : {2, 3}) {
    SmallModel small;
    small.m.tiling = t;
    const VoxelModel model(small.m, small.set);
    ASSERT_EQ(model.nx(), 12 * t);
    ASSERT_EQ(model.ny(), 6 * t);
    ASSERT_EQ(model.nz(), 4 * t);
    EXPECT_DOUBLE_EQ(model.voxel_size()[0], 0.012 / (4 * t));
    std::vector<int> layer;
    for (std::int64_t Z = 0; Z < model.nz(); ++Z) {
      model.layer(Z, layer);
      for (std::int64_t Y = 0; Y < model.ny(); ++Y)
        for (std::int64_t X = 0; X < model.nx(); ++X) {
          // Cell of the tiled voxel, then the voxel inside one copy.
          const std::int64_t cx = X / (4 * t), cy = Y / (3 * t), cz = Z / (2 * t);
          ASSERT_EQ(layer[std::size_t(X + model.nx() * Y)], small.id(4 * cx + X % 4, 3 * cy + Y % 3, 2 * cz + Z % 2))
              << t << ": " << X << " " << Y << " " << Z;
        }
    }
    // The voxel file holds every layer of the tiled model.
    const std::string path = mapping_scratch("tiled.voxels.h5").string();
    write_voxels_artifact(path, model, "test", "", {}, 0);
    const VoxelsReader in(path);
    ASSERT_EQ(in.nz(), model.nz());
    for (std::int64_t Z = 0; Z < model.nz(); ++Z) {
      model.layer(Z, layer);
      ASSERT_EQ(in.layer(Z), layer) << t << ": layer " << Z;
    }
  }
  SmallModel bad;
  bad.m.tiling = 0;
  EXPECT_THROW(write_mapped_artifact(mapping_scratch("bad_tiling.mapped.h5").string(), bad.m, "test", "", {}, 0),
               std::invalid_argument);
}

TEST(Mapping, VoxelFileReadsBackAsTheAssembledModel) {
  const SmallModel small;
  const VoxelModel model(small.m, small.set);
  ASSERT_EQ(model.nx(), 12);
  ASSERT_EQ(model.ny(), 6);
  ASSERT_EQ(model.nz(), 4);
  const std::string path = mapping_scratch("small.voxels.h5").string();
  write_voxels_artifact(path, model, "test", "", {}, 0);
  const VoxelsReader in(path);
  EXPECT_EQ(in.bits_per_voxel(), 2);
  ASSERT_EQ(in.nz(), 4);
  for (std::int64_t Z = 0; Z < 4; ++Z) {
    const std::vector<int> layer = in.layer(Z);
    ASSERT_EQ(layer.size(), 72u);
    for (std::int64_t Y = 0; Y < 6; ++Y)
      for (std::int64_t X = 0; X < 12; ++X)
        ASSERT_EQ(layer[std::size_t(X + 12 * Y)], small.id(X, Y, Z)) << X << " " << Y << " " << Z;
  }
  // The rows are pack_voxels of each layer, as stored.
  const H5File f = H5File::open(path);
  const NdArray<std::uint8_t> rows = f.read_dataset<std::uint8_t>("/voxels");
  ASSERT_EQ(rows.shape, (std::vector<hsize_t>{4, 18}));
  std::vector<int> layer2;
  model.layer(2, layer2);
  const std::vector<std::uint8_t> packed = pack_voxels(layer2, 2);
  EXPECT_TRUE(std::equal(packed.begin(), packed.end(), rows.values.begin() + 2 * 18));
}

TEST(Mapping, StlHasTwoTrianglesPerDifferingVoxelFace) {
  const SmallModel small;
  const VoxelModel model(small.m, small.set);
  const std::string stem = mapping_scratch("small").string();
  const StlExport stl = write_material_stls(stem, model);
  ASSERT_EQ(stl.paths.size(), 2u);
  const Vec3 h = model.voxel_size();
  for (int material = 1; material <= 2; ++material) {
    // Faces between this material and anything else, the outside void.
    auto at = [&](std::int64_t X, std::int64_t Y, std::int64_t Z) {
      return X < 0 || Y < 0 || Z < 0 || X >= 12 || Y >= 6 || Z >= 4 ? 0 : small.id(X, Y, Z);
    };
    std::int64_t faces = 0;
    for (std::int64_t Z = 0; Z < 4; ++Z)
      for (std::int64_t Y = 0; Y < 6; ++Y)
        for (std::int64_t X = 0; X < 12; ++X) {
          if (at(X, Y, Z) != material) continue;
          faces += (at(X - 1, Y, Z) != material) + (at(X + 1, Y, Z) != material) + (at(X, Y - 1, Z) != material) +
                   (at(X, Y + 1, Z) != material) + (at(X, Y, Z - 1) != material) + (at(X, Y, Z + 1) != material);
        }
    ASSERT_GT(faces, 0);
    EXPECT_EQ(stl.triangles[std::size_t(material - 1)], 2 * faces);
    std::ifstream file(stl.paths[std::size_t(material - 1)], std::ios::binary);
    std::vector<char> bytes((std::istreambuf_iterator<char>(file)), std::istreambuf_iterator<char>());
    ASSERT_EQ(bytes.size(), 84u + 50u * std::size_t(2 * faces));
    std::uint32_t count = 0;
    std::memcpy(&count, bytes.data() + 80, 4);
    EXPECT_EQ(std::int64_t(count), 2 * faces);
    // Each triangle: half a voxel face, wound counter-clockwise about its
    // stored axis-aligned normal; a closed surface sums n dA to zero.
    Vec3 flux = Vec3::Zero();
    for (std::uint32_t t = 0; t < count; ++t) {
      float v[12];
      std::memcpy(v, bytes.data() + 84 + 50 * std::size_t(t), 48);
      const Vec3 n(v[0], v[1], v[2]), a(v[3], v[4], v[5]), b(v[6], v[7], v[8]), c(v[9], v[10], v[11]);
      const Vec3 area = 0.5 * (b - a).cross(c - a);
      ASSERT_NEAR(n.norm(), 1.0, 1e-7);
      ASSERT_GT(area.dot(n), 0);
      int axis = 0;
      n.cwiseAbs().maxCoeff(&axis);
      const double half_face = 0.5 * h[(axis + 1) % 3] * h[(axis + 2) % 3];
      ASSERT_NEAR(area.norm(), half_face, 1e-6 * half_face);  // float coordinates
      flux += area;
    }
    EXPECT_LT(flux.norm(), 1e-10);
  }
  // No tmp files are left behind.
  for (const auto& entry : fs::directory_iterator(mapping_scratch("").parent_path()))
    EXPECT_NE(entry.path().extension(), ".tmp") << entry.path();
}

TEST(Mapping, PngSlicesOnePerLayer) {
  const SmallModel small;
  const VoxelModel model(small.m, small.set);
  const std::string folder = mapping_scratch("small.slices").string();
  EXPECT_EQ(write_png_slices(folder, model), 4);
  for (const char* name : {"z00000.png", "z00003.png"}) {
    std::ifstream file(fs::path(folder) / name, std::ios::binary);
    char signature[8] = {};
    file.read(signature, 8);
    EXPECT_EQ(std::string(signature + 1, 3), "PNG") << name;
  }
  EXPECT_FALSE(fs::exists(fs::path(folder) / "z00004.png"));
}

// --- bad input ---------------------------------------------------------------------

void mapping_expect_input_error(const std::function<void()>& f, const std::string& fragment) {
  try {
    f();
    ADD_FAILURE() << "no InputError; expected one mentioning '" << fragment << "'";
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find(fragment), std::string::npos) << e.what();
  }
}

TEST(Mapping, BadInputsAreInputErrorsNamingTheFile) {
  const MicrostructureSet set2d = random_set(5, 4, 4, 1, 1);
  const MicrostructureSet set3d = random_set(5, 4, 4, 4, 2);
  const Design d2 = mapping_random_design(set2d, 3, 3, 1, 3);
  EXPECT_NO_THROW(check_mapping_inputs(d2, "d.h5", set2d, "s.h5"));
  Design simp = d2;
  simp.space = "simp2d";
  mapping_expect_input_error([&] { check_mapping_inputs(simp, "d.h5", set2d, "s.h5"); },
                             "d.h5: design space 'simp2d' is not a gamut space");
  Design ortho = d2;
  ortho.space = "orthotropic2d";
  mapping_expect_input_error([&] { check_mapping_inputs(ortho, "d.h5", set2d, "s.h5"); },
                             "s.h5: microstructure space 'cubic2d' differs from the design's 'orthotropic2d'");
  MicrostructureSet empty = set2d;
  empty.items.clear();
  mapping_expect_input_error([&] { check_mapping_inputs(d2, "d.h5", empty, "s.h5"); },
                             "s.h5: the microstructure set holds no structures");
  MicrostructureSet flat_as_3d = set3d;
  flat_as_3d.space = "cubic2d";
  mapping_expect_input_error([&] { check_mapping_inputs(d2, "d.h5", flat_as_3d, "s.h5"); },
                             "s.h5: 3D structures (4 x 4 x 4 voxels) for the 2D design d.h5");
  Design d3 = mapping_random_design(set3d, 2, 2, 2, 4);
  MicrostructureSet flat = set2d;
  flat.space = "cubic3d";
  mapping_expect_input_error([&] { check_mapping_inputs(d3, "d.h5", flat, "s.h5"); }, "2D structures");
  MicrostructureSet renamed = set2d;
  renamed.property_names = {"E", "nu", "Gxy"};
  mapping_expect_input_error([&] { check_mapping_inputs(d2, "d.h5", renamed, "s.h5"); }, "property names");

  // Files: a missing one, and a microstructures artifact given as the design.
  mapping_expect_input_error([&] { read_design_artifact(mapping_scratch("missing.h5").string()); },
                             "missing.h5: no such file");
  const std::string structures = mapping_scratch("set.microstructures.h5").string();
  write_microstructures_artifact(structures, set2d, "test", "", {}, 0);
  mapping_expect_input_error([&] { read_design_artifact(structures); }, "expected schema 'msfab.design'");
  mapping_expect_input_error([&] { read_mapped_artifact(structures); }, "expected schema 'msfab.mapped'");
  mapping_expect_input_error([&] { VoxelsReader reader(structures); }, "expected schema 'msfab.voxels'");
  // A mapping that does not fit the set's cells.
  const SmallModel small;
  mapping_expect_input_error([&] { VoxelModel model(small.m, set3d); }, "voxels, the structures 4 x 4 x 4");
}

TEST(Mapping, ChunkedDatasetSlabsRoundTrip) {
  const std::string path = mapping_scratch("slabs.h5").string();
  {
    H5File f = H5File::create(path);
    f.create_chunked_dataset<std::int32_t>("/a", {5, 7}, {2, 7}, 4);
    for (int r = 0; r < 5; r += 2) {
      const int rows = std::min(2, 5 - r);
      std::vector<std::int32_t> block(std::size_t(rows) * 7);
      for (std::size_t i = 0; i < block.size(); ++i) block[i] = r * 7 + int(i);
      f.write_slab("/a", block.data(), {hsize_t(r), 0}, {hsize_t(rows), 7});
    }
    EXPECT_THROW(f.write_slab("/a", std::vector<std::int32_t>(14).data(), {4, 0}, {2, 7}), std::out_of_range);
  }
  const H5File f = H5File::open(path);
  const NdArray<std::int32_t> all = f.read_dataset<std::int32_t>("/a");
  for (int i = 0; i < 35; ++i) EXPECT_EQ(all.values[std::size_t(i)], i);
  EXPECT_EQ(f.read_slab<double>("/a", {3, 2}, {1, 3}), (std::vector<double>{23, 24, 25}));
}

}  // namespace
}  // namespace msfab
