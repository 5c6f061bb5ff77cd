#pragma once
// The boundary of a hex mesh: quadrilateral faces used by exactly one
// element, and the nodes on them (the only nodes that can touch anything).
#include <array>
#include <vector>

#include "fem/hex_mesh.hpp"

namespace msfab {

struct HexBoundary {
  // Each face's four nodes, counter-clockwise seen from outside.
  std::vector<std::array<int, 4>> faces;
  std::vector<int> face_element;  // the element each face belongs to
  std::vector<int> nodes;         // sorted
};

HexBoundary hex_boundary(const HexMesh& mesh);

}  // namespace msfab
