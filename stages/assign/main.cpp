// msfab-assign: a design written by hand. Every design cell of a scene is
// given a structure of a microstructure set by a pattern, not by the
// optimizer (thesis Table 3.1: the cubes of periodic layers and of random
// assignments, Fig. 3-22; the tiling study of Fig. 3-23):
//
//   1. the scene: grid, domain, supports and loads, read as msfab-topopt
//      reads them (and stored in the design for msfab-verify-map)
//   2. per design cell a structure index by the pattern: one structure
//      everywhere (uniform), layers along an axis, or drawn at random
//   3. write `msfab.design` with each cell's target equal to its
//      structure's properties; msfab-map with one candidate maps it back
//      to exactly these structures
#include <spdlog/spdlog.h>

#include <algorithm>
#include <cstdio>
#include <string>
#include <vector>

#include "cli/stage_app.hpp"
#include "core/errors.hpp"
#include "gamut/microstructure_set.hpp"
#include "mapping/cell_pattern.hpp"
#include "topopt/cell_material.hpp"
#include "topopt/topopt_scene.hpp"

using namespace msfab;

namespace {

constexpr const char* kDefaults = R"(
pattern:
  kind: uniform          # uniform | layers | random
  structures: [0]        # indices into the microstructure set (uniform: exactly one)
  axis: z                # layers: the axis the layers stack along (default z, 2D y)
  thickness: 1           # layers: cells per layer
)";

CellPattern read_pattern(const Config& config, int dimension, std::uint64_t seed) {
  const Config p = config.child("pattern");
  CellPattern pattern;
  const std::string kind = p.has("kind") ? p.one_of("kind", {"uniform", "layers", "random"}) : "uniform";
  pattern.kind = kind == "uniform"  ? PatternKind::uniform
                 : kind == "layers" ? PatternKind::layers
                                    : PatternKind::random;
  const auto structures = p.get<std::vector<int>>("structures");
  if (structures.empty()) p.fail("structures", "needs at least one structure index");
  for (int s : structures)
    if (s < 0) p.fail("structures", "indices must be >= 0");
  if (pattern.kind == PatternKind::uniform && structures.size() != 1)
    p.fail("structures", "a uniform pattern takes exactly one structure");
  pattern.structures.assign(structures.begin(), structures.end());
  const std::string axis = p.has("axis") ? p.one_of("axis", dimension == 3 ? std::vector<std::string>{"x", "y", "z"}
                                                                           : std::vector<std::string>{"x", "y"})
                                         : std::string(dimension == 3 ? "z" : "y");
  pattern.axis = axis[0] - 'x';
  pattern.thickness = p.get_or<int>("thickness", 1);
  if (pattern.thickness < 1) p.fail("thickness", "must be >= 1");
  pattern.seed = seed;
  return pattern;
}

const char* kind_name(PatternKind kind) {
  return kind == PatternKind::uniform ? "uniform" : kind == PatternKind::layers ? "layers" : "random";
}

// Per cell: its role, structure and target in the design, and the scene's
// node loads; about 250 B, measured with /usr/bin/time on 200 x 200 x 100
// cells (1.0 GB). Checked from grid.size before the scene is read.
void check_grid_memory(const StageContext& ctx) {
  const ConfigGridSize size = config_grid_size(ctx.config);
  ctx.check_memory(250.0 * size.cells, "a design of " + size.text + " cells (grid.size)", "use a coarser grid");
}

}  // namespace

int main(int argc, char** argv) {
  StageApp app("msfab-assign",
               "Write a design whose cells hold microstructures by a pattern (uniform, layers, random), not optimized");
  app.add_common_options();
  app.set_default_config(kDefaults);
  std::string structures_path;
  app.option("--structures", structures_path, "msfab.microstructures artifact the pattern indexes")
      .type_name("FILE")
      .required();
  return app.run(argc, argv, [&](StageContext& ctx) {
    Config& config = ctx.config;
    const std::string out = ctx.require_out();
    ctx.check_out_folder();
    const MicrostructureSet set = read_microstructures_artifact(structures_path);
    // 1. The scene, normalized by the set's base material.
    if (const std::string space = config.one_of("space", cell_material_spaces()); space != set.space)
      config.fail("space", "is " + space + ", the set " + structures_path + " holds " + set.space + " structures");
    check_grid_memory(ctx);
    const TopoptScene scene = read_topopt_scene(config, set.E_stiff, set.decades);
    const CellGrid& grid = scene.setup.grid;
    // 2. The pattern.
    const CellPattern pattern = read_pattern(config, grid.dimension(), ctx.options.seed);
    ctx.finish_config();
    for (std::int32_t s : pattern.structures)
      if (std::size_t(s) >= set.items.size())
        config.fail("pattern.structures", "index " + std::to_string(s) + " is outside the set " + structures_path +
                                              " (" + std::to_string(set.items.size()) + " structures)");
    const std::vector<std::int32_t> structure = pattern_structures(grid, scene.setup.roles, pattern);
    // 3. The design.
    const Design design = assigned_design(grid, scene.setup.roles, structure, set, structures_path);
    write_design_artifact(out, design, "msfab-assign", config.resolved_text(), {structures_path}, ctx.options.seed);

    std::int64_t design_cells = 0;
    for (CellRole r : scene.setup.roles) design_cells += r == CellRole::design;
    std::string list;
    for (std::int32_t s : pattern.structures) list += (list.empty() ? "" : ", ") + std::to_string(s);
    std::printf("msfab-assign: %lld cells (%d x %d x %d), %lld design cells, pattern %s over structures [%s] of %s\n",
                static_cast<long long>(grid.cells()), grid.nx(), grid.ny(), grid.nz(),
                static_cast<long long>(design_cells), kind_name(pattern.kind), list.c_str(), structures_path.c_str());
    std::printf("  artifact: %s\n", out.c_str());
  });
}
