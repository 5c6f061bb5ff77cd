#pragma once
// Coarse spaces that follow the material: the node copies and transfers of
// a multigrid hierarchy on a voxel grid whose material has holes, gaps and
// thin joints (printed microstructures).
//
// A trilinear coarse hat function spans material on both sides of a gap a
// voxel wide: it moves two members that the fine model leaves free to move
// apart, so the coarse space misses the structure's softest motions and CG
// crawls (docs/solvers.md, "Coarse spaces that follow the material"). Here
// a level-l lattice point (every 2^l voxels) gets one copy of its unknowns
// per connected piece of material inside its hat function's support, the box
// of (2^(l+1))^3 voxels around it; each copy's hat function is the trilinear
// one restricted to its piece (cut-cell multigrid, as in the hexahedral
// multigrid of Dick, Georgii and Westermann for cut meshes). Voxels are
// connected when they share a corner, which makes every fine node belong to
// exactly one piece of each box that contains it, so each piece's copies
// still form a partition of unity (rigid motions of every piece are
// represented). The levels are nested: a copy's piece lies inside exactly
// one piece of every coarser box that holds its support.
#include <cstdint>
#include <vector>

namespace msfab {

// One level of node copies. Lattice point (i, j, k) sits at voxel corner
// spacing * (i, j, k); points run up to the first one at or beyond the grid's
// far corner on each axis.
struct ComponentLevel {
  int spacing = 1;
  int points[3]{0, 0, 0};
  std::vector<int> first;                    // per lattice point (x fastest): its first copy; size points + 1
  std::vector<std::int64_t> representative;  // per copy: one voxel of its piece

  int copies() const { return first.empty() ? 0 : first.back(); }
  std::int64_t point(int i, int j, int k) const {
    return i + std::int64_t(points[0]) * (j + std::int64_t(points[1]) * k);
  }
  std::int64_t num_points() const { return std::int64_t(points[0]) * points[1] * points[2]; }
};

// Interpolation from a coarse level to the next finer one: per fine copy
// (or fine node) up to 8 coarse copies with trilinear weights, and the
// transpose. Both lists are in a fixed order, so every product over them is
// deterministic for any thread count. The weights are 1, 1/2, 1/4 or 1/8:
// exact in single precision, which halves what the level-0 transfer (a
// few entries per fine node) costs.
struct ComponentTransfer {
  std::vector<int> parent_start, parent;  // per fine row
  std::vector<float> parent_weight;
  std::vector<int> child_start, child;  // per coarse copy
  std::vector<float> child_weight;

  int fine_rows() const { return static_cast<int>(parent_start.size()) - 1; }
  int coarse_copies() const { return static_cast<int>(child_start.size()) - 1; }
};

// The hierarchy over a grid of nx x ny x nz voxels (solid: one flag per
// voxel, x fastest). levels()[0] is the grid itself: one copy per node that
// touches a solid voxel, in node order (levels()[0].first numbers the
// nodes; a node only void touches has no copy). levels()[l] (l >= 1)
// takes every other lattice point of level l - 1; transfers()[l]
// interpolates levels()[l + 1] to levels()[l].
class MaterialComponents {
 public:
  // Levels are added until a level has at most `coarse_copies` copies, stops
  // shrinking, or spans the grid with two points per axis. Requires even
  // dimensions (level 1 takes every other node). InputError on bad sizes.
  MaterialComponents(int nx, int ny, int nz, const std::vector<char>& solid, int coarse_copies, int threads);

  const std::vector<ComponentLevel>& levels() const { return levels_; }
  const std::vector<ComponentTransfer>& transfers() const { return transfers_; }

  // The level-1 copy that corner `corner` (hex_lattice order) of the level-1
  // element holding voxel (i, j, k) has for that voxel's piece; -1 if the
  // voxel is void.
  int element_copy(int i, int j, int k, int corner) const;

  int nx() const { return n_[0]; }
  int ny() const { return n_[1]; }
  int nz() const { return n_[2]; }

 private:
  int n_[3];
  std::vector<char> solid_;
  std::vector<ComponentLevel> levels_;
  std::vector<ComponentTransfer> transfers_;
};

}  // namespace msfab
