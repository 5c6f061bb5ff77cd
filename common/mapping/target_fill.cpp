#include "mapping/target_fill.hpp"

#include <algorithm>
#include <cmath>
#include <string>
#include <unordered_set>

#include "core/errors.hpp"
#include "gamut/batch_homogenization.hpp"
#include "gamut/material_space.hpp"
#include "gamut/structure_ops.hpp"
#include "homog/periodic_homogenization.hpp"
#include "mapping/candidates.hpp"
#include "mapping/mapper.hpp"

namespace msfab {
namespace {

MaterialSpace space_of(const MicrostructureSet& set) {
  return MaterialSpace(MaterialSpace::parse_kind(set.space), set.E_stiff, set.decades);
}

// The coordinates candidates are found by (design_candidates).
Eigen::Index search_columns(const MicrostructureSet& set, const CandidateOptions& o) {
  return Eigen::Index(set.property_names.size()) - (o.stiffness_only ? 1 : 0);
}

MatX unit_points(const MicrostructureSet& set, Eigen::Index columns) {
  MatX points(Eigen::Index(set.items.size()), columns);
  for (std::size_t i = 0; i < set.items.size(); ++i)
    points.row(Eigen::Index(i)) = set.items[i].unit.head(columns).transpose();
  return points;
}

// Structures ordered by gap to `raw` (ties: the earlier in `indices`, i.e. nearer).
std::vector<std::pair<double, std::int32_t>> by_gap(const MaterialSpace& space, const MicrostructureSet& set,
                                                    const std::vector<std::int32_t>& indices, const VecX& raw) {
  std::vector<std::pair<double, std::int32_t>> out;
  for (std::int32_t s : indices)
    out.emplace_back(relative_stiffness_gap(space, set.items[std::size_t(s)].properties, raw), s);
  std::stable_sort(out.begin(), out.end(), [](const auto& a, const auto& b) { return a.first < b.first; });
  return out;
}

}  // namespace

std::int64_t CellCoverage::above(double limit) const {
  std::int64_t n = 0;
  for (std::size_t c = 0; c < gap.size(); ++c) n += best[c] >= 0 && gap[c] > limit;
  return n;
}

CellCoverage cell_coverage(const Design& design, const MicrostructureSet& set, const CandidateOptions& candidates) {
  if (candidates.k < 1) throw InputError("candidates must be >= 1");
  const MaterialSpace space = space_of(set);
  const CellCandidates found = design_candidates(design, set, candidates);
  const std::int64_t cells = design.cells();
  CellCoverage out;
  out.gap.assign(std::size_t(cells), 0.0);
  out.best.assign(std::size_t(cells), -1);
#pragma omp parallel for schedule(dynamic, 16)
  for (std::int64_t c = 0; c < cells; ++c) {
    if (design.roles[std::size_t(c)] != CellRole::design || found.count(c) == 0) continue;
    const std::vector<std::int32_t> indices(found.structure.begin() + found.offsets[c],
                                            found.structure.begin() + found.offsets[c + 1]);
    const auto ranked = by_gap(space, set, indices, design.raw.row(c).transpose());
    out.gap[std::size_t(c)] = ranked.front().first;
    out.best[std::size_t(c)] = ranked.front().second;
  }
  double sum = 0;
  for (std::int64_t c = 0; c < cells; ++c) {
    if (out.best[std::size_t(c)] < 0) continue;
    ++out.design_cells;
    sum += out.gap[std::size_t(c)];
    out.max_gap = std::max(out.max_gap, out.gap[std::size_t(c)]);
  }
  out.mean_gap = out.design_cells ? sum / double(out.design_cells) : 0.0;
  return out;
}

std::vector<FillTarget> plan_targets(const Design& design, const MicrostructureSet& set, const CellCoverage& coverage,
                                     const FillPlanOptions& options) {
  if (!(options.gap > 0) || !std::isfinite(options.gap)) throw InputError("gap must be a finite number > 0");
  if (options.candidates.k < 1) throw InputError("candidates must be >= 1");
  if (options.starts < 1 || options.starts > options.candidates.k) throw InputError("starts must be 1..candidates");
  if (!(options.cluster_radius >= 0) || !std::isfinite(options.cluster_radius))
    throw InputError("cluster_radius must be a finite number >= 0");
  if (options.max_targets < 0) throw InputError("max_targets must be >= 0");
  std::vector<std::int64_t> open;  // uncovered design cells, worst first
  for (std::int64_t c = 0; c < design.cells(); ++c)
    if (coverage.best[std::size_t(c)] >= 0 && coverage.gap[std::size_t(c)] > options.gap) open.push_back(c);
  std::stable_sort(open.begin(), open.end(), [&](std::int64_t a, std::int64_t b) {
    return coverage.gap[std::size_t(a)] > coverage.gap[std::size_t(b)];
  });

  const MaterialSpace space = space_of(set);
  const Eigen::Index columns = search_columns(set, options.candidates);
  const KdTree tree(unit_points(set, columns));
  std::vector<bool> taken(open.size(), false);
  std::vector<FillTarget> targets;
  for (std::size_t i = 0; i < open.size() && int(targets.size()) < options.max_targets; ++i) {
    if (taken[i]) continue;
    FillTarget t;
    const VecX centre = design.unit.row(open[i]).head(columns).transpose();
    VecX sum = VecX::Zero(design.unit.cols());
    for (std::size_t j = i; j < open.size(); ++j) {
      if (taken[j] || (design.unit.row(open[j]).head(columns).transpose() - centre).norm() > options.cluster_radius)
        continue;
      taken[j] = true;
      t.cells.push_back(open[j]);
      sum += design.unit.row(open[j]).transpose();
    }
    t.unit = sum / double(t.cells.size());
    t.raw = space.denormalize(t.unit);
    const VecX query = t.unit.head(columns);
    std::vector<std::int32_t> near;
    for (const Neighbour& n : tree.nearest(query.data(), options.candidates.k)) near.push_back(n.index);
    const auto ranked = by_gap(space, set, near, t.raw);
    t.gap = ranked.front().first;
    for (int s = 0; s < options.starts && s < int(ranked.size()); ++s)
      t.starts.push_back(ranked[std::size_t(s)].second);
    targets.push_back(std::move(t));
  }
  return targets;
}

GeneratedStructure generate_at_target(const MicrostructureSet& set, const FillTarget& target,
                                      const ContinuousOptions& options, double void_stiffness) {
  const MaterialSpace space = space_of(set);
  const bool plane = set.nz == 1;
  RefinementTarget goal;
  goal.G = plane ? MatX(space.tensor_2d(target.raw).inverse()) : MatX(space.tensor_3d(target.raw).inverse());
  goal.rho = target.raw[target.raw.size() - 1];
  ContinuousOptions o = options;
  o.void_stiffness = void_stiffness;
  o.symmetry = space.kind() == MaterialSpaceKind::orthotropic2d ? CellSymmetry::orthotropic : CellSymmetry::cubic;
  const std::vector<MaterialPtr> palette = base_palette(set);
  const MaterialPtr stiff = palette[1], soft = set.soft_is_void ? nullptr : palette[2];
  const int soft_id = set.soft_is_void ? 0 : 2;
  HomogenizationOptions ho;
  ho.void_stiffness = void_stiffness;
  ho.use_symmetry = ho.use_mirror_symmetry = options.use_symmetry;
  ho.threads = 1;  // targets run in parallel, one thread each

  GeneratedStructure best;
  for (std::int32_t s : target.starts) {
    VoxelGrid cell(set.nx, set.ny, set.nz, 1.0 / set.nx);
    cell.ids = set.items[std::size_t(s)].ids;
    const ContinuousResult r = refine_structure(cell, 1, soft_id, stiff, soft, goal, o);
    if (!r.found || r.structure.count_solid() == 0) continue;
    const HomogenizationResult h = homogenize(r.structure, palette, ho);
    const double rho = h.volume_fraction.size() > 1 ? h.volume_fraction[1] : 0.0;
    VecX properties = space.cell_properties(h.C, rho);
    VecX unit = space.normalize(properties);
    if (!MaterialSpace::clamp_to_box(unit)) continue;
    const double gap = relative_stiffness_gap(space, properties, target.raw);
    if (best.found && !(gap < best.gap)) continue;
    best.found = true;
    best.ids = r.structure.ids;
    best.C = h.C;
    best.rho = rho;
    best.gap = gap;
    best.parent = s;
  }
  return best;
}

std::vector<std::uint8_t> add_face_connector(MicrostructureSet& set, int half_width, int depth, double void_stiffness) {
  const VoxelGrid probe(set.nx, set.ny, set.nz, 1.0 / set.nx);
  const std::vector<std::uint8_t> mask = face_connector(probe, half_width, depth);
  for (Microstructure& m : set.items)
    for (std::size_t v = 0; v < mask.size(); ++v)
      if (mask[v]) m.ids[v] = 1;
  BatchOptions batch;
  batch.homogenization.void_stiffness = void_stiffness;
  homogenize_set(set, batch);
  return mask;
}

int generated_record_size(const MicrostructureSet& set) { return 4 + 36 + set.nx * set.ny * set.nz; }

void write_generated_record(const GeneratedStructure& g, double* r) {
  r[0] = g.found ? 1 : 0;
  r[1] = g.gap;
  r[2] = g.parent;
  r[3] = g.rho;
  for (int k = 0; k < 36; ++k) r[4 + k] = g.C(k / 6, k % 6);
  for (std::size_t v = 0; v < g.ids.size(); ++v) r[40 + v] = g.ids[v];
}

GeneratedStructure read_generated_record(const MicrostructureSet& set, const double* r) {
  GeneratedStructure g;
  g.found = r[0] == 1;
  if (!g.found) return g;
  g.gap = r[1];
  g.parent = static_cast<std::int32_t>(r[2]);
  g.rho = r[3];
  for (int k = 0; k < 36; ++k) g.C(k / 6, k % 6) = r[4 + k];
  g.ids.resize(std::size_t(set.nx) * set.ny * set.nz);
  for (std::size_t v = 0; v < g.ids.size(); ++v) g.ids[v] = static_cast<int>(r[40 + v]);
  return g;
}

int append_generated(MicrostructureSet& set, const std::vector<FillTarget>& targets,
                     const std::vector<GeneratedStructure>& generated, int round) {
  if (targets.size() != generated.size()) throw std::invalid_argument("append_generated: one result per target");
  const MaterialSpace space = space_of(set);
  std::unordered_set<std::uint64_t> known;
  for (const Microstructure& m : set.items) known.insert(voxel_hash(m.ids));
  int added = 0;
  for (std::size_t t = 0; t < targets.size(); ++t) {
    const GeneratedStructure& g = generated[t];
    if (!g.found || !(g.gap < targets[t].gap)) continue;
    if (!known.insert(voxel_hash(g.ids)).second) continue;
    Microstructure m;
    m.ids = g.ids;
    m.C = g.C;
    m.properties = space.cell_properties(g.C, g.rho);
    m.unit = space.normalize(m.properties);
    MaterialSpace::clamp_to_box(m.unit);
    m.cycle = round;
    m.step = SampleStep::targeted;
    m.parent = g.parent;
    set.items.push_back(std::move(m));
    ++added;
  }
  return added;
}

}  // namespace msfab
