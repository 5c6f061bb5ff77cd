#pragma once
// The voxel cell of msfab-homogenize: a `cell` section with its size and
// either a `layout` (the scene painting of docs/scenes.md, in cell
// coordinates [0, size * voxel_size]) or a `voxels` text file; or one
// structure of a microstructures artifact (`structures`, `index`) with the
// set's base materials as Neo-Hookean.
#include <functional>
#include <string>
#include <vector>

#include "fem/voxel_grid.hpp"
#include "io/config.hpp"
#include "scene/scene.hpp"

namespace msfab {

struct CellInput {
  VoxelGrid cell;
  std::vector<PaletteEntry> palette;
  std::vector<MaterialPtr> material_by_id;  // [0] = void
  std::string source;              // the microstructures artifact the cell came from (an input of the result), or empty
  std::vector<std::string> files;  // the voxel files the cell was read from (inputs of the result)
};

// InputError naming the key (or the voxel file and line) on bad input.
// `check_size(nx, ny, nz)` runs once the cell's size is known and before a
// cell given by `size` is allocated (the memory check of the stage).
CellInput read_cell_input(const Config& config, const std::function<void(int, int, int)>& check_size = {});

// Voxel text file: "nx ny nz" then nx*ny*nz integer ids, x fastest; '#'
// starts a comment. InputError naming the file and what is wrong.
VoxelGrid read_voxel_text(const std::string& path, double voxel_size);

}  // namespace msfab
