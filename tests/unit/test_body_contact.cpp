// Contact between bodies and of a body with itself (vertex-face, thesis
// B.5): closest points on boundary quads, which node-face pairs count,
// separating touching bodies, momentum and restitution of a head-on
// collision under the three impact models, Coulomb friction between two
// bodies, and a body folding onto itself.
#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>

#include "dynamics/mass_matrix.hpp"
#include "dynamics/newmark_integrator.hpp"
#include "dynamics/surface_contact.hpp"
#include "fem/hex_boundary.hpp"
#include "fem/hex_mesh_bodies.hpp"
#include "fem/voxel_grid.hpp"
#include "material/neo_hookean.hpp"

using namespace msfab;

namespace {

// Voxel mesh of `grid` (ids 1.. = body label + 1, all of one material) with
// the bodies separated.
DynamicsModel bodies_model(const VoxelGrid& grid, const MaterialPtr& material, double density, double b,
                           const std::vector<std::string>& body_material) {
  std::vector<MaterialPtr> palette{nullptr};
  for (size_t i = 0; i < body_material.size(); ++i) palette.push_back(material);
  const VoxelMesh voxels = build_voxel_mesh(grid, palette);
  DynamicsModel model;
  model.mesh = voxels.mesh;
  std::vector<int> body;
  for (int e = 0; e < model.mesh.num_elements(); ++e) body.push_back(grid.ids[voxels.element_voxel[e]] - 1);
  separate_bodies(model.mesh, body);
  const size_t ne = model.mesh.num_elements();
  model.density.assign(ne, density);
  model.damping_a.assign(ne, 0.0);
  model.damping_b.assign(ne, b);
  for (int e = 0; e < model.mesh.num_elements(); ++e) model.element_material_name.push_back(body_material[body[e]]);
  model.contact = true;
  model.body_contact = true;
  return model;
}

VecX momentum(const NewmarkIntegrator& sim) {
  const VecX p = sim.mass_matrix() * sim.velocities();
  Vec3 l = Vec3::Zero();
  for (int i = 0; i < p.size() / 3; ++i) l += p.segment<3>(3 * i);
  return l;
}

// Mean x velocity of the nodes whose rest x is below / above `split`.
std::pair<double, double> body_velocities(const NewmarkIntegrator& sim, double split) {
  double sum[2] = {0, 0}, count[2] = {0, 0};
  const HexMesh& mesh = sim.model().mesh;
  for (int i = 0; i < mesh.num_nodes(); ++i) {
    const int side = mesh.nodes(i, 0) > split ? 1 : 0;
    sum[side] += sim.velocities()(3 * i);
    count[side] += 1;
  }
  return {sum[0] / count[0], sum[1] / count[1]};
}

}  // namespace

TEST(SurfaceContact, ClosestPointOnAWarpedQuadMatchesADenseSearch) {
  const std::array<Vec3, 4> x{Vec3(0, 0, 0), Vec3(1.0, 0.1, 0.05), Vec3(1.2, 0.9, -0.1), Vec3(-0.1, 1.0, 0.08)};
  const Vec3 p(0.37, 0.52, 0.4);
  const QuadProjection q = project_to_quad(x, p, 1e-9);
  auto point = [&](double s, double t) {
    return Vec3((1 - s) * (1 - t) * x[0] + s * (1 - t) * x[1] + s * t * x[2] + (1 - s) * t * x[3]);
  };
  double best = INFINITY, bs = 0, bt = 0;
  for (int i = 0; i <= 400; ++i)
    for (int j = 0; j <= 400; ++j) {
      const double d = (point(i / 400.0, j / 400.0) - p).norm();
      if (d < best) best = d, bs = i / 400.0, bt = j / 400.0;
    }
  EXPECT_TRUE(q.inside);
  EXPECT_NEAR(q.s, bs, 3e-3);
  EXPECT_NEAR(q.t, bt, 3e-3);
  EXPECT_LE((point(q.s, q.t) - p).norm(), best + 1e-12);
  // Outward for a quad listed counter-clockwise seen from +z.
  EXPECT_GT(quad_normal(x, q.s, q.t).z(), 0.9);
  // A point beyond the rim is not inside; its closest point is clamped.
  const QuadProjection out = project_to_quad(x, Vec3(2.0, 0.5, 0.0), 0.02);
  EXPECT_FALSE(out.inside);
  EXPECT_DOUBLE_EQ(out.s, 1.0);
}

TEST(SurfaceContact, OneBodyAtRestHasNoSelfContactAndFacingBodiesDo) {
  // An L-shaped body: convex and concave edges, nodes beside faces of their
  // own body that are not theirs.
  VoxelGrid l_shape(3, 2, 3, 0.01, 0);
  for (int i = 0; i < 3; ++i)
    for (int j = 0; j < 2; ++j) l_shape.at(i, j, 0) = 1;
  for (int k = 1; k < 3; ++k)
    for (int j = 0; j < 2; ++j) l_shape.at(0, j, k) = 1;
  DynamicsModel l = bodies_model(l_shape, std::make_shared<NeoHookean>(1e6, 0.3), 1000, 0, {"a"});
  const HexBoundary lb = hex_boundary(l.mesh);
  const BoundarySurface ls(lb, lb.nodes);
  const VecX rest = Eigen::Map<const VecX>(l.mesh.nodes.data(), l.mesh.num_dofs());
  EXPECT_TRUE(ls.find(rest, rest, 0.05 * 0.01, 0.25 * 0.01).empty());

  // Two 2x2x1 slabs, one above the other with a gap of 1e-4 m.
  VoxelGrid slabs(2, 2, 2, 0.01, 1);
  for (int i = 0; i < 2; ++i)
    for (int j = 0; j < 2; ++j) slabs.at(i, j, 1) = 2;
  DynamicsModel two = bodies_model(slabs, std::make_shared<NeoHookean>(1e6, 0.3), 1000, 0, {"a", "b"});
  VecX q = Eigen::Map<const VecX>(two.mesh.nodes.data(), two.mesh.num_dofs());
  for (int i = 0; i < two.mesh.num_nodes(); ++i)
    if (i >= two.mesh.num_nodes() / 2) q(3 * i + 2) += 1e-4;  // the upper slab's nodes come second
  const HexBoundary tb = hex_boundary(two.mesh);
  const BoundarySurface ts(tb, tb.nodes);
  const auto found = ts.find(q, q, 0.05 * 0.01, 0.25 * 0.01);
  // Each facing surface has 3 x 3 nodes, each against the other slab.
  ASSERT_EQ(found.size(), 18u);
  for (const NodeFaceContact& c : found) {
    EXPECT_NEAR(c.gap_end, 1e-4, 1e-12);
    EXPECT_NEAR(std::abs(c.normal.z()), 1.0, 1e-12);
  }
}

TEST(SurfaceContact, SeparatingBodiesDuplicatesOnlyTheSharedNodes) {
  VoxelGrid grid(2, 2, 2, 0.01, 1);
  for (int i = 0; i < 2; ++i)
    for (int j = 0; j < 2; ++j) grid.at(i, j, 1) = 2;
  const VoxelMesh voxels =
      build_voxel_mesh(grid, {nullptr, std::make_shared<NeoHookean>(1e6, 0.3), std::make_shared<NeoHookean>(1e6, 0.3)});
  HexMesh mesh = voxels.mesh;
  EXPECT_EQ(mesh.num_nodes(), 27);
  EXPECT_EQ(element_components(mesh), std::vector<int>(8, 0));
  std::vector<int> body;
  for (int e = 0; e < mesh.num_elements(); ++e) body.push_back(grid.ids[voxels.element_voxel[e]]);
  const std::vector<int> source = separate_bodies(mesh, body);
  EXPECT_EQ(mesh.num_nodes(), 27 + 9);
  const std::vector<int> components = element_components(mesh);
  for (int e = 0; e < mesh.num_elements(); ++e) EXPECT_EQ(components[e], body[e] - body[0]);
  for (int i = 0; i < mesh.num_nodes(); ++i)
    EXPECT_EQ((mesh.nodes.row(i) - voxels.mesh.nodes.row(source[i])).norm(), 0.0);
}

namespace {

struct Collision {
  double relative_velocity_after;  // v_B - v_A at the end (positive: separating)
  double momentum_error;           // |P_end - P_0| / |P_0|
  double max_penetration;
  int contact_steps = 0;
};

// Two stiff, damped 1 cm cubes in space; A moves at v0 toward B at rest.
Collision head_on(ImpactModel impact) {
  VoxelGrid grid(5, 2, 2, 0.005, 0);
  for (int i = 0; i < 5; ++i)
    for (int j = 0; j < 2; ++j)
      for (int k = 0; k < 2; ++k) grid.at(i, j, k) = i < 2 ? 1 : (i > 2 ? 2 : 0);
  DynamicsModel model = bodies_model(grid, std::make_shared<NeoHookean>(0.65e9, 0.45), 1200, 1.64e-4, {"a", "b"});
  model.gravity.setZero();
  model.impact = impact;
  NewmarkOptions opt;
  opt.time_step = 1e-4;
  NewmarkIntegrator sim(model, opt);
  const double v0 = 0.77;
  VecX v = VecX::Zero(model.mesh.num_dofs());
  for (int i = 0; i < model.mesh.num_nodes(); ++i)
    if (model.mesh.nodes(i, 0) < 0.0125) v(3 * i) = v0;
  sim.set_state(sim.assembler().rest_positions(), v);
  const Vec3 p0 = momentum(sim);
  Collision c{0, 0, 0};
  while (sim.time() < 0.02) {
    const StepReport r = sim.step();
    c.max_penetration = std::max(c.max_penetration, r.max_penetration);
    if (r.active_contacts > 0) ++c.contact_steps;
  }
  const auto [va, vb] = body_velocities(sim, 0.0125);
  c.relative_velocity_after = (vb - va) / v0;
  c.momentum_error = (momentum(sim) - p0).norm() / p0.norm();
  return c;
}

}  // namespace

TEST(BodyContact, HeadOnCollisionConservesMomentumAndOrdersTheImpactModels) {
  const Collision comp = head_on(ImpactModel::kComplementarity);
  const Collision dke = head_on(ImpactModel::kDke);
  const Collision bbi = head_on(ImpactModel::kBbi);
  std::printf("  separation speed / approach speed: complementarity %.4f, DKE %.4f, BBI %.4f\n",
              comp.relative_velocity_after, dke.relative_velocity_after, bbi.relative_velocity_after);
  std::printf("  momentum error: %.2e %.2e %.2e; penetration %.2e %.2e %.2e m\n", comp.momentum_error,
              dke.momentum_error, bbi.momentum_error, comp.max_penetration, dke.max_penetration, bbi.max_penetration);
  for (const Collision* c : {&comp, &dke, &bbi}) {
    EXPECT_GT(c->contact_steps, 0);
    // Contact impulses are internal: +f on the node, -w_i f on the face.
    EXPECT_LT(c->momentum_error, 1e-9);
    EXPECT_LE(c->max_penetration, 1e-3 * 0.005);
  }
  EXPECT_GT(comp.relative_velocity_after, 0.5);            // nearly elastic
  EXPECT_LT(std::abs(bbi.relative_velocity_after), 0.05);  // inelastic: they move on together
  EXPECT_LT(dke.relative_velocity_after, comp.relative_velocity_after);
}

TEST(BodyContact, BlockSlidingOnAnotherStopsAfterTheCoulombDistance) {
  // A 2x2x1 block on a clamped 6x4x1 block, long enough for the slider's
  // centre of mass to stay over it and wide enough that its edges are not
  // on the base's rim; the friction pair names the two materials (the
  // default is frictionless, so a missed lookup never stops).
  VoxelGrid grid(6, 4, 2, 0.005, 1);
  for (int i = 0; i < 6; ++i)
    for (int j = 0; j < 4; ++j) grid.at(i, j, 1) = i < 2 && j >= 1 && j <= 2 ? 2 : 0;
  DynamicsModel model = bodies_model(grid, std::make_shared<NeoHookean>(2e7, 0.3), 1200, 2e-4, {"base", "slider"});
  model.friction = true;
  const double mu = 0.4, v0 = 0.2, g = 9.81;
  model.friction_table.pairs[{"slider", "base"}] = mu;
  model.fixed.assign(model.mesh.num_dofs(), 0);
  const int lower_nodes = 7 * 5 * 2;  // the base's nodes come first (element order)
  for (int i = 0; i < 3 * lower_nodes; ++i) model.fixed[i] = 1;
  NewmarkOptions opt;
  opt.time_step = 5e-4;
  NewmarkIntegrator sim(model, opt);
  VecX v = VecX::Zero(model.mesh.num_dofs());
  for (int i = lower_nodes; i < model.mesh.num_nodes(); ++i) v(3 * i) = v0;
  VecX q = sim.assembler().rest_positions();
  sim.set_state(q, v);
  auto slider_x = [&] {
    double x = 0;
    for (int i = lower_nodes; i < model.mesh.num_nodes(); ++i) x += sim.positions()(3 * i);
    return x / (model.mesh.num_nodes() - lower_nodes);
  };
  const double x0 = slider_x();
  double penetration = 0;
  while (sim.time() < v0 / (mu * g) + 0.02) penetration = std::max(penetration, sim.step().max_penetration);
  const double travel = slider_x() - x0, expected = v0 * v0 / (2 * mu * g);
  std::printf("  slider stopped after %.5e m (expected %.5e), penetration %.2e m\n", travel, expected, penetration);
  EXPECT_NEAR(travel / expected, 1.0, 1e-3);
  EXPECT_LE(penetration, 1e-3 * 0.005);
}

TEST(BodyContact, ABodyFoldingOntoItselfIsStoppedBySelfContact) {
  // A C-shaped body: a clamped lower arm, a back wall, and an upper arm
  // thrown down toward the lower arm across a one-voxel slot.
  auto run = [](bool self_contact, double* min_slot) {
    VoxelGrid grid(4, 1, 3, 0.005, 0);
    for (int i = 0; i < 4; ++i) grid.at(i, 0, 0) = grid.at(i, 0, 2) = 1;
    grid.at(0, 0, 1) = 1;
    DynamicsModel model = bodies_model(grid, std::make_shared<NeoHookean>(2e5, 0.3), 1000, 1e-3, {"c"});
    model.body_contact = self_contact;
    model.contact = self_contact;
    model.gravity.setZero();
    model.fixed.assign(model.mesh.num_dofs(), 0);
    for (int i = 0; i < model.mesh.num_nodes(); ++i)
      if (model.mesh.nodes(i, 2) < 1e-9) model.fixed[3 * i] = model.fixed[3 * i + 1] = model.fixed[3 * i + 2] = 1;
    NewmarkOptions opt;
    opt.time_step = 2e-4;
    NewmarkIntegrator sim(model, opt);
    VecX v = VecX::Zero(model.mesh.num_dofs());
    for (int i = 0; i < model.mesh.num_nodes(); ++i)
      if (model.mesh.nodes(i, 2) > 0.0099) v(3 * i + 2) = -3.0 * model.mesh.nodes(i, 0) / 0.02;
    sim.set_state(sim.assembler().rest_positions(), v);
    *min_slot = INFINITY;
    int active = 0;
    while (sim.time() < 0.03) {
      active += sim.step().active_contacts > 0;
      // The slot: upper arm's underside (z = 0.01 at rest) above the lower
      // arm's top (z = 0.005), at the free end x = 0.02.
      double under = INFINITY, top = -INFINITY;
      for (int i = 0; i < model.mesh.num_nodes(); ++i) {
        if (std::abs(model.mesh.nodes(i, 0) - 0.02) > 1e-9) continue;
        const double z = sim.positions()(3 * i + 2);
        if (std::abs(model.mesh.nodes(i, 2) - 0.010) < 1e-9) under = std::min(under, z);
        if (std::abs(model.mesh.nodes(i, 2) - 0.005) < 1e-9) top = std::max(top, z);
      }
      *min_slot = std::min(*min_slot, under - top);
    }
    return active;
  };
  double with = 0, without = 0;
  const int active = run(true, &with);
  run(false, &without);
  std::printf("  smallest slot at the free end: %.3e m with self-contact, %.3e m without\n", with, without);
  EXPECT_GT(active, 0);
  EXPECT_GE(with, -1e-3 * 0.005);
  EXPECT_LT(without, -1e-3);  // without it the arm passes through
}
