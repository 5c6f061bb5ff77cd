// Quasistatic loading with unilateral no-slip contact (App. B.3): checked
// against static solves with the contact set clamped, force and moment
// balance, and the sign conditions of B.24.
#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <memory>

#include "core/errors.hpp"
#include "dynamics/mass_matrix.hpp"
#include "dynamics/quasistatic_loading.hpp"
#include "fem/elastic_assembler.hpp"
#include "fem/voxel_grid.hpp"
#include "material/neo_hookean.hpp"
#include "scene/scene.hpp"
#include "solve/newton.hpp"

using namespace msfab;

namespace {

constexpr double kH = 0.01;  // voxel edge, 1 cm

struct QuasistaticBody {
  VoxelGrid grid;
  VoxelMesh vm;
  std::unique_ptr<ElasticAssembler> assembler;
  VecX rest;
  VecX force;
};

// A solid nx x ny x nz block of 1 cm voxels with its lower corner at
// `origin`, Neo-Hookean rubber, loaded by its weight (rho = 1000 kg/m^3).
std::unique_ptr<QuasistaticBody> make_block(int nx, int ny, int nz, const Vec3& origin, double E = 1e6,
                                            double nu = 0.3) {
  auto s = std::make_unique<QuasistaticBody>();
  s->grid = VoxelGrid(nx, ny, nz, kH, 1);
  s->grid.origin = origin;
  s->vm = build_voxel_mesh(s->grid, {nullptr, std::make_shared<NeoHookean>(E, nu)});
  s->assembler = std::make_unique<ElasticAssembler>(s->vm.mesh);
  s->rest = s->assembler->rest_positions();
  const SpMat m = scalar_mass_matrix(s->vm.mesh, std::vector<double>(s->vm.mesh.num_elements(), 1000.0));
  const VecX node_mass = m * VecX::Ones(m.cols());
  s->force = VecX::Zero(s->vm.mesh.num_dofs());
  for (int i = 0; i < s->vm.mesh.num_nodes(); ++i) s->force[3 * i + 2] = -9.81 * node_mass[i];
  return s;
}

// Adds a total force spread over the nodes of a region by their weights.
void add_region_load(QuasistaticBody& s, const Region& region, const Vec3& total) {
  const RegionNodes sel = select_region(region, s.grid, s.vm);
  double sum = 0;
  for (double w : sel.weight) sum += w;
  for (size_t k = 0; k < sel.nodes.size(); ++k) s.force.segment<3>(3 * sel.nodes[k]) += total * sel.weight[k] / sum;
}

Obstacle ground(double z = 0.0) {
  Obstacle o;
  o.kind = Obstacle::Kind::kGround;
  o.name = "ground";
  o.ground_z = z;
  return o;
}

// Static solve with the given nodes clamped where `x` has them.
VecX clamped_solve(const QuasistaticBody& s, const std::vector<int>& nodes, const VecX& x) {
  auto dc = DirichletConditions::none(s.vm.mesh.num_dofs());
  for (int i : nodes)
    for (int a = 0; a < 3; ++a) {
      dc.fixed[3 * i + a] = 1;
      dc.displacement[3 * i + a] = x[3 * i + a] - s.rest[3 * i + a];
    }
  NewtonOptions opt;
  opt.relative_tolerance = 1e-10;
  opt.load_steps = 2;
  opt.linear_solver = "cholmod";
  const NewtonResult r = solve_static(*s.assembler, dc, s.force, opt);
  EXPECT_TRUE(r.converged) << r.failure;
  return r.x;
}

double max_abs(const VecX& v) { return v.cwiseAbs().maxCoeff(); }

// Net force and moment (about the origin) of the loads plus the reactions,
// relative to the load's magnitude and the moment arm of the mesh size.
void expect_balanced(const QuasistaticBody& s, const QuasistaticResult& r, double rel) {
  Vec3 force = Vec3::Zero(), moment = Vec3::Zero(), load = Vec3::Zero();
  double load_abs = 0;
  for (int i = 0; i < s.vm.mesh.num_nodes(); ++i) {
    const Vec3 f = s.force.segment<3>(3 * i);
    force += f;
    load += f;
    load_abs += f.norm();
    moment += r.x.segment<3>(3 * i).cross(f);
  }
  for (const ContactVertex& c : r.contacts) {
    force += c.reaction;
    moment += r.x.segment<3>(3 * c.node).cross(c.reaction);
  }
  const double arm = (s.vm.mesh.bbox_max() - s.vm.mesh.bbox_min()).norm() + r.x.cwiseAbs().maxCoeff();
  std::printf("  net force %.3e N, net moment %.3e N m (load %.3e N)\n", force.norm(), moment.norm(), load_abs);
  EXPECT_LT(force.norm(), rel * load_abs);
  EXPECT_LT(moment.norm(), rel * load_abs * arm);
}

// Sign conditions of B.24: no active vertex is pulled, none is away from
// its face, no free vertex is inside an obstacle.
void expect_admissible(const QuasistaticBody& s, const std::vector<Obstacle>& obstacles, const QuasistaticResult& r) {
  std::vector<char> active(s.vm.mesh.num_nodes(), 0);
  double scale = 0;
  for (const ContactVertex& c : r.contacts) scale = std::max(scale, c.reaction.norm());
  for (const ContactVertex& c : r.contacts) {
    active[c.node] = 1;
    EXPECT_GE(c.plane.normal.dot(c.reaction), -1e-9 * scale) << "node " << c.node << " pulls on the obstacle";
    EXPECT_NEAR(c.plane.gap(r.x.segment<3>(3 * c.node)), 0.0, 1e-12) << "active node " << c.node << " off its face";
  }
  double deepest = 0;
  for (int i = 0; i < s.vm.mesh.num_nodes(); ++i)
    for (const Obstacle& o : obstacles)
      if (!active[i]) deepest = std::min(deepest, signed_distance(o, r.x.segment<3>(3 * i), nullptr));
  EXPECT_GE(deepest, -1e-12) << "a free vertex penetrates";
}

std::vector<int> contact_nodes(const QuasistaticResult& r) {
  std::vector<int> nodes;
  for (const ContactVertex& c : r.contacts) nodes.push_back(c.node);
  return nodes;
}

}  // namespace

TEST(QuasistaticLoading, CharacteristicSizeOfVoxelMeshIsVoxelEdge) {
  auto s = make_block(3, 2, 1, Vec3::Zero());
  EXPECT_NEAR(characteristic_element_size(s->vm.mesh), kH, 1e-15);
}

TEST(QuasistaticLoading, BlockPressedOnGroundEqualsClampedBottomSolve) {
  // 4x4x2 block under 1e5 Pa on top (about 10% strain) and its weight: the
  // whole bottom stays in compression, so the answer is the static solve
  // with the bottom face clamped.
  auto s = make_block(4, 4, 2, Vec3::Zero());
  Region top;
  top.axis = 2;
  top.upper = true;
  add_region_load(*s, top, Vec3(0, 0, -1e5 * 16 * kH * kH));
  const std::vector<Obstacle> obstacles = {ground()};
  QuasistaticOptions opt;
  opt.relative_tolerance = 1e-11;
  const QuasistaticResult r = solve_quasistatic_loading(*s->assembler, obstacles, s->force, VecX(), opt);

  std::vector<int> bottom;
  for (int i = 0; i < s->vm.mesh.num_nodes(); ++i)
    if (s->vm.mesh.nodes(i, 2) == 0.0) bottom.push_back(i);
  EXPECT_EQ(contact_nodes(r), bottom) << "every bottom vertex, and only those, stays active";
  const VecX ref = clamped_solve(*s, bottom, s->rest);
  const double diff = max_abs(r.x - ref), u = max_abs(r.x - s->rest);
  std::printf("  pressed block: %d iterations, max |u| %.4e m, max |x - x_clamped| %.3e m, energy %.6e J\n",
              r.iterations, u, diff, r.elastic_energy);
  EXPECT_GT(u, 5e-4);  // a real load
  EXPECT_LT(diff, 1e-8 * u);
  expect_admissible(*s, obstacles, r);
  expect_balanced(*s, r, 1e-8);
  EXPECT_NEAR(r.elastic_energy, s->assembler->energy(r.x), 0.0);
  ASSERT_FALSE(r.history.empty());
  EXPECT_LE(r.history.back().residual, 1e-11);
}

TEST(QuasistaticLoading, BarLiftedAtOneEndReleasesContacts) {
  // A 10x2x2 soft bar lying on the ground is pulled up at its x = L end by
  // less than its weight: the near end of the bottom lifts, the rest keeps
  // it down.
  auto s = make_block(10, 2, 2, Vec3::Zero(), 2e5, 0.3);
  Region end;
  end.kind = Region::Kind::Box;
  end.lo = Vec3(10 * kH, -1, -1);
  end.hi = Vec3(10 * kH, 1, 1);
  const double weight = 1000 * 9.81 * 40 * kH * kH * kH;
  add_region_load(*s, end, Vec3(0, 0, 0.3 * weight));
  const std::vector<Obstacle> obstacles = {ground()};
  QuasistaticOptions opt;
  opt.relative_tolerance = 1e-11;
  const QuasistaticResult r = solve_quasistatic_loading(*s->assembler, obstacles, s->force, VecX(), opt);

  int bottom = 0, released = 0;
  double lift = 0;
  std::vector<char> active(s->vm.mesh.num_nodes(), 0);
  for (const ContactVertex& c : r.contacts) active[c.node] = 1;
  for (int i = 0; i < s->vm.mesh.num_nodes(); ++i) {
    if (s->vm.mesh.nodes(i, 2) != 0.0) continue;
    ++bottom;
    if (!active[i]) {
      ++released;
      lift = std::max(lift, r.x[3 * i + 2]);
    }
  }
  // The bottom lifts in one piece at the pulled end.
  double last_active = -1, first_released = 1;
  for (int i = 0; i < s->vm.mesh.num_nodes(); ++i) {
    if (s->vm.mesh.nodes(i, 2) != 0.0) continue;
    double& bound = active[i] ? last_active : first_released;
    bound = active[i] ? std::max(bound, s->vm.mesh.nodes(i, 0)) : std::min(bound, s->vm.mesh.nodes(i, 0));
  }
  EXPECT_LT(last_active, first_released);
  std::printf("  lifted bar: %d iterations, %d of %d bottom vertices released (x >= %.3f m), max lift %.4e m\n",
              r.iterations, released, bottom, first_released, lift);
  EXPECT_GT(released, 0);
  EXPECT_LT(released, bottom);
  EXPECT_GT(lift, 1e-5);
  expect_admissible(*s, obstacles, r);
  expect_balanced(*s, r, 1e-8);

  const VecX ref = clamped_solve(*s, contact_nodes(r), r.x);
  const double diff = max_abs(r.x - ref), u = max_abs(r.x - s->rest);
  std::printf("  lifted bar vs clamped converged active set: max |x - x_ref| %.3e m (max |u| %.3e m)\n", diff, u);
  EXPECT_LT(diff, 1e-8 * u);
}

namespace {

// A box platform with its top at z = 2 cm holds 6 of a bar's 10 voxels; the
// other 4 overhang and bend down under their weight and a tip load, which
// also tips the bar about the ledge's edge and lifts its far end. The
// ground lies at ground_z.
struct LedgeCase {
  std::unique_ptr<QuasistaticBody> s;
  std::vector<Obstacle> obstacles;
  QuasistaticResult r;
  double tip_drop = 0;  // of the bottom edge at the tip
};
LedgeCase run_ledge(double ground_z) {
  LedgeCase c;
  c.s = make_block(10, 2, 1, Vec3(0, 0, 2 * kH), 2e5, 0.3);
  Region tip;
  tip.kind = Region::Kind::Box;
  tip.lo = Vec3(10 * kH, -1, -1);
  tip.hi = Vec3(10 * kH, 1, 1);
  add_region_load(*c.s, tip, Vec3(0, 0, -0.02));
  Obstacle box;
  box.kind = Obstacle::Kind::kBox;
  box.name = "ledge";
  box.lo = Vec3(-0.05, -0.05, 0);
  box.hi = Vec3(6 * kH, 0.05, 2 * kH);
  c.obstacles = {ground(ground_z), box};
  QuasistaticOptions opt;
  opt.relative_tolerance = 1e-11;
  c.r = solve_quasistatic_loading(*c.s->assembler, c.obstacles, c.s->force, VecX(), opt);
  for (int i = 0; i < c.s->vm.mesh.num_nodes(); ++i)
    if (c.s->vm.mesh.nodes(i, 0) == 10 * kH && c.s->vm.mesh.nodes(i, 2) == 2 * kH)
      c.tip_drop = std::max(c.tip_drop, c.s->rest[3 * i + 2] - c.r.x[3 * i + 2]);
  return c;
}

}  // namespace

TEST(QuasistaticLoading, BarOverhangingALedgeRestsOnTheBoxTop) {
  const LedgeCase c = run_ledge(0.0);
  const QuasistaticBody& s = *c.s;
  ASSERT_FALSE(c.r.contacts.empty());
  double last_lifted = -1, first_held = 1;  // x of the lifted / held bottom nodes
  std::vector<char> active(s.vm.mesh.num_nodes(), 0);
  for (const ContactVertex& v : c.r.contacts) {
    active[v.node] = 1;
    EXPECT_EQ(v.obstacle, 1);
    // Edge vertices touch two faces; the top carries them.
    EXPECT_EQ(v.plane.normal, Vec3::UnitZ());
    EXPECT_LE(s.vm.mesh.nodes(v.node, 0), 6 * kH + 1e-12);
    first_held = std::min(first_held, s.vm.mesh.nodes(v.node, 0));
  }
  int lifted = 0;
  for (int i = 0; i < s.vm.mesh.num_nodes(); ++i)
    if (s.vm.mesh.nodes(i, 2) == 2 * kH && s.vm.mesh.nodes(i, 0) <= 6 * kH && !active[i]) {
      ++lifted;
      last_lifted = std::max(last_lifted, s.vm.mesh.nodes(i, 0));
    }
  std::printf("  ledge: %d iterations, %zu contacts, %d lifted behind the edge (up to x = %.3f m), tip drop %.4e m\n",
              c.r.iterations, c.r.contacts.size(), lifted, last_lifted, c.tip_drop);
  // The bar pivots on the edge; the overhang's moment bows the supported part
  // up behind the edge while the weight keeps the far end down.
  EXPECT_GT(lifted, 0);
  EXPECT_EQ(first_held, 0.0);
  EXPECT_LT(last_lifted, 6 * kH);
  for (int i = 0; i < s.vm.mesh.num_nodes(); ++i)
    if (s.vm.mesh.nodes(i, 2) == 2 * kH && s.vm.mesh.nodes(i, 0) == 6 * kH) {
      EXPECT_TRUE(active[i]) << "edge node " << i;
    }
  EXPECT_GT(c.tip_drop, 1e-3);
  expect_admissible(s, c.obstacles, c.r);
  expect_balanced(s, c.r, 1e-8);
  const VecX ref = clamped_solve(s, contact_nodes(c.r), c.r.x);
  EXPECT_LT(max_abs(c.r.x - ref), 1e-8 * max_abs(c.r.x - s.rest));
}

TEST(QuasistaticLoading, OverhangTouchingDownIsProjectedAndHeld) {
  // With the ground 2 mm below the ledge top the bending tip (3.4 mm drop
  // without it) lands: vertices that were free must be stopped at the
  // ground, become active and carry compressive reactions.
  const LedgeCase c = run_ledge(2 * kH - 0.002);
  const QuasistaticBody& s = *c.s;
  int on_ground = 0, activated = 0;
  for (const ContactVertex& v : c.r.contacts)
    if (v.obstacle == 0) {
      ++on_ground;
      EXPECT_GT(s.vm.mesh.nodes(v.node, 0), 6 * kH);
      EXPECT_NEAR(c.r.x[3 * v.node + 2], 2 * kH - 0.002, 1e-15);
      EXPECT_GT(v.reaction.z(), 0.0);
    }
  for (const auto& h : c.r.history) activated += h.activated;
  std::printf("  touch-down: %d iterations, %d vertices on the ground, %d activations, tip drop %.4e m\n",
              c.r.iterations, on_ground, activated, c.tip_drop);
  EXPECT_GT(on_ground, 0);
  EXPECT_GE(activated, on_ground);
  EXPECT_NEAR(c.tip_drop, 0.002, 1e-12);
  expect_admissible(s, c.obstacles, c.r);
  expect_balanced(s, c.r, 1e-8);
  const VecX ref = clamped_solve(s, contact_nodes(c.r), c.r.x);
  EXPECT_LT(max_abs(c.r.x - ref), 1e-8 * max_abs(c.r.x - s.rest));
}

TEST(QuasistaticLoading, IterationLimitCountsFromTheLastActiveSetChange) {
  // A long bar lifted at one end in one load increment peels off the ground
  // a few vertices per iteration. With a limit below the number of those
  // active-set updates the increment still converges (the limit counts
  // iterations at a settled set), to the same iterates as with the default.
  auto s = make_block(24, 1, 1, Vec3::Zero(), 2e5, 0.3);
  Region end;
  end.kind = Region::Kind::Box;
  end.lo = Vec3(24 * kH, -1, -1);
  end.hi = Vec3(24 * kH, 1, 1);
  const double weight = 1000 * 9.81 * 24 * kH * kH * kH;
  add_region_load(*s, end, Vec3(0, 0, 0.45 * weight));
  QuasistaticOptions opt;
  opt.relative_tolerance = 1e-11;
  opt.load_steps = 1;
  opt.max_step_halvings = 0;
  const QuasistaticResult full = solve_quasistatic_loading(*s->assembler, {ground()}, s->force, VecX(), opt);
  int changes = 0, last_change = 0;
  for (const QuasistaticIteration& h : full.history)
    if (h.released > 0) ++changes, last_change = h.iteration;
  std::printf("  peeling bar: %d iterations, %d with releases, the last at iteration %d\n", full.iterations, changes,
              last_change);
  ASSERT_GE(changes, 4) << "the test needs a front that moves over several iterations";
  opt.max_iterations = changes - 1;  // the old count of all iterations would stop here
  const QuasistaticResult limited = solve_quasistatic_loading(*s->assembler, {ground()}, s->force, VecX(), opt);
  EXPECT_EQ(limited.iterations, full.iterations);
  EXPECT_EQ((limited.x - full.x).cwiseAbs().maxCoeff(), 0.0);
  // A limit below the Newton iterations needed at the settled set still fails.
  opt.max_iterations = 1;
  const QuasistaticResult short_of_it = solve_quasistatic_loading(*s->assembler, {ground()}, s->force, VecX(), opt);
  EXPECT_FALSE(short_of_it.converged);
  EXPECT_FALSE(short_of_it.failure.empty());
}

TEST(QuasistaticLoading, NoEquilibriumIsReportedWithHistory) {
  // Pulled up by more than its weight, the bar leaves the ground: no static
  // equilibrium exists. As solve_static, the result says so instead of
  // throwing, holds the rest state (the last converged load factor, 0) and
  // the history of the failed tries.
  auto s = make_block(3, 1, 1, Vec3::Zero());
  s->force = -3.0 * s->force;
  QuasistaticOptions opt;
  opt.max_iterations = 10;
  opt.max_step_halvings = 1;
  opt.load_steps = 1;
  const QuasistaticResult r = solve_quasistatic_loading(*s->assembler, {ground()}, s->force, VecX(), opt);
  EXPECT_FALSE(r.converged);
  EXPECT_NE(r.failure.find("load factor"), std::string::npos) << r.failure;
  EXPECT_FALSE(r.history.empty());
  EXPECT_EQ(r.load_steps, 2);  // the full step and its half
  EXPECT_EQ((r.x - s->assembler->rest_positions()).cwiseAbs().maxCoeff(), 0.0);
  const std::string table = format_quasistatic_history(r.history);
  EXPECT_NE(table.find("residual"), std::string::npos) << table;
}

TEST(QuasistaticLoading, BadInputsAreInputErrors) {
  auto s = make_block(2, 2, 1, Vec3::Zero());
  const std::vector<Obstacle> obstacles = {ground()};
  const int n = s->vm.mesh.num_dofs();
  // Initial state 1 mm (0.1 dx) below the ground: deeper than 1e-2 dx.
  VecX sunk = s->rest - 1e-3 * Eigen::Vector3d::UnitZ().replicate(n / 3, 1);
  EXPECT_THROW(solve_quasistatic_loading(*s->assembler, obstacles, s->force, sunk), InputError);
  try {
    solve_quasistatic_loading(*s->assembler, obstacles, s->force, sunk);
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find("ground"), std::string::npos) << e.what();
  }
  // Within the tolerance it is accepted (projected onto the ground).
  VecX grazing = s->rest - 1e-5 * Eigen::Vector3d::UnitZ().replicate(n / 3, 1);
  const QuasistaticResult r = solve_quasistatic_loading(*s->assembler, obstacles, s->force, grazing);
  EXPECT_EQ(r.contacts.size(), 9u);
  for (const ContactVertex& c : r.contacts) EXPECT_EQ(r.x[3 * c.node + 2], 0.0);

  EXPECT_THROW(solve_quasistatic_loading(*s->assembler, obstacles, VecX::Zero(n - 3)), InputError);
  VecX bad = s->force;
  bad[4] = std::nan("");
  EXPECT_THROW(solve_quasistatic_loading(*s->assembler, obstacles, bad), InputError);
  EXPECT_THROW(solve_quasistatic_loading(*s->assembler, obstacles, s->force, VecX::Zero(5)), InputError);
  Obstacle flat;
  flat.kind = Obstacle::Kind::kBox;
  flat.name = "flat";
  flat.lo = Vec3(0, 0, -1);
  flat.hi = Vec3(1, 1, -1);
  EXPECT_THROW(solve_quasistatic_loading(*s->assembler, {ground(), flat}, s->force), InputError);
  QuasistaticOptions opt;
  opt.load_steps = 0;
  EXPECT_THROW(solve_quasistatic_loading(*s->assembler, obstacles, s->force, VecX(), opt), InputError);
}
