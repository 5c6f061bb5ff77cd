#pragma once
// Bodies of a hex mesh. Voxel boxes that touch share nodes and so form one
// body; a scene that wants two bodies touching at rest (a cube lying in a
// basket) labels its elements, and the shared nodes are duplicated so the
// bodies only interact through contact.
#include <vector>

#include "fem/hex_mesh.hpp"

namespace msfab {

// Renumbers the nodes so that elements with different labels share none: a
// node used by k labels becomes k nodes at the same rest position. Nodes
// are numbered in order of first use (element order), so the result is
// deterministic. Returns, per new node, the old node it copies.
std::vector<int> separate_bodies(HexMesh& mesh, const std::vector<int>& element_body);

// Connected components of elements sharing a node: per element, the index
// of its component, numbered by the lowest element in each.
std::vector<int> element_components(const HexMesh& mesh);

}  // namespace msfab
