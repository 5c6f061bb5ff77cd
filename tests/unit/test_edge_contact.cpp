// Edge-edge contact (surface_contact.hpp): closest points of two lines, no
// pairs on a body at rest, and two bars laid crosswise -- one hexahedron
// each, so that no vertex lies over the other bar's faces and vertex-face
// contact alone lets them pass through each other.
#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>

#include "dynamics/newmark_integrator.hpp"
#include "dynamics/surface_contact.hpp"
#include "fem/hex_boundary.hpp"
#include "fem/hex_mesh_bodies.hpp"
#include "fem/voxel_grid.hpp"
#include "material/neo_hookean.hpp"
#include "two_body_test_model.hpp"

using namespace msfab;

namespace {

constexpr double kBarLength = 0.06, kBarWidth = 0.01;

// Bar A along x on z in [0, w]; bar B along y, `gap` above it. One element
// each, nodes 0-7 (A) and 8-15 (B) in hex8 order (node = 4x + 2y + z).
DynamicsModel crossing_bars_model(double gap) {
  NodeArray nodes(16, 3);
  std::vector<std::array<int, 8>> elements(2);
  for (int bar = 0; bar < 2; ++bar)
    for (int i = 0; i < 8; ++i) {
      const double sx = (i >> 2) - 0.5, sy = ((i >> 1) & 1) - 0.5, sz = i & 1;
      const int node = 8 * bar + i;
      if (bar == 0) {
        nodes.row(node) << sx * kBarLength, sy * kBarWidth, sz * kBarWidth;
      } else {
        nodes.row(node) << sx * kBarWidth, sy * kBarLength, kBarWidth + gap + sz * kBarWidth;
      }
      elements[bar][i] = node;
    }
  return contact_test::two_body_model(nodes, elements);
}

VecX rest_of(const HexMesh& mesh) { return Eigen::Map<const VecX>(mesh.nodes.data(), mesh.num_dofs()); }

// Mean z of bar B's lower face minus mean z of bar A's upper face.
double crossing_clearance(const VecX& q) {
  double b_bottom = 0, a_top = 0;
  for (int i = 0; i < 8; ++i) {
    if (i & 1) a_top += q(3 * i + 2) / 4;
    if (!(i & 1)) b_bottom += q(3 * (8 + i) + 2) / 4;
  }
  return b_bottom - a_top;
}

Vec3 total_momentum(const NewmarkIntegrator& sim) {
  const VecX p = sim.mass_matrix() * sim.velocities();
  Vec3 l = Vec3::Zero();
  for (int i = 0; i < p.size() / 3; ++i) l += p.segment<3>(3 * i);
  return l;
}

}  // namespace

TEST(EdgeContact, ClosestLineParametersAreTheCommonPerpendicular) {
  double alpha = 0, beta = 0;
  // The x axis from 0 to 1 and a line along y through (0.3, ., 1).
  ASSERT_TRUE(
      closest_line_parameters(Vec3(0, 0, 0), Vec3(1, 0, 0), Vec3(0.3, -1, 1), Vec3(0.3, 1, 1), 0.05, alpha, beta));
  EXPECT_NEAR(alpha, 0.3, 1e-14);
  EXPECT_NEAR(beta, 0.5, 1e-14);
  // Skew lines in general position: the connecting vector is perpendicular
  // to both.
  const Vec3 a0(0.1, 0.2, -0.3), a1(1.1, 0.7, 0.4), b0(-0.5, 1.0, 0.9), b1(0.8, -0.6, 0.2);
  ASSERT_TRUE(closest_line_parameters(a0, a1, b0, b1, 0.05, alpha, beta));
  const Vec3 d = (a0 + alpha * (a1 - a0)) - (b0 + beta * (b1 - b0));
  EXPECT_NEAR(d.dot(a1 - a0), 0.0, 1e-13);
  EXPECT_NEAR(d.dot(b1 - b0), 0.0, 1e-13);
  // Parallel within the sine bound: no common normal.
  EXPECT_FALSE(
      closest_line_parameters(Vec3(0, 0, 0), Vec3(1, 0, 0), Vec3(0, 1, 0), Vec3(1, 1.01, 0), 0.05, alpha, beta));
}

TEST(EdgeContact, NoPairsOnABodyAtRestAndFourOnCrossingBars) {
  // An L-shaped voxel body: convex and concave edges, edges beside edges
  // of the same body.
  VoxelGrid l_shape(3, 2, 3, 0.01, 0);
  for (int i = 0; i < 3; ++i)
    for (int j = 0; j < 2; ++j) l_shape.at(i, j, 0) = 1;
  for (int k = 1; k < 3; ++k)
    for (int j = 0; j < 2; ++j) l_shape.at(0, j, k) = 1;
  const VoxelMesh voxels = build_voxel_mesh(l_shape, {nullptr, std::make_shared<NeoHookean>(1e6, 0.3)});
  const HexBoundary lb = hex_boundary(voxels.mesh);
  const BoundarySurface ls(lb, lb.nodes);
  const VecX l_rest = rest_of(voxels.mesh);
  EXPECT_TRUE(ls.find_edges(l_rest, l_rest, 0.05 * 0.01, 0.25 * 0.01).empty());

  const double gap = 1e-4;
  const DynamicsModel bars = crossing_bars_model(gap);
  const HexBoundary bb = hex_boundary(bars.mesh);
  const BoundarySurface bs(bb, bb.nodes);
  EXPECT_EQ(bs.edges().size(), 24u);
  const VecX q = rest_of(bars.mesh);
  // No vertex of either bar lies over the other's faces.
  EXPECT_TRUE(bs.find(q, q, 0.05 * kBarWidth, 0.25 * kBarWidth).empty());
  // A's two upper long edges cross B's two lower long edges.
  const auto found = bs.find_edges(q, q, 0.05 * kBarWidth, 0.25 * kBarWidth);
  ASSERT_EQ(found.size(), 4u);
  for (const EdgeEdgeContact& c : found) {
    EXPECT_NEAR(c.gap_end, gap, 1e-12);
    EXPECT_NEAR(c.gap_start, gap, 1e-12);
    // Edge a is A's (lower node indices), and n points from B to A.
    EXPECT_LT(bs.edges()[c.edge_a].nodes[1], 8);
    EXPECT_GE(bs.edges()[c.edge_b].nodes[0], 8);
    EXPECT_NEAR(c.normal.z(), -1.0, 1e-12);
    EXPECT_NEAR(std::abs(c.alpha - 0.5), kBarWidth / kBarLength / 2, 1e-12);
    EXPECT_NEAR(std::abs(c.beta - 0.5), kBarWidth / kBarLength / 2, 1e-12);
  }
  // B moved down through A within one step: found from the start side.
  VecX through = q;
  for (int i = 8; i < 16; ++i) through(3 * i + 2) -= 2 * gap;
  const auto crossed = bs.find_edges(q, through, 0.05 * kBarWidth, 0.25 * kBarWidth);
  ASSERT_EQ(crossed.size(), 4u);
  for (const EdgeEdgeContact& c : crossed) EXPECT_NEAR(c.gap_end, -gap, 1e-12);
}

TEST(EdgeContact, ABarDroppedCrosswiseRestsOnAClampedBar) {
  auto run = [](bool edges, double* lowest) {
    DynamicsModel model = crossing_bars_model(1e-3);
    model.fixed.assign(model.mesh.num_dofs(), 0);
    for (int i = 0; i < 24; ++i) model.fixed[i] = 1;  // bar A
    NewmarkIntegrator sim(model, contact_test::drop_options(edges));
    contact_test::drop_body_b(sim, 0.5);
    *lowest = INFINITY;
    int active = 0;
    while (sim.time() < 0.03) {
      active += sim.step().active_contacts > 0;
      *lowest = std::min(*lowest, crossing_clearance(sim.positions()));
    }
    return active;
  };
  double with = 0, without = 0;
  const int active = run(true, &with);
  run(false, &without);
  std::printf("  lowest clearance of the upper bar: %.3e m with edge contact, %.3e m without\n", with, without);
  EXPECT_GT(active, 0);
  // The contact holds the edges' closest points apart; the faces' means
  // also include the bars' bending, a small fraction of the 1 mm start gap.
  EXPECT_GE(with, -1e-3 * kBarWidth);
  EXPECT_LT(without, -kBarWidth);  // vertex-face contact alone: straight through
}

TEST(EdgeContact, FreeCrossingBarsCollideConservingMomentum) {
  DynamicsModel model = crossing_bars_model(1e-3);
  model.gravity.setZero();
  NewmarkOptions opt;
  opt.time_step = 1e-4;
  NewmarkIntegrator sim(model, opt);
  VecX v = VecX::Zero(model.mesh.num_dofs());
  for (int i = 8; i < 16; ++i) v(3 * i + 2) = -0.5;
  sim.set_state(sim.assembler().rest_positions(), v);
  const Vec3 p0 = total_momentum(sim);
  double lowest = INFINITY;
  while (sim.time() < 0.02) {
    sim.step();
    lowest = std::min(lowest, crossing_clearance(sim.positions()));
  }
  double va = 0;
  for (int i = 0; i < 8; ++i) va += sim.velocities()(3 * i + 2) / 8;
  std::printf("  momentum error %.2e, lower bar's velocity %.4f m/s, lowest clearance %.3e m\n",
              (total_momentum(sim) - p0).norm() / p0.norm(), va, lowest);
  // Edge impulses are internal: coefficients (1 - alpha, alpha, beta - 1, -beta).
  EXPECT_LT((total_momentum(sim) - p0).norm() / p0.norm(), 1e-9);
  EXPECT_LT(va, -0.1);  // the lower bar was struck
  EXPECT_GE(lowest, -1e-3 * kBarWidth);
}
