#pragma once
// The multi-material voxel model of a mapped design and its exports
// (docs/mapping.md): a bit-packed voxel artifact, one binary STL surface per
// material, and a PNG per voxel layer.
//
// The model is never assembled whole: VoxelModel::layer() produces one
// layer of voxels along z from the cell assignment and the structures, and
// every export streams layer by layer, so memory stays at a few layers
// (plus one layer of cells for the voxel file) whatever the model's size.
//
// Voxel (X, Y, Z) lies in cell (X / (t vx), Y / (t vy), Z / (t vz)), t the
// mapping's tiling (1 unless each cell holds t^3 copies of its structure;
// no tiling along z in 2D), at local (x, y, z) = (X mod vx, ...); a design cell holding structure s with the
// half shift reads s at ((x + vx/2) mod vx, (y + vy/2) mod vy,
// (z + vz/2) mod vz), as half_shifted() builds it. Forced empty cells are id
// 0 (void), forced solid cells id 1 (the stiff material).
#include <cstdint>
#include <string>
#include <vector>

#include "core/types.hpp"
#include "gamut/microstructure_set.hpp"
#include "io/artifact.hpp"
#include "io/hdf5_file.hpp"
#include "io/png_image.hpp"
#include "mapping/mapped_artifact.hpp"

namespace msfab {

class VoxelModel {
 public:
  // Keeps references to both; they must outlive the model. InputError when
  // the mapping does not fit the set (voxels per cell, structure indices).
  VoxelModel(const MappedDesign& mapped, const MicrostructureSet& set);

  std::int64_t nx() const { return std::int64_t(m_.nx) * m_.vx * m_.tiling; }
  std::int64_t ny() const { return std::int64_t(m_.ny) * m_.vy * m_.tiling; }
  std::int64_t nz() const { return std::int64_t(m_.nz) * m_.vz * tiling_z(); }
  // Voxels per cell edge along x, y, z.
  int cell_voxels_x() const { return m_.vx * m_.tiling; }
  int cell_voxels_y() const { return m_.vy * m_.tiling; }
  int cell_voxels_z() const { return m_.vz * tiling_z(); }
  std::int64_t voxels() const { return nx() * ny() * nz(); }
  int max_id() const { return set_.soft_is_void ? 1 : 2; }
  // Edge lengths of a voxel (m): cell_size / voxels per cell edge; a 2D model is
  // one voxel thick, as thick as a voxel is wide.
  Vec3 voxel_size() const;
  const MappedDesign& mapping() const { return m_; }

  // Layer z: nx * ny ids, x fastest (parallel over rows, deterministic).
  void layer(std::int64_t z, std::vector<int>& ids) const;

 private:
  int tiling_z() const { return m_.dimension == 3 ? m_.tiling : 1; }
  const MappedDesign& m_;
  const MicrostructureSet& set_;
};

// --- the voxel artifact: `msfab.voxels` version 1 ----------------------------
inline constexpr const char* kVoxelsSchema = "msfab.voxels";
inline constexpr int kVoxelsSchemaVersion = 1;

// Writes /voxels (nz, layer bytes) uint8, one bit-packed layer per row
// (pack_voxels: x fastest, bits_per_voxel bits each, least significant
// first, each layer padded to whole bytes), in gzip chunks, one layer of
// cells at a time.
void write_voxels_artifact(const std::string& path, const VoxelModel& model, const std::string& executable,
                           const std::string& config_text, const std::vector<std::string>& inputs, std::uint64_t seed);

// Reads a voxel artifact layer by layer.
class VoxelsReader {
 public:
  explicit VoxelsReader(const std::string& path);  // InputError on a wrong file
  std::int64_t nx() const { return nx_; }
  std::int64_t ny() const { return ny_; }
  std::int64_t nz() const { return nz_; }
  int bits_per_voxel() const { return bits_; }
  std::vector<int> layer(std::int64_t z) const;

 private:
  ArtifactReader in_;
  std::int64_t nx_ = 0, ny_ = 0, nz_ = 0;
  int bits_ = 1;
  std::size_t row_bytes_ = 0;
};

// --- surfaces ---------------------------------------------------------------
// One binary STL per material id 1..max_id, "<stem>.material<id>.stl": every
// voxel face between a voxel of that id and one of another id (the outside
// of the model counts as void) as two triangles, normal pointing out of the
// material, coordinates in m. Written atomically (tmp + rename).
struct StlExport {
  std::vector<std::string> paths;
  std::vector<std::int64_t> triangles;  // per file
};
StlExport write_material_stls(const std::string& stem, const VoxelModel& model);

// --- slices -----------------------------------------------------------------
// One PNG per voxel layer along z into `folder` (created if missing):
// z00000.png, z00001.png, ..., one pixel per voxel, y up, a colour per id
// (slice_color). Layers are compressed in parallel, one per thread at a
// time. Returns the number of files.
std::int64_t write_png_slices(const std::string& folder, const VoxelModel& model);
Rgb slice_color(int id);

}  // namespace msfab
