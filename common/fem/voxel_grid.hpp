#pragma once
// A regular grid of voxels with one material id each (0 = void), and the
// hex mesh built from its non-void voxels.
#include <cstdint>
#include <vector>

#include "fem/hex_mesh.hpp"

namespace msfab {

struct VoxelGrid {
  int nx = 0, ny = 0, nz = 0;
  double voxel_size = 1.0;  // edge length h, metres
  Vec3 origin = Vec3::Zero();
  std::vector<int> ids;  // x fastest: index = i + nx * (j + ny * k)

  VoxelGrid() = default;
  VoxelGrid(int nx_, int ny_, int nz_, double h, int fill = 0)
      : nx(nx_), ny(ny_), nz(nz_), voxel_size(h), ids(size_t(nx_) * ny_ * nz_, fill) {}

  size_t index(int i, int j, int k) const { return size_t(i) + size_t(nx) * (size_t(j) + size_t(ny) * k); }
  int& at(int i, int j, int k) { return ids[index(i, j, k)]; }
  int at(int i, int j, int k) const { return ids[index(i, j, k)]; }
  size_t size() const { return ids.size(); }
  Vec3 voxel_center(int i, int j, int k) const { return origin + voxel_size * Vec3(i + 0.5, j + 0.5, k + 0.5); }
  Vec3 extent() const { return voxel_size * Vec3(nx, ny, nz); }
  size_t count_solid() const;
};

// Mesh of the non-void voxels. palette[id] is the material of voxel id
// (palette[0], void, is ignored). Lattice nodes used by no element are
// dropped; node and element order follow the grid (x fastest), so the mesh
// is identical for identical grids.
struct VoxelMesh {
  HexMesh mesh;
  std::vector<int> element_voxel;  // element -> voxel index
  std::vector<int> voxel_element;  // voxel -> element or -1
  std::vector<int> lattice_node;   // lattice node (nx+1)(ny+1)(nz+1) -> mesh node or -1
};
VoxelMesh build_voxel_mesh(const VoxelGrid& grid, const std::vector<MaterialPtr>& palette);

}  // namespace msfab
