// Void removed from the full-resolution model (common/verify/solid_pieces):
// face-connected pieces, the rigid motions supports restrain, removal of
// pieces not held, and a bar inside void that solves as the bar alone.
#include <gtest/gtest.h>

#include <cmath>

#include "topopt/cell_material.hpp"
#include "topopt/grid_elasticity.hpp"
#include "verify/solid_pieces.hpp"

namespace msfab {
namespace {

std::vector<char> cells_of(const CellGrid& g, const std::vector<std::array<int, 3>>& list) {
  std::vector<char> solid(std::size_t(g.cells()), 0);
  for (const auto& c : list) solid[std::size_t(g.cell_index(c[0], c[1], c[2]))] = 1;
  return solid;
}

// Every unknown of the nodes with coordinate `index` on `axis` (in nodes).
std::vector<char> plane_fixed(const CellGrid& g, int axis, int index) {
  std::vector<char> fixed(std::size_t(g.unknowns()), 0);
  for (std::int64_t n = 0; n < g.nodes(); ++n)
    if (g.node_coords(n)[std::size_t(axis)] == index)
      for (int d = 0; d < 3; ++d) fixed[std::size_t(3 * n + d)] = 1;
  return fixed;
}

TEST(SolidPieces, PiecesJoinAtFacesNotAtEdgesOrCorners) {
  const CellGrid g(3, 4, 4, 4, 1.0);
  // Two cells sharing a face; one touching them along an edge; one touching that at a corner.
  const auto solid = cells_of(g, {{0, 0, 0}, {1, 0, 0}, {2, 1, 0}, {3, 2, 1}});
  const SolidPieces p = face_connected_pieces(g, solid);
  ASSERT_EQ(p.count(), 3);
  EXPECT_EQ(p.size[0], 2);
  EXPECT_EQ(p.size[1], 1);
  EXPECT_EQ(p.size[2], 1);
  EXPECT_EQ(p.piece[std::size_t(g.cell_index(0, 0, 0))], p.piece[std::size_t(g.cell_index(1, 0, 0))]);
  EXPECT_EQ(p.piece[std::size_t(g.cell_index(0, 1, 0))], -1);
}

TEST(SolidPieces, SupportsRestrainTheRigidMotionsTheyShould) {
  const CellGrid g(3, 4, 2, 2, 1.0);
  const std::vector<char> solid(std::size_t(g.cells()), 1);
  const SolidPieces p = face_connected_pieces(g, solid);
  ASSERT_EQ(p.count(), 1);
  std::vector<char> fixed(std::size_t(g.unknowns()), 0);
  EXPECT_EQ(restrained_rigid_motions(g, p, fixed)[0], 0);
  // One node in all components: the three rotations about it are free.
  const std::int64_t origin = g.node_index(0, 0, 0);
  for (int d = 0; d < 3; ++d) fixed[std::size_t(3 * origin + d)] = 1;
  EXPECT_EQ(restrained_rigid_motions(g, p, fixed)[0], 3);
  // A line of nodes (the edge x = 0, y = 0): the rotation about it is free.
  for (int k = 0; k <= 2; ++k)
    for (int d = 0; d < 3; ++d) fixed[std::size_t(3 * g.node_index(0, 0, k) + d)] = 1;
  EXPECT_EQ(restrained_rigid_motions(g, p, fixed)[0], 5);
  // A clamped face holds it.
  EXPECT_EQ(restrained_rigid_motions(g, p, plane_fixed(g, 0, 0))[0], 6);
  // Rollers on three faces (x on x = 0, y on y = 0, z on z = 0) hold it too.
  std::vector<char> rollers(std::size_t(g.unknowns()), 0);
  for (std::int64_t n = 0; n < g.nodes(); ++n)
    for (int d = 0; d < 3; ++d)
      if (g.node_coords(n)[std::size_t(d)] == 0) rollers[std::size_t(3 * n + d)] = 1;
  EXPECT_EQ(restrained_rigid_motions(g, p, rollers)[0], 6);
}

TEST(SolidPieces, PiecesNotHeldAreRemovedAndCounted) {
  const CellGrid g(3, 6, 2, 2, 1.0);
  // A clamped bar along x = 0..2 and a floating cell at x = 4, and one hanging on the bar by an edge.
  std::vector<std::array<int, 3>> list;
  for (int i = 0; i < 3; ++i) list.push_back({i, 0, 0});
  list.push_back({4, 1, 1});
  list.push_back({3, 1, 0});  // shares only the edge x = 3, y = 1 with cell (2, 0, 0)
  std::vector<char> solid = cells_of(g, list);
  const PieceRemoval r = remove_unheld_pieces(g, solid, plane_fixed(g, 0, 0));
  EXPECT_EQ(r.pieces, 3);
  EXPECT_EQ(r.removed, 2);
  EXPECT_EQ(r.removed_cells, 2);
  EXPECT_EQ(r.kept_cells, 3);
  EXPECT_EQ(solid[std::size_t(g.cell_index(4, 1, 1))], 0);
  EXPECT_EQ(solid[std::size_t(g.cell_index(3, 1, 0))], 0);
  EXPECT_EQ(solid[std::size_t(g.cell_index(2, 0, 0))], 1);
  std::vector<char> fixed(std::size_t(g.unknowns()), 0);
  const std::int64_t fixed_nodes = fix_unknowns_without_material(g, solid_nodes(g, solid), fixed);
  EXPECT_EQ(fixed_nodes, g.nodes() - 4 * 4);  // the bar's 4 x 2 x 2 nodes keep their unknowns
}

// A 8 x 2 x 2 bar in the corner of an 8 x 4 x 4 grid of void (with a
// floating cube in the void), clamped at x = 0 and pulled at x = 8: with
// void removed the matrix-free multigrid gives the bar's own solution on
// its own grid; ersatz void at 1e-6 does not.
TEST(SolidPieces, RemovingVoidLeavesASolidBarAsItIs) {
  const MatX C = isotropic_voigt(3, 1e6, 0.3);
  auto pairs_for = [&](const std::vector<char>& solid, double void_ratio) {
    MatX p(Eigen::Index(solid.size()), 21);
    for (std::size_t c = 0; c < solid.size(); ++c)
      for (int a = 0; a < 6; ++a)
        for (int t = a; t < 6; ++t)
          p(Eigen::Index(c), CellGrid::pair_index(a, t, 6)) = (solid[c] ? 1.0 : void_ratio) * C(a, t);
    return p;
  };
  // End faces: x = 0 clamped, x = 8 prescribed 0.01 along x, free across.
  auto supports = [](const CellGrid& g, VecX& prescribed) {
    std::vector<char> fixed = plane_fixed(g, 0, 0);
    prescribed = VecX::Zero(g.unknowns());
    for (std::int64_t n = 0; n < g.nodes(); ++n)
      if (g.node_coords(n)[0] == g.nx()) {
        fixed[std::size_t(3 * n)] = 1;
        prescribed[3 * n] = 0.01;
      }
    return fixed;
  };
  const CellGrid bar(3, 8, 2, 2, 0.25);
  VecX bar_prescribed;
  GridElasticity alone(bar, supports(bar, bar_prescribed), "cholmod", {});
  alone.set_stiffness(pairs_for(std::vector<char>(std::size_t(bar.cells()), 1), 0));
  const VecX u_bar = alone.solve(VecX::Zero(bar.unknowns()), bar_prescribed);

  const CellGrid box(3, 8, 4, 4, 0.25);
  std::vector<char> solid(std::size_t(box.cells()), 0);
  for (int i = 0; i < 8; ++i)
    for (int j = 0; j < 2; ++j)
      for (int k = 0; k < 2; ++k) solid[std::size_t(box.cell_index(i, j, k))] = 1;
  const std::vector<char> bar_cells = solid;
  solid[std::size_t(box.cell_index(4, 3, 3))] = 1;  // floating
  VecX prescribed;
  std::vector<char> fixed = supports(box, prescribed);
  const PieceRemoval removal = remove_unheld_pieces(box, solid, fixed);
  EXPECT_EQ(removal.removed, 1);
  EXPECT_EQ(solid, bar_cells);
  fix_unknowns_without_material(box, solid_nodes(box, solid), fixed);
  LinearSolverOptions options;
  options.pcg_tolerance = 1e-13;
  GridElasticity removed(box, fixed, "matrix-free", options);
  removed.set_stiffness(pairs_for(solid, 0));
  const VecX u_removed = removed.solve(VecX::Zero(box.unknowns()), prescribed);

  GridElasticity ersatz(box, supports(box, prescribed), "matrix-free", options);
  ersatz.set_stiffness(pairs_for(bar_cells, 1e-6));
  const VecX u_ersatz = ersatz.solve(VecX::Zero(box.unknowns()), prescribed);

  double difference = 0, ersatz_difference = 0, scale = 0;
  for (std::int64_t n = 0; n < bar.nodes(); ++n) {
    const auto c = bar.node_coords(n);
    const std::int64_t m = box.node_index(c[0], c[1], c[2]);
    difference = std::max(difference, (u_removed.segment<3>(3 * m) - u_bar.segment<3>(3 * n)).norm());
    ersatz_difference = std::max(ersatz_difference, (u_ersatz.segment<3>(3 * m) - u_bar.segment<3>(3 * n)).norm());
    scale = std::max(scale, u_bar.segment<3>(3 * n).norm());
  }
  EXPECT_LT(difference, 1e-9 * scale);
  EXPECT_LT(std::abs(removed.energy(u_removed) - alone.energy(u_bar)), 1e-9 * alone.energy(u_bar));
  // The ersatz void around the bar carries part of the load.
  EXPECT_GT(std::abs(ersatz.energy(u_ersatz) - alone.energy(u_bar)), 1e-8 * alone.energy(u_bar));
  EXPECT_GT(ersatz_difference, 1e-8 * scale);
}

}  // namespace
}  // namespace msfab
