#include "sampler_options.hpp"

#include <algorithm>
#include <filesystem>

#include "core/errors.hpp"
#include "io/material_config.hpp"

namespace msfab {

const char* const kDefaultSamplerConfig = R"(# A small 2D cubic gamut: two materials 100x apart (docs/gamut.md).
space: cubic2d            # cubic3d | cubic2d | orthotropic2d
resolution: 16            # voxels per cell side (2D cells are n x n x 1)
materials:
  stiff: {E: 1.0e6, nu: 0.3}
  soft:  {E: 1.0e4, nu: 0.45}   # leave out for stiff material and void
  void: false               # true with soft: two materials and void (discrete sampling only)
population: 24
cycles: 6                 # the most; stop earlier once the coverage stops growing:
stop: {coverage_growth: 0, window: 3}   # relative growth of the best coverage over `window` cycles below which the run ends (0: off)
initial_beams: 8
beams: {max: 3, min_radius: 0.5, max_radius: 2.0}
continuous: {per_cycle: 4, step: 0.1, adaptive_step: false, max_iterations: 30, penalty: 3, filter_radius: 1.5, density_weight: 1.0, start_offset: 0.3, projection_beta: 0}
# Pushes along named objectives (min_nu | max_nu | min_shear | max_shear); per_cycle 0: none.
directed: {objectives: [min_nu], per_cycle: 0, modulus_drop: 0.25, max_iterations: 150, projection_beta: 16, filter_radius: 2.5}
level_set: {cells: 16, margin: 0.1, smoothing_steps: 2}
density_radius: 0.1
boundary_depth: 0.1
decades: 4
void_stiffness: 1.0e-6
use_symmetry: true        # cell problems on the symmetric part (exact); false: six cases on the whole cell
min_feature: 1            # the printer's smallest beam or gap, voxels (1: no limit)
backbone: 0               # half-width (voxels) of axis beams through the centre that every structure keeps (0: none)
mode: sampler             # sampler | random (the benchmark's baseline) | set (initial_set's structures alone)
void_variants: false      # also write the structures with the soft material removed (thesis 3.6.1)
)";

namespace {
BaseMaterial read_base(const Config& m) {
  BaseMaterial b;
  const ElasticConstants elastic = read_elastic_constants(m);
  b.E = elastic.E;
  b.nu = elastic.nu;
  m.check_no_unknown_keys();
  return b;
}
const std::vector<std::string> kDirectedObjectives = {"min_nu", "max_nu", "min_shear", "max_shear"};

}  // namespace

double best_coverage(const std::vector<GamutCycle>& history, std::size_t through) {
  double best = 0;
  for (std::size_t c = 0; c <= through && c < history.size(); ++c) best = std::max(best, history[c].coverage);
  return best;
}

double best_coverage_growth(const std::vector<GamutCycle>& history, int window) {
  if (history.empty() || window < 1) return 0;
  const std::size_t last = history.size() - 1;
  const double before = best_coverage(history, last - std::min<std::size_t>(window, last));
  return before > 0 ? best_coverage(history, last) / before - 1 : 0;
}

bool coverage_converged(const std::vector<GamutCycle>& history, double growth, int window) {
  if (!(growth > 0) || window < 1 || static_cast<int>(history.size()) <= window) return false;
  const double before = best_coverage(history, history.size() - 1 - window);
  return before > 0 && best_coverage_growth(history, window) < growth;
}

VecX directed_direction(const MaterialSpace& space, const std::string& objective) {
  VecX d = VecX::Zero(space.dimension());
  const bool ortho = space.kind() == MaterialSpaceKind::orthotropic2d;
  const int nu = ortho ? 2 : 1, shear = ortho ? 3 : 2;
  if (objective == "min_nu")
    d[nu] = -1;
  else if (objective == "max_nu")
    d[nu] = 1;
  else if (objective == "min_shear")
    d[shear] = -1;
  else if (objective == "max_shear")
    d[shear] = 1;
  else
    throw InputError("directed objective '" + objective + "': expected min_nu, max_nu, min_shear or max_shear");
  return d;
}

SamplerOptions read_sampler_options(const Config& config) {
  SamplerOptions o;
  if (config.has("space")) o.space = config.one_of("space", {"cubic3d", "cubic2d", "orthotropic2d"});
  o.kind = MaterialSpace::parse_kind(o.space);
  o.resolution = config.get_or<int>("resolution", o.resolution);
  if (o.resolution < 4 || o.resolution > 128) config.fail("resolution", "must be in 4..128");
  const Config mats = config.child("materials");
  o.stiff = read_base(mats.child("stiff"));
  o.soft_is_void = !mats.has("soft");
  if (!o.soft_is_void) {
    o.soft = read_base(mats.child("soft"));
    if (!(o.soft.E < o.stiff.E)) mats.fail("soft", "E must be below the stiff material's");
  }
  if (mats.has("void")) {
    const bool with_void = mats.get_or<bool>("void", false);
    if (o.soft_is_void && !with_void)
      mats.fail("void", "false needs materials.soft (without it the second phase is void)");
    o.three_phase = with_void && !o.soft_is_void;
  }
  mats.check_no_unknown_keys();
  o.decades = config.get_or<double>("decades", o.decades);
  if (!(o.decades > 0 && o.decades <= 12)) config.fail("decades", "must be in (0, 12]");
  o.void_stiffness = config.get_or<double>("void_stiffness", o.void_stiffness);
  if (!(o.void_stiffness > 0 && o.void_stiffness < 1e-2)) config.fail("void_stiffness", "must be in (0, 0.01)");

  o.use_symmetry = config.get_or<bool>("use_symmetry", o.use_symmetry);
  o.population = config.get_or<int>("population", o.population);
  if (o.population < 2) config.fail("population", "must be >= 2");
  o.cycles = config.get_or<int>("cycles", o.cycles);
  if (o.cycles < 0) config.fail("cycles", "must be >= 0");
  if (config.has("stop")) {
    const Config st = config.child("stop");
    o.stop_coverage_growth = st.get_or<double>("coverage_growth", o.stop_coverage_growth);
    if (!(o.stop_coverage_growth >= 0 && o.stop_coverage_growth < 1))
      st.fail("coverage_growth", "must be in [0, 1) (relative growth; 0 runs all cycles)");
    o.stop_window = st.get_or<int>("window", o.stop_window);
    if (o.stop_window < 1 || o.stop_window > 1000) st.fail("window", "must be in 1..1000 (cycles)");
    st.check_no_unknown_keys();
  }
  o.initial_beams = config.get_or<int>("initial_beams", o.initial_beams);
  if (o.initial_beams < 1) config.fail("initial_beams", "must be >= 1");
  if (config.has("beams")) {
    const Config b = config.child("beams");
    o.move.max_beams = b.get_or<int>("max", o.move.max_beams);
    if (o.move.max_beams < 1) b.fail("max", "must be >= 1");
    o.move.min_radius = b.get_or<double>("min_radius", o.move.min_radius);
    o.move.max_radius = b.get_or<double>("max_radius", o.move.max_radius);
    if (!(o.move.min_radius > 0) || !(o.move.max_radius >= o.move.min_radius))
      b.fail("max_radius", "need 0 < min_radius <= max_radius");
    b.check_no_unknown_keys();
  }
  o.move.materials = o.three_phase ? 2 : 1;
  o.move.cut_id = o.soft_is_void || o.three_phase ? 0 : 2;
  o.move.symmetry = o.kind == MaterialSpaceKind::orthotropic2d ? CellSymmetry::orthotropic : CellSymmetry::cubic;

  if (config.has("continuous")) {
    const Config c = config.child("continuous");
    o.continuous_per_cycle = c.get_or<int>("per_cycle", o.continuous_per_cycle);
    if (o.continuous_per_cycle < 0) c.fail("per_cycle", "must be >= 0");
    o.continuous_step = c.get_or<double>("step", o.continuous_step);
    if (!(o.continuous_step > 0 && o.continuous_step <= 1)) c.fail("step", "must be in (0, 1]");
    o.continuous_adaptive = c.get_or<bool>("adaptive_step", o.continuous_adaptive);
    ContinuousOptions& k = o.continuous;
    k.max_iterations = c.get_or<int>("max_iterations", k.max_iterations);
    if (k.max_iterations < 1) c.fail("max_iterations", "must be >= 1");
    k.penalty = c.get_or<double>("penalty", k.penalty);
    if (!(k.penalty >= 1)) c.fail("penalty", "must be >= 1");
    k.filter_radius = c.get_or<double>("filter_radius", k.filter_radius);
    if (!(k.filter_radius >= 0)) c.fail("filter_radius", "must be >= 0");
    k.density_weight = c.get_or<double>("density_weight", k.density_weight);
    if (!(k.density_weight >= 0)) c.fail("density_weight", "must be >= 0");
    k.start_offset = c.get_or<double>("start_offset", k.start_offset);
    if (!(k.start_offset >= 0 && k.start_offset < 0.5)) c.fail("start_offset", "must be in [0, 0.5)");
    k.projection_beta = c.get_or<double>("projection_beta", k.projection_beta);
    if (!(k.projection_beta >= 0 && k.projection_beta <= 1024)) c.fail("projection_beta", "must be in [0, 1024]");
    c.check_no_unknown_keys();
  }
  o.min_feature = config.get_or<int>("min_feature", o.min_feature);
  if (o.min_feature < 1 || o.min_feature > o.resolution / 2)
    config.fail("min_feature", "must be in 1..resolution/2 (" + std::to_string(o.resolution / 2) + ")");
  o.continuous.min_feature = o.min_feature;
  o.backbone = config.get_or<int>("backbone", o.backbone);
  if (o.backbone < 0 || o.backbone > o.resolution / 2)
    config.fail("backbone", "must be in 0..resolution/2 (" + std::to_string(o.resolution / 2) + "; 0: none)");
  if (o.backbone > 0 && !o.soft_is_void && !o.three_phase)
    config.fail("backbone",
                "needs a void phase (leave out materials.soft, or set materials.void: true): with two "
                "materials every cell is solid");
  o.continuous.void_stiffness = o.void_stiffness;
  o.continuous.symmetry = o.move.symmetry;
  o.continuous.use_symmetry = o.use_symmetry;

  o.directed = o.continuous;  // min_feature, void_stiffness, symmetry, use_symmetry
  o.directed.max_iterations = 150;
  o.directed.projection_beta = 16;
  o.directed.filter_radius = 2.5;
  o.directed_objectives = {"min_nu"};
  if (config.has("directed")) {
    const Config d = config.child("directed");
    o.directed_objectives = d.get_or<std::vector<std::string>>("objectives", o.directed_objectives);
    if (o.directed_objectives.empty() || o.directed_objectives.size() > 4) d.fail("objectives", "needs 1 to 4 names");
    for (std::size_t i = 0; i < o.directed_objectives.size(); ++i) {
      const std::string& name = o.directed_objectives[i];
      if (std::find(kDirectedObjectives.begin(), kDirectedObjectives.end(), name) == kDirectedObjectives.end())
        d.fail("objectives", "'" + name + "' is not one of min_nu, max_nu, min_shear, max_shear");
      if (std::find(o.directed_objectives.begin(), o.directed_objectives.begin() + i, name) !=
          o.directed_objectives.begin() + i)
        d.fail("objectives", "'" + name + "' is listed twice");
    }
    o.directed_per_cycle = d.get_or<int>("per_cycle", o.directed_per_cycle);
    if (o.directed_per_cycle < 0 || o.directed_per_cycle > 10000) d.fail("per_cycle", "must be in 0..10000");
    o.directed_modulus_drop = d.get_or<double>("modulus_drop", o.directed_modulus_drop);
    if (!(o.directed_modulus_drop > 0 && o.directed_modulus_drop <= 1)) d.fail("modulus_drop", "must be in (0, 1]");
    ContinuousOptions& k = o.directed;
    k.max_iterations = d.get_or<int>("max_iterations", k.max_iterations);
    if (k.max_iterations < 1 || k.max_iterations > 100000) d.fail("max_iterations", "must be in 1..100000");
    k.projection_beta = d.get_or<double>("projection_beta", k.projection_beta);
    if (!(k.projection_beta >= 0 && k.projection_beta <= 1024)) d.fail("projection_beta", "must be in [0, 1024]");
    k.filter_radius = d.get_or<double>("filter_radius", k.filter_radius);
    if (!(k.filter_radius >= 0 && k.filter_radius <= 64)) d.fail("filter_radius", "must be in [0, 64]");
    k.penalty = d.get_or<double>("penalty", k.penalty);
    if (!(k.penalty >= 1 && k.penalty <= 16)) d.fail("penalty", "must be in [1, 16]");
    d.check_no_unknown_keys();
  }

  // The continuous and directed steps interpolate between two phases
  // (SIMP stiff/soft or stiff/void); a third has no place in them.
  const auto refuse_step = [&](const std::string& step, int per_cycle, const std::string& what) {
    const std::string why = "must be 0 with two materials and void (materials.void: true): " + what;
    if (config.has(step)) config.child(step).fail("per_cycle", why);
    config.fail(step, "per_cycle is " + std::to_string(per_cycle) + " by default and " + why);
  };
  if (o.three_phase && o.continuous_per_cycle > 0)
    refuse_step("continuous", o.continuous_per_cycle, "the continuous step interpolates between two phases");
  if (o.three_phase && o.directed_per_cycle > 0)
    refuse_step("directed", o.directed_per_cycle, "directed pushes interpolate between two phases");

  if (config.has("level_set")) {
    const Config l = config.child("level_set");
    o.level_set.cells = l.get_or<int>("cells", o.level_set.cells);
    if (o.level_set.cells < 4 || o.level_set.cells > 64) l.fail("cells", "must be in 4..64");
    o.level_set.margin = l.get_or<double>("margin", o.level_set.margin);
    if (!(o.level_set.margin >= 0 && o.level_set.margin <= 0.5)) l.fail("margin", "must be in [0, 0.5]");
    o.level_set.smoothing_steps = l.get_or<int>("smoothing_steps", o.level_set.smoothing_steps);
    if (o.level_set.smoothing_steps < 0) l.fail("smoothing_steps", "must be >= 0");
    l.check_no_unknown_keys();
  }
  o.density_radius = config.get_or<double>("density_radius", o.density_radius);
  if (!(o.density_radius > 0 && o.density_radius <= 1)) config.fail("density_radius", "must be in (0, 1]");
  o.boundary_depth = config.get_or<double>("boundary_depth", o.boundary_depth);
  if (!(o.boundary_depth > 0 && o.boundary_depth <= 1)) config.fail("boundary_depth", "must be in (0, 1]");
  o.void_variants = config.get_or<bool>("void_variants", o.void_variants);
  if (o.void_variants && o.soft_is_void)
    config.fail("void_variants", "needs a soft material to remove (materials.soft)");
  if (config.has("mode")) {
    const std::string mode = config.one_of("mode", {"sampler", "random", "set"});
    o.random_baseline = mode == "random";
    o.set_only = mode == "set";
  }
  if (config.has("initial_set")) {
    const Config seeds = config.child("initial_set");
    o.initial_set = seeds.get_path("path");
    if (std::error_code ec; !std::filesystem::is_regular_file(o.initial_set, ec))
      seeds.fail("path", o.initial_set + ": no such file (a microstructures artifact)");
    o.initial_refine = seeds.get_or<int>("refine", 1);
    if (o.initial_refine < 1 || o.initial_refine > 8) seeds.fail("refine", "must be in 1..8");
    seeds.check_no_unknown_keys();
  }
  if (o.set_only && o.initial_set.empty()) config.fail("mode", "set needs initial_set.path (the structures to keep)");
  if (o.set_only && o.cycles != 0)
    config.fail("cycles", "must be 0 with mode: set (the gamut of the given structures, nothing sampled)");
  return o;
}

}  // namespace msfab
