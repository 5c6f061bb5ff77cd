#include "ddfem/coarse_grid.hpp"

#include <algorithm>
#include <array>
#include <chrono>
#include <cmath>
#include <sstream>
#include <unordered_map>

#include "core/errors.hpp"
#include "core/timing.hpp"
#include "material/neo_hookean.hpp"

namespace msfab {
namespace {

using Clock = std::chrono::steady_clock;

struct ChildIdsHash {
  size_t operator()(const ChildIds& c) const {
    size_t h = 1469598103934665603ull;
    for (int v : c) h = (h ^ static_cast<size_t>(static_cast<unsigned>(v))) * 1099511628211ull;
    return h;
  }
};

// Blocks of 2 x 2 x 2 voxels of `ids`; the result's level, fine sizes and
// timing are the caller's to fill in.
CoarseGrid group_blocks(const VoxelGrid& g) {
  if (g.nx <= 0 || g.ny <= 0 || g.nz <= 0) throw InputError("coarsening: voxel grid has a non-positive dimension");
  if (!(g.voxel_size > 0)) throw InputError("coarsening: voxel size must be positive");
  if (g.ids.size() != size_t(g.nx) * g.ny * g.nz)
    throw InputError("coarsening: voxel grid holds " + std::to_string(g.ids.size()) + " ids for " +
                     std::to_string(g.nx) + " x " + std::to_string(g.ny) + " x " + std::to_string(g.nz) + " voxels");
  CoarseGrid c;
  c.nx = (g.nx + 1) / 2;
  c.ny = (g.ny + 1) / 2;
  c.nz = (g.nz + 1) / 2;
  c.cell_size = 2 * g.voxel_size;
  c.origin = g.origin;
  c.cell_combination.assign(size_t(c.nx) * c.ny * c.nz, -1);
  std::unordered_map<ChildIds, int, ChildIdsHash> known;
  for (int K = 0; K < c.nz; ++K)
    for (int J = 0; J < c.ny; ++J)
      for (int I = 0; I < c.nx; ++I) {
        ChildIds child{};
        bool solid = false;
        for (int q = 0; q < 8; ++q) {
          const int i = 2 * I + (q >> 2 & 1), j = 2 * J + (q >> 1 & 1), k = 2 * K + (q & 1);
          // Padding: children beyond an odd upper boundary are void.
          child[q] = (i < g.nx && j < g.ny && k < g.nz) ? g.at(i, j, k) : 0;
          solid |= child[q] != 0;
        }
        if (!solid) continue;
        auto it = known.find(child);
        if (it == known.end()) {
          it = known.emplace(child, static_cast<int>(c.combinations.size())).first;
          c.combinations.push_back(child);
        }
        c.cell_combination[c.index(I, J, K)] = it->second;
      }
  if (c.combinations.empty()) throw InputError("coarsening: the voxel grid is empty (every voxel is void)");
  return c;
}

// The fine voxel grid every level of a hierarchy refers back to.
void set_fine_frame(CoarseGrid& c, int nx, int ny, int nz, double voxel_size) {
  c.fine_nx = nx;
  c.fine_ny = ny;
  c.fine_nz = nz;
  c.fine_voxel_size = voxel_size;
}

}  // namespace

int CoarseGrid::num_elements() const {
  int n = 0;
  for (int c : cell_combination) n += c >= 0;
  return n;
}

VoxelGrid CoarseGrid::as_voxel_grid() const {
  VoxelGrid g(nx, ny, nz, cell_size, 0);
  g.origin = origin;
  for (size_t i = 0; i < cell_combination.size(); ++i) g.ids[i] = cell_combination[i] + 1;
  return g;
}

CoarseGrid coarsen_grid(const VoxelGrid& fine) {
  const auto t0 = Clock::now();
  CoarseGrid c = group_blocks(fine);
  c.level = 1;
  set_fine_frame(c, fine.nx, fine.ny, fine.nz, fine.voxel_size);
  c.seconds = seconds_since(t0);
  return c;
}

CoarseGrid coarsen_grid(const CoarseGrid& coarse) {
  const auto t0 = Clock::now();
  CoarseGrid c = group_blocks(coarse.as_voxel_grid());
  c.level = coarse.level + 1;
  set_fine_frame(c, coarse.fine_nx, coarse.fine_ny, coarse.fine_nz, coarse.fine_voxel_size);
  c.seconds = seconds_since(t0);
  return c;
}

CoarseGrid with_one_combination_per_cell(const CoarseGrid& grid) {
  CoarseGrid out = grid;
  out.combinations.clear();
  for (int& c : out.cell_combination)
    if (c >= 0) {
      out.combinations.push_back(grid.combinations[c]);
      c = static_cast<int>(out.combinations.size()) - 1;
    }
  return out;
}

VoxelMesh build_coarse_mesh(const CoarseGrid& grid, const CoarseMaterialLookup& lookup, int points_per_axis,
                            CoarseMeshStats* stats, bool enhanced_modes) {
  if (!lookup) throw InputError("coarse mesh: no material lookup given");
  return build_coarse_mesh(grid, IndexedMaterialLookup([&](int c) { return lookup(grid.combinations[c]); }),
                           points_per_axis, stats, enhanced_modes);
}

VoxelMesh build_coarse_mesh(const CoarseGrid& grid, const IndexedMaterialLookup& lookup, int points_per_axis,
                            CoarseMeshStats* stats, bool enhanced_modes) {
  const auto t0 = Clock::now();
  if (!lookup) throw InputError("coarse mesh: no material lookup given");
  if (points_per_axis == 0) points_per_axis = std::min(4, grid.fine_per_cell());
  // The rules an element may carry, told apart by its number of materials:
  // the Gauss rule (or one material for all its points), the Gauss rule and
  // the centre (ddfem/coarse_fit.hpp), or one point set per fine voxel (the
  // Galerkin element of ddfem/baseline_coarsening.hpp); or their own.
  const hex8::QuadratureRule gauss = hex8::gauss_rule(points_per_axis);
  const hex8::QuadratureRule composite = hex8::composite_gauss_rule(grid.fine_per_cell(), 2);
  enum Rule { kGauss, kGaussCentre, kComposite, kRules };
  auto rule_of = [&](int n) {
    if (n == 1 || n == gauss.size()) return kGauss;
    if (n == gauss.size() + 1) return kGaussCentre;
    if (n == composite.size()) return kComposite;
    return kRules;
  };

  // The node lattice, elements and colouring are those of a voxel mesh of the
  // cell grid; a temporary palette is used for meshing and the lookups then set every element's materials.
  const MaterialPtr meshing_material = std::make_shared<NeoHookean>(1.0, 0.3);
  VoxelMesh vm =
      build_voxel_mesh(grid.as_voxel_grid(), std::vector<MaterialPtr>(grid.combinations.size() + 1, meshing_material));
  HexMesh& mesh = vm.mesh;

  mesh.materials.clear();
  mesh.materials.reserve(grid.combinations.size());
  for (size_t c = 0; c < grid.combinations.size(); ++c) {
    QuadratureMaterials m = lookup(static_cast<int>(c));
    const int n = static_cast<int>(m.at_point.size());
    if (m.rule && m.rule->size() != n)
      throw InputError("coarse mesh: the material lookup returned " + std::to_string(n) + " materials for the " +
                       std::to_string(m.rule->size()) + " points of its own rule (combination " + std::to_string(c) +
                       ")");
    if (!m.rule && rule_of(n) == kRules) {
      std::ostringstream msg;
      msg << "coarse mesh: the material lookup returned " << n << " materials for combination " << c << "; expected 1, "
          << gauss.size() << " (one per quadrature point), " << gauss.size() + 1 << " (and one at the centre) or "
          << composite.size() << " (8 per fine voxel)";
      throw InputError(msg.str());
    }
    // Null entries are points without material (void voxels of a Galerkin
    // element); an element needs at least one point with material.
    if (std::none_of(m.at_point.begin(), m.at_point.end(), [](const MaterialPtr& p) { return bool(p); }))
      throw InputError("coarse mesh: the material lookup returned no material for combination " + std::to_string(c));
    mesh.materials.push_back(std::move(m));
  }
  hex8::NodeMatrix cube;
  for (int c = 0; c < 8; ++c) cube.row(c) = grid.cell_size * Vec3(c >> 2 & 1, c >> 1 & 1, c & 1).transpose();
  auto geometry = [&](const hex8::QuadratureRule& rule) {
    return enhanced_modes ? hex8::enhanced_element_geometry(cube, rule) : hex8::element_geometry(cube, rule);
  };
  // Geometry 0 is the Gauss rule; the others are added as elements need them.
  mesh.geometries.assign(1, geometry(gauss));
  std::array<int, kRules> index{0, -1, -1};
  std::vector<int> own_index(mesh.materials.size(), -1);  // materials with their own rule
  for (int e = 0; e < mesh.num_elements(); ++e) {
    const int m = mesh.element_tag[e] - 1;
    mesh.element_material[e] = m;
    if (mesh.materials[m].rule) {
      if (own_index[m] < 0) {
        own_index[m] = static_cast<int>(mesh.geometries.size());
        mesh.geometries.push_back(geometry(*mesh.materials[m].rule));
      }
      mesh.element_geometry[e] = own_index[m];
      continue;
    }
    const Rule r = rule_of(static_cast<int>(mesh.materials[m].at_point.size()));
    if (index[r] < 0) {
      index[r] = static_cast<int>(mesh.geometries.size());
      mesh.geometries.push_back(r == kGaussCentre ? hex8::with_centre_point(mesh.geometries[0], cube)
                                                  : geometry(composite));
    }
    mesh.element_geometry[e] = index[r];
  }

  if (stats) {
    stats->elements = mesh.num_elements();
    stats->distinct_combinations = static_cast<int>(grid.combinations.size());
    stats->seconds = seconds_since(t0);
  }
  return vm;
}

SpMat coarse_to_fine_interpolation(const VoxelGrid& fine_grid, const VoxelMesh& fine_mesh, const CoarseGrid& coarse,
                                   const VoxelMesh& coarse_mesh) {
  const double tol = 1e-9 * fine_grid.voxel_size;
  if (fine_grid.nx != coarse.fine_nx || fine_grid.ny != coarse.fine_ny || fine_grid.nz != coarse.fine_nz ||
      std::abs(fine_grid.voxel_size - coarse.fine_voxel_size) > tol || (fine_grid.origin - coarse.origin).norm() > tol)
    throw InputError(
        "coarse-to-fine interpolation: the coarse grid was not built from this fine grid "
        "(sizes, voxel size or origin differ)");
  if (coarse_mesh.voxel_element.size() != size_t(coarse.num_cells()))
    throw InputError("coarse-to-fine interpolation: the coarse mesh does not belong to the coarse grid");
  const int f = coarse.fine_per_cell();
  const int lx = fine_grid.nx + 1, ly = fine_grid.ny + 1;
  const HexMesh& fm = fine_mesh.mesh;
  std::vector<char> done(fm.num_nodes(), 0);
  std::vector<Eigen::Triplet<double, int>> trip;
  trip.reserve(size_t(fm.num_nodes()) * 8);
  for (int e = 0; e < fm.num_elements(); ++e) {
    const int v = fine_mesh.element_voxel[e];
    const int i = v % fine_grid.nx, j = (v / fine_grid.nx) % fine_grid.ny, k = v / (fine_grid.nx * fine_grid.ny);
    const int I = i / f, J = j / f, K = k / f;
    const int ce = coarse_mesh.voxel_element[coarse.index(I, J, K)];
    if (ce < 0) throw InputError("coarse-to-fine interpolation: a solid fine voxel lies in a void coarse cell");
    const auto& cnodes = coarse_mesh.mesh.elements[ce];
    for (int c = 0; c < 8; ++c) {
      const int a = i + (c >> 2 & 1), b = j + (c >> 1 & 1), d = k + (c & 1);
      const int node = fine_mesh.lattice_node[a + lx * (b + ly * d)];
      if (done[node]) continue;
      done[node] = 1;
      // Local coordinates of the fine node in the coarse cell, in [0, 1].
      const double t[3] = {double(a - f * I) / f, double(b - f * J) / f, double(d - f * K) / f};
      for (int cc = 0; cc < 8; ++cc) {
        double w = 1;
        for (int ax = 0; ax < 3; ++ax) w *= (cc >> (2 - ax) & 1) ? t[ax] : 1 - t[ax];
        if (w != 0) trip.emplace_back(node, cnodes[cc], w);
      }
    }
  }
  SpMat P(fm.num_nodes(), coarse_mesh.mesh.num_nodes());
  P.setFromTriplets(trip.begin(), trip.end());
  P.makeCompressed();
  return P;
}

StaticConditions coarse_static_conditions(const Scene& fine_scene, const VoxelMesh& fine_mesh, const CoarseGrid& coarse,
                                          const VoxelMesh& coarse_mesh) {
  const StaticConditions fine = build_static_conditions(fine_scene, fine_mesh);

  Scene cs;
  cs.name = fine_scene.name;
  cs.grid = coarse.as_voxel_grid();
  cs.boundary = fine_scene.boundary;
  cs.material_by_id = fine_scene.material_by_id;
  StaticConditions out;
  out.dirichlet = build_static_conditions(cs, coarse_mesh).dirichlet;

  const SpMat P = coarse_to_fine_interpolation(fine_scene.grid, fine_mesh, coarse, coarse_mesh);
  using Rows3 = Eigen::Matrix<double, Eigen::Dynamic, 3, Eigen::RowMajor>;
  const Eigen::Map<const Rows3> ff(fine.force.data(), fine_mesh.mesh.num_nodes(), 3);
  out.force = VecX::Zero(coarse_mesh.mesh.num_dofs());
  Eigen::Map<Rows3> fc(out.force.data(), coarse_mesh.mesh.num_nodes(), 3);
  fc = P.transpose() * ff;
  return out;
}

}  // namespace msfab
