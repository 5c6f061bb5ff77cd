#pragma once
// Surface meshes a user brings: STL (binary or ASCII) and Wavefront OBJ.
// Only the geometry is read (OBJ: `v` and `f` lines; texture coordinates,
// normals, groups and materials are skipped; polygons are split into fans).
// STL normals are ignored: orientation comes from the vertex order, and the
// voxelizer does not need it to be outward (fem/surface_voxelizer.hpp).
#include <cstdint>
#include <string>

#include "fem/surface_voxelizer.hpp"

namespace msfab {

// Largest surface file read (a 10-million-triangle binary STL is 500 MB).
inline constexpr std::uint64_t kMaxSurfaceMeshBytes = std::uint64_t(1) << 30;

// By extension (.stl, .obj; any case). InputError naming the file (and line
// for text formats) on a missing, unreadable, truncated or malformed file,
// on an unknown extension, on non-finite coordinates and on a file without
// triangles. Vertices are not merged (see merge_equal_vertices).
TriangleSurface read_surface_mesh(const std::string& path);

TriangleSurface parse_stl(const std::string& bytes, const std::string& source);
TriangleSurface parse_obj(const std::string& text, const std::string& source);

}  // namespace msfab
