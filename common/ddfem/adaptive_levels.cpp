#include "ddfem/adaptive_levels.hpp"

#include <algorithm>
#include <cmath>
#include <queue>
#include <stdexcept>
#include <tuple>

#include "core/errors.hpp"
#include "fem/hex_element.hpp"

namespace msfab {

namespace {
using Rows3 = Eigen::Matrix<double, Eigen::Dynamic, 3, Eigen::RowMajor>;
}  // namespace

LevelErrors level_errors_from_difference(double difference, double rate) {
  if (!(difference >= 0) || !std::isfinite(difference)) throw InputError("level difference must be finite and >= 0");
  if (!(rate > 0) || !std::isfinite(rate)) throw InputError("convergence rate must be finite and > 0");
  const double e1 = difference / (std::pow(2.0, rate) - 1.0);
  return {0.0, e1, std::pow(2.0, rate) * e1};
}

double predicted_error(const std::vector<CellErrorModel>& cells, const LevelErrors& errors,
                       const std::vector<int>& cell_level) {
  if (cell_level.size() != cells.size()) throw InputError("predicted_error: one level per cell expected");
  double sum = 0;
  for (size_t c = 0; c < cells.size(); ++c)
    sum += cells[c].energy_share * errors[cell_level[c]] * errors[cell_level[c]];
  return std::sqrt(sum);
}

namespace {

// Refines `levels` greedily, by the largest decrease of the sum of
// term(c, level) per element added (to any finer level), until the sum
// meets goal. Deterministic: ties go to the lower cell index.
template <typename Term>
void refine_greedily(const std::vector<CellErrorModel>& cells, std::vector<int>& levels, const Term& term,
                     double goal) {
  double sum = 0;
  for (size_t c = 0; c < cells.size(); ++c) sum += term(c, levels[c]);
  // Moves (gain per element added, -cell, to-level, from-level).
  using Move = std::tuple<double, long, int, int>;
  std::priority_queue<Move> moves;
  auto push_moves = [&](size_t c, int from) {
    for (int to = from - 1; to >= 0; --to) {
      const double gain = term(c, from) - term(c, to);
      if (!(gain > 0)) continue;
      const double added = std::max(1.0, double(cells[c].elements[to] - cells[c].elements[from]));
      moves.emplace(gain / added, -long(c), to, from);
    }
  };
  for (size_t c = 0; c < cells.size(); ++c) push_moves(c, levels[c]);
  // Relative slack so that round-off in the running sum cannot keep refining.
  while (sum > goal * (1 + 1e-12) && !moves.empty()) {
    const auto [ratio, minus_c, to, from] = moves.top();
    moves.pop();
    const size_t c = size_t(-minus_c);
    if (levels[c] != from) continue;  // stale: the cell moved since
    sum += term(c, to) - term(c, from);
    levels[c] = to;
    push_moves(c, to);
  }
}

void check_level_errors(const LevelErrors& errors) {
  for (double e : errors)
    if (!(e >= 0) || !std::isfinite(e)) throw InputError("level errors must be finite and >= 0");
}

}  // namespace

LevelChoice choose_cell_levels(const std::vector<CellErrorModel>& cells, const LevelErrors& errors, double target) {
  if (!(target >= 0) || !std::isfinite(target)) throw InputError("target error must be finite and >= 0");
  check_level_errors(errors);
  LevelChoice out;
  out.cell_level.assign(cells.size(), target == 0 ? 0 : 2);
  if (target > 0) {
    auto term = [&](size_t c, int level) { return cells[c].energy_share * errors[level] * errors[level]; };
    refine_greedily(cells, out.cell_level, term, target * target);
  }
  out.predicted_error = predicted_error(cells, errors, out.cell_level);
  return out;
}

LevelErrors calibrated_level_errors(const std::vector<CellErrorModel>& cells, const LevelErrors& errors,
                                    const std::vector<int>& levels, const std::vector<double>& cell_error_energy,
                                    double measured_error) {
  const size_t n = cells.size();
  if (levels.size() != n || cell_error_energy.size() != n)
    throw InputError("calibrated_level_errors: one level and one error energy per cell expected");
  if (!(measured_error >= 0) || !std::isfinite(measured_error))
    throw InputError("calibrated_level_errors: the measured error must be finite and >= 0");
  check_level_errors(errors);
  // Per coarse level: its cells' energy share and the measured field's
  // energy in them. Fine cells' field energy is induced by the coarse
  // cells around them and is left out.
  std::array<double, 3> share{}, field{};
  for (size_t c = 0; c < n; ++c) {
    if (levels[c] < 0 || levels[c] > 2) throw InputError("calibrated_level_errors: levels are 0, 1 or 2");
    if (levels[c] == 0) continue;
    share[levels[c]] += cells[c].energy_share;
    field[levels[c]] += std::max(0.0, cell_error_energy[c]);
  }
  const double total = field[1] + field[2];
  if (!(total > 0) || !std::isfinite(total)) return errors;
  LevelErrors out = errors;
  std::array<bool, 3> measured{};
  for (int level = 1; level <= 2; ++level)
    if (share[level] > 0) {
      out[level] = measured_error * std::sqrt(field[level] / total / share[level]);
      measured[level] = true;
    }
  // A level without cells keeps its a-priori ratio to the measured one.
  for (int level = 1; level <= 2; ++level) {
    const int other = 3 - level;
    if (!measured[level] && measured[other] && errors[other] > 0)
      out[level] = errors[level] * out[other] / errors[other];
  }
  return out;
}

LevelChoice refine_cell_levels(const std::vector<CellErrorModel>& cells, const LevelErrors& errors,
                               const std::vector<int>& levels, double target) {
  if (levels.size() != cells.size()) throw InputError("refine_cell_levels: one level per cell expected");
  for (int l : levels)
    if (l < 0 || l > 2) throw InputError("refine_cell_levels: levels are 0, 1 or 2");
  if (!(target >= 0) || !std::isfinite(target)) throw InputError("target error must be finite and >= 0");
  check_level_errors(errors);
  LevelChoice out;
  out.cell_level = levels;
  auto term = [&](size_t c, int level) { return cells[c].energy_share * errors[level] * errors[level]; };
  refine_greedily(cells, out.cell_level, term, target * target);
  out.predicted_error = predicted_error(cells, errors, out.cell_level);
  return out;
}

namespace {

// Every cell of `finer` at the level of `coarser` or below it.
bool refines(const std::vector<int>& finer, const std::vector<int>& coarser) {
  if (finer.size() != coarser.size()) return false;
  for (size_t c = 0; c < finer.size(); ++c)
    if (finer[c] > coarser[c]) return false;
  return true;
}

}  // namespace

double ranked_estimate(const std::vector<CheckedSolve>& solves, std::size_t index) {
  if (index >= solves.size()) throw std::out_of_range("ranked_estimate: no such solve");
  const CheckedSolve& s = solves[index];
  double ranked = s.estimate;
  if (s.measured) return ranked;
  for (size_t j = 0; j < solves.size(); ++j)
    if (j != index && solves[j].measured && refines(solves[j].cell_level, s.cell_level))
      ranked = std::max(ranked, solves[j].estimate);
  return ranked;
}

std::size_t kept_solve(const std::vector<CheckedSolve>& solves) {
  if (solves.empty()) throw std::invalid_argument("kept_solve: no solves");
  size_t kept = 0;
  double kept_ranked = ranked_estimate(solves, 0);
  for (size_t i = 1; i < solves.size(); ++i) {
    const double r = ranked_estimate(solves, i);
    // Later solves win ties; a measured estimate beats an extrapolated one.
    const bool better = r < kept_ranked || (r == kept_ranked && (solves[i].measured || !solves[kept].measured));
    if (better) kept = i, kept_ranked = r;
  }
  return kept;
}

std::vector<CellErrorModel> cell_error_models(const VoxelGrid& fine, const CoarseGrid& level1, const CoarseGrid& level2,
                                              const VoxelMesh& level1_mesh, const std::vector<double>& level1_energy) {
  if (level1.level != 1 || level2.level != 2 || level1_mesh.voxel_element.size() != size_t(level1.num_cells()))
    throw InputError("cell_error_models: the level-1 mesh and the grids do not belong together");
  if (level1_energy.size() != size_t(level1_mesh.mesh.num_elements()))
    throw InputError("cell_error_models: one energy per level-1 element expected");
  std::vector<CellErrorModel> cells(level2.num_cells());
  double total = 0;
  for (int K = 0; K < level2.nz; ++K)
    for (int J = 0; J < level2.ny; ++J)
      for (int I = 0; I < level2.nx; ++I) {
        const size_t cell = level2.index(I, J, K);
        if (level2.cell_combination[cell] < 0) continue;
        CellErrorModel& m = cells[cell];
        m.elements[2] = 1;
        for (int q = 0; q < 8; ++q) {
          const int i1 = 2 * I + (q >> 2 & 1), j1 = 2 * J + (q >> 1 & 1), k1 = 2 * K + (q & 1);
          if (i1 >= level1.nx || j1 >= level1.ny || k1 >= level1.nz) continue;
          const int e = level1_mesh.voxel_element[level1.index(i1, j1, k1)];
          if (e < 0) continue;
          ++m.elements[1];
          m.energy_share += std::max(0.0, level1_energy[e]);
          for (int r = 0; r < 8; ++r) {
            const int i = 2 * i1 + (r >> 2 & 1), j = 2 * j1 + (r >> 1 & 1), k = 2 * k1 + (r & 1);
            if (i < fine.nx && j < fine.ny && k < fine.nz && fine.at(i, j, k) != 0) ++m.elements[0];
          }
        }
        total += m.energy_share;
      }
  for (CellErrorModel& m : cells) m.energy_share = total > 0 ? m.energy_share / total : 0.0;
  return cells;
}

std::vector<double> element_energies(const HexMesh& mesh, const VecX& x) {
  std::vector<double> out(mesh.num_elements());
#pragma omp parallel for schedule(static)
  for (int e = 0; e < mesh.num_elements(); ++e) {
    hex8::NodeMatrix xe;
    for (int i = 0; i < 8; ++i) xe.row(i) = x.segment<3>(3 * mesh.elements[e][i]).transpose();
    out[e] = hex_energy(mesh.geometries[mesh.element_geometry[e]], mesh.materials[mesh.element_material[e]], xe);
  }
  return out;
}

std::vector<double> cell_field_energies(const VoxelMesh& fine, const CoarseGrid& level2, const VecX& on_fine,
                                        const VecX& field) {
  const HexMesh& mesh = fine.mesh;
  if (on_fine.size() != 3 * mesh.num_nodes() || field.size() != on_fine.size())
    throw InputError("cell_field_energies: one displacement per fine node expected");
  if (level2.num_cells() == 0 || int(fine.voxel_element.size()) != level2.fine_nx * level2.fine_ny * level2.fine_nz)
    throw InputError("cell_field_energies: the fine mesh and the grid do not belong together");
  VecX rest(3 * mesh.num_nodes());
  Eigen::Map<Rows3>(rest.data(), mesh.num_nodes(), 3) = mesh.nodes;
  const VecX x = rest + on_fine;
  const std::vector<double> at = element_energies(mesh, x);
  const std::vector<double> plus = element_energies(mesh, VecX(x + field));
  const std::vector<double> minus = element_energies(mesh, VecX(x - field));
  std::vector<double> at_rest;  // only where x - field inverts an element
  std::vector<double> cells(level2.num_cells(), 0.0);
  const int n = level2.fine_per_cell();
  for (int e = 0; e < mesh.num_elements(); ++e) {
    double energy = 0.5 * (plus[e] + minus[e]) - at[e];
    if (!std::isfinite(energy)) {
      if (at_rest.empty()) at_rest = element_energies(mesh, VecX(rest + field));
      energy = at_rest[e];
    }
    const int v = fine.element_voxel[e];
    const int i = v % level2.fine_nx, j = (v / level2.fine_nx) % level2.fine_ny,
              k = v / (level2.fine_nx * level2.fine_ny);
    cells[level2.index(i / n, j / n, k / n)] += std::max(0.0, energy);
  }
  return cells;
}

}  // namespace msfab
