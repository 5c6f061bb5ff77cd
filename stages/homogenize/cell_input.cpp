#include "cell_input.hpp"

#include <sstream>

#include "core/errors.hpp"
#include "gamut/microstructure_set.hpp"
#include "io/input_file.hpp"
#include "material/neo_hookean.hpp"

namespace msfab {

VoxelGrid read_voxel_text(const std::string& path, double voxel_size) {
  std::istringstream in(read_text_file(path, kMaxTextInputBytes));
  std::vector<long long> numbers;
  std::string line;
  for (int line_no = 1; std::getline(in, line); ++line_no) {
    const std::size_t hash = line.find('#');
    if (hash != std::string::npos) line.resize(hash);
    std::istringstream is(line);
    std::string token;
    while (is >> token) {
      try {
        std::size_t used = 0;
        numbers.push_back(std::stoll(token, &used));
        if (used != token.size()) throw std::invalid_argument(token);
      } catch (const std::exception&) {
        throw InputError(path + ": line " + std::to_string(line_no) + ": '" + token + "' is not an integer");
      }
    }
  }
  if (numbers.size() < 3) throw InputError(path + ": expected 'nx ny nz' and then the voxel ids");
  for (int a = 0; a < 3; ++a)
    if (numbers[a] < 1 || numbers[a] > 4096) throw InputError(path + ": cell size must be 1..4096 per axis");
  VoxelGrid g(static_cast<int>(numbers[0]), static_cast<int>(numbers[1]), static_cast<int>(numbers[2]), voxel_size, 0);
  if (numbers.size() - 3 != g.size())
    throw InputError(path + ": " + std::to_string(numbers.size() - 3) + " voxel ids for a " + std::to_string(g.nx) +
                     " x " + std::to_string(g.ny) + " x " + std::to_string(g.nz) + " cell (" +
                     std::to_string(g.size()) + " expected)");
  for (std::size_t v = 0; v < g.size(); ++v) {
    if (numbers[3 + v] < 0 || numbers[3 + v] > 65535) throw InputError(path + ": voxel ids must be 0..65535");
    g.ids[v] = static_cast<int>(numbers[3 + v]);
  }
  return g;
}

namespace {

// Structure `index` of a microstructures artifact, with the set's base
// materials as Neo-Hookean (C^H is the same for any model linearized at
// rest; the finite-strain check needs a hyperelastic one).
CellInput read_set_structure(const Config& config, const Config& c) {
  if (config.has("materials"))
    config.fail("materials", "come from cell.structures (the set's base materials); drop it");
  if (config.has("layout")) config.fail("layout", "the cell comes from cell.structures; drop the layout");
  if (c.has("size") || c.has("voxels")) c.fail("structures", "give one of structures, voxels or size + layout");
  const std::string path = c.get_path("structures");
  const MicrostructureSet set = read_microstructures_artifact(path);
  if (set.items.empty()) c.fail("structures", path + " holds no structures");
  const int index = c.get<int>("index");
  if (index < 0 || index >= static_cast<int>(set.items.size()))
    c.fail("index", "must be in 0.." + std::to_string(set.items.size() - 1) + " (" + path + " holds " +
                        std::to_string(set.items.size()) + " structures)");
  CellInput in;
  in.source = path;
  in.cell = VoxelGrid(set.nx, set.ny, set.nz, 1.0, 0);
  in.cell.ids = set.items[index].ids;
  in.material_by_id.assign(set.soft_is_void ? 2 : 3, nullptr);
  auto add = [&](int id, const char* name, const BaseMaterial& b) {
    PaletteEntry e;
    e.id = id, e.name = name, e.model = "neo-hookean", e.E = b.E, e.nu = b.nu;
    e.material = std::make_shared<NeoHookean>(b.E, b.nu);
    in.material_by_id[id] = e.material;
    in.palette.push_back(e);
  };
  add(1, "stiff", set.stiff);
  if (!set.soft_is_void) add(2, "soft", set.soft);
  return in;
}

}  // namespace

CellInput read_cell_input(const Config& config, const std::function<void(int, int, int)>& check_size) {
  const Config c = config.child("cell");
  const auto checked = [&](int nx, int ny, int nz) {
    if (check_size) check_size(nx, ny, nz);
  };
  if (c.has("structures")) {
    CellInput in = read_set_structure(config, c);
    checked(in.cell.nx, in.cell.ny, in.cell.nz);
    in.cell.voxel_size = c.get_or<double>("voxel_size", 1.0 / in.cell.nx);
    if (!(in.cell.voxel_size > 0)) c.fail("voxel_size", "must be > 0");
    return in;
  }
  CellInput in;
  in.palette = read_materials(config, &in.material_by_id);
  const bool has_voxels = c.has("voxels"), has_layout = config.has("layout");
  if (has_voxels == has_layout) config.fail("layout", "give either cell.voxels (a voxel file) or a layout, not both");
  if (has_voxels) {
    in.files.push_back(c.get_path("voxels"));
    in.cell = read_voxel_text(in.files.back(), 1.0);  // at most kMaxTextInputBytes of text
    if (c.has("size")) c.fail("size", "comes from the voxel file; drop it");
    checked(in.cell.nx, in.cell.ny, in.cell.nz);
  } else {
    const auto size = c.get<std::vector<int>>("size");
    if (size.size() != 3) c.fail("size", "expected [nx, ny, nz]");
    for (int n : size)
      if (n < 1 || n > 4096) c.fail("size", "cell dimensions must be 1..4096");
    checked(size[0], size[1], size[2]);
    in.cell = VoxelGrid(size[0], size[1], size[2], 1.0, 0);
  }
  // The cell spans [0, 1] along x by default: C^H does not depend on the scale.
  in.cell.voxel_size = c.get_or<double>("voxel_size", 1.0 / in.cell.nx);
  if (!(in.cell.voxel_size > 0)) c.fail("voxel_size", "must be > 0");
  if (has_layout) in.files = paint_layout(config, in.cell, in.material_by_id);
  for (int id : in.cell.ids)
    if (id > 0 && (id >= static_cast<int>(in.material_by_id.size()) || !in.material_by_id[id]))
      config.fail("materials", "the cell uses material id " + std::to_string(id) + ", which is not defined");
  return in;
}

}  // namespace msfab
