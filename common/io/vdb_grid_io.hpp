#pragma once
// Scalar grids from OpenVDB files (.vdb), the sparse volumes that Houdini,
// Blender and the OpenVDB tools write. Two uses (docs/scenes.md, "Your own
// object"):
//
//   ids     a grid whose values are material ids, read in index space: the
//           scene's voxel (i, j, k) takes the value stored at index
//           coordinate origin + (i, j, k); a voxel the file does not store
//           takes the grid's background. Value types bool, int32, int64,
//           float and double; a float or double value must be a whole number.
//   shape   a level set or a density ("fog") grid, sampled in the file's world
//           coordinates: trilinearly for float and double grids, the
//           containing voxel for bool grids.
//
// The OpenVDB types stay in vdb_grid_io.cpp, the one file that includes
// OpenVDB's headers. A build without OpenVDB (MSFAB_WITH_OPENVDB off) still
// has these functions; they refuse every file with an InputError that says
// how to get OpenVDB.
#include <array>
#include <cstdint>
#include <memory>
#include <string>
#include <vector>

#include "core/types.hpp"

namespace msfab {

// Whether this build reads .vdb files.
bool vdb_input_available();

// Material ids of an nx x ny x nz box of the grid `grid_name` (empty: the
// file's only grid), x fastest; scene voxel (i, j, k) is index coordinate
// origin + (i, j, k). InputError naming the file on: no OpenVDB, an
// unreadable or malformed file, a missing grid (the message lists the
// file's grids), several grids and no name, a value type other than those
// above, or a value that is not a whole number in 0 .. 2^31 - 1 (naming the
// index coordinate).
struct VdbVoxelIds {
  std::vector<int> ids;
  long long active_outside = 0;  // active voxels of the file outside the box (cut off)
};
VdbVoxelIds read_vdb_voxel_ids(const std::string& path, const std::string& grid_name, int nx, int ny, int nz,
                               const std::array<long long, 3>& origin);

// A level set or density grid for inside/outside queries in the file's world
// coordinates. A level set (OpenVDB grid class "level set") is inside where
// its value is below `threshold`; any other grid where its value is above
// it. Queries are not thread-safe (each volume caches the tree nodes it
// visited last, which is what makes a sweep over voxel centres fast).
class VdbVolume {
 public:
  // InputError naming the file as for read_vdb_voxel_ids; value types
  // float, double and bool.
  static VdbVolume read(const std::string& path, const std::string& grid_name);

  bool is_level_set() const;
  // "level set" -> 0, otherwise 0.5 (a density, or a bool grid's 0/1).
  double default_threshold() const;
  // The value at a world point: trilinear between voxel centres for float
  // and double grids, the containing voxel's value (0 or 1) for bool grids;
  // the background far from stored values.
  double sample(const Vec3& world_point) const;
  bool inside(const Vec3& world_point, double threshold) const;
  // World box of the stored voxels and tiles that are inside, each voxel a
  // cube of the file's voxel size around its centre; lo > hi if none is.
  std::array<Vec3, 2> inside_box(double threshold) const;
  // Human-readable summary: grid name, value type, class, voxel size.
  std::string describe() const;

  VdbVolume(VdbVolume&&) noexcept;
  VdbVolume& operator=(VdbVolume&&) noexcept;
  ~VdbVolume();

 private:
  struct Impl;
  explicit VdbVolume(std::unique_ptr<Impl> impl);
  std::unique_ptr<Impl> impl_;
};

}  // namespace msfab
