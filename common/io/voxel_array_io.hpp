#pragma once
// Voxel arrays a user brings: a NumPy .npy file (what numpy.save writes) or a
// headerless raw file, holding one integer material id per voxel.
//
//   .npy  a 3D array a of shape (nx, ny, nz), a[i, j, k] the id of voxel
//         (i, j, k) (x = first index), C or Fortran order; a 2D array of
//         shape (nx, ny) for a grid one voxel thick. Integer or bool
//         dtypes of 1, 2, 4 or 8 bytes, either byte order.
//   raw   nx * ny * nz values of the given dtype, little-endian, x fastest
//         (the grid's own order), no header.
#include <cstdint>
#include <string>
#include <vector>

namespace msfab {

// Largest voxel array read (2^31 one-byte voxels).
inline constexpr std::uint64_t kMaxVoxelArrayBytes = std::uint64_t(2) << 30;

// The dtypes a raw file may hold: uint8, int8, uint16, int16, uint32, int32,
// uint64, int64.
std::vector<std::string> raw_voxel_dtypes();

// The ids of a grid of nx * ny * nz voxels, x fastest. `raw_dtype` is used
// for files that do not end in .npy (and must then be one of
// raw_voxel_dtypes(); empty -> InputError asking for it). InputError naming
// the file on: a missing or unreadable file, a malformed .npy header, an
// unsupported dtype, a shape or size that does not match the grid (the
// message gives both), or an id outside 0 .. 2^31 - 1.
std::vector<int> read_voxel_ids(const std::string& path, int nx, int ny, int nz, const std::string& raw_dtype = "");

// The same from the file's bytes (`source` names it in messages).
std::vector<int> parse_npy_voxel_ids(const std::string& bytes, const std::string& source, int nx, int ny, int nz);

}  // namespace msfab
