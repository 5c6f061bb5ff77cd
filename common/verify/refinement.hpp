#pragma once
// The full-resolution model of a mapped design (thesis §3.6, Table 3.1):
// every coarse cell of a 3D CellGrid becomes r x r x r voxels, and the
// supports, prescribed displacements and loads of the coarse grid are
// carried to the fine nodes; the fine displacement is sampled back at the
// coarse nodes to compare the two models (docs/verify_map.md).
//
// Fine node (i, j, k) sits at (i, j, k) h / r; coarse node (I, J, K) is fine
// node (r I, r J, r K). A fine node lies on a smallest coarse "entity": the
// coarse node it coincides with, a coarse edge, face or cell, whose corners
// are the coarse nodes of that entity and whose trilinear weights (the
// coarse hat functions at the fine node) sum to 1.
//
// Rules (each documented with its reason in docs/verify_map.md):
//  * supports: a fine unknown is fixed when every corner of its entity is
//    fixed in that component, with the interpolated prescribed value, so a
//    clamped face stays a clamped face and a clamped edge an edge. A coarse
//    node fixed alone in a component (no lattice neighbour fixed in it: a
//    point support) fixes its coincident fine node, or, when only void
//    touches that node, the nearest fine nodes with material on the same
//    outer faces.
//  * loads: each coarse nodal force is spread over the fine nodes of the
//    loaded coarse edges and faces through its node (those whose corners all
//    carry a force) in proportion to the coarse hat function times the fine
//    node's trapezoid weight in the loaded region, so every coarse node's
//    force is kept exactly, and the consistent coarse load of a uniform
//    traction becomes the consistent fine load of the same traction. A point
//    load (no loaded edge through its node) is spread with the hat weights
//    over the outer faces of the grid that hold the node, within one coarse
//    cell. Fine nodes that only void touches take no load; their weight goes
//    to the others.
//  * sampling: the fine displacement at a coarse node is the coincident fine
//    node's when material touches it, else the mean over the nearest fine
//    nodes with material (same outer faces, up to half a cell away).
#include <cstdint>
#include <string>
#include <vector>

#include "core/types.hpp"
#include "topopt/cell_grid.hpp"

namespace msfab {

class CellRefinement {
 public:
  // InputError for a 2D grid or r < 1.
  CellRefinement(const CellGrid& coarse, int resolution);

  const CellGrid& coarse() const { return coarse_; }
  const CellGrid& fine() const { return fine_; }
  int resolution() const { return r_; }

  // The fine node coinciding with a coarse node.
  std::int64_t fine_node_of(std::int64_t coarse_node) const;

  // The coarse entity a fine node lies on: up to 8 corners with weights.
  struct Entity {
    int corners = 0;
    std::int64_t node[8];
    double weight[8];
  };
  Entity entity(std::int64_t fine_node) const;

  // Per fine node: 1 when a voxel (fine cell) with material touches it.
  // `voxel_material` holds one flag per fine cell.
  std::vector<char> material_nodes(const std::vector<char>& voxel_material) const;

  // Fine nodes nearest to a coarse node with material: the coincident node
  // if it has material, else those at the smallest Chebyshev distance d
  // (1 <= d <= max_distance, in fine nodes) that do, restricted to the outer
  // faces of the grid the coarse node lies on. Empty when none.
  std::vector<std::int64_t> nearest_material(std::int64_t coarse_node, const std::vector<char>& node_material,
                                             int max_distance) const;

  struct Supports {
    std::vector<char> fixed;          // per fine unknown
    SpMat values;                     // fine unknowns x coarse unknowns: prescribed_fine = values * prescribed_coarse
    std::int64_t point_supports = 0;  // coarse (node, component) fixed alone
    std::int64_t moved_point_supports = 0;  // of those, carried to nearest material nodes
    std::int64_t lost_point_supports = 0;   // of those, with no material within half a cell (fixed on void)
  };
  // `coarse_fixed`: one flag per coarse unknown.
  Supports refine_supports(const std::vector<char>& coarse_fixed, const std::vector<char>& node_material) const;

  struct LoadStats {
    std::int64_t loaded_nodes = 0;  // coarse nodes carrying a force
    std::int64_t point_loads = 0;   // of those, point loads (spread over the surface patch)
    std::int64_t fallbacks = 0;     // loads whose footprint held only void and went to the surface patch / cell volume
    std::int64_t fine_nodes = 0;    // fine nodes that received a force
  };
  // Fine nodal forces for coarse nodal forces (per unknown). InputError when
  // a coarse node's force finds no fine node with material within one cell;
  // `what` names the load case in that message.
  VecX refine_forces(const VecX& coarse_force, const std::vector<char>& node_material, const std::string& what,
                     LoadStats* stats = nullptr) const;

 private:
  // Whether a fine node lies on one of the outer grid faces the coarse
  // node lies on (always true for a coarse node inside the grid).
  bool on_faces_of(std::int64_t coarse_node, std::int64_t fine_node) const;

  CellGrid coarse_, fine_;
  int r_ = 1;
};

}  // namespace msfab
