#include "ddfem/mixed_level_mesh.hpp"

#include <algorithm>
#include <cmath>
#include <functional>
#include <map>

#include "core/errors.hpp"
#include "material/neo_hookean.hpp"

namespace msfab {
namespace {

using Triplet = Eigen::Triplet<double, int>;
using Rows3 = Eigen::Matrix<double, Eigen::Dynamic, 3, Eigen::RowMajor>;

constexpr int kCellSize = 4;  // fine voxels per level-2 cell edge

// Trilinear weight of corner c (hex8 bit order) at local coordinates t in [0, 1]^3.
double corner_weight(int c, const double t[3]) {
  double w = 1;
  for (int ax = 0; ax < 3; ++ax) w *= (c >> (2 - ax) & 1) ? t[ax] : 1 - t[ax];
  return w;
}

struct LatticeIndex {
  std::array<int, 3> n;
  int operator()(int a, int b, int c) const { return a + n[0] * (b + n[1] * c); }
  std::array<int, 3> coords(int p) const { return {p % n[0], (p / n[0]) % n[1], p / (n[0] * n[1])}; }
};

// Per element: the lattice point of its corner 0 and its edge in fine voxels.
struct ElementBox {
  std::array<int, 3> corner;
  int size;
};

void check_mixed_level_inputs(const VoxelGrid& fine, const CoarseGrid& level1, const CoarseGrid& level2,
                              const std::vector<int>& cell_level, const CoarseMaterialLookup& level1_materials,
                              const CoarseMaterialLookup& level2_materials) {
  if (level1.level != 1 || level2.level != 2 || level1.fine_nx != fine.nx || level1.fine_ny != fine.ny ||
      level1.fine_nz != fine.nz || level2.fine_nx != fine.nx || level2.fine_ny != fine.ny || level2.fine_nz != fine.nz)
    throw InputError("mixed-level mesh: the level-1 and level-2 grids were not built from this voxel grid");
  if (cell_level.size() != size_t(level2.num_cells()))
    throw InputError("mixed-level mesh: " + std::to_string(cell_level.size()) + " cell levels for " +
                     std::to_string(level2.num_cells()) + " level-2 cells");
  for (int l : cell_level)
    if (l < 0 || l > 2) throw InputError("mixed-level mesh: a cell level must be 0, 1 or 2, got " + std::to_string(l));
  if (!level1_materials || !level2_materials) throw InputError("mixed-level mesh: a material lookup is missing");
}

// Geometries per (level, rule), told apart by an element's number of
// materials as in build_coarse_mesh: the Gauss rule (or one material for
// all points), the Gauss rule and the centre, or 8 points per fine voxel
// (the Galerkin element). Coarse elements carry the bubble modes when
// asked; fine voxels are always trilinear (they are the reference model).
enum Rule { kGauss, kGaussCentre, kComposite };
struct GeometrySlots {
  double h;
  bool enhanced_modes;
  HexMesh& mesh;
  std::map<std::pair<int, Rule>, int> slot = {};
  std::map<int, int> own_slot = {};  // materials index -> geometry, for materials with their own rule
  // The mesh's geometry index for (level, rule), added on first use.
  int operator()(int level, Rule rule) {
    auto it = slot.find({level, rule});
    if (it != slot.end()) return it->second;
    const int size = 1 << level;
    const hex8::QuadratureRule quadrature =
        rule == kComposite ? hex8::composite_gauss_rule(size, 2) : hex8::gauss_rule(level == 2 ? 4 : 2);
    hex8::ElementGeometry geo = build(level, quadrature);
    if (rule == kGaussCentre) geo = hex8::with_centre_point(geo, cube(level));
    mesh.geometries.push_back(std::move(geo));
    const int index = static_cast<int>(mesh.geometries.size()) - 1;
    slot.emplace(std::make_pair(level, rule), index);
    return index;
  }
  // The geometry of materials[material_index]'s own rule on a level-`level` element.
  int own(int level, int material_index) {
    auto it = own_slot.find(material_index);
    if (it != own_slot.end()) return it->second;
    mesh.geometries.push_back(build(level, *mesh.materials[material_index].rule));
    const int index = static_cast<int>(mesh.geometries.size()) - 1;
    own_slot.emplace(material_index, index);
    return index;
  }
  hex8::NodeMatrix cube(int level) const {
    hex8::NodeMatrix x;
    for (int c = 0; c < 8; ++c) x.row(c) = (1 << level) * h * Vec3(c >> 2 & 1, c >> 1 & 1, c & 1).transpose();
    return x;
  }
  hex8::ElementGeometry build(int level, const hex8::QuadratureRule& quadrature) const {
    return enhanced_modes && level > 0 ? hex8::enhanced_element_geometry(cube(level), quadrature)
                                       : hex8::element_geometry(cube(level), quadrature);
  }
};

// Hanging nodes: mesh nodes on the boundary of a larger element other than
// its corners, each interpolated in the largest such element (the first in
// element order among equals; elements sharing the face or edge agree).
// Fills m's unknown nodes and hanging-node count and returns the map from
// the unknowns to every mesh node.
std::shared_ptr<NodeConstraints> hanging_node_constraints(const std::vector<ElementBox>& boxes,
                                                          const std::vector<int>& lattice_node,
                                                          const LatticeIndex& lattice, MixedLevelMesh& m) {
  const HexMesh& mesh = m.mesh;
  const int num_nodes = mesh.num_nodes();
  std::vector<int> master(num_nodes, -1);
  for (int e = 0; e < mesh.num_elements(); ++e) {
    const ElementBox& b = boxes[e];
    if (b.size == 1) continue;
    for (int dk = 0; dk <= b.size; ++dk)
      for (int dj = 0; dj <= b.size; ++dj)
        for (int di = 0; di <= b.size; ++di) {
          const bool on_boundary = di == 0 || dj == 0 || dk == 0 || di == b.size || dj == b.size || dk == b.size;
          const bool corner = (di % b.size == 0) && (dj % b.size == 0) && (dk % b.size == 0);
          if (!on_boundary || corner) continue;
          const int node = lattice_node[lattice(b.corner[0] + di, b.corner[1] + dj, b.corner[2] + dk)];
          if (node < 0) continue;
          if (master[node] < 0 || boxes[master[node]].size < b.size) master[node] = e;
        }
  }
  // Unknown nodes in mesh-node order; hanging nodes expanded recursively
  // (corners of a larger element can only hang on a still larger one).
  std::vector<int> unknown_of(num_nodes, -1);
  for (int n = 0; n < num_nodes; ++n)
    if (master[n] < 0) {
      unknown_of[n] = static_cast<int>(m.unknown_node.size());
      m.unknown_node.push_back(n);
    }
  m.hanging_nodes = num_nodes - m.num_unknown_nodes();
  std::vector<std::vector<std::pair<int, double>>> expansion(num_nodes);
  std::vector<char> expanded(num_nodes, 0);
  std::function<const std::vector<std::pair<int, double>>&(int)> expand = [&](int n) -> const auto& {
    if (expanded[n]) return expansion[n];
    std::map<int, double> acc;
    if (master[n] < 0) {
      acc[unknown_of[n]] = 1.0;
    } else {
      const ElementBox& b = boxes[master[n]];
      const auto a = lattice.coords(m.node_lattice[n]);
      const double t[3] = {double(a[0] - b.corner[0]) / b.size, double(a[1] - b.corner[1]) / b.size,
                           double(a[2] - b.corner[2]) / b.size};
      for (int c = 0; c < 8; ++c) {
        const double w = corner_weight(c, t);
        if (w == 0) continue;
        for (const auto& [u, wu] : expand(mesh.elements[master[n]][c])) acc[u] += w * wu;
      }
    }
    expansion[n].assign(acc.begin(), acc.end());
    expanded[n] = 1;
    return expansion[n];
  };
  std::vector<Triplet> trip;
  trip.reserve(size_t(num_nodes) + 8 * size_t(m.hanging_nodes));
  for (int n = 0; n < num_nodes; ++n)
    for (const auto& [u, w] : expand(n)) trip.emplace_back(n, u, w);
  auto constraints = std::make_shared<NodeConstraints>();
  constraints->node_map.resize(num_nodes, m.num_unknown_nodes());
  constraints->node_map.setFromTriplets(trip.begin(), trip.end());
  constraints->node_map.makeCompressed();
  constraints->unknown_rest.resize(m.num_unknown_nodes(), 3);
  for (int u = 0; u < m.num_unknown_nodes(); ++u) constraints->unknown_rest.row(u) = mesh.nodes.row(m.unknown_node[u]);
  return constraints;
}

}  // namespace

MixedLevelMesh build_mixed_level_mesh(const VoxelGrid& fine, const std::vector<MaterialPtr>& palette,
                                      const CoarseGrid& level1, const CoarseGrid& level2,
                                      const std::vector<int>& cell_level, const CoarseMaterialLookup& level1_materials,
                                      const CoarseMaterialLookup& level2_materials, bool enhanced_modes) {
  check_mixed_level_inputs(fine, level1, level2, cell_level, level1_materials, level2_materials);
  MixedLevelMesh m;
  HexMesh& mesh = m.mesh;
  m.lattice = {kCellSize * level2.nx + 1, kCellSize * level2.ny + 1, kCellSize * level2.nz + 1};
  const LatticeIndex lattice{m.lattice};
  std::vector<int> lattice_node(size_t(m.lattice[0]) * m.lattice[1] * m.lattice[2], -1);
  std::vector<ElementBox> boxes;
  m.voxel_element.assign(fine.size(), -1);

  GeometrySlots geometry{fine.voxel_size, enhanced_modes, mesh};
  const double h = fine.voxel_size;
  std::map<std::pair<int, int>, int> material_slot;  // (level, id or combination) -> materials index
  auto material = [&](int level, int key, const auto& make) {
    auto it = material_slot.find({level, key});
    if (it != material_slot.end()) return it->second;
    mesh.materials.push_back(make());
    const int slot = static_cast<int>(mesh.materials.size()) - 1;
    material_slot.emplace(std::make_pair(level, key), slot);
    return slot;
  };
  auto add_element = [&](int level, const std::array<int, 3>& corner, int material_index, int tag) {
    const int size = 1 << level;
    const QuadratureMaterials& mat = mesh.materials[material_index];
    const int points = level == 2 ? 64 : 8;
    const int composite = 8 * size * size * size;
    const int n = static_cast<int>(mat.at_point.size());
    Rule rule = kGauss;
    if (mat.rule) {
      if (mat.rule->size() != n)
        throw InputError("mixed-level mesh: a level-" + std::to_string(level) + " material lookup returned " +
                         std::to_string(n) + " materials for the " + std::to_string(mat.rule->size()) +
                         " points of its own rule");
    } else if (n == points + 1) {
      rule = kGaussCentre;
    } else if (level > 0 && n == composite) {
      rule = kComposite;
    } else if (n != 1 && n != points) {
      throw InputError("mixed-level mesh: a level-" + std::to_string(level) + " material lookup returned " +
                       std::to_string(n) + " materials (expected 1, " + std::to_string(points) + ", " +
                       std::to_string(points + 1) + " or " + std::to_string(composite) + ")");
    }
    std::array<int, 8> el;
    for (int c = 0; c < 8; ++c) {
      const int p =
          lattice(corner[0] + size * (c >> 2 & 1), corner[1] + size * (c >> 1 & 1), corner[2] + size * (c & 1));
      if (lattice_node[p] < 0) {
        lattice_node[p] = static_cast<int>(m.node_lattice.size());
        m.node_lattice.push_back(p);
      }
      el[c] = lattice_node[p];
    }
    const int e = mesh.num_elements();
    mesh.elements.push_back(el);
    mesh.element_material.push_back(material_index);
    mesh.element_geometry.push_back(mat.rule ? geometry.own(level, material_index) : geometry(level, rule));
    mesh.element_tag.push_back(tag);
    m.element_level.push_back(level);
    ++m.elements_per_level[level];
    boxes.push_back({corner, size});
    for (int k = corner[2]; k < std::min(corner[2] + size, fine.nz); ++k)
      for (int j = corner[1]; j < std::min(corner[1] + size, fine.ny); ++j)
        for (int i = corner[0]; i < std::min(corner[0] + size, fine.nx); ++i) m.voxel_element[fine.index(i, j, k)] = e;
    return e;
  };

  for (int K = 0; K < level2.nz; ++K)
    for (int J = 0; J < level2.ny; ++J)
      for (int I = 0; I < level2.nx; ++I) {
        const size_t cell = level2.index(I, J, K);
        const int comb2 = level2.cell_combination[cell];
        if (comb2 < 0) continue;
        const int level = cell_level[cell];
        if (level == 2) {
          const int slot = material(2, comb2, [&] { return level2_materials(level2.combinations[comb2]); });
          add_element(2, {4 * I, 4 * J, 4 * K}, slot, -2);
          continue;
        }
        for (int q = 0; q < 8; ++q) {
          const int i1 = 2 * I + (q >> 2 & 1), j1 = 2 * J + (q >> 1 & 1), k1 = 2 * K + (q & 1);
          if (i1 >= level1.nx || j1 >= level1.ny || k1 >= level1.nz) continue;
          const int comb1 = level1.cell_combination[level1.index(i1, j1, k1)];
          if (comb1 < 0) continue;
          if (level == 1) {
            const int slot = material(1, comb1, [&] { return level1_materials(level1.combinations[comb1]); });
            add_element(1, {2 * i1, 2 * j1, 2 * k1}, slot, -1);
            continue;
          }
          for (int r = 0; r < 8; ++r) {
            const int i = 2 * i1 + (r >> 2 & 1), j = 2 * j1 + (r >> 1 & 1), k = 2 * k1 + (r & 1);
            if (i >= fine.nx || j >= fine.ny || k >= fine.nz) continue;
            const int id = fine.at(i, j, k);
            if (id == 0) continue;
            if (id < 0 || id >= static_cast<int>(palette.size()) || !palette[id])
              throw InputError("mixed-level mesh: voxel (" + std::to_string(i) + ", " + std::to_string(j) + ", " +
                               std::to_string(k) + ") has material id " + std::to_string(id) + " outside the palette");
            const int slot = material(0, id, [&] { return QuadratureMaterials{{palette[id]}}; });
            add_element(0, {i, j, k}, slot, id);
          }
        }
      }
  if (mesh.num_elements() == 0) throw InputError("mixed-level mesh: the voxel grid is empty");

  const int num_nodes = static_cast<int>(m.node_lattice.size());
  mesh.nodes.resize(num_nodes, 3);
  for (int n = 0; n < num_nodes; ++n) {
    const auto a = lattice.coords(m.node_lattice[n]);
    mesh.nodes.row(n) = (fine.origin + h * Vec3(a[0], a[1], a[2])).transpose();
  }
  mesh.colors = greedy_element_coloring(mesh);

  m.constraints = hanging_node_constraints(boxes, lattice_node, lattice, m);
  return m;
}

SpMat mixed_to_fine_interpolation(const VoxelGrid& fine_grid, const VoxelMesh& fine_mesh, const MixedLevelMesh& mixed) {
  if (mixed.voxel_element.size() != fine_grid.size())
    throw InputError("mixed-to-fine interpolation: the mixed mesh was not built from this voxel grid");
  const LatticeIndex lattice{mixed.lattice};
  const HexMesh& fm = fine_mesh.mesh;
  const HexMesh& mm = mixed.mesh;
  const int lx = fine_grid.nx + 1, ly = fine_grid.ny + 1;
  std::vector<char> done(fm.num_nodes(), 0);
  std::vector<Triplet> trip;
  trip.reserve(size_t(fm.num_nodes()) * 8);
  for (int e = 0; e < fm.num_elements(); ++e) {
    const int v = fine_mesh.element_voxel[e];
    const int me = mixed.voxel_element[v];
    if (me < 0) throw InputError("mixed-to-fine interpolation: a solid fine voxel lies outside every mixed element");
    const int i = v % fine_grid.nx, j = (v / fine_grid.nx) % fine_grid.ny, k = v / (fine_grid.nx * fine_grid.ny);
    const auto corner = lattice.coords(mixed.node_lattice[mm.elements[me][0]]);
    const int size = 1 << mixed.element_level[me];
    for (int c = 0; c < 8; ++c) {
      const int a = i + (c >> 2 & 1), b = j + (c >> 1 & 1), d = k + (c & 1);
      const int node = fine_mesh.lattice_node[a + lx * (b + ly * d)];
      if (done[node]) continue;
      done[node] = 1;
      const double t[3] = {double(a - corner[0]) / size, double(b - corner[1]) / size, double(d - corner[2]) / size};
      for (int cc = 0; cc < 8; ++cc) {
        const double w = corner_weight(cc, t);
        if (w != 0) trip.emplace_back(node, mm.elements[me][cc], w);
      }
    }
  }
  SpMat to_mesh(fm.num_nodes(), mm.num_nodes());
  to_mesh.setFromTriplets(trip.begin(), trip.end());
  SpMat out = to_mesh * mixed.constraints->node_map;
  out.makeCompressed();
  return out;
}

VecX uniform_displacement_at(const CoarseGrid& grid, const VoxelMesh& coarse_mesh, const VecX& x_coarse,
                             const NodeArray& points) {
  const HexMesh& cm = coarse_mesh.mesh;
  if (x_coarse.size() != cm.num_dofs() || coarse_mesh.voxel_element.size() != size_t(grid.num_cells()))
    throw InputError("uniform start: the solution does not belong to the coarse mesh of this grid");
  const int f = grid.fine_per_cell();
  const double h = grid.fine_voxel_size;
  const std::array<int, 3> cells{grid.nx, grid.ny, grid.nz};
  auto element_at = [&](const std::array<int, 3>& c) {
    for (int ax = 0; ax < 3; ++ax)
      if (c[ax] < 0 || c[ax] >= cells[ax]) return -1;
    return coarse_mesh.voxel_element[grid.index(c[0], c[1], c[2])];
  };
  VecX out = VecX::Zero(3 * points.rows());
  for (int p = 0; p < points.rows(); ++p) {
    std::array<int, 3> a;  // fine lattice point
    for (int ax = 0; ax < 3; ++ax) a[ax] = int(std::lround((points(p, ax) - grid.origin[ax]) / h));
    // A cell touching the point (up to 8 share a node); else the nearest
    // cell with an element within a few cells, extrapolated.
    std::array<int, 3> cell{};
    int e = -1;
    for (int q = 0; q < 8 && e < 0; ++q) {
      std::array<int, 3> c;
      for (int ax = 0; ax < 3; ++ax) {
        const int shifted = a[ax] - ((q >> (2 - ax)) & 1);
        c[ax] = shifted < 0 ? -1 : shifted / f;
      }
      if ((e = element_at(c)) >= 0) cell = c;
    }
    for (int radius = 1; radius <= 3 && e < 0; ++radius)
      for (int dk = -radius; dk <= radius && e < 0; ++dk)
        for (int dj = -radius; dj <= radius && e < 0; ++dj)
          for (int di = -radius; di <= radius && e < 0; ++di) {
            const std::array<int, 3> c{a[0] / f + di, a[1] / f + dj, a[2] / f + dk};
            if ((e = element_at(c)) >= 0) cell = c;
          }
    if (e < 0) continue;  // no coarse element near: start at rest
    const double t[3] = {double(a[0] - f * cell[0]) / f, double(a[1] - f * cell[1]) / f,
                         double(a[2] - f * cell[2]) / f};
    for (int c = 0; c < 8; ++c) {
      const int node = cm.elements[e][c];
      const Vec3 u = x_coarse.segment<3>(3 * node) - cm.nodes.row(node).transpose();
      out.segment<3>(3 * p) += corner_weight(c, t) * u;
    }
  }
  return out;
}

namespace {

// The scene's Dirichlet conditions evaluated on a grid of cells (a coarse
// grid as voxels), with the node numbering of its voxel mesh.
struct GridDirichlet {
  DirichletConditions dirichlet;
  std::vector<int> lattice_node;
  int lx = 0, ly = 0;
};

GridDirichlet grid_dirichlet(const Scene& scene, const VoxelGrid& grid) {
  int max_id = 0;
  for (int id : grid.ids) max_id = std::max(max_id, id);
  const MaterialPtr any = std::make_shared<NeoHookean>(1.0, 0.3);
  Scene cs;
  cs.name = scene.name;
  cs.grid = grid;
  cs.boundary = scene.boundary;
  cs.material_by_id.assign(max_id + 1, any);
  const VoxelMesh vm = build_voxel_mesh(grid, cs.material_by_id);
  GridDirichlet g;
  g.dirichlet = build_static_conditions(cs, vm).dirichlet;
  g.lattice_node = vm.lattice_node;
  g.lx = grid.nx + 1;
  g.ly = grid.ny + 1;
  return g;
}

}  // namespace

StaticConditions mixed_static_conditions(const Scene& scene, const VoxelMesh& fine_mesh,
                                         const StaticConditions& fine_conditions, const CoarseGrid& level1,
                                         const CoarseGrid& level2, const MixedLevelMesh& mixed,
                                         std::vector<int>* unresolved) {
  const int nu = mixed.num_unknown_nodes();
  StaticConditions out;
  const SpMat W = mixed_to_fine_interpolation(scene.grid, fine_mesh, mixed);
  out.force = VecX::Zero(3 * nu);
  Eigen::Map<Rows3>(out.force.data(), nu, 3) =
      W.transpose() * Eigen::Map<const Rows3>(fine_conditions.force.data(), fine_mesh.mesh.num_nodes(), 3);

  GridDirichlet grids[3];
  grids[0].dirichlet = fine_conditions.dirichlet;
  grids[0].lattice_node = fine_mesh.lattice_node;
  grids[0].lx = scene.grid.nx + 1;
  grids[0].ly = scene.grid.ny + 1;
  const bool coarse_used = mixed.elements_per_level[1] + mixed.elements_per_level[2] > 0;
  if (coarse_used) {
    grids[1] = grid_dirichlet(scene, level1.as_voxel_grid());
    grids[2] = grid_dirichlet(scene, level2.as_voxel_grid());
  }
  const int lz_fine[3] = {scene.grid.nz + 1, level1.nz + 1, level2.nz + 1};
  const LatticeIndex lattice{mixed.lattice};
  // The condition of the node at lattice point a, from the first model with a node there that fixes it.
  auto condition = [&](const std::array<int, 3>& a, int axis, double* value) {
    for (int level = 0; level < (coarse_used ? 3 : 1); ++level) {
      const int s = 1 << level;
      if (a[0] % s || a[1] % s || a[2] % s) continue;
      const GridDirichlet& g = grids[level];
      const int i = a[0] / s, j = a[1] / s, k = a[2] / s;
      if (i >= g.lx || j >= g.ly || k >= lz_fine[level]) continue;
      const int node = g.lattice_node[i + g.lx * (j + g.ly * k)];
      if (node < 0 || !g.dirichlet.fixed[3 * node + axis]) continue;
      *value = g.dirichlet.displacement[3 * node + axis];
      return true;
    }
    return false;
  };
  out.dirichlet = DirichletConditions::none(3 * nu);
  for (int u = 0; u < nu; ++u) {
    const auto a = lattice.coords(mixed.node_lattice[mixed.unknown_node[u]]);
    for (int axis = 0; axis < 3; ++axis) {
      double value = 0;
      if (condition(a, axis, &value)) {
        out.dirichlet.fixed[3 * u + axis] = 1;
        out.dirichlet.displacement[3 * u + axis] = value;
      }
    }
  }
  if (unresolved) {
    unresolved->clear();
    const SpMat Tr = SpMat(mixed.constraints->node_map.transpose());  // column n: the unknowns of mesh node n
    std::vector<char> is_unknown(mixed.mesh.num_nodes(), 0);
    for (int n : mixed.unknown_node) is_unknown[n] = 1;
    for (int n = 0; n < mixed.mesh.num_nodes(); ++n) {
      if (is_unknown[n]) continue;
      const auto a = lattice.coords(mixed.node_lattice[n]);
      for (int axis = 0; axis < 3; ++axis) {
        double value = 0;
        if (!condition(a, axis, &value)) continue;
        bool free_corner = false;
        for (SpMat::InnerIterator it(Tr, n); it; ++it) free_corner |= !out.dirichlet.fixed[3 * int(it.row()) + axis];
        if (!free_corner) continue;
        // The level-2 cells around the node: refining them removes the hanging.
        for (int c = 0; c < 8; ++c) {
          const int I = (a[0] - (c >> 2 & 1)) / kCellSize, J = (a[1] - (c >> 1 & 1)) / kCellSize,
                    K = (a[2] - (c & 1)) / kCellSize;
          if (a[0] - (c >> 2 & 1) < 0 || a[1] - (c >> 1 & 1) < 0 || a[2] - (c & 1) < 0) continue;
          if (I < level2.nx && J < level2.ny && K < level2.nz) unresolved->push_back(int(level2.index(I, J, K)));
        }
        break;
      }
    }
    std::sort(unresolved->begin(), unresolved->end());
    unresolved->erase(std::unique(unresolved->begin(), unresolved->end()), unresolved->end());
  }
  return out;
}

}  // namespace msfab
