// Benchmark of one FEM solve of 3D topology optimization (GridElasticity):
// a cantilever of nx x ny x nz unit cells clamped at x = 0, a total load of
// -1 in z spread over the nodes of the edge x = nx, z = 0; isotropic SIMP
// stiffness (E = 1, nu = 0.3, penalty 3, E_min 1e-9) from a density field:
//   uniform  rho = 0.5 everywhere (the first design iteration)
//   random   rho uniform in [0, 1] per cell (contrast up to 1e9 between neighbours)
// Prints one table row: cells, unknowns, solver, setup (assembly +
// factorization / hierarchy) seconds, solve seconds, CG iterations, peak
// resident memory, and the compliance f.u (to compare solvers).
// Usage: bench_grid_solver nx ny nz solver [uniform|random] [--tolerance T]
#include <sys/resource.h>

#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <random>
#include <string>

#include "core/errors.hpp"
#include "topopt/cell_grid.hpp"
#include "topopt/grid_elasticity.hpp"

using namespace msfab;

namespace {

double now() { return std::chrono::duration<double>(std::chrono::steady_clock::now().time_since_epoch()).count(); }

double peak_memory_mb() {
  rusage usage{};
  getrusage(RUSAGE_SELF, &usage);
  return usage.ru_maxrss / 1024.0;
}

}  // namespace

int main(int argc, char** argv) {
  if (argc < 5) {
    std::fprintf(stderr, "usage: %s nx ny nz solver [uniform|random] [--tolerance T]\n", argv[0]);
    return 2;
  }
  const int nx = std::atoi(argv[1]), ny = std::atoi(argv[2]), nz = std::atoi(argv[3]);
  const std::string solver = argv[4];
  std::string field = "uniform";
  double tolerance = 1e-8;
  for (int a = 5; a < argc; ++a) {
    if (!std::strcmp(argv[a], "--tolerance") && a + 1 < argc)
      tolerance = std::atof(argv[++a]);
    else
      field = argv[a];
  }
  if (field != "uniform" && field != "random") {
    std::fprintf(stderr, "field must be uniform or random\n");
    return 2;
  }
  try {
    const CellGrid grid(3, nx, ny, nz, 1.0);
    std::vector<char> fixed(grid.unknowns(), 0);
    for (int k = 0; k <= nz; ++k)
      for (int j = 0; j <= ny; ++j)
        for (int d = 0; d < 3; ++d) fixed[3 * grid.node_index(0, j, k) + d] = 1;
    VecX force = VecX::Zero(grid.unknowns());
    for (int j = 0; j <= ny; ++j) force[3 * grid.node_index(nx, j, 0) + 2] = -1.0 / (ny + 1);

    // Isotropic C0 (E = 1, nu = 0.3) scaled by E_min + rho^3 (1 - E_min).
    const double nu = 0.3, lambda = nu / ((1 + nu) * (1 - 2 * nu)), mu = 1 / (2 * (1 + nu));
    VecX C0 = VecX::Zero(grid.voigt_pairs());
    for (int s = 0; s < 3; ++s) {
      for (int t = s; t < 3; ++t) C0[CellGrid::pair_index(s, t, 6)] = s == t ? lambda + 2 * mu : lambda;
      C0[CellGrid::pair_index(3 + s, 3 + s, 6)] = mu;
    }
    std::mt19937 rng(1);
    std::uniform_real_distribution<double> u(0.0, 1.0);
    MatX pairs(grid.cells(), grid.voigt_pairs());
    for (std::int64_t c = 0; c < grid.cells(); ++c) {
      const double rho = field == "uniform" ? 0.5 : u(rng);
      pairs.row(c) = ((1e-9 + std::pow(rho, 3) * (1 - 1e-9)) * C0).transpose();
    }

    LinearSolverOptions options;
    options.pcg_tolerance = tolerance;
    const double t0 = now();
    GridElasticity elasticity(grid, fixed, solver, options);
    elasticity.set_stiffness(pairs);
    const double t1 = now();
    const VecX x = elasticity.solve(force);
    const double t2 = now();
    std::printf("| %dx%dx%d | %lld | %s | %s | %.2f | %.2f | %lld | %.0f | %.10e |\n", nx, ny, nz,
                static_cast<long long>(grid.unknowns()), elasticity.solver_name().c_str(), field.c_str(), t1 - t0,
                t2 - t1, elasticity.stats().iterations, peak_memory_mb(), force.dot(x));
    return 0;
  } catch (const std::exception& e) {
    std::fprintf(stderr, "bench_grid_solver: %s\n", e.what());
    return 1;
  }
}
