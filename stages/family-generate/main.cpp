// msfab-family-generate: structures from a family's reduced parameters
// (thesis Appendix A). For each requested r in [-1, 1]^2 the family's full
// template parameters are interpolated between its base and its plus/minus
// templates, the template's beams are drawn at the requested resolution and
// mirrored by the 48 symmetries of the cube, and the structures are
// homogenized, so the result is a `msfab.microstructures` set that the
// mapper, the homogenizer and the optimizer read like any gamut's.
//
//   msfab-family-generate --families out/families/auxetic.families.h5 --family 1
//       --reduced 0.5,-0.2 --set resolution=64 --out family1.microstructures.h5
//   msfab-family-generate ... --sweep 5     # each reduced parameter over 5 values in [-1, 1], the others 0
//
// Without --families the structures come from templates written out in the
// config (`templates:`, beams in unit-cell coordinates), each drawn at
// `count` cross-section scales evenly spread over `scale`: hand-made
// families, e.g. to check that family discovery finds them again.
#include <omp.h>
#include <spdlog/spdlog.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <sstream>

#include "cli/stage_app.hpp"
#include "core/errors.hpp"
#include "families/beam_template.hpp"
#include "families/families_artifact.hpp"
#include "families/family_selection.hpp"
#include "gamut/batch_homogenization.hpp"
#include "gamut/microstructure_set.hpp"
#include "gamut/structure_ops.hpp"
#include "homog/periodic_homogenization.hpp"

using namespace msfab;

namespace {

constexpr const char* kDefaults = R"(
resolution: 0       # voxels per cell edge; 0: the family's input set's resolution (16 for templates)
homogenize: true    # compute C^H and the properties of every structure (false: ids only, properties 0)
material: {E: 1.0e6, nu: 0.3}   # templates: the base material (with --families: the family's own)
decades: 4          # templates: the normalization of the moduli
# templates:        # without --families: explicit templates, e.g.
#   - caps: true
#     beams: [{a: [0, 0, 0], b: [0.5, 0.5, 0.5], r0: 0.06, r1: 0.04, theta: 0}]
#     scale: [0.8, 1.2]   # cross-section sizes times values evenly spread over this range
#     count: 10           # thicknesses
#     moves: 1            # end positions per thickness, from a, b to a beam's a_to, b_to
)";

struct TemplateRequest {
  BeamTemplate tpl;
  std::vector<Vec3> a_to, b_to;  // per beam: where its ends move over the sweep
  std::vector<double> scales;
  int moves = 1;  // end positions per scale (from a, b to a_to, b_to)
};

// A beam's ends `a` and `b` (unit-cell coordinates) from its config item.
Beam read_beam_ends(const Config& b) {
  Beam beam;
  for (const char* key : {"a", "b"}) {
    const std::vector<double> v = b.get<std::vector<double>>(key);
    if (v.size() != 3) b.fail(key, "must be [x, y, z] in unit-cell coordinates");
    (std::string(key) == "a" ? beam.a : beam.b) = Vec3(v[0], v[1], v[2]);
  }
  return beam;
}

// The config's `templates:` list.
std::vector<TemplateRequest> read_templates(const Config& config) {
  std::vector<TemplateRequest> out;
  if (!config.has("templates")) return out;
  const std::vector<Config> items = config.children("templates");
  for (std::size_t t = 0; t < items.size(); ++t) {
    const Config& item = items[t];
    TemplateRequest req;
    req.tpl.caps = item.get_or<bool>("caps", true);
    const std::vector<Config> beams = item.children("beams");
    if (beams.empty()) item.fail("beams", "needs at least one beam");
    for (const Config& b : beams) {
      Beam beam = read_beam_ends(b);
      beam.r0 = b.require_positive("r0", "cross-section half-size");
      beam.r1 = b.require_positive("r1", "cross-section half-size");
      beam.theta = b.get_or<double>("theta", 0.0);
      // Optional ends at the last member of the sweep (moved linearly).
      Vec3 to[2] = {beam.a, beam.b};
      for (int e = 0; e < 2; ++e) {
        const char* key = e == 0 ? "a_to" : "b_to";
        if (!b.has(key)) continue;
        const std::vector<double> v = b.get<std::vector<double>>(key);
        if (v.size() != 3) b.fail(key, "must be [x, y, z] in unit-cell coordinates");
        to[e] = Vec3(v[0], v[1], v[2]);
      }
      req.a_to.push_back(to[0]);
      req.b_to.push_back(to[1]);
      req.tpl.beams.push_back(beam);
    }
    const std::vector<double> scale = item.get_or<std::vector<double>>("scale", {1.0, 1.0});
    if (scale.size() != 2 || !(scale[0] > 0 && scale[1] >= scale[0]))
      item.fail("scale", "must be [low, high] with 0 < low <= high");
    const int count = item.get_or<int>("count", 1);
    if (count < 1 || count > 10000) item.fail("count", "must be 1..10000");
    for (int c = 0; c < count; ++c)
      req.scales.push_back(count == 1 ? scale[0] : scale[0] + (scale[1] - scale[0]) * c / (count - 1));
    req.moves = item.get_or<int>("moves", 1);
    if (req.moves < 1 || req.moves > 1000) item.fail("moves", "must be 1..1000");
    out.push_back(std::move(req));
  }
  return out;
}

// The config's `grid:`: one template whose beams take their half-sizes
// from the axes of a tensor grid. The set records the grid
// (MicrostructureSet::grid), so a two-scale design can move along the
// family's parameters (topopt space family3d).
struct GridRequest {
  BeamTemplate tpl;
  std::vector<int> beam_axis;  // per beam: the axis its half-size comes from
  StructureGrid grid;
  bool empty() const { return grid.empty(); }
};

GridRequest read_grid(const Config& config) {
  GridRequest req;
  if (!config.has("grid")) return req;
  const Config g = config.child("grid");
  req.tpl.caps = g.get_or<bool>("caps", true);
  const std::vector<Config> parameters = g.children("parameters");
  if (parameters.empty() || parameters.size() > 3) g.fail("parameters", "needs 1 to 3 parameters");
  for (const Config& p : parameters) {
    const std::string name = p.get<std::string>("name");
    if (name.empty() || name.find(',') != std::string::npos) p.fail("name", "must be non-empty, without commas");
    for (const std::string& other : req.grid.names)
      if (other == name) p.fail("name", "'" + name + "' is given twice");
    const std::vector<double> values = p.get<std::vector<double>>("values");
    if (values.empty() || values.size() > 64) p.fail("values", "needs 1 to 64 values");
    for (std::size_t i = 0; i < values.size(); ++i)
      if (!(std::isfinite(values[i]) && values[i] >= 0 && values[i] <= 1) || (i > 0 && !(values[i] > values[i - 1])))
        p.fail("values", "half-sizes must lie in [0, 1] and increase strictly");
    req.grid.names.push_back(name);
    req.grid.axes.push_back(values);
  }
  const std::vector<Config> beams = g.children("beams");
  if (beams.empty()) g.fail("beams", "needs at least one beam");
  for (const Config& b : beams) {
    Beam beam = read_beam_ends(b);
    beam.theta = b.get_or<double>("theta", 0.0);
    const std::string name = b.get<std::string>("parameter");
    const auto it = std::find(req.grid.names.begin(), req.grid.names.end(), name);
    if (it == req.grid.names.end()) b.fail("parameter", "'" + name + "' is not one of grid.parameters");
    req.beam_axis.push_back(int(it - req.grid.names.begin()));
    req.tpl.beams.push_back(beam);
  }
  return req;
}

// The grid point's template: each beam at its axis's half-size, beams of
// half-size 0 left out.
BeamTemplate grid_template(const GridRequest& req, const std::vector<int>& index) {
  BeamTemplate tpl;
  tpl.caps = req.tpl.caps;
  for (std::size_t b = 0; b < req.tpl.beams.size(); ++b) {
    const double r = req.grid.axes[std::size_t(req.beam_axis[b])][std::size_t(index[std::size_t(req.beam_axis[b])])];
    if (r == 0) continue;
    Beam beam = req.tpl.beams[b];
    beam.r0 = beam.r1 = r;
    tpl.beams.push_back(beam);
  }
  return tpl;
}

// "0.5,-0.2" -> {0.5, -0.2}; InputError naming the option on anything else.
std::vector<double> parse_reduced(const std::string& text) {
  std::vector<double> r;
  std::stringstream in(text);
  std::string item;
  while (std::getline(in, item, ',')) {
    std::size_t used = 0;
    double v = 0;
    try {
      v = std::stod(item, &used);
    } catch (const std::exception&) {
      used = 0;
    }
    if (used == 0 || item.find_first_not_of(" \t", used) != std::string::npos)
      throw InputError("--reduced " + text + ": '" + item + "' is not a number");
    r.push_back(v);
  }
  if (r.empty()) throw InputError("--reduced " + text + ": no values");
  return r;
}

std::string reduced_text(const std::vector<double>& r) {
  std::string s;
  for (std::size_t j = 0; j < r.size(); ++j) s += (j ? "," : "") + std::to_string(r[j]).substr(0, 6);
  return s;
}

// A set of the given cells, homogenized on request.
MicrostructureSet make_set(std::vector<VoxelGrid> cells, int resolution, double E_stiff, double decades,
                           BaseMaterial stiff, bool homogenize, int threads) {
  MicrostructureSet set;
  set.space = "cubic3d";
  set.property_names = {"E", "nu", "G", "rho"};
  set.E_stiff = E_stiff;
  set.decades = decades;
  set.nx = set.ny = set.nz = resolution;
  set.stiff = stiff;
  set.soft_is_void = true;
  for (VoxelGrid& cell : cells) {
    if (!has_cubic_symmetry(cell)) throw std::logic_error("a template rasterized without cubic symmetry");
    Microstructure m;
    m.ids = std::move(cell.ids);
    m.properties = VecX::Zero(4);
    m.unit = VecX::Zero(4);
    set.items.push_back(std::move(m));
  }
  if (homogenize) {
    BatchOptions options;
    options.threads = threads;
    options.homogenization.threads = threads;
    homogenize_set(set, options);
  }
  return set;
}

}  // namespace

int main(int argc, char** argv) {
  StageApp app("msfab-family-generate", "Structures from a family's reduced template parameters (thesis Appendix A)");
  app.add_common_options();
  app.set_default_config(kDefaults);
  std::string families_path;
  int family = 0, sweep = 0;
  std::vector<std::string> reduced_options;
  app.option("--families", families_path, "msfab.families artifact (without it: the config's templates)")
      .type_name("FILE");
  app.option("--family", family, "family number, from 1 (with --families)");
  app.option("--reduced", reduced_options, "reduced parameters r1,r2 in [-1, 1] (repeatable)").type_name("R1,R2");
  app.option("--sweep", sweep, "each reduced parameter over N values in [-1, 1], the others 0").type_name("N");
  return app.run(argc, argv, [&](StageContext& ctx) {
    int resolution = ctx.config.get_or<int>("resolution", 0);
    if (resolution < 0 || resolution > 512) ctx.config.fail("resolution", "must be 0..512 (0: the input set's)");
    const bool homogenize = ctx.config.get_or<bool>("homogenize", true);
    BaseMaterial material{ctx.config.get_or<double>("material.E", 1e6), ctx.config.get_or<double>("material.nu", 0.3)};
    if (!(material.E > 0)) ctx.config.fail("material.E", "must be > 0");
    if (!(material.nu > -1 && material.nu < 0.5)) ctx.config.fail("material.nu", "must be in (-1, 0.5)");
    double decades = ctx.config.get_or<double>("decades", 4.0);
    if (!(decades > 0)) ctx.config.fail("decades", "must be > 0");
    const std::vector<TemplateRequest> templates = read_templates(ctx.config);
    const GridRequest grid = read_grid(ctx.config);
    if (!grid.empty() && !templates.empty()) ctx.config.fail("grid", "give either templates or a grid, not both");
    if (!grid.empty() && !families_path.empty()) ctx.config.fail("grid", "is for generating without --families");
    ctx.finish_config();
    const std::string out = ctx.require_out();
    ctx.check_out_folder();

    std::vector<VoxelGrid> cells;
    std::vector<std::string> labels;
    std::vector<std::string> inputs;
    double E_stiff = material.E;
    // The cells (4 bytes per voxel, twice: the rasterized grids and the set)
    // and, when homogenizing, one cell problem per thread (docs/cli.md,
    // "Memory").
    const auto check_memory = [&](std::size_t count, int n, const std::string& what) {
      const double voxels = double(n) * n * n;
      const double threads = ctx.options.threads > 0 ? ctx.options.threads : omp_get_max_threads();
      const double per_cell = homogenize ? homogenization_peak_bytes(n, n, n, "auto") : 0.0;
      ctx.check_memory(8.0 * voxels * double(count) + threads * per_cell,
                       std::to_string(count) + " structures of " + std::to_string(n) + "^3 voxels (" + what + ")",
                       "generate fewer structures or lower the resolution");
    };
    if (!grid.empty()) {
      // One template over a grid of half-sizes, first axis slowest.
      if (family != 0 || sweep != 0 || !reduced_options.empty())
        throw InputError("--family, --reduced and --sweep need --families");
      if (resolution == 0) resolution = 16;
      check_memory(grid.grid.points(), resolution, "grid.parameters");
      for (std::size_t i = 0; i < grid.grid.points(); ++i) {
        std::vector<int> index(grid.grid.axes.size());
        std::size_t rest = i;
        for (std::size_t a = grid.grid.axes.size(); a-- > 0;) {
          index[a] = int(rest % grid.grid.axes[a].size());
          rest /= grid.grid.axes[a].size();
        }
        const BeamTemplate tpl = grid_template(grid, index);
        std::string label;
        for (std::size_t a = 0; a < index.size(); ++a)
          label += (a ? ", " : "") + grid.grid.names[a] + " " +
                   std::to_string(grid.grid.axes[a][std::size_t(index[a])]).substr(0, 5);
        if (tpl.beams.empty()) ctx.config.fail("grid.parameters", "the point (" + label + ") leaves every beam out");
        cells.push_back(rasterize_template(tpl, resolution));
        labels.push_back(label);
      }
    } else if (families_path.empty()) {
      // Hand-written templates.
      if (templates.empty())
        throw InputError("nothing to generate: give --families FILE --family K, or templates or a grid in the config");
      if (family != 0 || sweep != 0 || !reduced_options.empty())
        throw InputError("--family, --reduced and --sweep need --families");
      if (resolution == 0) resolution = 16;
      std::size_t members = 0;
      for (const TemplateRequest& req : templates) members += req.scales.size() * std::size_t(req.moves);
      check_memory(members, resolution, "templates");
      for (std::size_t t = 0; t < templates.size(); ++t) {
        const TemplateRequest& req = templates[t];
        const std::size_t count = req.scales.size() * std::size_t(req.moves);
        for (std::size_t c = 0; c < count; ++c) {
          const int move = int(c % std::size_t(req.moves));
          const double s = req.moves > 1 ? double(move) / double(req.moves - 1) : 0.0;
          const double scale = req.scales[c / std::size_t(req.moves)];
          BeamTemplate tpl = req.tpl;
          for (std::size_t b = 0; b < tpl.beams.size(); ++b) {
            Beam& beam = tpl.beams[b];
            beam.a += s * (req.a_to[b] - beam.a);
            beam.b += s * (req.b_to[b] - beam.b);
            beam.r0 *= scale, beam.r1 *= scale;
          }
          cells.push_back(rasterize_template(tpl, resolution));
          labels.push_back("template " + std::to_string(t + 1) + ", member " + std::to_string(c + 1));
        }
      }
    } else {
      // A family's reduced parameters.
      if (!templates.empty()) ctx.config.fail("templates", "is for generating without --families; drop one of them");
      if (sweep == 1 || sweep < 0) throw InputError("--sweep " + std::to_string(sweep) + ": needs at least 2 values");
      const FamiliesResult families = read_families_artifact(families_path);
      if (family < 1 || std::size_t(family) > families.families.size())
        throw InputError("--family " + std::to_string(family) + ": " + families_path + " holds " +
                         std::to_string(families.families.size()) + " families (numbered from 1)");
      const FamilyRecord& fam = families.families[std::size_t(family - 1)];
      if (!fam.has_reduced)
        throw InputError(families_path + ": family " + std::to_string(family) +
                         " has no reduced parameters (too few members fit its template)");
      if (resolution == 0) resolution = families.resolution;
      material = {families.stiff_E, families.stiff_nu};
      E_stiff = families.E_stiff;
      decades = families.decades;
      inputs.push_back(families_path);

      std::vector<std::vector<double>> requests;
      for (const std::string& text : reduced_options) requests.push_back(parse_reduced(text));
      const std::size_t reduced_count = fam.reduced.plus.size();
      check_memory(
          std::max<std::size_t>(1, reduced_options.size() + (sweep >= 2 ? reduced_count * std::size_t(sweep) : 0)),
          resolution, "--sweep and --reduced");
      for (std::size_t j = 0; sweep >= 2 && j < reduced_count; ++j)
        for (int s = 0; s < sweep; ++s) {
          std::vector<double> r(reduced_count, 0.0);
          r[j] = -1.0 + 2.0 * s / (sweep - 1);
          requests.push_back(r);
        }
      if (requests.empty()) requests.push_back(std::vector<double>(reduced_count, 0.0));
      for (const std::vector<double>& r : requests) {
        const VecX parameters = reduced_to_parameters(fam.reduced, r);  // InputError outside [-1, 1]
        cells.push_back(rasterize_template(template_from_parameters(parameters, fam.caps), resolution));
        labels.push_back("r = (" + reduced_text(r) + ")");
      }
      std::printf("msfab-family-generate: family %d of %s; predicted per unit r_j (r_j > 0):", family,
                  families_path.c_str());
      for (Eigen::Index j = 0; j < fam.reduced.property_slope.cols(); ++j)
        std::printf(" r%d: dlog10E %+.3f, dnu %+.3f;", int(j + 1), fam.reduced.property_slope(0, j),
                    fam.reduced.property_slope(1, j));
      std::printf("\n");
    }

    MicrostructureSet set =
        make_set(std::move(cells), resolution, E_stiff, decades, material, homogenize, ctx.options.threads);
    set.grid = grid.grid;
    write_microstructures_artifact(out, set, "msfab-family-generate", ctx.config.resolved_text(), inputs,
                                   ctx.options.seed);
    std::printf("msfab-family-generate: %zu structures of %d^3 voxels\n", set.items.size(), resolution);
    for (std::size_t i = 0; i < set.items.size(); ++i) {
      const Microstructure& m = set.items[i];
      std::size_t solid = 0;
      for (int id : m.ids) solid += id != 0;
      const double fraction = double(solid) / double(m.ids.size());
      if (homogenize)
        std::printf("  %s: solid %.3f, E/E_stiff %.4g, nu %.4f, G' %.4f\n", labels[i].c_str(), fraction,
                    m.properties[0] / set.E_stiff, m.properties[1],
                    shear_modulus_ratio(m.properties[0], m.properties[1], m.properties[2]));
      else
        std::printf("  %s: solid %.3f\n", labels[i].c_str(), fraction);
    }
    std::printf("  artifact: %s\n", out.c_str());
  });
}
