#pragma once
// An unstructured hexahedral mesh: shared nodes, elements with their
// quadrature data and materials. Voxel grids and arbitrary hex meshes both
// end up here; the assembler only sees this.
#include <array>
#include <vector>

#include "fem/hex_element.hpp"

namespace msfab {

using NodeArray = Eigen::Matrix<double, Eigen::Dynamic, 3, Eigen::RowMajor>;

struct HexMesh {
  NodeArray nodes;                           // rest positions X, one row per node
  std::vector<std::array<int, 8>> elements;  // node indices in hex8 order
  // Elements of identical shape share one geometry (a voxel mesh has one).
  std::vector<hex8::ElementGeometry> geometries;
  std::vector<int> element_geometry;
  // Elements with identical constitutive data share one entry.
  std::vector<QuadratureMaterials> materials;
  std::vector<int> element_material;
  // Label written to outputs (the voxel material id for voxel meshes).
  std::vector<int> element_tag;
  // Colour classes: elements of one colour share no node, so they can be
  // assembled in parallel without races and in an order that does not depend
  // on the thread count.
  std::vector<std::vector<int>> colors;

  int num_nodes() const { return static_cast<int>(nodes.rows()); }
  int num_elements() const { return static_cast<int>(elements.size()); }
  int num_dofs() const { return 3 * num_nodes(); }

  hex8::NodeMatrix element_rest_positions(int e) const;
  // Axis-aligned bounding box of the rest configuration.
  Vec3 bbox_min() const;
  Vec3 bbox_max() const;
};

// Greedy colouring in element order (deterministic); used for meshes that do
// not come with a colouring of their own.
std::vector<std::vector<int>> greedy_element_coloring(const HexMesh& mesh);

// Builds a mesh from explicit nodes and elements, one geometry per element,
// one material for all (used for irregular meshes and tests).
HexMesh make_hex_mesh(const NodeArray& nodes, const std::vector<std::array<int, 8>>& elements,
                      const MaterialPtr& material, int points_per_axis = 2);

}  // namespace msfab
