#include "dynamics/dynamics_scene.hpp"

#include <algorithm>
#include <cmath>
#include <sstream>

#include "core/errors.hpp"
#include "dynamics/coarse_dynamics.hpp"
#include "dynamics/dac_model_artifact.hpp"
#include "dynamics/scene_parameters.hpp"
#include "fem/hex_mesh_bodies.hpp"
#include "fem/voxel_shapes.hpp"
#include "io/material_config.hpp"
#include "material/neo_hookean.hpp"
#include "scene/scene.hpp"

namespace msfab {

namespace {

Vec3 vec3(const Config& c, const std::string& key) {
  const auto v = c.get<std::vector<double>>(key);
  if (v.size() != 3) c.fail(key, "needs three numbers [x, y, z]");
  for (double x : v)
    if (!std::isfinite(x)) c.fail(key, "must be finite");
  return Vec3(v[0], v[1], v[2]);
}

// Solid boxes need volume; selection regions (clamps, loads) may be flat.
void read_box(const Config& c, Vec3& lo, Vec3& hi, bool flat_allowed = false) {
  lo = vec3(c, "min");
  hi = vec3(c, "max");
  if (flat_allowed ? !(lo.array() <= hi.array()).all() : !(lo.array() < hi.array()).all())
    c.fail("max", flat_allowed ? "must not be below min in any coordinate" : "must exceed min in every coordinate");
}

Mat3 rotation_from_degrees(const Vec3& deg) {
  const Vec3 r = deg * M_PI / 180.0;
  return (Eigen::AngleAxisd(r.z(), Vec3::UnitZ()) * Eigen::AngleAxisd(r.y(), Vec3::UnitY()) *
          Eigen::AngleAxisd(r.x(), Vec3::UnitX()))
      .toRotationMatrix();
}

std::vector<SceneMaterial> read_materials(const Config& c) {
  std::vector<SceneMaterial> out;
  // Every modulus times this: a printer's material variation, for studies
  // of how robust a design is (msfab-jump-design's robustness check).
  const double modulus_scale = c.get_or<double>("modulus_scale", 1.0);
  if (!(modulus_scale > 0)) c.fail("modulus_scale", "must be positive (a factor on every material's E)");
  for (const Config& m : c.children("materials")) {
    SceneMaterial s;
    s.name = m.get<std::string>("name");
    s.nu = read_poissons_ratio(m);
    s.density = read_density(m);
    if (m.has("dac_model")) {
      // The numerical modulus and damping fitted by msfab-dac-calibrate.
      for (const char* key : {"E", "damping_a", "damping_b"})
        if (m.has(key)) m.fail(key, "is taken from dac_model; give one or the other");
      const DacModel dac = read_dac_model_artifact(m.get_path("dac_model"));
      s.E = dac.youngs_modulus;
      s.damping_a = dac.damping_a;
      s.damping_b = dac.damping_b;
    } else {
      s.E = read_youngs_modulus(m, "Young's modulus (the numerical modulus E_n for coarse meshes)");
      s.damping_a = m.get_or<double>("damping_a", 0.0);
      s.damping_b = m.get_or<double>("damping_b", 0.0);
    }
    s.E *= modulus_scale;
    if (!(s.damping_a >= 0) || !std::isfinite(s.damping_a)) m.fail("damping_a", "must be finite and >= 0");
    if (!(s.damping_b >= 0) || !std::isfinite(s.damping_b)) m.fail("damping_b", "must be finite and >= 0");
    for (const SceneMaterial& other : out)
      if (other.name == s.name) m.fail("name", "material '" + s.name + "' is defined twice");
    out.push_back(s);
  }
  if (out.empty()) c.fail("materials", "needs at least one material");
  return out;
}

int material_index(const Config& c, const std::string& key, const std::vector<SceneMaterial>& materials) {
  const std::string name = c.get<std::string>(key);
  for (size_t i = 0; i < materials.size(); ++i)
    if (materials[i].name == name) return static_cast<int>(i);
  std::string known;
  for (const auto& m : materials) known += (known.empty() ? "" : ", ") + m.name;
  c.fail(key, "unknown material '" + name + "' (defined: " + known + ")");
}

// The voxel materials, and in `body` each voxel's body (boxes with the same
// `body:` name, default "body", form one body; numbered in order of first
// appearance). The files a layout read are appended to `files`.
VoxelGrid paint_geometry(const Config& g, const std::vector<SceneMaterial>& materials, VoxelGrid& body,
                         std::vector<std::string>& body_names, std::vector<std::string>& files) {
  const double h = g.require_positive<double>("voxel_size", "voxel edge length (m)");
  struct Box {
    Vec3 lo, hi;
    int id, body;
  };
  std::vector<Box> boxes;
  Vec3 lo = Vec3::Constant(INFINITY), hi = Vec3::Constant(-INFINITY);
  for (const Config& b : g.children("boxes")) {
    Box box;
    read_box(b, box.lo, box.hi);
    box.id = material_index(b, "material", materials) + 1;
    const std::string name = b.get_or("body", "body");
    box.body = static_cast<int>(std::find(body_names.begin(), body_names.end(), name) - body_names.begin());
    if (box.body == static_cast<int>(body_names.size())) body_names.push_back(name);
    lo = lo.cwiseMin(box.lo);
    hi = hi.cwiseMax(box.hi);
    boxes.push_back(box);
  }
  if (boxes.empty()) g.fail("boxes", "needs at least one box");
  Eigen::Vector3i n;
  for (int a = 0; a < 3; ++a) {
    n(a) = static_cast<int>(std::lround((hi(a) - lo(a)) / h));
    if (n(a) < 1) g.fail("voxel_size", "is larger than the geometry");
    if (std::abs(n(a) * h - (hi(a) - lo(a))) > 1e-6 * h)
      g.fail("voxel_size", "does not divide the geometry's extent along " + std::string(1, "xyz"[a]) +
                               " (the voxels must resolve every box)");
  }
  if (double(n(0)) * n(1) * n(2) > 5e7) g.fail("voxel_size", "gives more than 5e7 voxels");
  VoxelGrid grid(n(0), n(1), n(2), h, 0);
  grid.origin = lo;
  // Body labels are painted as body + 1 so that 0 marks an unpainted voxel:
  // a box may repaint its own body's voxels, never another body's.
  body = VoxelGrid(n(0), n(1), n(2), h, 0);
  body.origin = lo;
  for (size_t k = 0; k < boxes.size(); ++k) {
    const Box& b = boxes[k];
    VoxelGrid mine(n(0), n(1), n(2), h, 0);
    mine.origin = lo;
    paint_box(mine, b.lo, b.hi, 1);
    for (size_t v = 0; v < mine.size(); ++v)
      if (mine.ids[v] && body.ids[v] && body.ids[v] != b.body + 1)
        g.fail("boxes[" + std::to_string(k) + "]",
               "overlaps a box of body '" + body_names[body.ids[v] - 1] + "' (bodies may touch, not overlap)");
    paint_box(grid, b.lo, b.hi, b.id);
    paint_box(body, b.lo, b.hi, b.body + 1);
  }
  for (int& v : body.ids) v = std::max(v - 1, 0);
  if (g.has("layout")) {
    // The layout of a static scene (fibres, layers, a random field, ...)
    // repaints the materials inside the boxes; it never adds solid, and void
    // it paints becomes a hole. Ids are 1-based indices into `materials`.
    VoxelGrid painted = grid;
    files = paint_layout(g, painted, scene_palette(materials));
    for (size_t v = 0; v < grid.ids.size(); ++v)
      if (grid.ids[v]) grid.ids[v] = painted.ids[v];
  }
  if (grid.count_solid() == 0) g.fail("boxes", "paint no voxel");
  return grid;
}

std::vector<Obstacle> read_obstacles(const Config& c) {
  std::vector<Obstacle> out;
  if (!c.has("obstacles")) return out;
  int index = 0;
  for (const Config& o : c.children("obstacles")) {
    Obstacle ob;
    const std::string type = o.one_of("type", {"ground", "box"});
    ob.name = o.get_or("name", type == "ground" ? "ground" : "box" + std::to_string(index));
    ob.surface = o.get_or("surface", "default");
    if (type == "ground") {
      ob.kind = Obstacle::Kind::kGround;
      ob.ground_z = o.get_or<double>("z", 0.0);
    } else {
      ob.kind = Obstacle::Kind::kBox;
      read_box(o, ob.lo, ob.hi);
    }
    out.push_back(ob);
    ++index;
  }
  return out;
}

FrictionTable read_friction(const Config& c, const std::vector<SceneMaterial>& materials) {
  FrictionTable t;
  if (!c.has("friction")) return t;
  const Config f = c.child("friction");
  t.default_mu = f.get_or<double>("default", 0.0);
  if (!(t.default_mu >= 0) || !std::isfinite(t.default_mu))
    f.fail("default", "friction coefficient must be >= 0 (got " + std::to_string(t.default_mu) + ")");
  if (f.has("pairs"))
    for (const Config& p : f.children("pairs")) {
      const std::string material = materials[material_index(p, "material", materials)].name;
      const std::string surface = p.get<std::string>("surface");
      const double mu = p.get<double>("mu");
      if (!(mu >= 0) || !std::isfinite(mu))
        p.fail("mu", "friction coefficient must be >= 0 (got " + std::to_string(mu) + ")");
      t.pairs[{material, surface}] = mu;
    }
  return t;
}

RegionLoad read_region_load(const Config& c) {
  RegionLoad r;
  read_box(c.child("region"), r.lo, r.hi, true);
  r.force = vec3(c, "force");
  return r;
}

}  // namespace

std::vector<MaterialPtr> scene_palette(const std::vector<SceneMaterial>& materials) {
  std::vector<MaterialPtr> palette{nullptr};
  for (const SceneMaterial& m : materials) palette.push_back(std::make_shared<NeoHookean>(m.E, m.nu));
  return palette;
}

VecX region_force(const DynamicsScene& s, const RegionLoad& load, const std::string& what) {
  // A coarsened design is loaded where the fine one is: on the fine nodes,
  // restricted to the coarse ones by P^T.
  const VecX& positions = s.coarsening ? s.coarsening->fine_initial_positions : s.initial_positions;
  const int nodes = static_cast<int>(positions.size() / 3);
  std::vector<int> inside;
  for (int i = 0; i < nodes; ++i) {
    const Vec3 x = positions.segment<3>(3 * i);
    if ((x.array() >= load.lo.array() - 1e-12).all() && (x.array() <= load.hi.array() + 1e-12).all())
      inside.push_back(i);
  }
  if (inside.empty()) throw InputError(what + ": the region holds no node of the body");
  VecX f = VecX::Zero(3 * nodes);
  for (int i : inside) f.segment<3>(3 * i) = load.force / static_cast<double>(inside.size());
  if (!s.coarsening) return f;
  using NodeRows = Eigen::Matrix<double, Eigen::Dynamic, 3, Eigen::RowMajor>;
  const SpMat& P = s.coarsening->to_fine;
  VecX coarse(3 * P.cols());
  Eigen::Map<NodeRows>(coarse.data(), P.cols(), 3) = P.transpose() * Eigen::Map<const NodeRows>(f.data(), nodes, 3);
  return coarse;
}

namespace {

// The `simulation` block: time step and duration, output, contact and
// impact switches, the Newton tolerance and rigid flight. Friction is on by
// default where the scene has a friction table.
void read_simulation_settings(const Config& sim, bool has_friction_table, DynamicsScene& s) {
  DynamicsModel& model = s.model;
  s.newmark.time_step = sim.get<double>("time_step");
  if (!(s.newmark.time_step > 0) || !std::isfinite(s.newmark.time_step))
    sim.fail("time_step", "must be positive (got " + std::to_string(s.newmark.time_step) + ")");
  s.duration = sim.require_positive<double>("duration", "simulated time (s)");
  // A step longer than the run takes no step at all, and a tiny one takes
  // more steps than any run can finish: both are typos, refused up front.
  if (s.newmark.time_step > s.duration) {
    std::ostringstream msg;
    msg << "is longer than duration (" << s.duration << " s): no step would be taken";
    sim.fail("time_step", msg.str());
  }
  constexpr double kMaxTimeSteps = 1e8;
  if (s.duration / s.newmark.time_step > kMaxTimeSteps) {
    std::ostringstream msg;
    msg << "gives " << s.duration / s.newmark.time_step << " steps over duration " << s.duration << " s; at most "
        << kMaxTimeSteps << " are allowed (use a larger time_step or a shorter duration)";
    sim.fail("time_step", msg.str());
  }
  s.event_substeps = sim.get_or<int>("event_substeps", 0);
  if (s.event_substeps < 0 || s.event_substeps > 12) sim.fail("event_substeps", "must be 0..12");
  s.output_every = sim.get_or<int>("output_every", 10);
  if (s.output_every < 1) sim.fail("output_every", "must be >= 1");
  model.body_contact = sim.get_or<bool>("body_contact", s.body_names.size() > 1);
  model.contact = sim.get_or<bool>("contact", !model.obstacles.empty() || model.body_contact);
  model.friction = sim.get_or<bool>("friction", has_friction_table);
  if (model.contact && model.obstacles.empty() && !model.body_contact)
    sim.fail("contact", "is on but the scene has no obstacles and body_contact is off");
  if (model.body_contact && !model.contact) sim.fail("body_contact", "needs contact on");
  s.newmark.edge_contact = sim.get_or<bool>("edge_contact", s.newmark.edge_contact);
  model.impact = parse_impact_model(sim.get_or("impact", "bbi"), sim.key_path("impact"));
  s.newmark.newton_tolerance = sim.get_or<double>("newton_tolerance", s.newmark.newton_tolerance);
  if (sim.has("rigid_flight")) {
    const Config r = sim.child("rigid_flight");
    s.rigid.enabled = r.get_or<bool>("enabled", true);
    s.rigid.elastic_fraction = r.get_or<double>("elastic_fraction", s.rigid.elastic_fraction);
    s.rigid.lookahead_steps = r.get_or<int>("lookahead_steps", s.rigid.lookahead_steps);
    if (!(s.rigid.elastic_fraction > 0)) r.fail("elastic_fraction", "must be positive");
    if (s.rigid.lookahead_steps < 1) r.fail("lookahead_steps", "must be >= 1");
    if (s.rigid.enabled && s.body_names.size() > 1)
      r.fail("enabled", "rigid flight projects the whole mesh to one rigid body; the scene has " +
                            std::to_string(s.body_names.size()) + " bodies");
  }
}

// The preload: a static pluck or a press (quasistatic or dynamic).
void read_preload(const Config& c, DynamicsScene& s) {
  const DynamicsModel& model = s.model;
  if (c.has("pluck") && c.has("press")) c.fail("press", "a scene has either a pluck or a press preload, not both");
  if (c.has("pluck")) {
    s.preload = Preload::kStaticPluck;
    s.load = read_region_load(c.child("pluck"));
    s.preload_steps = c.child("pluck").get_or<int>("steps", s.preload_steps);
    if (model.fixed.empty()) c.fail("pluck", "needs a clamp (a free body has no static equilibrium)");
  } else if (c.has("press")) {
    const Config press = c.child("press");
    const bool dynamic = press.has("mode") && press.one_of("mode", {"quasistatic", "dynamic"}) == "dynamic";
    s.preload = dynamic ? Preload::kDynamicPress : Preload::kQuasistaticPress;
    s.load = read_region_load(press);
    s.preload_steps = press.get_or<int>("steps", s.preload_steps);
    s.stop_at_touch = press.get_or<bool>("stop_at_touch", false);
    s.press_self_contact = press.get_or<bool>("self_contact", false);
    if (s.press_self_contact && s.stop_at_touch)
      press.fail("self_contact",
                 "and stop_at_touch exclude each other (with self-contact the press carries the load "
                 "on through the parts that touch)");
    if (model.obstacles.empty()) c.fail("press", "needs obstacles to press against");
    if (dynamic) {
      s.press_ramp_time = press.require_positive<double>("ramp_time", "seconds from zero to the full load");
      if (s.stop_at_touch) press.fail("stop_at_touch", "belongs to the quasistatic press (mode: quasistatic)");
      if (s.press_self_contact)
        press.fail("self_contact", "belongs to the quasistatic press (a dynamic press uses simulation.body_contact)");
      if (s.rigid.enabled)
        c.fail("simulation.rigid_flight.enabled", "a body under a dynamic press is not in free flight");
    } else if (press.has("ramp_time")) {
      press.fail("ramp_time", "belongs to mode: dynamic (the quasistatic press steps its load with press.steps)");
    }
    if (s.body_names.size() > 1)
      c.fail("press", "the quasistatic press handles one body; a scene with several bodies preloads with a pluck");
  }
}

// Bodies must not start inside an obstacle.
void check_start_clear_of_obstacles(const Config& c, const DynamicsScene& s) {
  const int nn = s.model.mesh.num_nodes();
  const double tolerance = 1e-6 * s.grid.voxel_size;
  for (int i = 0; i < nn; ++i)
    for (const Obstacle& o : s.model.obstacles)
      if (signed_distance(o, s.initial_positions.segment<3>(3 * i), nullptr) < -tolerance)
        c.fail("placement", "the body starts inside obstacle '" + o.name + "' (node at " +
                                std::to_string(s.initial_positions(3 * i)) + ", " +
                                std::to_string(s.initial_positions(3 * i + 1)) + ", " +
                                std::to_string(s.initial_positions(3 * i + 2)) + ")");
}

}  // namespace

DynamicsScene read_dynamics_scene(const Config& c, const CoarseningRequest& coarsening) {
  DynamicsScene s;
  // Named parameters: expressions become numbers, the mesh is built at the
  // reference values and morphed to the current ones (scene_parameters.hpp).
  const GeometryMorph morph = apply_scene_parameters(c);
  s.name = c.get_or("name", "dynamics");
  s.materials = read_materials(c);
  VoxelGrid body_grid;
  s.grid = paint_geometry(c.child("geometry"), s.materials, body_grid, s.body_names, s.geometry_files);

  const std::vector<MaterialPtr> palette = scene_palette(s.materials);
  DynamicsModel& model = s.model;
  std::shared_ptr<DynamicsCoarsening> coarse_state;  // filled further once the placement is known
  if (coarsening.level > 0) {
    // Coarse elements span several voxels: of one body, at the reference
    // geometry, on the element the static fits were verified on.
    if (s.body_names.size() > 1)
      throw InputError("--coarsen: the scene has " + std::to_string(s.body_names.size()) +
                       " bodies; coarse blocks would join them (coarsen scenes of one body)");
    if (!morph.is_identity())
      throw InputError(
          "--coarsen: the scene's parameters move its geometry; coarse fits hold for the reference "
          "geometry only (coarsen a scene without geometry parameters)");
    coarse_state = coarsen_dynamics_design(s.grid, s.materials, palette, coarsening, model);
    s.element_body.assign(model.mesh.num_elements(), 0);
    s.coarsening = coarse_state;
  } else {
    const VoxelMesh voxels = build_voxel_mesh(s.grid, palette);
    model.mesh = voxels.mesh;
    for (int e = 0; e < model.mesh.num_elements(); ++e)
      s.element_body.push_back(body_grid.ids[voxels.element_voxel[e]]);
    if (s.body_names.size() > 1) separate_bodies(model.mesh, s.element_body);
    morph.apply(model.mesh);
    for (int e = 0; e < model.mesh.num_elements(); ++e) {
      const SceneMaterial& m = s.materials[model.mesh.element_tag[e] - 1];
      model.density.push_back(m.density);
      model.damping_a.push_back(m.damping_a);
      model.damping_b.push_back(m.damping_b);
      model.element_material_name.push_back(m.name);
    }
  }
  model.gravity = c.has("gravity") ? vec3(c, "gravity") : Vec3(0, 0, -9.81);

  // Placement: rotate about the geometry's centre, then translate. The rest
  // configuration stays axis-aligned; only the initial state moves.
  const Config place = c.has("placement") ? c.child("placement") : Config();
  const Mat3 R = c.has("placement") && place.has("rotation_deg") ? rotation_from_degrees(vec3(place, "rotation_deg"))
                                                                 : Mat3::Identity();
  const Vec3 t = c.has("placement") && place.has("translation") ? vec3(place, "translation") : Vec3::Zero();
  // About the fine design's centre also when coarsened: padded coarse cells
  // may reach beyond it.
  const HexMesh& design = s.coarsening ? s.coarsening->fine.mesh : model.mesh;
  const Vec3 center = 0.5 * (design.bbox_min() + design.bbox_max());
  auto placed = [&](const NodeArray& nodes) {
    VecX x(3 * nodes.rows());
    for (int i = 0; i < nodes.rows(); ++i) x.segment<3>(3 * i) = center + t + R * (nodes.row(i).transpose() - center);
    return x;
  };
  const int nn = model.mesh.num_nodes();
  s.initial_positions = placed(model.mesh.nodes);
  if (coarse_state) coarse_state->fine_initial_positions = placed(design.nodes);
  s.initial_velocities = VecX::Zero(3 * nn);
  if (c.has("initial_velocity")) {
    const Vec3 v = vec3(c, "initial_velocity");
    for (int i = 0; i < nn; ++i) s.initial_velocities.segment<3>(3 * i) = v;
  }

  if (c.has("clamp")) {
    Vec3 lo, hi;
    read_box(c.child("clamp"), lo, hi, true);
    model.fixed.assign(3 * nn, 0);
    int count = 0;
    for (int i = 0; i < nn; ++i) {
      const Vec3 x = s.initial_positions.segment<3>(3 * i);
      if ((x.array() >= lo.array() - 1e-12).all() && (x.array() <= hi.array() + 1e-12).all()) {
        model.fixed[3 * i] = model.fixed[3 * i + 1] = model.fixed[3 * i + 2] = 1;
        ++count;
      }
    }
    if (count == 0)
      c.child("clamp").fail("min", s.coarsening
                                       ? "the clamp box holds no node of the coarse mesh (its nodes lie every " +
                                             std::to_string(s.coarsening->coarse.grid.fine_per_cell()) + " voxels)"
                                       : "the clamp box holds no node of the body");
  }

  model.obstacles = read_obstacles(c);
  model.friction_table = read_friction(c, s.materials);

  read_simulation_settings(c.child("simulation"), c.has("friction"), s);
  read_preload(c, s);
  if (s.preload_steps < 1) c.fail(s.preload == Preload::kStaticPluck ? "pluck.steps" : "press.steps", "must be >= 1");
  validate_dynamics_model(model);

  if (model.contact) check_start_clear_of_obstacles(c, s);
  return s;
}

}  // namespace msfab
