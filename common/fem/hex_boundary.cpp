#include "fem/hex_boundary.hpp"

#include <algorithm>
#include <map>

namespace msfab {

namespace {

// Local faces of a hex8 in toolkit order (node = 4x + 2y + z), each listed
// counter-clockwise seen from outside the element.
constexpr int kFaces[6][4] = {
    {0, 1, 3, 2},  // x = 0 (normal -x)
    {4, 6, 7, 5},  // x = 1 (+x)
    {0, 4, 5, 1},  // y = 0 (-y)
    {2, 3, 7, 6},  // y = 1 (+y)
    {0, 2, 6, 4},  // z = 0 (-z)
    {1, 5, 7, 3},  // z = 1 (+z)
};

}  // namespace

HexBoundary hex_boundary(const HexMesh& mesh) {
  struct Entry {
    int count = 0;
    std::array<int, 4> face;
    int element = 0;
  };
  // Key: the sorted node quadruple.
  std::map<std::array<int, 4>, Entry> faces;
  for (int e = 0; e < mesh.num_elements(); ++e) {
    const auto& el = mesh.elements[e];
    for (const auto& f : kFaces) {
      std::array<int, 4> face{el[f[0]], el[f[1]], el[f[2]], el[f[3]]};
      std::array<int, 4> key = face;
      std::sort(key.begin(), key.end());
      auto [it, inserted] = faces.try_emplace(key, Entry{0, face, e});
      ++it->second.count;
    }
  }
  HexBoundary b;
  std::vector<char> on_boundary(mesh.num_nodes(), 0);
  for (const auto& [key, entry] : faces)
    if (entry.count == 1) {
      b.faces.push_back(entry.face);
      b.face_element.push_back(entry.element);
      for (int n : key) on_boundary[n] = 1;
    }
  for (int n = 0; n < mesh.num_nodes(); ++n)
    if (on_boundary[n]) b.nodes.push_back(n);
  return b;
}

}  // namespace msfab
