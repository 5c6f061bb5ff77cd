#pragma once
// A set of sampled microstructures with their homogenized properties: the
// `msfab.microstructures` artifact (docs/artifacts.md) that the gamut
// sampler writes and the topology optimizer, the mapper and the family
// discovery read.
//
// Voxels are bit-packed: each cell's ids, x fastest, in ceil(log2(max id
// + 1)) bits per voxel, least significant bits first, one row of bytes per
// structure.
#include <cstdint>
#include <string>
#include <vector>

#include "core/types.hpp"
#include "homog/elastic_tensor.hpp"
#include "io/hdf5_file.hpp"
#include "material/material.hpp"

namespace msfab {

inline constexpr const char* kMicrostructuresSchema = "msfab.microstructures";
inline constexpr int kMicrostructuresSchemaVersion = 1;

// Which step of the sampler produced a structure.
// targeted: generated at a design cell's target by msfab-fill-targets.
enum class SampleStep : int { initial = 0, discrete = 1, continuous = 2, void_variant = 3, directed = 4, targeted = 5 };
const char* step_name(SampleStep step);

struct Microstructure {
  std::vector<int> ids;   // nx * ny * nz voxel ids (0 void, 1 stiff, 2 soft)
  VecX properties;        // raw properties, MaterialSpace order
  VecX unit;              // the same, normalized to the unit cube
  Mat6 C = Mat6::Zero();  // full 3D C^H (a 2D cell: the plane-strain problem's)
  int cycle = 0;
  SampleStep step = SampleStep::initial;
  std::int64_t parent = -1;  // index of the structure it came from, -1 for none
};

struct BaseMaterial {
  double E = 0, nu = 0;
};

// Structures laid out on a tensor grid of a family's parameters
// (msfab-family-generate `grid:`): item i is the grid point whose indices,
// first axis slowest, spell i. A two-scale design can then move along the
// family's own parameters (topopt space family3d) instead of a level set
// around its members. Empty for a set that is not such a grid.
struct StructureGrid {
  std::vector<std::string> names;         // one per axis
  std::vector<std::vector<double>> axes;  // per axis: the parameter values, strictly increasing
  bool empty() const { return axes.empty(); }
  std::size_t points() const;
  // The item of the grid point with these indices (one per axis).
  std::size_t item(const std::vector<int>& index) const;
};

struct MicrostructureSet {
  std::string space;  // MaterialSpace kind name: cubic3d | cubic2d | orthotropic2d
  std::vector<std::string> property_names;
  double E_stiff = 0, decades = 4;  // the normalization (MaterialSpace)
  int nx = 0, ny = 0, nz = 0;
  BaseMaterial stiff, soft;  // ids 1 and 2
  bool soft_is_void = true;  // no id 2; cuts leave void
  std::vector<Microstructure> items;
  StructureGrid grid;  // empty unless the items are a parameter grid (a stage that adds
                       // or removes items must clear it)
};

// The set's base materials as a palette: [0] void, [1] stiff, [2] soft
// (absent when the second phase is void).
std::vector<MaterialPtr> base_palette(const MicrostructureSet& set);
// FNV-1a of a structure's voxel ids: how the sampler and msfab-fill-targets
// recognize a structure the set already holds.
std::uint64_t voxel_hash(const std::vector<int>& ids);

std::vector<std::uint8_t> pack_voxels(const std::vector<int>& ids, int bits);
std::vector<int> unpack_voxels(const std::uint8_t* bytes, std::size_t voxels, int bits);
int bits_per_voxel(int max_id);

// Writes the set under `group` ("/" for an artifact's root) of an open file.
void write_microstructure_set(H5File& file, const std::string& group, const MicrostructureSet& set);
// Reads what write_microstructure_set wrote; InputError naming the file and
// field on anything inconsistent.
MicrostructureSet read_microstructure_set(const H5File& file, const std::string& group);

// The artifact: `msfab.microstructures` v1.
void write_microstructures_artifact(const std::string& path, const MicrostructureSet& set,
                                    const std::string& executable, const std::string& config_text,
                                    const std::vector<std::string>& inputs, std::uint64_t seed);
MicrostructureSet read_microstructures_artifact(const std::string& path);

}  // namespace msfab
