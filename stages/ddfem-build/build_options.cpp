#include "build_options.hpp"

#include "core/errors.hpp"
#include "io/material_config.hpp"

namespace msfab {

BuildOptions read_build_options(const Config& config) {
  BuildOptions o;
  if (config.has("base_database")) o.base_database = config.get_path("base_database");
  if (!o.base_database.empty()) {
    if (config.has("palette")) config.fail("palette", "a level-2 build takes its palette from base_database");
    if (config.has("symmetry")) config.fail("symmetry", "applies to level-1 builds only");
    if (config.has("level2")) {
      const Config l = config.child("level2");
      HierarchyOptions& h = o.hierarchy;
      if (l.has("representatives")) {
        const auto k = l.get<std::vector<int>>("representatives");
        if (k.size() != 3)
          l.fail("representatives", "expected three counts [x, y, z], got " + std::to_string(k.size()));
        for (int i = 0; i < 3; ++i) {
          if (k[i] < 1) l.fail("representatives", "counts must be >= 1");
          h.representatives[i] = k[i];
        }
      }
      h.deformations = l.get_or<int>("deformations", h.deformations);
      if (h.deformations < 1) l.fail("deformations", "must be >= 1");
      h.strain = l.get_or<double>("strain", h.strain);
      if (!(h.strain > 0 && h.strain < 0.5)) l.fail("strain", "must be in (0, 0.5)");
      h.seed = l.get_or<std::uint64_t>("seed", h.seed);
      h.corner_moves = l.get_or<bool>("corner_moves", h.corner_moves);
      const std::string samples = l.get_or<std::string>("samples", "level1");
      if (samples != "level1" && samples != "voxels")
        l.fail("samples",
               "must be level1 (2 x 2 x 2 level-1 elements) or voxels (4 x 4 x 4 fine voxels), got '" + samples + "'");
      o.level2_voxel_samples = samples == "voxels";
      l.check_no_unknown_keys();
    }
  } else if (config.has("level2")) {
    config.fail("level2", "needs base_database (a level-1 database)");
  }
  const std::vector<Config> palette = o.base_database.empty() ? config.children("palette") : std::vector<Config>{};
  if (palette.empty() && o.base_database.empty())
    config.fail("palette", "must list at least one material (or give base_database for a level-2 build)");
  for (const Config& m : palette) {
    DbMaterial d;
    d.name = m.get_or("name", "");
    const ElasticConstants elastic = read_elastic_constants(m);
    d.E = elastic.E;
    d.nu = elastic.nu;
    d.density = read_density(m, 1000.0);
    m.check_no_unknown_keys();
    o.materials.push_back(d);
  }
  if (o.materials.size() > 15) config.fail("palette", "at most 15 materials (16^8 combinations)");
  o.voxel_size = config.get_or<double>("voxel_size", 1e-3);
  if (!(o.voxel_size > 0)) config.fail("voxel_size", "must be > 0");

  if (config.has("sampling")) {
    const Config s = config.child("sampling");
    ForceSamplingOptions& f = o.fit.sampling;
    f.include_axes = s.get_or<bool>("include_axes", f.include_axes);
    f.sphere_directions = s.get_or<int>("sphere_directions", f.sphere_directions);
    if (f.sphere_directions < 0) s.fail("sphere_directions", "must be >= 0");
    f.magnitudes = s.get_or<int>("magnitudes", f.magnitudes);
    if (f.magnitudes < 1) s.fail("magnitudes", "must be >= 1");
    f.max_strain = s.get_or<double>("max_strain", f.max_strain);
    if (!(f.max_strain > 0 && f.max_strain < 1)) s.fail("max_strain", "must be in (0, 1)");
    f.seed = s.get_or<std::uint64_t>("seed", f.seed);
    f.newton_tolerance = s.get_or<double>("newton_tolerance", f.newton_tolerance);
    if (!(f.newton_tolerance > 0)) s.fail("newton_tolerance", "must be > 0");
    const std::string mode = s.get_or<std::string>("mode", sampling_mode_name(f.mode));
    if (mode != "isolated" && mode != "patch" && mode != "periodic")
      s.fail("mode", "must be isolated, patch or periodic, got '" + mode + "'");
    f.mode = parse_sampling_mode(mode);
    f.context = s.get_or<int>("context", f.context);
    if (f.context < 1 || f.context > 4) s.fail("context", "must be 1 to 4 voxels of periodic copies");
    s.check_no_unknown_keys();
  }
  if (config.has("anisotropy")) {
    const Config a = config.child("anisotropy");
    AnisotropyOptions& an = o.fit.anisotropy;
    an.directions = a.get_or<int>("directions", an.directions);
    if (an.directions < 3) a.fail("directions", "must be >= 3");
    an.strain = a.get_or<double>("strain", an.strain);
    if (!(an.strain > 0 && an.strain < 1)) a.fail("strain", "must be in (0, 1)");
    an.seed = a.get_or<std::uint64_t>("seed", an.seed);
    a.check_no_unknown_keys();
  }
  if (config.has("fit")) {
    const Config f = config.child("fit");
    o.fit.regularization = f.get_or<double>("regularization", o.fit.regularization);
    if (!(o.fit.regularization >= 0)) f.fail("regularization", "must be >= 0");
    o.fit.heldout_fraction = f.get_or<double>("heldout_fraction", o.fit.heldout_fraction);
    if (!(o.fit.heldout_fraction >= 0 && o.fit.heldout_fraction < 1)) f.fail("heldout_fraction", "must be in [0, 1)");
    o.fit.split_seed = f.get_or<std::uint64_t>("split_seed", o.fit.split_seed);
    o.fit.anisotropic = f.get_or<bool>("anisotropic", o.fit.anisotropic);
    o.fit.centre_point = f.get_or<bool>("centre_point", o.fit.centre_point);
    const std::string element = f.get_or<std::string>("element", o.fit.enhanced_element ? "enhanced" : "trilinear");
    if (element != "trilinear" && element != "enhanced") f.fail("element", "must be trilinear or enhanced");
    o.fit.enhanced_element = element == "enhanced";
    o.fit.bubble_rounds = f.get_or<int>("bubble_rounds", o.fit.bubble_rounds);
    if (o.fit.bubble_rounds < 1 || o.fit.bubble_rounds > 100) f.fail("bubble_rounds", "must be in 1..100");
    o.fit.kind_weight[int(ForceKind::pinch)] = f.get_or<double>("pinch_weight", o.fit.kind_weight[4]);
    if (!(o.fit.kind_weight[4] >= 0)) f.fail("pinch_weight", "must be >= 0");
    for (ForceKind kind : {ForceKind::stretch, ForceKind::shear, ForceKind::bend, ForceKind::twist}) {
      const std::string key = force_kind_name(kind) + "_weight";
      double& w = o.fit.kind_weight[int(kind)];
      w = f.get_or<double>(key, w);
      if (!(w >= 0)) f.fail(key, "must be >= 0");
    }
    o.fit.mixed_blocks_affine_only = f.get_or<bool>("mixed_affine_only", o.fit.mixed_blocks_affine_only);
    const std::string residual = f.get_or<std::string>("residual", fit_residual_name(o.fit.residual));
    try {
      o.fit.residual = parse_fit_residual(residual);
    } catch (const InputError& e) {
      f.fail("residual", e.what());
    }
    o.fit.balance_kinds = f.get_or<bool>("balance_kinds", o.fit.balance_kinds);
    f.check_no_unknown_keys();
  }
  if (config.has("void_children")) {
    if (!o.base_database.empty())
      config.fail("void_children", "applies to level-1 builds only (level 2 takes the level-1 database's blocks)");
    o.void_children = config.get<bool>("void_children");
    // An isolated or patch sample loads the block's own nodes; a void child
    // leaves its coarse corner without a fine node and its solid children
    // may hang together by an edge. Among periodic copies every corner class
    // has material and the sample prescribes the corners.
    if (o.void_children && o.fit.sampling.mode != ForceSamplingOptions::Mode::periodic)
      config.fail("void_children",
                  "needs sampling.mode: periodic (blocks with void children are sampled among "
                  "their periodic copies)");
  }
  if (o.level2_voxel_samples && o.fit.sampling.mode != ForceSamplingOptions::Mode::periodic)
    config.child("level2").fail("samples",
                                "voxels needs sampling.mode: periodic (a block of 4 x 4 x 4 voxels is "
                                "sampled among its periodic copies)");
  o.use_symmetry = config.get_or<bool>("symmetry", o.use_symmetry);
  o.orbits_per_round = config.get_or<int>("orbits_per_round", o.orbits_per_round);
  if (o.orbits_per_round < 1) config.fail("orbits_per_round", "must be >= 1");
  return o;
}

}  // namespace msfab
