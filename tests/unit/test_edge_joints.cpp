// Edge joints (topopt/edge_joints.hpp): a diagonal chain of stiff cells in
// a soft grid has one joint per step; a stiff bridge cell removes its
// joint; a uniform grid and a face-connected staircase have none; 2D
// corners count like 3D edges.
#include <gtest/gtest.h>

#include <stdexcept>

#include "topopt/cell_grid.hpp"
#include "topopt/edge_joints.hpp"

namespace msfab {
namespace {

// Voigt pairs of an isotropic-looking cell of normal stiffness s.
MatX joint_test_pairs(const CellGrid& g, const std::vector<double>& s) {
  MatX pairs = MatX::Zero(g.cells(), g.voigt_pairs());
  for (std::int64_t c = 0; c < g.cells(); ++c)
    for (int a = 0; a < g.voigt(); ++a) pairs(c, CellGrid::pair_index(a, a, g.voigt())) = s[std::size_t(c)];
  return pairs;
}

TEST(EdgeJoints, ADiagonalChainHasOneJointPerStep) {
  const CellGrid g(3, 5, 2, 5, 1.0);
  std::vector<double> s(std::size_t(g.cells()), 0.01);
  for (int t = 0; t < 5; ++t) s[std::size_t(g.cell_index(t, 0, t))] = 1.0;  // x and z step together
  EdgeJoints j = find_edge_joints(g, joint_test_pairs(g, s));
  EXPECT_EQ(j.count, 4);
  EXPECT_NEAR(j.largest_ratio, 100.0, 1e-9);
  // Half as stiff bridges: below the ratio 10 no more.
  std::vector<double> t = s;
  t[std::size_t(g.cell_index(1, 0, 0))] = 0.2;
  j = find_edge_joints(g, joint_test_pairs(g, t));
  EXPECT_EQ(j.count, 3);
  // A face-connected staircase: every step has a stiff bridge.
  for (int k = 0; k < 4; ++k) t[std::size_t(g.cell_index(k + 1, 0, k))] = 1.0;
  EXPECT_EQ(find_edge_joints(g, joint_test_pairs(g, t)).count, 0);
  // The chain running the other way along z counts as well.
  std::vector<double> u(std::size_t(g.cells()), 0.01);
  for (int k = 0; k < 5; ++k) u[std::size_t(g.cell_index(4 - k, 1, k))] = 1.0;
  EXPECT_EQ(find_edge_joints(g, joint_test_pairs(g, u)).count, 4);
  // Void bridges: the ratio is capped, not infinite.
  std::vector<double> v(std::size_t(g.cells()), 0.0);
  v[std::size_t(g.cell_index(0, 0, 0))] = v[std::size_t(g.cell_index(1, 1, 0))] = 1.0;
  j = find_edge_joints(g, joint_test_pairs(g, v));
  EXPECT_EQ(j.count, 1);
  EXPECT_DOUBLE_EQ(j.largest_ratio, 1e12);
}

TEST(EdgeJoints, UniformGridsHaveNoneAnd2DCornersCount) {
  const CellGrid g3(3, 3, 3, 3, 1.0);
  EXPECT_EQ(find_edge_joints(g3, joint_test_pairs(g3, std::vector<double>(27, 2.0))).count, 0);
  EXPECT_NEAR(find_edge_joints(g3, joint_test_pairs(g3, std::vector<double>(27, 2.0))).largest_ratio, 1.0, 1e-12);
  const CellGrid g2(2, 4, 4, 1, 1.0);
  std::vector<double> s(16, 1e-3);  // a checkerboard
  for (int j = 0; j < 4; ++j)
    for (int i = 0; i < 4; ++i)
      if ((i + j) % 2 == 0) s[std::size_t(g2.cell_index(i, j, 0))] = 1.0;
  // Stiff cells meet at every interior corner of the 4 x 4 board: 3 x 3 corners, one stiff diagonal each.
  EXPECT_EQ(find_edge_joints(g2, joint_test_pairs(g2, s)).count, 9);
  EXPECT_THROW(find_edge_joints(g2, MatX::Zero(15, 6)), std::invalid_argument);
  EXPECT_THROW(find_edge_joints(g2, joint_test_pairs(g2, s), 1.0), std::invalid_argument);
}

}  // namespace
}  // namespace msfab
