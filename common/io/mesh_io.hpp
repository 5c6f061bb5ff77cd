#pragma once
// Hex meshes inside artifacts: the layout every artifact with a mesh uses
// (docs/artifacts.md, group "mesh").
#include <string>

#include "fem/hex_mesh.hpp"
#include "io/hdf5_file.hpp"

namespace msfab {

// Writes <group>/nodes (n,3) float64 [m], <group>/elements (e,8) int32 in
// toolkit node order, <group>/elements_vtk (e,8) int32 for XDMF, and
// <group>/element_tag (e) int32.
void write_hex_mesh(H5File& file, const std::string& group, const HexMesh& mesh);

// Node positions and connectivity (toolkit order) read back, for
// post-processing; materials are not stored in the mesh group.
struct StoredHexMesh {
  NodeArray nodes;
  std::vector<std::array<int, 8>> elements;
  std::vector<int> element_tag;
};
StoredHexMesh read_hex_mesh(const H5File& file, const std::string& group);

}  // namespace msfab
