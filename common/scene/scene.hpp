#pragma once
// A voxel scene: grid, material palette, material layout, boundary
// conditions and loads, read from a strict YAML config (docs/scenes.md).
// Every stage that simulates a voxel object reads its scene through here.
#include <string>
#include <vector>

#include "fem/voxel_grid.hpp"
#include "io/config.hpp"
#include "solve/newton.hpp"

namespace msfab {

struct PaletteEntry {
  int id = 0;
  std::string name;
  std::string model;  // "neo-hookean" | "linear" | "linear-anisotropic"
  double E = 0, nu = 0, density = 0;
  MaterialPtr material;
};

// Which nodes a condition acts on: a face of the grid's bounding box, or an
// axis-aligned box (physical coordinates, boundaries included).
struct Region {
  enum class Kind { Face, Box } kind = Kind::Face;
  int axis = 0;                               // face: 0/1/2 for x/y/z
  bool upper = false;                         // face: max side
  Vec3 lo = Vec3::Zero(), hi = Vec3::Zero();  // box
  std::string describe() const;
};

struct BoundaryCondition {
  std::string where;  // config path, for messages
  Region region;
  bool fix[3] = {false, false, false};
  Vec3 displacement = Vec3::Zero();
  bool has_rotation = false;
  Vec3 rotation_axis = Vec3::UnitZ(), rotation_center = Vec3::Zero();
  double rotation_angle = 0;  // radians
};

struct Load {
  std::string where;
  Region region;
  bool is_traction = false;  // traction (Pa) on a face, else a total force (N)
  Vec3 value = Vec3::Zero();
};

struct Scene {
  std::string name;
  VoxelGrid grid;
  std::vector<PaletteEntry> palette;        // as listed in the config
  std::vector<MaterialPtr> material_by_id;  // index = voxel id, [0] = void
  std::vector<BoundaryCondition> boundary;
  std::vector<Load> loads;
  Vec3 gravity = Vec3::Zero();
  NewtonOptions newton;
  bool nonlinear = true;                    // false when every material is linear
  std::vector<std::string> geometry_files;  // voxel arrays and surface meshes the layout read
};

// Parses and validates a scene. Unknown keys are left for the caller's
// check_no_unknown_keys() so stage-specific sections can sit beside it.
Scene read_scene(const Config& config);

// The pieces of read_scene that other stages share. `materials` (a list of
// {id, name, model, E, nu, ...}) -> palette entries and material_by_id
// ([0] = void = nullptr); InputError naming the key on bad input.
std::vector<PaletteEntry> read_materials(const Config& config, std::vector<MaterialPtr>* material_by_id);
// Paints the `layout` list (fill, box, layers, cylinder, helical_fibers,
// checker, random_field, voxels from a .npy or raw file, a closed surface
// mesh from an STL or OBJ file) onto the grid, in physical coordinates.
// Returns the files it read (voxel arrays, surface meshes) in layout order:
// inputs of the result artifact, hashed there.
std::vector<std::string> paint_layout(const Config& config, VoxelGrid& grid,
                                      const std::vector<MaterialPtr>& material_by_id);

// Boundary conditions and external forces on the mesh of a scene. Throws
// InputError for a region that selects no solid node (a load on void), for a
// scene without Dirichlet conditions, and for a mesh part whose rigid motion
// the conditions leave free (a singular system).
struct StaticConditions {
  DirichletConditions dirichlet;
  VecX force;
};
StaticConditions build_static_conditions(const Scene& scene, const VoxelMesh& vm);

// Nodes selected by a region, with their share of the region's area (face
// regions, m^2) or an equal share (box regions, summing to 1).
struct RegionNodes {
  std::vector<int> nodes;
  std::vector<double> weight;
};
RegionNodes select_region(const Region& region, const VoxelGrid& grid, const VoxelMesh& vm);

}  // namespace msfab
