#include "fem/hex_mesh_bodies.hpp"

#include <map>
#include <numeric>
#include <stdexcept>
#include <utility>

namespace msfab {

std::vector<int> separate_bodies(HexMesh& mesh, const std::vector<int>& element_body) {
  if (static_cast<int>(element_body.size()) != mesh.num_elements())
    throw std::invalid_argument("separate_bodies: one label per element expected");
  std::map<std::pair<int, int>, int> index;  // (old node, body) -> new node
  std::vector<int> source;
  for (int e = 0; e < mesh.num_elements(); ++e)
    for (int& node : mesh.elements[e]) {
      const auto [it, inserted] = index.try_emplace({node, element_body[e]}, static_cast<int>(source.size()));
      if (inserted) source.push_back(node);
      node = it->second;
    }
  NodeArray nodes(static_cast<Eigen::Index>(source.size()), 3);
  for (size_t i = 0; i < source.size(); ++i) nodes.row(static_cast<Eigen::Index>(i)) = mesh.nodes.row(source[i]);
  mesh.nodes = std::move(nodes);
  return source;
}

std::vector<int> element_components(const HexMesh& mesh) {
  // Union-find over nodes, then each element takes its first node's root.
  std::vector<int> parent(mesh.num_nodes());
  std::iota(parent.begin(), parent.end(), 0);
  auto root = [&](int i) {
    while (parent[i] != i) i = parent[i] = parent[parent[i]];
    return i;
  };
  for (const auto& el : mesh.elements)
    for (int k = 1; k < 8; ++k) {
      const int a = root(el[0]), b = root(el[k]);
      if (a != b) parent[std::max(a, b)] = std::min(a, b);
    }
  std::map<int, int> number;
  std::vector<int> component(mesh.num_elements());
  for (int e = 0; e < mesh.num_elements(); ++e) {
    const auto [it, inserted] = number.try_emplace(root(mesh.elements[e][0]), static_cast<int>(number.size()));
    component[e] = it->second;
  }
  return component;
}

}  // namespace msfab
