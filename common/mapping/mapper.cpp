#include "mapping/mapper.hpp"

#include <algorithm>
#include <stdexcept>

#include "core/errors.hpp"
#include "gamut/material_space.hpp"

namespace msfab {
namespace {

std::string joined(const std::vector<std::string>& names) {
  std::string s;
  for (const auto& n : names) s += (s.empty() ? "" : ",") + n;
  return s;
}

// The candidates of each cell whose property gap is at most max(limit, the
// cell's smallest), in their order.
CellCandidates keep_within_gap(const CellCandidates& in, const Design& design, const MicrostructureSet& set,
                               double limit) {
  const MaterialSpace space(MaterialSpace::parse_kind(set.space), set.E_stiff, set.decades);
  const std::int64_t cells = in.cells();
  std::vector<std::vector<std::uint8_t>> keep(static_cast<std::size_t>(cells));
#pragma omp parallel for schedule(dynamic, 64)
  for (std::int64_t c = 0; c < cells; ++c) {
    const std::int64_t n = in.count(c);
    if (n == 0) continue;
    const VecX target = design.raw.row(c).transpose();
    std::vector<double> gap(static_cast<std::size_t>(n));
    for (std::int64_t i = 0; i < n; ++i)
      gap[std::size_t(i)] =
          relative_stiffness_gap(space, set.items[std::size_t(in.structure[in.offsets[c] + i])].properties, target);
    const double bound = std::max(limit, *std::min_element(gap.begin(), gap.end()));
    keep[std::size_t(c)].resize(std::size_t(n));
    for (std::int64_t i = 0; i < n; ++i) keep[std::size_t(c)][std::size_t(i)] = gap[std::size_t(i)] <= bound;
  }
  CellCandidates out;
  out.offsets.assign(std::size_t(cells) + 1, 0);
  for (std::int64_t c = 0; c < cells; ++c) {
    for (std::int64_t i = 0; i < in.count(c); ++i)
      if (keep[std::size_t(c)][std::size_t(i)]) {
        out.structure.push_back(in.structure[in.offsets[c] + i]);
        out.distance.push_back(in.distance[in.offsets[c] + i]);
      }
    out.offsets[c + 1] = std::int64_t(out.structure.size());
  }
  return out;
}

}  // namespace

bool read_stiffness_only(const Config& config) {
  const std::string match = config.get_or<std::string>("match", std::string("all"));
  if (match != "all" && match != "stiffness") config.fail("match", "must be 'all' or 'stiffness', not '" + match + "'");
  return match == "stiffness";
}

void check_mapping_inputs(const Design& design, const std::string& design_path, const MicrostructureSet& set,
                          const std::string& structures_path) {
  if (!is_gamut_space(design.space))
    throw InputError(design_path + ": design space '" + design.space +
                     "' is not a gamut space (cubic3d, cubic2d, orthotropic2d); only designs optimized in a "
                     "microstructure gamut can be mapped to microstructures");
  if (set.items.empty()) throw InputError(structures_path + ": the microstructure set holds no structures");
  if (design.space != set.space)
    throw InputError(structures_path + ": microstructure space '" + set.space + "' differs from the design's '" +
                     design.space + "' (" + design_path + ")");
  if (design.property_names != set.property_names)
    throw InputError(structures_path + ": property names '" + joined(set.property_names) +
                     "' differ from the design's '" + joined(design.property_names) + "' (" + design_path + ")");
  const bool flat_set = set.nz == 1;
  if (design.dimension == 2 && !flat_set)
    throw InputError(structures_path + ": 3D structures (" + std::to_string(set.nx) + " x " + std::to_string(set.ny) +
                     " x " + std::to_string(set.nz) + " voxels) for the 2D design " + design_path);
  if (design.dimension == 3 && flat_set)
    throw InputError(structures_path + ": 2D structures (" + std::to_string(set.nx) + " x " + std::to_string(set.ny) +
                     " voxels) for the 3D design " + design_path);
  if (design.cells() < 1) throw InputError(design_path + ": the design has no cells");
  const Eigen::Index d = Eigen::Index(design.property_names.size());
  if (design.unit.cols() != d || design.unit.rows() != design.cells())
    throw InputError(design_path + ": /cells/unit must be cells x properties");
  if (std::int64_t(design.roles.size()) != design.cells())
    throw InputError(design_path + ": /cells/role must have one entry per cell");
  if (!design.unit.allFinite()) throw InputError(design_path + ": /cells/unit holds non-finite values");
  for (std::size_t i = 0; i < set.items.size(); ++i)
    if (set.items[i].unit.size() != d || !set.items[i].unit.allFinite())
      throw InputError(structures_path + ": structure " + std::to_string(i) + " has no finite unit properties");
}

CellCandidates design_candidates(const Design& design, const MicrostructureSet& set, const CandidateOptions& options) {
  const Eigen::Index d = design.unit.cols() - (options.stiffness_only ? 1 : 0);
  MatX points(Eigen::Index(set.items.size()), d);
  for (std::size_t i = 0; i < set.items.size(); ++i)
    points.row(Eigen::Index(i)) = set.items[i].unit.head(d).transpose();
  std::vector<bool> wanted(std::size_t(design.cells()));
  for (std::size_t c = 0; c < wanted.size(); ++c) wanted[c] = design.roles[c] == CellRole::design;
  CellCandidates found = find_candidates(design.unit.leftCols(d), wanted, points, options);
  if (options.max_gap > 0) found = keep_within_gap(found, design, set, options.max_gap);
  return found;
}

MismatchProblem mismatch_problem(const Design& design, const MicrostructureSet& set, const CellCandidates& candidates,
                                 bool half_shift, double void_pair_cost) {
  const int variants = half_shift ? 2 : 1;
  FaceTable table(set.nx, set.ny, set.nz, design.dimension);
  const int empty = table.add_uniform(0);
  const int solid = table.add_uniform(1);
  // Faces only of the structures some cell may take: entry of structure s,
  // variant v is first_entry[s] + v.
  std::vector<int> first_entry(set.items.size(), -1);
  for (std::int32_t s : candidates.structure) first_entry[std::size_t(s)] = 0;
  for (std::size_t s = 0; s < set.items.size(); ++s) {
    if (first_entry[s] < 0) continue;
    first_entry[s] = table.add(set.items[s].ids);
    if (half_shift) table.add(half_shifted(set.items[s].ids, set.nx, set.ny, set.nz));
  }
  const std::int64_t cells = design.cells();
  std::vector<std::int64_t> offsets(std::size_t(cells) + 1, 0);
  for (std::int64_t c = 0; c < cells; ++c)
    offsets[c + 1] = offsets[c] + (design.roles[c] == CellRole::design ? candidates.count(c) * variants : 1);
  std::vector<std::int32_t> options(std::size_t(offsets.back()));
  for (std::int64_t c = 0; c < cells; ++c) {
    std::int64_t o = offsets[c];
    if (design.roles[c] != CellRole::design) {
      options[o] = design.roles[c] == CellRole::empty ? empty : solid;
      continue;
    }
    for (std::int64_t j = candidates.offsets[c]; j < candidates.offsets[c + 1]; ++j)
      for (int v = 0; v < variants; ++v) options[o++] = first_entry[candidates.structure[j]] + v;
  }
  FaceGrid grid{design.dimension, design.nx, design.ny, design.nz};
  return MismatchProblem(grid, std::move(table), std::move(offsets), std::move(options), void_pair_cost);
}

MappedDesign mapped_design(const Design& design, const MicrostructureSet& set, const CellCandidates& candidates,
                           const MismatchProblem& problem, const DescentReport& report, const MapperOptions& options) {
  const int variants = options.half_shift ? 2 : 1;
  MappedDesign m;
  m.space = design.space;
  m.property_names = design.property_names;
  m.dimension = design.dimension;
  m.nx = design.nx, m.ny = design.ny, m.nz = design.nz;
  m.cell_size = design.cell_size;
  m.vx = set.nx, m.vy = set.ny, m.vz = set.nz;
  m.roles = design.roles;
  const std::size_t n = std::size_t(design.cells());
  m.structure.assign(n, -1);
  m.shift.assign(n, 0);
  m.distance.assign(n, 0.0);
  const MaterialSpace space(MaterialSpace::parse_kind(set.space), set.E_stiff, set.decades);
  // Every artifact's properties are the space's (moduli, ratios and rho);
  // a set without them has no tensor to compare and no gap.
  const bool with_gap = design.raw.cols() == space.dimension() &&
                        std::all_of(set.items.begin(), set.items.end(),
                                    [&](const Microstructure& s) { return s.properties.size() == space.dimension(); });
  if (with_gap) m.property_gap.assign(n, 0.0);
  m.candidates.assign(n, 0);
  m.mismatch.resize(n);
  for (std::size_t c = 0; c < n; ++c) {
    m.mismatch[c] = problem.energy(std::int64_t(c));
    if (design.roles[c] != CellRole::design) continue;
    const int o = problem.choice()[c];
    const std::int64_t j = candidates.offsets[c] + o / variants;
    m.structure[c] = candidates.structure[std::size_t(j)];
    m.shift[c] = static_cast<std::uint8_t>(o % variants);
    m.distance[c] = candidates.distance[std::size_t(j)];
    if (with_gap)
      m.property_gap[c] = relative_stiffness_gap(space, set.items[std::size_t(m.structure[c])].properties,
                                                 design.raw.row(Eigen::Index(c)).transpose());
    m.candidates[c] = std::int32_t(candidates.count(std::int64_t(c)));
  }
  m.history = report.history;
  m.history_cell = report.changed;
  m.k = options.candidates.k;
  m.radius = options.candidates.radius;
  m.half_shift = options.half_shift;
  m.max_distance = options.max_distance;
  m.void_pair_cost = options.void_pair_cost;
  const MismatchProblem::FacePairs pairs = problem.face_pairs();
  m.mismatch_pairs = pairs.mismatch, m.void_pairs = pairs.both_void, m.contact_pairs = pairs.contact;
  m.evaluations = report.evaluations;
  m.seconds = report.seconds;
  return m;
}

double relative_stiffness_gap(const MaterialSpace& ms, const VecX& a, const VecX& b) {
  if (a.size() != ms.dimension() || b.size() != ms.dimension())
    throw std::invalid_argument("relative_stiffness_gap: properties of another space");
  if (ms.kind() == MaterialSpaceKind::cubic3d) {
    const Mat6 Cb = ms.tensor_3d(b);
    return (ms.tensor_3d(a) - Cb).norm() / Cb.norm();
  }
  const Mat3 Cb = ms.tensor_2d(b);
  return (ms.tensor_2d(a) - Cb).norm() / Cb.norm();
}

DistanceSummary summarize_distances(const CellCandidates& candidates, const MappedDesign& mapped, double max_distance) {
  DistanceSummary s;
  for (std::int64_t c = 0; c < mapped.cells(); ++c) {
    if (mapped.roles[std::size_t(c)] != CellRole::design) continue;
    ++s.design_cells;
    const double nearest = candidates.nearest_distance(c);
    if (nearest > max_distance) ++s.far_cells;
    s.max_nearest = std::max(s.max_nearest, nearest);
    s.max_chosen = std::max(s.max_chosen, mapped.distance[std::size_t(c)]);
    if (!mapped.property_gap.empty()) {
      s.max_gap = std::max(s.max_gap, mapped.property_gap[std::size_t(c)]);
      s.mean_gap += mapped.property_gap[std::size_t(c)];
    }
  }
  if (s.design_cells > 0) s.mean_gap /= double(s.design_cells);
  return s;
}

double mapping_peak_bytes(const Design& design, const MicrostructureSet& set, const MapperOptions& options) {
  const double shifts = options.half_shift ? 2 : 1, k = options.candidates.k;
  std::int64_t design_cells = 0;
  for (CellRole role : design.roles) design_cells += role == CellRole::design;
  const double per_cell = 16 + 256 + 16.0 * double(design.raw.cols());
  const double per_design_cell = 12 * k + 4 * k * shifts;
  const double faces = 6.0 * (double(set.nx) * set.ny + double(set.ny) * set.nz + double(set.nx) * set.nz) / 3;
  return per_cell * double(design.cells()) + per_design_cell * double(design_cells) +
         4 * faces * shifts * double(set.items.size());
}

}  // namespace msfab
