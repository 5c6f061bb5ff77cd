#include "fem/hex_mesh.hpp"

#include <algorithm>

namespace msfab {

hex8::NodeMatrix HexMesh::element_rest_positions(int e) const {
  hex8::NodeMatrix X;
  for (int i = 0; i < 8; ++i) X.row(i) = nodes.row(elements[e][i]);
  return X;
}

Vec3 HexMesh::bbox_min() const { return nodes.colwise().minCoeff().transpose(); }
Vec3 HexMesh::bbox_max() const { return nodes.colwise().maxCoeff().transpose(); }

std::vector<std::vector<int>> greedy_element_coloring(const HexMesh& mesh) {
  // For each node, the colours already used by elements touching it, as a bit mask.
  std::vector<uint64_t> node_colors(mesh.num_nodes(), 0);
  std::vector<std::vector<int>> colors;
  for (int e = 0; e < mesh.num_elements(); ++e) {
    uint64_t used = 0;
    for (int n : mesh.elements[e]) used |= node_colors[n];
    int c = 0;
    while (c < 64 && (used >> c & 1u)) ++c;
    if (c == 64) c = 63;  // cannot happen for hex meshes of bounded valence
    if (c >= static_cast<int>(colors.size())) colors.resize(c + 1);
    colors[c].push_back(e);
    for (int n : mesh.elements[e]) node_colors[n] |= uint64_t(1) << c;
  }
  return colors;
}

HexMesh make_hex_mesh(const NodeArray& nodes, const std::vector<std::array<int, 8>>& elements,
                      const MaterialPtr& material, int points_per_axis) {
  HexMesh mesh;
  mesh.nodes = nodes;
  mesh.elements = elements;
  const hex8::QuadratureRule rule = hex8::gauss_rule(points_per_axis);
  for (int e = 0; e < mesh.num_elements(); ++e) {
    mesh.geometries.push_back(hex8::element_geometry(mesh.element_rest_positions(e), rule));
    mesh.element_geometry.push_back(e);
  }
  mesh.materials.push_back(QuadratureMaterials{{material}});
  mesh.element_material.assign(elements.size(), 0);
  mesh.element_tag.assign(elements.size(), 1);
  mesh.colors = greedy_element_coloring(mesh);
  return mesh;
}

}  // namespace msfab
