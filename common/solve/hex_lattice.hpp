#pragma once
// Index arithmetic of hexahedra on a node lattice, shared by the grid
// multigrid solvers: corner a of an element sits at (a>>2&1, a>>1&1, a&1)
// (fem/voxel_stiffness_field.hpp), and a node's 27 lattice neighbours are
// coded by their offset.
namespace msfab::hex_lattice {

constexpr int corner_x(int a) { return a >> 2 & 1; }
constexpr int corner_y(int a) { return a >> 1 & 1; }
constexpr int corner_z(int a) { return a & 1; }
// Lattice offset (dx, dy, dz) in {-1, 0, 1}^3 as 0..26.
constexpr int offset_code(int dx, int dy, int dz) { return (dx + 1) + 3 * (dy + 1) + 9 * (dz + 1); }
// Offset of corner b relative to corner a.
constexpr int corner_code(int a, int b) {
  return offset_code(corner_x(b) - corner_x(a), corner_y(b) - corner_y(a), corner_z(b) - corner_z(a));
}

}  // namespace msfab::hex_lattice
