// A family whose members connect through their faces whatever their
// thicknesses (configs/families/graded_lattice.yaml, docs/mapping.md): the
// three axis beams through the cell centre meet every neighbour's at the
// shared face centre. Checked the way the full-resolution model sees it:
// face-connected pieces of the voxel object built from cells of random
// members. Half-shifting a member moves its axis beams to the cell edges,
// which breaks the property (why the mapping of such a family runs with
// half_shift: false).
#include <gtest/gtest.h>

#include <random>

#include "core/errors.hpp"
#include "families/beam_template.hpp"
#include "gamut/structure_ops.hpp"
#include "mapping/mismatch.hpp"
#include "verify/solid_pieces.hpp"

namespace msfab {
namespace {

constexpr int kCell = 16;

// One member: axis beams of half-size `axis`, body diagonals of half-size
// `diagonal` (none for 0).
std::vector<int> lattice_member(double axis, double diagonal) {
  BeamTemplate tpl;
  Beam a;
  a.a = Vec3(0.5, 0.5, 0.5);
  a.b = Vec3(1.0, 0.5, 0.5);
  a.r0 = a.r1 = axis;
  tpl.beams.push_back(a);
  if (diagonal > 0) {
    Beam d;
    d.a = Vec3(0.5, 0.5, 0.5);
    d.b = Vec3(1.0, 1.0, 1.0);
    d.r0 = d.r1 = diagonal;
    tpl.beams.push_back(d);
  }
  return rasterize_template(tpl, kCell).ids;
}

// The voxel object of cells x cells x cells cells, cell c holding members[pick[c]].
SolidPieces pieces_of(const std::vector<std::vector<int>>& members, const std::vector<int>& pick, int cells) {
  const int n = cells * kCell;
  const CellGrid grid(3, n, n, n, 1.0);
  std::vector<char> solid(std::size_t(grid.cells()), 0);
  for (int ck = 0; ck < cells; ++ck)
    for (int cj = 0; cj < cells; ++cj)
      for (int ci = 0; ci < cells; ++ci) {
        const std::vector<int>& ids = members[std::size_t(pick[std::size_t(ci + cells * (cj + cells * ck))])];
        for (int k = 0; k < kCell; ++k)
          for (int j = 0; j < kCell; ++j)
            for (int i = 0; i < kCell; ++i)
              if (ids[std::size_t(i + kCell * (j + kCell * k))] != 0)
                solid[std::size_t(grid.cell_index(ci * kCell + i, cj * kCell + j, ck * kCell + k))] = 1;
      }
  return face_connected_pieces(grid, solid);
}

TEST(ConnectedFamily, RandomNeighboursFormOnePiece) {
  // The thinnest and thickest axis beams of the config, with and without diagonals.
  std::vector<std::vector<int>> members;
  for (double axis : {0.045, 0.10, 0.22, 0.29})
    for (double diagonal : {0.0, 0.05, 0.14}) members.push_back(lattice_member(axis, diagonal));
  const int cells = 3;
  std::mt19937 rng(7);
  std::uniform_int_distribution<int> any(0, int(members.size()) - 1);
  for (int trial = 0; trial < 4; ++trial) {
    std::vector<int> pick(std::size_t(cells * cells * cells));
    for (int& p : pick) p = any(rng);
    EXPECT_EQ(pieces_of(members, pick, cells).count(), 1) << "trial " << trial;
  }
}

TEST(ConnectedFamily, HalfShiftedMembersDoNotConnect) {
  // The thinnest axis-only member beside its half-shifted copy: the axis
  // beams of one end at face centres, those of the other run along the cell
  // edges; they meet nowhere.
  const std::vector<int> thin = lattice_member(0.045, 0.0);
  const std::vector<std::vector<int>> members = {thin, half_shifted(thin, kCell, kCell, kCell)};
  std::vector<int> pick(8, 0);
  pick[1] = 1;  // cell (1, 0, 0)
  EXPECT_GT(pieces_of(members, pick, 2).count(), 1);
}

TEST(ConnectedFamily, AxisBackboneJoinsAnyStructures) {
  // Random voxel clouds given the backbone (what `backbone: 1` does to every
  // sampled structure): each cell becomes one piece that holds the three
  // axis beams, and any arrangement of such cells is one piece.
  std::mt19937 rng(11);
  std::bernoulli_distribution solid(0.3);
  std::vector<std::vector<int>> members;
  for (int m = 0; m < 6; ++m) {
    VoxelGrid cell(kCell, kCell, kCell, 1.0 / kCell);
    for (int& id : cell.ids) id = solid(rng) ? 1 : 0;
    add_axis_backbone(cell, 1);
    for (int i = 0; i < kCell; ++i) {  // the x beam: the 2 x 2 central voxels of every x
      EXPECT_EQ(cell.at(i, kCell / 2 - 1, kCell / 2), 1);
      EXPECT_EQ(cell.at(i, kCell / 2, kCell / 2 - 1), 1);
    }
    EXPECT_EQ(pieces_of({cell.ids}, {0}, 1).count(), 1) << "member " << m;
    members.push_back(cell.ids);
  }
  std::uniform_int_distribution<int> any(0, int(members.size()) - 1);
  std::vector<int> pick(27);
  for (int& p : pick) p = any(rng);
  EXPECT_EQ(pieces_of(members, pick, 3).count(), 1);
}

TEST(ConnectedFamily, AxisBackboneKeepsTheCubicSymmetry) {
  VoxelGrid cell(kCell, kCell, kCell, 1.0 / kCell);
  cell.ids = lattice_member(0.10, 0.05);
  ASSERT_TRUE(has_cubic_symmetry(cell));
  add_axis_backbone(cell, 3);
  EXPECT_TRUE(has_cubic_symmetry(cell));
  EXPECT_THROW(add_axis_backbone(cell, 0), InputError);
  EXPECT_THROW(add_axis_backbone(cell, kCell), InputError);
}

}  // namespace
}  // namespace msfab
