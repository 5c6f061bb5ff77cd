#include "fem/voxel_grid.hpp"

#include <algorithm>
#include <sstream>

#include "core/errors.hpp"

namespace msfab {

size_t VoxelGrid::count_solid() const {
  return static_cast<size_t>(std::count_if(ids.begin(), ids.end(), [](int v) { return v != 0; }));
}

VoxelMesh build_voxel_mesh(const VoxelGrid& grid, const std::vector<MaterialPtr>& palette) {
  if (grid.nx <= 0 || grid.ny <= 0 || grid.nz <= 0) throw InputError("voxel grid has a non-positive dimension");
  if (!(grid.voxel_size > 0)) throw InputError("voxel size must be positive");
  if (grid.count_solid() == 0) throw InputError("voxel grid is empty: every voxel is void (id 0)");

  VoxelMesh vm;
  HexMesh& mesh = vm.mesh;
  const int lx = grid.nx + 1, ly = grid.ny + 1, lz = grid.nz + 1;
  auto lattice = [&](int i, int j, int k) { return i + lx * (j + ly * k); };

  // Mark the lattice nodes that solid voxels touch, then number them in lattice order.
  vm.lattice_node.assign(size_t(lx) * ly * lz, -1);
  for (int k = 0; k < grid.nz; ++k)
    for (int j = 0; j < grid.ny; ++j)
      for (int i = 0; i < grid.nx; ++i)
        if (grid.at(i, j, k) != 0)
          for (int c = 0; c < 8; ++c) vm.lattice_node[lattice(i + (c >> 2 & 1), j + (c >> 1 & 1), k + (c & 1))] = 0;
  int n_nodes = 0;
  for (int& n : vm.lattice_node)
    if (n == 0) n = n_nodes++;
  mesh.nodes.resize(n_nodes, 3);
  for (int k = 0; k < lz; ++k)
    for (int j = 0; j < ly; ++j)
      for (int i = 0; i < lx; ++i) {
        const int n = vm.lattice_node[lattice(i, j, k)];
        if (n >= 0) mesh.nodes.row(n) = (grid.origin + grid.voxel_size * Vec3(i, j, k)).transpose();
      }

  // One material entry per palette id actually used.
  std::vector<int> material_slot(palette.size(), -1);
  vm.voxel_element.assign(grid.size(), -1);
  std::vector<std::vector<int>> colors(8);
  for (int k = 0; k < grid.nz; ++k)
    for (int j = 0; j < grid.ny; ++j)
      for (int i = 0; i < grid.nx; ++i) {
        const int id = grid.at(i, j, k);
        if (id == 0) continue;
        if (id < 0 || id >= static_cast<int>(palette.size()) || !palette[id]) {
          std::ostringstream msg;
          msg << "voxel (" << i << ", " << j << ", " << k << ") has material id " << id
              << " but the palette defines ids 1.." << palette.size() - 1;
          throw InputError(msg.str());
        }
        if (material_slot[id] < 0) {
          material_slot[id] = static_cast<int>(mesh.materials.size());
          mesh.materials.push_back(QuadratureMaterials{{palette[id]}});
        }
        std::array<int, 8> el;
        for (int c = 0; c < 8; ++c) el[c] = vm.lattice_node[lattice(i + (c >> 2 & 1), j + (c >> 1 & 1), k + (c & 1))];
        const int e = mesh.num_elements();
        mesh.elements.push_back(el);
        mesh.element_material.push_back(material_slot[id]);
        mesh.element_tag.push_back(id);
        mesh.element_geometry.push_back(0);
        vm.element_voxel.push_back(static_cast<int>(grid.index(i, j, k)));
        vm.voxel_element[grid.index(i, j, k)] = e;
        // Voxels with the same index parity never share a node.
        colors[(i & 1) * 4 + (j & 1) * 2 + (k & 1)].push_back(e);
      }
  for (auto& c : colors)
    if (!c.empty()) mesh.colors.push_back(std::move(c));

  hex8::NodeMatrix cube;
  for (int c = 0; c < 8; ++c) cube.row(c) = grid.voxel_size * Vec3(c >> 2 & 1, c >> 1 & 1, c & 1).transpose();
  mesh.geometries.push_back(hex8::element_geometry(cube, hex8::gauss_rule(2)));
  return vm;
}

}  // namespace msfab
