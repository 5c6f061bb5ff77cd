#include "mapping/cell_pattern.hpp"

#include <stdexcept>

#include "core/errors.hpp"
#include "mapping/mismatch.hpp"

namespace msfab {

std::vector<std::int32_t> pattern_structures(const CellGrid& grid, const std::vector<CellRole>& roles,
                                             const CellPattern& pattern) {
  if (pattern.structures.empty()) throw std::invalid_argument("pattern_structures: no structures");
  if (pattern.kind == PatternKind::uniform && pattern.structures.size() != 1)
    throw std::invalid_argument("pattern_structures: a uniform pattern takes exactly one structure");
  if (pattern.axis < 0 || pattern.axis >= grid.dimension())
    throw std::invalid_argument("pattern_structures: axis outside the grid's dimension");
  if (pattern.thickness < 1) throw std::invalid_argument("pattern_structures: thickness must be >= 1");
  if (std::int64_t(roles.size()) != grid.cells()) throw std::invalid_argument("pattern_structures: one role per cell");
  const std::int64_t count = std::int64_t(pattern.structures.size());
  std::vector<std::int32_t> out(std::size_t(grid.cells()), -1);
  for (std::int64_t c = 0; c < grid.cells(); ++c) {
    if (roles[std::size_t(c)] != CellRole::design) continue;
    std::int64_t pick = 0;
    switch (pattern.kind) {
      case PatternKind::uniform: pick = 0; break;
      case PatternKind::layers:
        pick = (grid.cell_coords(c)[std::size_t(pattern.axis)] / pattern.thickness) % count;
        break;
      case PatternKind::random:
        pick = std::int64_t(hash_seed(pattern.seed, std::uint64_t(c)) % std::uint64_t(count));
        break;
    }
    out[std::size_t(c)] = pattern.structures[std::size_t(pick)];
  }
  return out;
}

Design assigned_design(const CellGrid& grid, const std::vector<CellRole>& roles,
                       const std::vector<std::int32_t>& structure, const MicrostructureSet& set,
                       const std::string& set_path) {
  const int set_dimension = set.nz > 1 ? 3 : 2;
  if (set_dimension != grid.dimension())
    throw InputError(set_path + ": holds " + std::to_string(set_dimension) + "D structures, the scene's grid is " +
                     std::to_string(grid.dimension()) + "D");
  if (set.items.empty()) throw InputError(set_path + ": the set holds no structures");
  Design d;
  d.space = set.space;
  d.property_names = set.property_names;
  d.E_stiff = set.E_stiff;
  d.decades = set.decades;
  d.dimension = grid.dimension();
  d.nx = grid.nx(), d.ny = grid.ny(), d.nz = grid.nz();
  d.cell_size = grid.h();
  d.roles = roles;
  const Eigen::Index n = Eigen::Index(set.property_names.size());
  d.unit = MatX::Zero(grid.cells(), n);
  d.raw = MatX::Zero(grid.cells(), n);
  d.phi = VecX::Zero(grid.cells());
  for (std::int64_t c = 0; c < grid.cells(); ++c) {
    if (roles[std::size_t(c)] == CellRole::solid) d.unit(c, n - 1) = d.raw(c, n - 1) = 1.0;  // density last
    const std::int32_t s = structure[std::size_t(c)];
    if (roles[std::size_t(c)] != CellRole::design) continue;
    if (s < 0 || std::size_t(s) >= set.items.size())
      throw InputError(set_path + ": structure " + std::to_string(s) + " requested, the set holds " +
                       std::to_string(set.items.size()) + " (indices 0.." + std::to_string(set.items.size() - 1) + ")");
    d.unit.row(c) = set.items[std::size_t(s)].unit.transpose();
    d.raw.row(c) = set.items[std::size_t(s)].properties.transpose();
  }
  return d;
}

}  // namespace msfab
