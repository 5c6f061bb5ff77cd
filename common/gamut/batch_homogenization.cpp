#include "gamut/batch_homogenization.hpp"

#include <omp.h>

#include <algorithm>
#include <chrono>

#include "cli/progress.hpp"
#include "core/errors.hpp"
#include "gamut/material_space.hpp"
#include "solve/sparse_ops.hpp"

namespace msfab {

std::vector<int> refine_ids(const std::vector<int>& ids, int nx, int ny, int nz, int refine) {
  const int rz = nz == 1 ? 1 : refine;
  const int NX = nx * refine, NY = ny * refine, NZ = nz * rz;
  std::vector<int> out(std::size_t(NX) * NY * NZ);
  for (int k = 0; k < NZ; ++k)
    for (int j = 0; j < NY; ++j)
      for (int i = 0; i < NX; ++i)
        out[i + std::size_t(NX) * (j + std::size_t(NY) * k)] =
            ids[i / refine + std::size_t(nx) * (j / refine + std::size_t(ny) * (k / rz))];
  return out;
}

BatchReport homogenize_set(MicrostructureSet& set, const BatchOptions& options) {
  const auto start = std::chrono::steady_clock::now();
  if (options.refine < 1) throw InputError("refine must be >= 1");
  const int r = options.refine, rz = set.nz == 1 ? 1 : r;
  const int NX = set.nx * r, NY = set.ny * r, NZ = set.nz * rz;
  if (std::max({NX, NY, NZ}) > 4096) throw InputError("refine: the refined cell would exceed 4096 voxels per axis");
  const MaterialSpace space(MaterialSpace::parse_kind(set.space), set.E_stiff, set.decades);
  const std::vector<MaterialPtr> palette = base_palette(set);

  BatchReport report;
  report.structures = static_cast<int>(set.items.size());
  report.solver = homogenization_solver(NX, NY, NZ, options.homogenization.solver);
  const int threads = resolve_thread_count(options.threads);
  const bool across = report.structures >= threads;
  HomogenizationOptions ho = options.homogenization;
  ho.threads = across ? 1 : threads;
  std::vector<double> change(set.items.size(), 0.0);
  std::vector<int> iterations(set.items.size(), 0), outside(set.items.size(), 0);
  Progress progress("homogenizing structures", set.items.size());
#pragma omp parallel for schedule(dynamic) num_threads(across ? threads : 1)
  for (std::int64_t s = 0; s < static_cast<std::int64_t>(set.items.size()); ++s) {
    Microstructure& m = set.items[s];
    VoxelGrid cell(NX, NY, NZ, 1.0 / NX);
    cell.ids = r == 1 ? m.ids : refine_ids(m.ids, set.nx, set.ny, set.nz, r);
    const HomogenizationResult h = homogenize(cell, palette, ho);
    const double rho = h.volume_fraction.size() > 1 ? h.volume_fraction[1] : 0.0;
    change[s] = (h.C - m.C).norm() / m.C.norm();
    iterations[s] = h.iterations;
    m.ids = std::move(cell.ids);
    m.C = h.C;
    m.properties = space.cell_properties(h.C, rho);
    m.unit = space.normalize(m.properties);
    outside[s] = !MaterialSpace::clamp_to_box(m.unit);
    progress.tick();
  }
  progress.done();
  set.nx = NX, set.ny = NY, set.nz = NZ;
  for (std::size_t s = 0; s < set.items.size(); ++s) {
    report.max_relative_change = std::max(report.max_relative_change, change[s]);
    report.iterations += iterations[s];
    report.outside += outside[s];
  }
  if (!change.empty()) {
    std::nth_element(change.begin(), change.begin() + change.size() / 2, change.end());
    report.median_relative_change = change[change.size() / 2];
  }
  report.seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  return report;
}

}  // namespace msfab
