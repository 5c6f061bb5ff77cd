// Self-contact in quasistatic loading (self_contact_ties.hpp): two bodies
// tied where they touch equal one body with those nodes merged; a body
// pressed shut rests on itself instead of folding through; the ties'
// reactions push and the obstacles carry the whole load.
#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <memory>

#include "dynamics/mass_matrix.hpp"
#include "dynamics/quasistatic_loading.hpp"
#include "dynamics/surface_contact.hpp"
#include "fem/elastic_assembler.hpp"
#include "fem/hex_boundary.hpp"
#include "fem/hex_mesh_bodies.hpp"
#include "fem/voxel_grid.hpp"
#include "material/neo_hookean.hpp"

using namespace msfab;

namespace {

constexpr double kEdge = 0.01;  // voxel edge, 1 cm

// A voxel mesh of `grid` (ids 1 and 2, one rubber), its bodies (the ids)
// kept apart or fused, loaded by its weight and by `top_load` shared by the
// nodes of the highest layer whose x is at least `load_from_x`.
struct PressedMesh {
  HexMesh mesh;
  std::unique_ptr<ElasticAssembler> assembler;
  VecX force;
};

// Returned through a pointer: the assembler refers to the mesh.
std::unique_ptr<PressedMesh> pressed_mesh(const VoxelGrid& grid, bool separate, double top_load, double load_from_x) {
  auto owner = std::make_unique<PressedMesh>();
  PressedMesh& p = *owner;
  const VoxelMesh vm =
      build_voxel_mesh(grid, {nullptr, std::make_shared<NeoHookean>(1e6, 0.3), std::make_shared<NeoHookean>(1e6, 0.3)});
  p.mesh = vm.mesh;
  if (separate) {
    std::vector<int> body;
    for (int e = 0; e < p.mesh.num_elements(); ++e) body.push_back(grid.ids[vm.element_voxel[e]]);
    separate_bodies(p.mesh, body);
  }
  p.assembler = std::make_unique<ElasticAssembler>(p.mesh);
  const SpMat m = scalar_mass_matrix(p.mesh, std::vector<double>(p.mesh.num_elements(), 1000.0));
  const VecX node_mass = m * VecX::Ones(m.cols());
  p.force = VecX::Zero(p.mesh.num_dofs());
  const double top = p.mesh.bbox_max().z();
  int loaded = 0;
  for (int i = 0; i < p.mesh.num_nodes(); ++i)
    loaded += p.mesh.nodes(i, 2) > top - 1e-12 && p.mesh.nodes(i, 0) >= load_from_x - 1e-12;
  for (int i = 0; i < p.mesh.num_nodes(); ++i) {
    p.force[3 * i + 2] = -9.81 * node_mass[i];
    if (p.mesh.nodes(i, 2) > top - 1e-12 && p.mesh.nodes(i, 0) >= load_from_x - 1e-12)
      p.force[3 * i + 2] -= top_load / loaded;
  }
  return owner;
}

Obstacle floor_plane() {
  Obstacle o;
  o.kind = Obstacle::Kind::kGround;
  o.name = "ground";
  o.ground_z = 0;
  return o;
}

// The push of a tie along its normal at `x`: a face's on its node, or edge
// b's on edge a (positive: pushing them apart).
double tie_push(const SelfContactTie& t, const VecX& x) { return t.push_normal(x).dot(t.reaction); }

}  // namespace

TEST(QuasistaticSelfContact, BodiesTiedWhereTheyTouchEqualTheFusedBody) {
  // A 3x3 slab (body 1) with a 1x3 bar (body 2) across its middle.
  VoxelGrid grid(3, 3, 2, kEdge, 1);
  for (int i = 0; i < 3; ++i)
    for (int j = 0; j < 3; ++j) grid.at(i, j, 1) = i == 1 ? 2 : 0;
  const auto fused_owner = pressed_mesh(grid, false, 4.0, 0.0);
  const auto apart_owner = pressed_mesh(grid, true, 4.0, 0.0);
  const PressedMesh& fused = *fused_owner;
  const PressedMesh& apart = *apart_owner;
  ASSERT_EQ(apart.mesh.num_nodes(), fused.mesh.num_nodes() + 2 * 4);  // the bar's underside duplicated
  QuasistaticOptions opt;
  opt.relative_tolerance = 1e-11;
  const QuasistaticResult ref = solve_quasistatic_loading(*fused.assembler, {floor_plane()}, fused.force, VecX(), opt);
  // Without self-contact nothing holds the bar up: it sinks through the
  // slab to the ground.
  const QuasistaticResult sunk = solve_quasistatic_loading(*apart.assembler, {floor_plane()}, apart.force, VecX(), opt);
  double highest_grounded = 0;  // rest height of the highest node on the ground
  for (const ContactVertex& v : sunk.contacts)
    highest_grounded = std::max(highest_grounded, apart.mesh.nodes(v.node, 2));
  EXPECT_GT(highest_grounded, 0.5 * kEdge);  // the bar's underside (rest z = 1 cm) ended on the ground
  opt.self_contact = true;
  const QuasistaticResult tied = solve_quasistatic_loading(*apart.assembler, {floor_plane()}, apart.force, VecX(), opt);
  EXPECT_EQ(tied.self_contacts.size(), 8u);
  // Each node of the separated mesh moves as the fused node at its rest
  // position.
  double scale = 0, worst = 0;
  for (int i = 0; i < fused.mesh.num_nodes(); ++i)
    scale = std::max(scale, (ref.x.segment<3>(3 * i) - fused.assembler->rest_positions().segment<3>(3 * i)).norm());
  for (int i = 0; i < apart.mesh.num_nodes(); ++i) {
    int match = -1;
    for (int j = 0; j < fused.mesh.num_nodes() && match < 0; ++j)
      if ((fused.mesh.nodes.row(j) - apart.mesh.nodes.row(i)).norm() < 1e-12) match = j;
    ASSERT_GE(match, 0);
    worst = std::max(worst, (tied.x.segment<3>(3 * i) - ref.x.segment<3>(3 * match)).norm());
  }
  std::printf("  largest displacement %.4e m; tied against fused: largest difference %.2e m\n", scale, worst);
  EXPECT_GT(scale, 1e-4);
  EXPECT_LT(worst, 1e-8 * scale);
  // The bar rests on the slab: every tie pushes.
  for (const SelfContactTie& t : tied.self_contacts) EXPECT_GT(tie_push(t, tied.x), 0.0) << "node " << t.node;
}

TEST(QuasistaticSelfContact, ACShapePressedShutRestsOnItsLowerArm) {
  // Lower arm on the ground, a back wall at x = 0, an upper arm over a
  // one-voxel slot, pressed down at its free end.
  VoxelGrid grid(5, 1, 3, kEdge, 0);
  for (int i = 0; i < 5; ++i) grid.at(i, 0, 0) = grid.at(i, 0, 2) = 1;
  grid.at(0, 0, 1) = 1;
  // 1 N: about 2.5 times the force that closes the slot.
  const auto owner = pressed_mesh(grid, false, 1.0, 0.04);
  const PressedMesh& c = *owner;
  const HexBoundary boundary = hex_boundary(c.mesh);
  const BoundarySurface surface(boundary, boundary.nodes);
  const VecX rest = c.assembler->rest_positions();
  auto deepest = [&](const VecX& x) {
    double depth = 0;
    for (const NodeFaceContact& f : surface.find(rest, x, 0.0, 0.25 * kEdge)) depth = std::max(depth, -f.gap_end);
    return depth;
  };
  QuasistaticOptions opt;
  opt.load_steps = 8;
  const QuasistaticResult folded = solve_quasistatic_loading(*c.assembler, {floor_plane()}, c.force, VecX(), opt);
  opt.self_contact = true;
  const QuasistaticResult shut = solve_quasistatic_loading(*c.assembler, {floor_plane()}, c.force, VecX(), opt);
  Vec3 reactions = Vec3::Zero(), load = Vec3::Zero();
  for (const ContactVertex& v : shut.contacts) reactions += v.reaction;
  for (int i = 0; i < c.mesh.num_nodes(); ++i) load += c.force.segment<3>(3 * i);
  std::printf(
      "  without self-contact a node ends %.3e m behind a face; with it %.3e m (%zu ties); "
      "ground reactions + load = %.2e N of %.3f N\n",
      deepest(folded.x), deepest(shut.x), shut.self_contacts.size(), (reactions + load).norm(), load.norm());
  EXPECT_GT(deepest(folded.x), 0.1 * kEdge);  // the arm goes through
  EXPECT_LE(deepest(shut.x), 1e-2 * kEdge);   // the line search's depth bound
  EXPECT_GT(shut.self_contacts.size(), 0u);
  // Ties are internal: the ground carries the whole load.
  EXPECT_LT((reactions + load).norm(), 1e-7 * load.norm());
  // No tie pulls (the solver releases those that would).
  for (const SelfContactTie& t : shut.self_contacts)
    EXPECT_GE(tie_push(t, shut.x), -1e-7 * load.norm()) << "node " << t.node;
}

TEST(QuasistaticSelfContact, ABarPressedCrosswiseOntoABarRestsOnItsEdges) {
  // Bar A (one element along x) on the ground, bar B (one element along y)
  // laid across it, touching: no vertex of either lies over a face of the
  // other, so only ties between their crossing edges can hold B up.
  constexpr double kLength = 0.06, kWidth = 0.01;
  NodeArray nodes(16, 3);
  std::vector<std::array<int, 8>> elements(2);
  for (int bar = 0; bar < 2; ++bar)
    for (int i = 0; i < 8; ++i) {
      const double sx = (i >> 2) - 0.5, sy = ((i >> 1) & 1) - 0.5, sz = i & 1;
      if (bar == 0)
        nodes.row(i) << sx * kLength, sy * kWidth, sz * kWidth;
      else
        nodes.row(8 + i) << sx * kWidth, sy * kLength, kWidth + sz * kWidth;
      elements[bar][i] = 8 * bar + i;
    }
  const HexMesh mesh = make_hex_mesh(nodes, elements, std::make_shared<NeoHookean>(1e6, 0.3));
  const ElasticAssembler assembler(mesh);
  VecX force = VecX::Zero(mesh.num_dofs());
  const double load = 2.0;  // N on B's top, about 400 times its weight
  for (int i = 0; i < 16; ++i) force[3 * i + 2] = -9.81 * 1000 * kLength * kWidth * kWidth / 8;
  for (int i = 8; i < 16; ++i)
    if (i & 1) force[3 * i + 2] -= load / 4;
  // Mean z of B's lower face minus mean z of A's upper face.
  auto clearance = [](const VecX& x) {
    double b_bottom = 0, a_top = 0;
    for (int i = 0; i < 8; ++i) {
      if (i & 1) a_top += x[3 * i + 2] / 4;
      if (!(i & 1)) b_bottom += x[3 * (8 + i) + 2] / 4;
    }
    return b_bottom - a_top;
  };
  QuasistaticOptions opt;
  opt.self_contact = true;
  opt.edge_contact = false;
  const QuasistaticResult through = solve_quasistatic_loading(assembler, {floor_plane()}, force, VecX(), opt);
  opt.edge_contact = true;
  const QuasistaticResult rests = solve_quasistatic_loading(assembler, {floor_plane()}, force, VecX(), opt);
  ASSERT_TRUE(rests.converged) << rests.failure;
  int edge_ties = 0;
  double apart = 0;  // largest distance between the two points a tie holds together
  for (const SelfContactTie& t : rests.self_contacts) {
    edge_ties += t.is_edge_pair();
    Vec3 a = Vec3::Zero(), b = Vec3::Zero();
    if (t.is_edge_pair()) {
      a = (1 - t.alpha) * rests.x.segment<3>(3 * t.edge_nodes[0]) + t.alpha * rests.x.segment<3>(3 * t.edge_nodes[1]);
      b = (1 - t.beta) * rests.x.segment<3>(3 * t.edge_nodes[2]) + t.beta * rests.x.segment<3>(3 * t.edge_nodes[3]);
    }
    apart = std::max(apart, (a - b).norm());
  }
  Vec3 reactions = Vec3::Zero(), applied = Vec3::Zero();
  for (const ContactVertex& v : rests.contacts) reactions += v.reaction;
  for (int i = 0; i < 16; ++i) applied += force.segment<3>(3 * i);
  const double largest = (rests.x - assembler.rest_positions()).cwiseAbs().maxCoeff();
  std::printf(
      "  clearance of the upper bar: %.3e m with edge ties (%d of %zu ties; largest displacement %.3e m), %.3e m "
      "without; tied points %.1e m apart; ground reactions + load = %.2e N of %.3f N\n",
      clearance(rests.x), edge_ties, rests.self_contacts.size(), largest, clearance(through.x), apart,
      (reactions + applied).norm(), applied.norm());
  EXPECT_GT(largest, 1e-3 * kWidth);               // the load deforms the bars
  EXPECT_LT(clearance(through.x), -0.5 * kWidth);  // node-face ties alone: B goes through A
  EXPECT_GT(edge_ties, 0);
  // B rests on A's edges: its lower face sags between them by its bending
  // alone, a small fraction of a width.
  EXPECT_GT(clearance(rests.x), -0.05 * kWidth);
  EXPECT_LT(apart, 1e-12);
  // Ties are internal: the ground carries the whole load, and no tie pulls.
  EXPECT_LT((reactions + applied).norm(), 1e-7 * applied.norm());
  for (const SelfContactTie& t : rests.self_contacts)
    EXPECT_GE(t.push_normal(rests.x).dot(t.reaction), -1e-7 * applied.norm()) << "node " << t.node;
}
