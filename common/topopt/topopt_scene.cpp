#include "topopt/topopt_scene.hpp"

#include <cmath>

#include "core/errors.hpp"
#include "io/linear_solver_config.hpp"
#include "io/material_config.hpp"

namespace msfab {

namespace {

struct Box {
  Vec3 lo = Vec3::Zero(), hi = Vec3::Zero();
  bool contains(const Vec3& x, double tol) const {
    return (x.array() >= lo.array() - tol).all() && (x.array() <= hi.array() + tol).all();
  }
};

Box read_box(const Config& item, const std::string& key, int dim) {
  const Config b = item.child(key);
  const auto lo = b.get<std::vector<double>>("min");
  const auto hi = b.get<std::vector<double>>("max");
  if (int(lo.size()) != dim) b.fail("min", "needs " + std::to_string(dim) + " coordinates");
  if (int(hi.size()) != dim) b.fail("max", "needs " + std::to_string(dim) + " coordinates");
  Box box;
  for (int a = 0; a < dim; ++a) {
    if (!(lo[a] <= hi[a])) b.fail("max", "every max coordinate must be >= min");
    box.lo[a] = lo[a], box.hi[a] = hi[a];
  }
  return box;
}

Vec3 read_vector(const Config& item, const std::string& key, int dim) {
  const auto v = item.get<std::vector<double>>(key);
  if (int(v.size()) != dim) item.fail(key, "needs " + std::to_string(dim) + " components");
  Vec3 out = Vec3::Zero();
  for (int a = 0; a < dim; ++a) {
    if (!std::isfinite(v[a])) item.fail(key, "must be finite");
    out[a] = v[a];
  }
  return out;
}

// Nodes selected by an item's `box` or `node` (grid indices).
std::vector<std::int64_t> select_nodes(const Config& item, const CellGrid& g) {
  const int dim = g.dimension();
  std::vector<std::int64_t> nodes;
  if (item.has("node")) {
    const auto idx = item.get<std::vector<int>>("node");
    if (int(idx.size()) != dim) item.fail("node", "needs " + std::to_string(dim) + " grid indices");
    const int k = dim == 3 ? idx[2] : 0;
    if (idx[0] < 0 || idx[0] > g.nx() || idx[1] < 0 || idx[1] > g.ny() || k < 0 || (dim == 3 && k > g.nz()))
      item.fail("node", "no such node: the grid has nodes 0.." + std::to_string(g.nx()) + " x 0.." +
                            std::to_string(g.ny()) + (dim == 3 ? " x 0.." + std::to_string(g.nz()) : ""));
    nodes.push_back(g.node_index(idx[0], idx[1], k));
    return nodes;
  }
  if (!item.has("box")) item.fail("", "needs a box or a node");
  const Box box = read_box(item, "box", dim);
  for (std::int64_t n = 0; n < g.nodes(); ++n)
    if (box.contains(g.node_position(n), 1e-9 * g.h())) nodes.push_back(n);
  if (nodes.empty()) item.fail("box", "selects no node of the grid");
  return nodes;
}

// Design domain: design everywhere, then the items in order.
void read_design_domain(const Config& config, const CellGrid& g, std::vector<CellRole>& roles) {
  const int dim = g.dimension();
  roles.assign(g.cells(), CellRole::design);
  if (config.has("domain")) {
    for (const Config& item : config.children("domain")) {
      const std::string role = item.one_of("role", {"design", "empty", "solid"});
      const CellRole r = role == "design" ? CellRole::design : role == "empty" ? CellRole::empty : CellRole::solid;
      int hits = 0;
      if (item.has("box")) {
        const Box box = read_box(item, "box", dim);
        for (std::int64_t c = 0; c < g.cells(); ++c)
          if (box.contains(g.cell_center(c), 1e-9 * g.h())) roles[c] = r, ++hits;
      } else if (item.has("cylinder")) {
        // A cylinder along z (3D) or a disk (2D).
        const Config cyl = item.child("cylinder");
        const auto centre = cyl.get<std::vector<double>>("center");
        if (centre.size() != 2) cyl.fail("center", "needs 2 coordinates (x, y)");
        const double radius = cyl.require_positive("radius");
        for (std::int64_t c = 0; c < g.cells(); ++c) {
          const Vec3 x = g.cell_center(c);
          if (std::hypot(x[0] - centre[0], x[1] - centre[1]) <= radius) roles[c] = r, ++hits;
        }
      } else {
        item.fail("", "a domain item needs a box or a cylinder");
      }
      if (hits == 0) item.fail("", "selects no cell of the grid");
    }
  }
}

// One load case: forces on carried nodes, prescribed displacements on
// supported unknowns, and for a target objective its target displacements.
LoadCase read_load_case(const Config& lc, const CellGrid& g, const std::vector<char>& fixed,
                        const std::vector<char>& carried, const VecX& support_values, bool any_value, size_t index) {
  const int dim = g.dimension();
  const std::int64_t n = g.unknowns();
  LoadCase l;
  l.name = lc.get_or<std::string>("name", "load" + std::to_string(index));
  l.weight = lc.get_or<double>("weight", 1.0);
  if (!(l.weight > 0)) lc.fail("weight", "must be > 0");
  const std::string objective = lc.one_of("objective", {"compliance", "target"});
  l.objective = objective == "compliance" ? ElasticObjective::compliance : ElasticObjective::target;
  l.force = VecX::Zero(n);
  if (lc.has("forces")) {
    for (const Config& f : lc.children("forces")) {
      const std::vector<std::int64_t> nodes = select_nodes(f, g);
      const Vec3 force = read_vector(f, "force", dim);
      // `total`: the force is shared by the selected nodes; `per_node`: each gets it.
      const std::string spread = f.get_or("distribute", "per_node");
      if (spread != "per_node" && spread != "total") f.fail("distribute", "is per_node or total");
      const double share = spread == "total" ? 1.0 / double(nodes.size()) : 1.0;
      for (std::int64_t node : nodes) {
        if (!carried[node]) f.fail("", "loads a node that only empty cells touch (a load on void)");
        for (int a = 0; a < dim; ++a) l.force[node * dim + a] += share * force[a];
      }
    }
  }
  l.prescribed = support_values;
  bool case_value = any_value;
  if (lc.has("prescribed")) {
    for (const Config& pr : lc.children("prescribed")) {
      const Vec3 value = read_vector(pr, "displacement", dim);
      for (std::int64_t node : select_nodes(pr, g))
        for (int a = 0; a < dim; ++a) {
          if (!fixed[node * dim + a]) pr.fail("displacement", "prescribes a value on an unknown no support fixes");
          l.prescribed[node * dim + a] = value[a];
          case_value = case_value || value[a] != 0;
        }
    }
  }
  if (!case_value) l.prescribed.resize(0);
  if (l.objective == ElasticObjective::target) {
    l.target = VecX::Zero(n);
    l.target_weight = VecX::Zero(n);
    if (!lc.has("targets")) lc.fail("targets", "is missing: a target objective needs target displacements");
    for (const Config& t : lc.children("targets")) {
      const Vec3 value = read_vector(t, "displacement", dim);
      const double w = t.get_or<double>("weight", 1.0);
      if (!(w > 0)) t.fail("weight", "must be > 0");
      for (std::int64_t node : select_nodes(t, g))
        for (int a = 0; a < dim; ++a) l.target[node * dim + a] = value[a], l.target_weight[node * dim + a] = w;
    }
  } else if (lc.has("targets")) {
    lc.fail("targets", "only a target objective takes targets");
  }
  if (l.force.squaredNorm() == 0 && l.prescribed.size() == 0)
    lc.fail("", "has neither a force nor a nonzero prescribed displacement");
  return l;
}

// Mass: a volume fraction or a weighted target, and local density targets.
void read_mass_terms(const Config& config, const CellGrid& g, TopoptScene& scene) {
  const int dim = g.dimension();
  if (config.has("mass")) {
    const Config m = config.child("mass");
    scene.volume_fraction = m.get_or<double>("volume_fraction", 0.0);
    if (!(scene.volume_fraction >= 0 && scene.volume_fraction <= 1)) m.fail("volume_fraction", "must be in [0, 1]");
    scene.setup.mass.total_weight = m.get_or<double>("weight", 0.0);
    if (!(scene.setup.mass.total_weight >= 0)) m.fail("weight", "must be >= 0");
    if (scene.setup.mass.total_weight > 0) scene.setup.mass.total_target = m.require_positive("target", "target mass");
  }
  if (config.has("local_density")) {
    scene.setup.mass.local_target = VecX::Zero(g.cells());
    for (const Config& item : config.children("local_density")) {
      const Box box = read_box(item, "box", dim);
      const double rho = item.require_range<double>("rho", 0.0, 1.0);
      const double w = item.require_positive("weight");
      scene.setup.mass.local_weight = std::max(scene.setup.mass.local_weight, w);
      for (std::int64_t c = 0; c < g.cells(); ++c)
        if (box.contains(g.cell_center(c), 1e-9 * g.h())) scene.setup.mass.local_target[c] = rho;
    }
  }
}

}  // namespace

TopoptScene read_topopt_scene(const Config& config, double gamut_E_stiff, double gamut_decades) {
  TopoptScene scene;
  // Grid.
  const Config grid = config.child("grid");
  const auto size = grid.get<std::vector<int>>("size");
  if (size.size() != 2 && size.size() != 3) grid.fail("size", "needs 2 (2D) or 3 (3D) cell counts");
  for (int n : size)
    if (n < 1) grid.fail("size", "every cell count must be >= 1");
  const int dim = int(size.size());
  const double h = grid.get_or<double>("cell_size", 1.0);
  if (!(h > 0)) grid.fail("cell_size", "must be > 0");
  const CellGrid g(dim, size[0], size[1], dim == 3 ? size[2] : 1, h);
  TopologySetup& s = scene.setup;
  s.grid = g;

  // Material space.
  scene.space = config.one_of("space", cell_material_spaces());
  if ((scene.space.back() == 'd') && (scene.space[scene.space.size() - 2] - '0') != dim)
    config.fail("space", "is " + std::string(1, scene.space[scene.space.size() - 2]) + "D but grid.size is " +
                             std::to_string(dim) + "D");
  const Config mat = config.has("material") ? config.child("material") : Config();
  const ElasticConstants solid =
      read_elastic_constants(mat, dim == 3 ? PoissonRange::Solid : PoissonRange::InPlane, ElasticConstants{1.0, 0.3});
  scene.E0 = solid.E;
  scene.nu = solid.nu;
  scene.penalty = mat.get_or<double>("penalty", 3.0);
  scene.E_min_ratio = mat.get_or<double>("E_min_ratio", 1e-9);
  scene.decades = mat.get_or<double>("decades", 4.0);
  if (!(scene.penalty >= 1)) mat.fail("penalty", "must be >= 1");
  if (!(scene.E_min_ratio > 0 && scene.E_min_ratio < 1)) mat.fail("E_min_ratio", "must be in (0, 1)");
  if (!(scene.decades > 0)) mat.fail("decades", "must be > 0");
  // 2D cells carry in-plane constants; a plane-strain solid (what a 2D
  // gamut's homogenized cells are) has E / (1 - nu^2), nu / (1 - nu).
  const std::string plane = mat.has("plane") ? mat.one_of("plane", {"stress", "strain"}) : "stress";
  if (plane == "strain") {
    if (dim != 2) mat.fail("plane", "applies to 2D grids only");
    if (!(scene.nu < 0.5)) mat.fail("nu", "must be below 0.5 for plane strain");
    scene.E0 /= 1 - scene.nu * scene.nu;
    scene.nu /= 1 - scene.nu;
  }
  if ((!required_gamut_space(scene.space).empty() || needs_family_grid(scene.space)) && gamut_E_stiff > 0) {
    scene.E0 = gamut_E_stiff;
    scene.decades = gamut_decades;
  }
  scene.elements_per_cell = config.get_or<int>("elements_per_cell", 1);
  if (scene.elements_per_cell < 1 || scene.elements_per_cell > 8) config.fail("elements_per_cell", "must be 1..8");
  if (scene.elements_per_cell > 1 && dim != 3) config.fail("elements_per_cell", "above 1 needs a 3D grid");
  const double void_ratio = mat.get_or<double>("void_stiffness", 1e-9);
  if (!(void_ratio > 0 && void_ratio < 1e-2)) mat.fail("void_stiffness", "must be in (0, 0.01)");
  s.solid_C = isotropic_voigt(dim, scene.E0, scene.nu);
  s.empty_C = void_ratio * s.solid_C;

  read_design_domain(config, g, s.roles);

  // Supports.
  const std::int64_t n = g.unknowns();
  s.fixed.assign(n, 0);
  VecX support_values = VecX::Zero(n);
  bool any_value = false;
  if (!config.has("supports")) config.fail("supports", "is missing: a design with no support floats");
  for (const Config& item : config.children("supports")) {
    const std::vector<std::int64_t> nodes = select_nodes(item, g);
    std::vector<int> comps;
    const auto fix = item.get_or<std::vector<std::string>>(
        "fix", dim == 3 ? std::vector<std::string>{"x", "y", "z"} : std::vector<std::string>{"x", "y"});
    for (const std::string& c : fix) {
      const int a = c == "x" ? 0 : c == "y" ? 1 : c == "z" ? 2 : -1;
      if (a < 0 || a >= dim) item.fail("fix", "components are x, y" + std::string(dim == 3 ? ", z" : ""));
      comps.push_back(a);
    }
    const Vec3 value = item.has("displacement") ? read_vector(item, "displacement", dim) : Vec3::Zero();
    for (std::int64_t node : nodes)
      for (int a : comps) {
        s.fixed[node * dim + a] = 1;
        support_values[node * dim + a] = value[a];
        any_value = any_value || value[a] != 0;
      }
  }
  if (std::none_of(s.fixed.begin(), s.fixed.end(), [](char f) { return f != 0; }))
    config.fail("supports", "fixes no unknown: a design with no support floats");

  // Which nodes touch a non-empty cell (a load there has something to act on).
  std::vector<char> carried(g.nodes(), 0);
  for (std::int64_t c = 0; c < g.cells(); ++c)
    if (s.roles[c] != CellRole::empty)
      for (int a = 0; a < g.corners(); ++a) carried[g.cell_nodes(c)[a]] = 1;

  // Load cases.
  for (const Config& lc : config.children("loads"))
    s.loads.push_back(read_load_case(lc, g, s.fixed, carried, support_values, any_value, s.loads.size()));
  if (s.loads.empty()) config.fail("loads", "needs at least one load case");

  read_mass_terms(config, g, scene);
  s.filter_radius = config.get_or<double>("filter.radius", 0.0);
  if (!(s.filter_radius >= 0)) config.fail("filter.radius", "must be >= 0");
  LinearSolverKeys keys;
  keys.legacy_kind = "solver";
  const LinearSolverChoice linear = read_linear_solver_choice(config, {"auto", "cholmod", "pcg-mg", "matrix-free"},
                                                              linear_solver_defaults("auto", s.solver_options), keys);
  s.solver = linear.kind;
  apply_linear_solver_limits(linear, s.solver_options);
  return scene;
}

}  // namespace msfab
