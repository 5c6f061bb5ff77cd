// msfab-homogenize: periodic linear-elastic homogenization of a voxel cell
// (thesis §3.2, the property evaluation of the gamut sampler).
//
//   1. read the materials and the cell (a layout or a voxel file; one
//      voxel along z = a 2D cell, plane strain)
//   2. count the cell's connected pieces (a floating piece carries no load)
//   3. solve the six periodic cell problems, one per unit Voigt strain
//   4. C^H by the energy form, G = (C^H)^-1, volume fractions, and for a
//      cubic tensor E, nu, G and the shear-modulus ratio G'
//   5. optionally, the cell under finite uniaxial stress (Neo-Hookean)
//      against the uniaxial response of C^H (thesis §3.3)
//   6. write `msfab.homogenized`
//
// Batch mode (--structures X.microstructures.h5): steps 2-4 for every
// structure of a gamut's set, optionally refined, written as a new
// `msfab.microstructures` artifact with the properties recomputed.
#include <omp.h>
#include <spdlog/spdlog.h>

#include <algorithm>
#include <cstdio>
#include <optional>

#include "cell_input.hpp"
#include "cli/stage_app.hpp"
#include "core/errors.hpp"
#include "finite_strain_check.hpp"
#include "gamut/batch_homogenization.hpp"
#include "homog/periodic_homogenization.hpp"
#include "homogenization_options.hpp"
#include "homogenized_artifact.hpp"

using namespace msfab;

namespace {
constexpr const char* kDefaults = R"(
# A stiff cubic frame of three orthogonal bars with a soft filling (docs/homogenization.md).
materials:
  - {id: 1, name: stiff, model: linear, E: 1.0e6, nu: 0.3}
  - {id: 2, name: soft,  model: linear, E: 1.0e3, nu: 0.45}
cell: {size: [12, 12, 12]}
layout:
  - {fill: 2}
  - {box: {min: [0, 0.333, 0.333], max: [1, 0.667, 0.667]}, id: 1}
  - {box: {min: [0.333, 0, 0.333], max: [0.667, 1, 0.667]}, id: 1}
  - {box: {min: [0.333, 0.333, 0], max: [0.667, 0.667, 1]}, id: 1}
void_stiffness: 1.0e-6
use_symmetry: true
)";

// Batch mode: materials and cells come from the structures artifact.
constexpr const char* kBatchDefaults = R"(
void_stiffness: 1.0e-6
refine: 1
use_symmetry: true
)";

void run_batch(StageContext& ctx, const std::string& structures) {
  const std::string& out = ctx.require_out();
  BatchOptions options;
  options.homogenization = read_homogenization_options(ctx.config);
  options.homogenization.threads = ctx.options.threads;
  options.threads = ctx.options.threads;
  options.refine = ctx.config.get_or<int>("refine", 1);
  if (options.refine < 1 || options.refine > 16) ctx.config.fail("refine", "must be 1..16");
  for (const char* key : {"materials", "cell", "layout"})
    if (ctx.config.has(key))
      ctx.config.fail(key, "batch mode (--structures) takes materials and cells from the structures artifact; drop it");
  ctx.finish_config();
  ctx.check_out_folder();
  MicrostructureSet set = read_microstructures_artifact(structures);
  if (set.items.empty()) throw InputError(structures + ": the set holds no structures");
  spdlog::info("{}: {} structures, {} x {} x {} voxels, space {}, refine {}", structures, set.items.size(), set.nx,
               set.ny, set.nz, set.space, options.refine);
  {
    const int threads = std::max(1, ctx.options.threads > 0 ? ctx.options.threads : omp_get_max_threads());
    const int r = options.refine;
    const int nz = set.nz > 1 ? set.nz * r : 1;
    ctx.check_memory(threads * homogenization_peak_bytes(set.nx * r, set.ny * r, nz, options.homogenization.solver),
                     std::to_string(threads) + " cells of " + std::to_string(set.nx * r) + " x " +
                         std::to_string(set.ny * r) + " x " + std::to_string(nz) + " voxels solved at once",
                     "use fewer --threads or a smaller refine");
  }
  const BatchReport report = homogenize_set(set, options);
  write_microstructures_artifact(out, set, "msfab-homogenize", ctx.config.resolved_text(), {structures},
                                 ctx.options.seed);
  std::printf("msfab-homogenize: %d structures of %d x %d x %d voxels (%s), %.3f s (%.2f structures/s)\n",
              report.structures, set.nx, set.ny, set.nz, report.solver.c_str(), report.seconds,
              report.structures / report.seconds);
  if (report.solver == "matrix-free")
    std::printf("  matrix-free multigrid: %.1f CG iterations per structure (over the strain cases solved)\n",
                double(report.iterations) / report.structures);
  std::printf("  change of C^H against the input: median %.3e, max %.3e (relative Frobenius)\n",
              report.median_relative_change, report.max_relative_change);
  if (report.outside > 0)
    spdlog::warn("{} structures now lie outside the material space's box (unit coordinates clamped)", report.outside);
  std::printf("  artifact: %s\n", out.c_str());
}
}  // namespace

int main(int argc, char** argv) {
  StageApp app("msfab-homogenize", "Periodic homogenization of a voxel cell: C^H, G, cubic moduli (thesis 3.2)");
  app.add_common_options();
  std::string structures;
  app.option("--structures", structures,
             "batch mode: homogenize every structure of this msfab.microstructures artifact");
  // The defaults depend on the mode, and are needed before parsing.
  bool batch = false;
  for (int i = 1; i < argc; ++i) batch = batch || std::string(argv[i]).rfind("--structures", 0) == 0;
  app.set_default_config(batch ? kBatchDefaults : kDefaults);
  return app.run(argc, argv, [&](StageContext& ctx) {
    if (!structures.empty()) return run_batch(ctx, structures);
    const std::string& out = ctx.require_out();
    // 1. Materials and cell.
    HomogenizationOptions options = read_homogenization_options(ctx.config);
    const CellInput in = read_cell_input(ctx.config, [&](int nx, int ny, int nz) {
      ctx.check_memory(homogenization_peak_bytes(nx, ny, nz, options.solver),
                       "a " + std::to_string(nx) + " x " + std::to_string(ny) + " x " + std::to_string(nz) +
                           " cell with the " + options.solver + " solver",
                       "use a smaller cell" +
                           std::string(nz > 1 && options.solver == "cholmod" ? " or linear_solver: matrix-free" : ""));
    });
    options.threads = ctx.options.threads;
    std::optional<FiniteStrainCheck> finite_strain = read_finite_strain_check(ctx.config);
    if (finite_strain && in.cell.nz < 2) ctx.config.fail("finite_strain", "needs a 3D cell (this one is 2D)");
    ctx.finish_config();
    ctx.check_out_folder();
    spdlog::info("cell {} x {} x {}, {} materials", in.cell.nx, in.cell.ny, in.cell.nz, in.palette.size());

    // 2-4. Pieces, cell problems, tensors.
    // A cell one voxel thick along z is a 2D cell (plane strain).
    std::optional<PlaneStrainResult> plane;
    if (in.cell.nz == 1) plane = homogenize_plane_strain(in.cell, in.material_by_id, options);
    const HomogenizationResult r = plane ? plane->full : homogenize(in.cell, in.material_by_id, options);
    if (r.pieces > 1)
      spdlog::warn("the cell has {} disconnected pieces; floating ones carry no load (void_stiffness holds them)",
                   r.pieces);

    std::printf("msfab-homogenize: %d x %d x %d cell, %lld unknowns%s, %s solver, %.3f s\n", in.cell.nx, in.cell.ny,
                in.cell.nz, static_cast<long long>(r.unknowns), r.octant ? " (one octant, mirror symmetry)" : "",
                r.solver.c_str(), r.seconds);
    const char* cases = r.symmetric_cases ? "2 strain cases (4 more by the cyclic symmetry)" : "the 6 strain cases";
    if (r.solver == "matrix-free")
      std::printf("  matrix-free multigrid: %d CG iterations over %s\n", r.iterations, cases);
    else
      std::printf("  cholmod: %s\n", cases);
    std::printf("  solid fraction %.4f, pieces %d\n", 1.0 - r.volume_fraction[0], r.pieces);
    const double dev = cubic_deviation(r.C);
    if (plane) {
      const PlaneModuli m = plane_moduli(plane->C);
      std::printf("  2D plane strain: Ex %.6g, Ey %.6g, nu_xy %.6f, G %.6g\n", m.Ex, m.Ey, m.nu_xy, m.G);
    } else if (dev < kCubicTolerance) {
      const CubicModuli m = cubic_moduli(r.C);
      std::printf("  cubic: E %.6g, nu %.6f, G %.6g, G' %.4f\n", m.E, m.nu, m.G, m.shear_ratio);
    } else {
      std::printf("  not cubic (deviation %.2e): C11 %.6g C22 %.6g C33 %.6g\n", dev, r.C(0, 0), r.C(1, 1), r.C(2, 2));
    }

    // 5. Optionally, the cell under finite uniaxial stress against C^H.
    if (finite_strain) run_finite_strain_check(*finite_strain, in, r.C);

    // 6. Artifact.
    write_homogenized(out, in, r, plane ? &*plane : nullptr, finite_strain ? &*finite_strain : nullptr,
                      ctx.config.resolved_text(), ctx.command_line, ctx.options.seed);
    std::printf("  artifact: %s\n", out.c_str());
  });
}
