#pragma once
// The 2 x 2 x 2 block of fine voxels that one coarse DDFEM element replaces
// (thesis §2.3): its hex mesh, the materials of its children and the fine
// nodes that coincide with the coarse element's eight corners.
#include <array>
#include <string>
#include <vector>

#include "fem/voxel_grid.hpp"

namespace msfab {

// Child (i, j, k) of the block, i, j, k in {0, 1}, has index 4i + 2j + k:
// the hex8 node order, so child c sits at coarse corner c.
using BlockMaterials = std::array<int, 8>;
bool is_all_void(const BlockMaterials& ids);
bool is_all_solid(const BlockMaterials& ids);
// "[1 2 0 1 1 2 2 1]", for messages.
std::string block_name(const BlockMaterials& ids);

struct FineBlock {
  double voxel_size = 1.0;  // fine edge h; the coarse element has edge n h
  // Voxels n along each edge of the block: 2 (one voxel per child, level 1)
  // or 4 (a level-2 block sampled on its fine voxels: each child is then
  // 2 x 2 x 2 voxels, see make_voxel_block).
  int voxels_per_edge = 2;
  BlockMaterials material_ids{};            // palette ids per child, 0 = void
  std::vector<MaterialPtr> child_material;  // per child, null for void
  // Voxels of context around the block on every side (in-situ sampling,
  // docs/ddfem.md): 0 is the isolated block; r > 0 surrounds it with r
  // layers of its own periodic copies, so the mesh covers (2 + 2r)^3 voxels
  // and a fibre or layer that crosses the block continues through its faces
  // as it does in a body. The block itself always spans [0, 2h]^3.
  int context = 0;
  VoxelMesh voxels;  // mesh of the non-void voxels (block and context)
  // Elements inside the block (1) or in its context (0): a sample's energy
  // is the energy of the block's own elements.
  std::vector<char> core_element;
  // Fine mesh node at coarse corner c (hex8 order), -1 where no solid voxel
  // touches that corner.
  std::array<int, 8> corner_nodes{};
  // The coarse element's Gauss rule: 2 points per axis at level 1 (one per
  // child), 4 for a 64-point element. Eq. 2.9's p^0 at each coarse point:
  // the Lame parameters of the material under it (0 in a void child).
  int coarse_points_per_axis = 2;
  std::vector<double> point_mu0, point_lambda0;

  const HexMesh& mesh() const { return voxels.mesh; }
  // Every coarse corner has a fine node (needed to sample the block).
  bool has_all_corners() const;
  // No child is void. Only such blocks are fitted (see docs/ddfem.md).
  bool all_children_solid() const;
  // The child of the block whose copy element e is (the element's own child
  // inside the block).
  int child_of_element(int e) const;
  double edge() const { return voxels_per_edge * voxel_size; }
  // Rest positions of the coarse element's corners (edge n h, origin at 0).
  hex8::NodeMatrix coarse_rest_positions() const;
  // The coarse element's Gauss geometry (its quadrature points k of
  // Eq. 2.6-2.7), and the child containing each point.
  hex8::ElementGeometry coarse_geometry() const;
  int coarse_points() const { return coarse_points_per_axis * coarse_points_per_axis * coarse_points_per_axis; }
  int child_of_point(int q) const;
  // The block voxel (i + n (j + n k), x fastest) coarse point q lies in.
  int voxel_of_point(int q) const;
  static int child_of_coarse_point(int q);  // the 2-point rule
  // Mesh node at block lattice position (i, j, k), i, j, k in {0, ..., n}
  // (offset by the context); -1 if absent.
  int lattice_node(int i, int j, int k) const;
};

// Builds the block for material ids (palette[id], id 0 = void), with
// `context` layers of periodic copies around it. Throws InputError if h is
// not positive, an id is out of range, a non-void id has no material, every
// child is void, or context is outside [0, 4].
FineBlock make_fine_block(const BlockMaterials& ids, const std::vector<MaterialPtr>& palette, double voxel_size,
                          int coarse_points_per_axis = 2, int context = 0);

// A level-2 block on its fine voxels (docs/ddfem.md, "Level 2"): 4 x 4 x 4
// voxels, `voxel_ids[i + 4 (j + 4 k)]` the palette id of voxel (i, j, k)
// (0 = void), coarsened into one element with the 4-point Gauss rule, one
// point in each voxel (p^0 there: that voxel's material). `label` names the
// block's eight children (e.g. their level-1 entries + 1, 0 for a void
// child). Periodic sampling only (no context). Throws InputError as
// make_fine_block, and on a wrong number of ids.
FineBlock make_voxel_block(const std::vector<int>& voxel_ids, const std::vector<MaterialPtr>& palette,
                           double voxel_size, const BlockMaterials& label);

}  // namespace msfab
