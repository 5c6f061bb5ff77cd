#include "sampler.hpp"

#include <algorithm>
#include <cmath>
#include <functional>
#include <optional>
#include <unordered_set>

#include "core/errors.hpp"
#include "gamut/batch_homogenization.hpp"
#include "gamut/continuous_refinement.hpp"
#include "gamut/particle_scoring.hpp"
#include "gamut/structure_evolution.hpp"
#include "gamut/structure_ops.hpp"
#include "homog/periodic_homogenization.hpp"
#include "material/linear_isotropic.hpp"
#include "parallel/fan_out.hpp"

namespace msfab {
namespace {

std::uint64_t splitmix(std::uint64_t x) {
  x += 0x9e3779b97f4a7c15ULL;
  x = (x ^ (x >> 30)) * 0xbf58476d1ce4e5b9ULL;
  x = (x ^ (x >> 27)) * 0x94d049bb133111ebULL;
  return x ^ (x >> 31);
}

// One independent stream per (seed, cycle, item, purpose): results do not
// depend on which rank or thread draws them.
std::uint64_t stream(std::uint64_t seed, int cycle, std::int64_t item, int purpose) {
  return splitmix(splitmix(splitmix(seed) ^ static_cast<std::uint64_t>(cycle)) ^
                  (static_cast<std::uint64_t>(item) << 8 | static_cast<std::uint64_t>(purpose)));
}

constexpr int kHeader = 2 + 36;  // ok, rho, C

}  // namespace

// The modulus that normalizes to 1: the stiff material's own, which in 2D
// is its plane-strain modulus E / (1 - nu^2); the solid stiff cell then
// sits on the top face of the unit cube instead of outside it.
static double modulus_scale(const SamplerOptions& o) {
  return o.kind == MaterialSpaceKind::cubic3d ? o.stiff.E : o.stiff.E / (1 - o.stiff.nu * o.stiff.nu);
}

GamutSampler::GamutSampler(const SamplerOptions& options, std::uint64_t seed)
    : o_(options), seed_(seed), space_(options.kind, modulus_scale(options), options.decades) {
  palette_ = {nullptr, std::make_shared<LinearIsotropic>(o_.stiff.E, o_.stiff.nu)};
  if (!o_.soft_is_void) palette_.push_back(std::make_shared<LinearIsotropic>(o_.soft.E, o_.soft.nu));
  void_palette_ = {nullptr, palette_[1]};
}

int GamutSampler::voxels_per_side_z() const { return o_.kind == MaterialSpaceKind::cubic3d ? o_.resolution : 1; }

VoxelGrid GamutSampler::solid_cell() const {
  return VoxelGrid(o_.resolution, o_.resolution, voxels_per_side_z(), 1.0 / o_.resolution, 1);
}

std::vector<VoxelGrid> GamutSampler::random_cuts(int cycle, int count) const {
  const VoxelGrid solid = solid_cell();
  BeamMoveOptions move = o_.move;
  move.max_beams = o_.initial_beams;
  std::vector<VoxelGrid> cells;
  for (int i = 0; i < count; ++i) cells.push_back(evolve_structure(solid, stream(seed_, cycle, i, 1), move));
  return cells;
}

VoxelGrid GamutSampler::cell_with(std::vector<int> ids) const {
  VoxelGrid c(o_.resolution, o_.resolution, voxels_per_side_z(), 1.0 / o_.resolution);
  c.ids = std::move(ids);
  return c;
}

VoxelGrid GamutSampler::cell_of(const Microstructure& m) const { return cell_with(m.ids); }

bool GamutSampler::fill_properties(Microstructure& m, const Mat6& C, double rho) const {
  m.C = C;
  m.properties = space_.cell_properties(C, rho);
  m.unit = space_.normalize(m.properties);
  return MaterialSpace::clamp_to_box(m.unit);
}

StepReport GamutSampler::add_structures(SamplerState& state, const std::vector<VoxelGrid>& given,
                                        const std::vector<std::int64_t>& parents, int cycle, SampleStep step,
                                        const std::vector<MaterialPtr>& palette) const {
  std::vector<VoxelGrid> with_backbone;
  if (o_.backbone > 0) {
    with_backbone = given;
    for (VoxelGrid& c : with_backbone) add_axis_backbone(c, o_.backbone);
  }
  const std::vector<VoxelGrid>& cells = o_.backbone > 0 ? with_backbone : given;
  StepReport report;
  report.tried = static_cast<int>(cells.size());
  std::vector<std::uint8_t> thin(cells.size(), 0);
  for (std::size_t i = 0; i < cells.size(); ++i) thin[i] = thin_feature_voxels(cells[i], o_.min_feature) > 0;
  HomogenizationOptions ho;
  ho.void_stiffness = o_.void_stiffness;
  ho.use_symmetry = ho.use_mirror_symmetry = o_.use_symmetry;
  const std::vector<double> records = fan_out(report.tried, kHeader, [&](int i, double* r) {
    if (cells[i].count_solid() == 0 || thin[i]) return;
    const HomogenizationResult h = homogenize(cells[i], palette, ho);
    r[0] = 1;
    r[1] = h.volume_fraction.size() > 1 ? h.volume_fraction[1] : 0.0;
    for (int k = 0; k < 36; ++k) r[2 + k] = h.C(k / 6, k % 6);
  });
  std::unordered_set<std::uint64_t> known;
  for (const Microstructure& m : state.set.items) known.insert(voxel_hash(m.ids));
  for (int i = 0; i < report.tried; ++i) {
    const double* r = &records[static_cast<std::size_t>(i) * kHeader];
    if (thin[i]) {
      ++report.thin;
      continue;
    }
    if (r[0] != 1) {
      ++report.failed;
      continue;
    }
    const std::uint64_t h = voxel_hash(cells[i].ids);
    if (known.count(h)) {
      ++report.duplicates;
      continue;
    }
    Microstructure m;
    m.ids = cells[i].ids;
    Mat6 C;
    for (int k = 0; k < 36; ++k) C(k / 6, k % 6) = r[2 + k];
    if (!fill_properties(m, C, r[1])) {
      ++report.outside;
      continue;
    }
    m.cycle = cycle;
    m.step = step;
    m.parent = parents[i];
    known.insert(h);
    state.set.items.push_back(std::move(m));
    state.refined.push_back(0);
    ++report.added;
  }
  return report;
}

std::vector<VoxelGrid> GamutSampler::initial_set_cells() const {
  if (o_.initial_set.empty()) return {};
  const std::string& path = o_.initial_set;
  MicrostructureSet seeds;
  try {
    seeds = read_microstructures_artifact(path);
  } catch (const InputError& e) {
    throw InputError(std::string("initial_set.path: ") + e.what());
  }
  const int r = o_.initial_refine, rz = seeds.nz == 1 ? 1 : r;
  const bool planar = voxels_per_side_z() == 1;
  const auto same = [](double a, double b) { return std::abs(a - b) <= 1e-12 * std::abs(b); };
  const std::string where = "initial_set.path " + path + ": ";
  if ((seeds.nz == 1) != planar)
    throw InputError(where + "holds " + (seeds.nz == 1 ? "2D" : "3D") + " cells, the " + o_.space + " space samples " +
                     (planar ? "2D" : "3D") + " ones");
  if (seeds.nx * r != o_.resolution || seeds.ny * r != o_.resolution || seeds.nz * rz != voxels_per_side_z())
    throw InputError(where + "cells of " + std::to_string(seeds.nx) + " voxels per side, refined " + std::to_string(r) +
                     " times, are not the sampler's resolution " + std::to_string(o_.resolution) +
                     " (set initial_set.refine)");
  if (!same(seeds.stiff.E, o_.stiff.E) || !same(seeds.stiff.nu, o_.stiff.nu) || seeds.soft_is_void != o_.soft_is_void ||
      (!o_.soft_is_void && (!same(seeds.soft.E, o_.soft.E) || !same(seeds.soft.nu, o_.soft.nu))))
    throw InputError(where + "its base materials (stiff E " + std::to_string(seeds.stiff.E) + ", nu " +
                     std::to_string(seeds.stiff.nu) + (seeds.soft_is_void ? ", void" : ", a soft material") +
                     ") are not the sampler's");
  // Two materials without void never hold void; a set of two materials and
  // void is not a start for such a run.
  if (!o_.soft_is_void && !o_.three_phase)
    for (std::size_t i = 0; i < seeds.items.size(); ++i)
      if (std::find(seeds.items[i].ids.begin(), seeds.items[i].ids.end(), 0) != seeds.items[i].ids.end())
        throw InputError(where + "structure " + std::to_string(i) +
                         " holds void, which this run of two materials does not (materials.void: true samples "
                         "two materials and void)");
  std::vector<VoxelGrid> cells;
  cells.reserve(seeds.items.size());
  for (const Microstructure& m : seeds.items)
    cells.push_back(cell_with(r == 1 ? m.ids : refine_ids(m.ids, seeds.nx, seeds.ny, seeds.nz, r)));
  return cells;
}

SamplerState GamutSampler::initialize(StepReport* report) const {
  SamplerState state;
  MicrostructureSet& set = state.set;
  set.space = o_.space;
  set.property_names = space_.names();
  set.E_stiff = modulus_scale(o_);
  set.decades = o_.decades;
  set.nx = set.ny = o_.resolution;
  set.nz = voxels_per_side_z();
  set.stiff = o_.stiff;
  set.soft = o_.soft;
  set.soft_is_void = o_.soft_is_void;

  std::vector<VoxelGrid> cells = {solid_cell()};
  if (!o_.set_only)
    for (VoxelGrid& c : random_cuts(0, o_.population)) cells.push_back(std::move(c));
  for (VoxelGrid& c : initial_set_cells()) cells.push_back(std::move(c));
  *report = add_structures(state, cells, std::vector<std::int64_t>(cells.size(), -1), 0, SampleStep::initial, palette_);
  if (state.set.items.empty())
    throw NumericalError("gamut sampler: no initial structure lies inside the material space's box");
  state.cycles_done = 0;
  resample(state, level_set(state), 0);
  return state;
}

StepReport GamutSampler::discrete_step(SamplerState& state, int cycle) const {
  std::vector<VoxelGrid> cells;
  std::vector<std::int64_t> parents;
  if (o_.random_baseline) {
    // The sampler's budget: one homogenization per particle and up to
    // max_iterations per continuous refinement.
    cells = random_cuts(cycle, o_.population + o_.continuous_per_cycle * o_.continuous.max_iterations);
    parents.assign(cells.size(), -1);
    return add_structures(state, cells, parents, cycle, SampleStep::discrete, palette_);
  }
  for (std::size_t i = 0; i < state.population.size(); ++i) {
    const std::int64_t p = state.population[i];
    cells.push_back(
        evolve_structure(cell_of(state.set.items[p]), stream(seed_, cycle, static_cast<std::int64_t>(i), 2), o_.move));
    parents.push_back(p);
  }
  return add_structures(state, cells, parents, cycle, SampleStep::discrete, palette_);
}

StepReport GamutSampler::add_refined(SamplerState& state, const std::vector<std::int64_t>& starts, int cycle,
                                     SampleStep step,
                                     const std::function<std::optional<VoxelGrid>(int)>& refine) const {
  const int voxels = o_.resolution * o_.resolution * voxels_per_side_z();
  const int record = 1 + voxels;
  const std::vector<double> records = fan_out(static_cast<int>(starts.size()), record, [&](int i, double* r) {
    const std::optional<VoxelGrid> cell = refine(i);
    if (!cell) return;
    r[0] = 1;
    for (int v = 0; v < voxels; ++v) r[1 + v] = cell->ids[v];
  });
  StepReport report;
  std::vector<VoxelGrid> cells;
  std::vector<std::int64_t> parents;
  for (std::size_t i = 0; i < starts.size(); ++i) {
    const double* r = &records[i * record];
    if (r[0] != 1) {
      ++report.failed;
      continue;
    }
    std::vector<int> ids(voxels);
    for (int v = 0; v < voxels; ++v) ids[v] = static_cast<int>(r[1 + v]);
    cells.push_back(cell_with(std::move(ids)));
    parents.push_back(starts[i]);
  }
  const StepReport added = add_structures(state, cells, parents, cycle, step, palette_);
  report.tried = static_cast<int>(starts.size());
  report.added = added.added;
  report.duplicates = added.duplicates;
  report.outside = added.outside;
  report.thin = added.thin;
  report.failed += added.failed;
  return report;
}

StepReport GamutSampler::continuous_step(SamplerState& state, const GamutLevelSet& gamut, int cycle) const {
  if (o_.continuous_per_cycle == 0 || o_.random_baseline) return {};
  // The unrefined structures nearest the boundary (ties: the older first).
  std::vector<std::pair<double, std::int64_t>> order;
  for (std::size_t i = 0; i < state.set.items.size(); ++i)
    if (!(state.refined[i] & 1))
      order.emplace_back(std::abs(gamut.value(state.set.items[i].unit)), static_cast<std::int64_t>(i));
  std::sort(order.begin(), order.end());
  order.resize(std::min<std::size_t>(order.size(), o_.continuous_per_cycle));
  std::vector<std::int64_t> starts;
  for (const auto& [distance, i] : order) starts.push_back(i), state.refined[i] |= 1;

  const int soft_id = o_.soft_is_void ? 0 : 2;
  const double step = state.push_step > 0 ? state.push_step : o_.continuous_step;
  const std::size_t before = state.set.items.size();
  StepReport report = add_refined(state, starts, cycle, SampleStep::continuous, [&](int i) -> std::optional<VoxelGrid> {
    const Microstructure& start = state.set.items[starts[i]];
    VecX g = gamut.gradient(start.unit);
    if (!(g.norm() > 1e-12)) return std::nullopt;
    VecX q = start.unit + step * g / g.norm();
    for (int a = 0; a < q.size(); ++a) q[a] = std::clamp(q[a], 0.005, 0.995);
    const VecX raw = space_.denormalize(q);
    RefinementTarget target;
    if (o_.kind == MaterialSpaceKind::cubic3d)
      target.G = space_.tensor_3d(raw).inverse();
    else
      target.G = space_.tensor_2d(raw).inverse();
    target.rho = raw[raw.size() - 1];
    return refine_structure(cell_of(start), 1, soft_id, palette_[1], o_.soft_is_void ? nullptr : palette_[2], target,
                            o_.continuous)
        .structure;
  });
  report.step = step;
  for (std::size_t i = before; i < state.set.items.size(); ++i)
    report.expanded += gamut.value(state.set.items[i].unit) > 0;
  state.push_step = step;
  if (o_.continuous_adaptive && report.tried > 0) {
    const double progress = double(report.expanded) / report.tried;
    if (progress >= 0.5)
      state.push_step = std::min(1.5 * step, 4 * o_.continuous_step);
    else if (progress < 0.25)
      state.push_step = std::max(step / 1.5, o_.continuous_step / 4);
  }
  return report;
}

StepReport GamutSampler::directed_step(SamplerState& state, int cycle) const {
  if (o_.directed_per_cycle == 0 || o_.random_baseline) return {};
  std::vector<std::int64_t> starts;
  std::vector<VecX> directions;  // per start
  for (std::size_t k = 0; k < o_.directed_objectives.size(); ++k) {
    const VecX d = directed_direction(space_, o_.directed_objectives[k]);
    const std::uint8_t bit = static_cast<std::uint8_t>(2u << k);
    // The structures furthest along the objective (ties: the older first).
    std::vector<std::pair<double, std::int64_t>> order;
    for (std::size_t i = 0; i < state.set.items.size(); ++i)
      if (!(state.refined[i] & bit)) order.emplace_back(-d.dot(state.set.items[i].unit), static_cast<std::int64_t>(i));
    std::sort(order.begin(), order.end());
    for (std::size_t i = 0; i < order.size() && i < static_cast<std::size_t>(o_.directed_per_cycle); ++i) {
      starts.push_back(order[i].second);
      directions.push_back(d);
      state.refined[order[i].second] |= bit;
    }
  }
  const int soft_id = o_.soft_is_void ? 0 : 2;
  return add_refined(state, starts, cycle, SampleStep::directed, [&](int i) -> std::optional<VoxelGrid> {
    const Microstructure& start = state.set.items[starts[i]];
    DirectedTarget target;
    target.direction = directions[i];
    // Floors on the moduli the objective leaves alone: the push may not buy
    // its direction with a collapse of the stiffness.
    target.floor = VecX::Constant(target.direction.size(), -1.0);
    for (int a = 0; a < target.direction.size(); ++a)
      if (target.direction[a] == 0 && space_.is_modulus(a)) target.floor[a] = start.unit[a] - o_.directed_modulus_drop;
    ContinuousResult c = refine_structure_directed(
        cell_of(start), 1, soft_id, palette_[1], o_.soft_is_void ? nullptr : palette_[2], space_, target, o_.directed);
    if (!c.found) return std::nullopt;
    return std::move(c.structure);
  });
}

SamplerState GamutSampler::void_variants(const SamplerState& state, StepReport* report) const {
  SamplerState out;
  out.set = state.set;
  out.set.items.clear();
  out.set.soft_is_void = true;
  out.set.soft = BaseMaterial{};
  out.cycles_done = state.cycles_done;
  std::vector<VoxelGrid> cells;
  std::vector<std::int64_t> parents;
  for (std::size_t i = 0; i < state.set.items.size(); ++i) {
    VoxelGrid c = cell_of(state.set.items[i]);
    for (int& id : c.ids)
      if (id == 2) id = 0;
    clean_structure(c);
    cells.push_back(std::move(c));
    parents.push_back(static_cast<std::int64_t>(i));
  }
  *report = add_structures(out, cells, parents, state.cycles_done, SampleStep::void_variant, void_palette_);
  return out;
}

GamutLevelSet GamutSampler::level_set(const SamplerState& state) const {
  std::vector<VecX> points;
  points.reserve(state.set.items.size());
  for (const Microstructure& m : state.set.items) points.push_back(m.unit);
  return GamutLevelSet::from_points(points, o_.level_set);
}

void GamutSampler::resample(SamplerState& state, const GamutLevelSet& gamut, int cycle) const {
  const std::size_t n = state.set.items.size();
  std::vector<VecX> units;
  for (const Microstructure& m : state.set.items) units.push_back(m.unit);
  std::vector<double> weights(n);
#pragma omp parallel for schedule(static)
  for (std::int64_t i = 0; i < static_cast<std::int64_t>(n); ++i) {
    const double D = sample_density(units[i], units, o_.density_radius);
    weights[i] = particle_score(gamut.value(units[i]), D, o_.boundary_depth);
  }
  double total = 0;
  for (double w : weights) total += w;
  if (!(total > 0)) std::fill(weights.begin(), weights.end(), 1.0);  // nothing near the boundary: uniform
  const double u0 = double(stream(seed_, cycle, 0, 3) >> 11) * 0x1.0p-53;
  const std::vector<int> picks = systematic_resample(weights, o_.population, u0);
  state.population.assign(picks.begin(), picks.end());
}

}  // namespace msfab
