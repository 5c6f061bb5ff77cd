#pragma once
// The two models msfab-verify-map compares: the design grid with each
// cell's homogenized stiffness, and the voxel model of the mapping with the
// base materials per voxel.
#include <cstdint>
#include <string>
#include <vector>

#include "core/types.hpp"
#include "fem/voxel_stiffness_field.hpp"
#include "gamut/microstructure_set.hpp"
#include "mapping/mapped_artifact.hpp"
#include "topopt/cell_grid.hpp"

namespace msfab {

// `mapped`: every non-empty cell holds its mapped structure; `solid`: every
// non-empty cell is the stiff material in both models, so they differ only
// by the mesh (the reference for the transfer of supports and loads).
enum class ModelFill { mapped, solid };

struct ModelMaterials {
  MatX stiff, soft, empty;  // Voigt 6 x 6: ids 1, 2 and void (void_ratio x stiff)
};
ModelMaterials model_materials(const MicrostructureSet& set, double void_ratio);

// Upper-triangle Voigt pairs (CellGrid::pair_index order) of a 6 x 6 stiffness.
VecX voigt_pairs(const MatX& C);

// cells x 21: design cells their structure's C^H (the half shift keeps
// it), forced solid cells the stiff material, forced empty cells void.
MatX homogenized_pairs(const CellGrid& grid, const MappedDesign& mapped, const MicrostructureSet& set,
                       const ModelMaterials& materials, ModelFill fill);

// Voxel ids of the full-resolution model (0 void, 1 stiff, 2 soft), one per
// fine cell, numbered X + NX (Y + NY Z).
std::vector<std::uint8_t> model_voxels(const MappedDesign& mapped, const MicrostructureSet& set, ModelFill fill);

// fine cells x 21 from the voxel ids.
MatX voxel_pairs(const std::vector<std::uint8_t>& ids, const ModelMaterials& materials);

// The same as a stiffness field for the matrix-free solver: one base
// matrix per independent material (stiffness_field of the three ids), and
// per voxel its id's weights, a few numbers instead of 21.
VoxelStiffnessField voxel_field(const CellGrid& fine, const std::vector<std::uint8_t>& ids,
                                const ModelMaterials& materials);

}  // namespace msfab
