#include "models.hpp"

#include <stdexcept>

#include "mapping/voxel_model.hpp"
#include "topopt/cell_material.hpp"
#include "topopt/grid_elasticity.hpp"

namespace msfab {

ModelMaterials model_materials(const MicrostructureSet& set, double void_ratio) {
  ModelMaterials m;
  m.stiff = isotropic_voigt(3, set.stiff.E, set.stiff.nu);
  m.soft = set.soft_is_void ? MatX(void_ratio * m.stiff) : isotropic_voigt(3, set.soft.E, set.soft.nu);
  m.empty = void_ratio * m.stiff;
  return m;
}

VecX voigt_pairs(const MatX& C) {
  VecX out(21);
  for (int s = 0; s < 6; ++s)
    for (int t = s; t < 6; ++t) out[CellGrid::pair_index(s, t, 6)] = 0.5 * (C(s, t) + C(t, s));
  return out;
}

MatX homogenized_pairs(const CellGrid& grid, const MappedDesign& mapped, const MicrostructureSet& set,
                       const ModelMaterials& materials, ModelFill fill) {
  if (grid.cells() != mapped.cells()) throw std::invalid_argument("homogenized_pairs: grid and mapping differ");
  const VecX stiff = voigt_pairs(materials.stiff), empty = voigt_pairs(materials.empty);
  MatX pairs(grid.cells(), 21);
  for (std::int64_t c = 0; c < grid.cells(); ++c) {
    const CellRole role = mapped.roles[std::size_t(c)];
    if (role == CellRole::empty)
      pairs.row(c) = empty.transpose();
    else if (role == CellRole::solid || fill == ModelFill::solid)
      pairs.row(c) = stiff.transpose();
    else
      pairs.row(c) = voigt_pairs(set.items[std::size_t(mapped.structure[std::size_t(c)])].C).transpose();
  }
  return pairs;
}

std::vector<std::uint8_t> model_voxels(const MappedDesign& mapped, const MicrostructureSet& set, ModelFill fill) {
  const VoxelModel model(mapped, set);
  std::vector<std::uint8_t> ids(std::size_t(model.voxels()));
  const std::size_t layer_size = std::size_t(model.nx() * model.ny());
  std::vector<int> layer;
  for (std::int64_t z = 0; z < model.nz(); ++z) {
    model.layer(z, layer);
    std::uint8_t* out = &ids[std::size_t(z) * layer_size];
    for (std::size_t i = 0; i < layer_size; ++i) out[i] = std::uint8_t(layer[i]);
  }
  if (fill == ModelFill::solid) {
    // Every voxel of a non-empty cell becomes stiff; forced empty cells stay void.
    const std::int64_t NX = model.nx(), NY = model.ny();
    for (std::int64_t z = 0; z < model.nz(); ++z)
      for (std::int64_t y = 0; y < NY; ++y)
        for (std::int64_t x = 0; x < NX; ++x) {
          const std::size_t cell = std::size_t(
              x / model.cell_voxels_x() +
              mapped.nx * (y / model.cell_voxels_y() + std::int64_t(mapped.ny) * (z / model.cell_voxels_z())));
          ids[std::size_t(x + NX * (y + NY * z))] = mapped.roles[cell] == CellRole::empty ? 0 : 1;
        }
  }
  return ids;
}

MatX voxel_pairs(const std::vector<std::uint8_t>& ids, const ModelMaterials& materials) {
  const VecX by_id[3] = {voigt_pairs(materials.empty), voigt_pairs(materials.stiff), voigt_pairs(materials.soft)};
  for (std::uint8_t id : ids)
    if (id > 2) throw std::invalid_argument("voxel_pairs: voxel id above 2");
  MatX pairs(Eigen::Index(ids.size()), 21);
#pragma omp parallel for schedule(static)
  for (std::int64_t c = 0; c < std::int64_t(ids.size()); ++c) pairs.row(c) = by_id[ids[std::size_t(c)]].transpose();
  return pairs;
}

VoxelStiffnessField voxel_field(const CellGrid& fine, const std::vector<std::uint8_t>& ids,
                                const ModelMaterials& materials) {
  if (std::int64_t(ids.size()) != fine.cells()) throw std::invalid_argument("voxel_field: one id per fine cell");
  for (std::uint8_t id : ids)
    if (id > 2) throw std::invalid_argument("voxel_field: voxel id above 2");
  const CellGrid by_id(3, 3, 1, 1, fine.h());
  MatX pairs(3, 21);
  pairs.row(0) = voigt_pairs(materials.empty).transpose();
  pairs.row(1) = voigt_pairs(materials.stiff).transpose();
  pairs.row(2) = voigt_pairs(materials.soft).transpose();
  const VoxelStiffnessField table = stiffness_field(by_id, pairs);
  const std::size_t G = table.basis.size();
  VoxelStiffnessField field;
  field.nx = fine.nx(), field.ny = fine.ny(), field.nz = fine.nz();
  field.h = fine.h();
  field.basis = table.basis;
  field.weights.resize(ids.size() * G);
#pragma omp parallel for schedule(static)
  for (std::int64_t v = 0; v < std::int64_t(ids.size()); ++v) {
    const std::size_t id = ids[std::size_t(v)];
    for (std::size_t g = 0; g < G; ++g) field.weights[std::size_t(v) * G + g] = table.weights[id * G + g];
  }
  return field;
}

}  // namespace msfab
