// Benchmark of the pcg-mg linear solver on a fibers-like voxel bar: a soft
// Neo-Hookean block (E = 1e5) with stiff helical fibers (E = 1e7), nu = 0.45,
// clamped at y = 0, rest-state stiffness. Not part of the build; compile by
// hand against the common library (one line):
//   g++ -O2 -march=x86-64-v2 -fopenmp -std=c++17 -I common -isystem /usr/include/eigen3
//     -isystem /usr/include/suitesparse tools/bench_multigrid.cpp
//     build-multigrid/common/libmsfab_common.a -lcholmod -lmetis -o /tmp/bench_multigrid
// and run with OMP_NUM_THREADS set.
// Usage: bench_multigrid [nx ny nz] [--degree D] [--coarse N] [--cholmod] [--solves K]
#include <sys/resource.h>

#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <memory>
#include <string>
#include <vector>

#include "fem/elastic_assembler.hpp"
#include "fem/voxel_grid.hpp"
#include "material/neo_hookean.hpp"
#include "solve/cholmod_solver.hpp"
#include "solve/multigrid_solver.hpp"
#include "solve/sparse_ops.hpp"

using namespace msfab;

namespace {

double now() { return std::chrono::duration<double>(std::chrono::steady_clock::now().time_since_epoch()).count(); }

double cpu_seconds() {
  rusage usage{};
  getrusage(RUSAGE_SELF, &usage);
  return usage.ru_utime.tv_sec + 1e-6 * usage.ru_utime.tv_usec;
}

// Four helical fibers of radius 2.5 voxels winding around the bar axis (y).
VoxelGrid fibers_grid(int nx, int ny, int nz) {
  VoxelGrid grid(nx, ny, nz, 1e-3, 1);
  const double cx = 0.5 * nx, cz = 0.5 * nz;
  const double orbit = 0.28 * std::min(nx, nz), radius = 2.5;
  const double pitch = 0.5 * ny;
  for (int k = 0; k < nz; ++k) {
    for (int j = 0; j < ny; ++j) {
      for (int i = 0; i < nx; ++i) {
        const double x = i + 0.5 - cx, y = j + 0.5, z = k + 0.5 - cz;
        for (int fiber = 0; fiber < 4; ++fiber) {
          const double angle = 2.0 * M_PI * (y / pitch + 0.25 * fiber);
          if (std::hypot(x - orbit * std::cos(angle), z - orbit * std::sin(angle)) < radius) {
            grid.at(i, j, k) = 2;
          }
        }
      }
    }
  }
  return grid;
}

struct Timer {
  double wall = now(), cpu = cpu_seconds();
  void report(const char* what) {
    std::printf("%-28s wall %7.3f s   user CPU %7.3f s\n", what, now() - wall, cpu_seconds() - cpu);
    wall = now();
    cpu = cpu_seconds();
  }
};

}  // namespace

int main(int argc, char** argv) {
  int dims[3] = {32, 100, 32};
  int degree = 2, coarse = 3000, solves = 2;
  bool with_cholmod = false;
  int positional = 0;
  for (int a = 1; a < argc; ++a) {
    if (!std::strcmp(argv[a], "--degree") && a + 1 < argc)
      degree = std::atoi(argv[++a]);
    else if (!std::strcmp(argv[a], "--coarse") && a + 1 < argc)
      coarse = std::atoi(argv[++a]);
    else if (!std::strcmp(argv[a], "--solves") && a + 1 < argc)
      solves = std::atoi(argv[++a]);
    else if (!std::strcmp(argv[a], "--cholmod"))
      with_cholmod = true;
    else if (positional < 3)
      dims[positional++] = std::atoi(argv[a]);
  }
  std::printf("grid %d x %d x %d voxels, threads %d, Chebyshev degree %d, coarse < %d unknowns\n", dims[0], dims[1],
              dims[2], resolve_thread_count(0), degree, coarse);

  Timer timer;
  const VoxelGrid grid = fibers_grid(dims[0], dims[1], dims[2]);
  const std::vector<MaterialPtr> palette = {nullptr, std::make_shared<NeoHookean>(1e5, 0.45),
                                            std::make_shared<NeoHookean>(1e7, 0.45)};
  const VoxelMesh voxels = build_voxel_mesh(grid, palette);
  const HexMesh& mesh = voxels.mesh;
  const ElasticAssembler assembler(mesh);
  SpMat K = assembler.pattern();
  assembler.evaluate(assembler.rest_positions(), nullptr, &K);
  const int n = mesh.num_dofs();
  std::vector<char> fixed(static_cast<std::size_t>(n), 0);
  for (int node = 0; node < mesh.num_nodes(); ++node) {
    if (mesh.nodes(node, 1) < 1e-12) fixed[3 * node] = fixed[3 * node + 1] = fixed[3 * node + 2] = 1;
  }
  double diagonal = 0.0;
  int free_count = 0;
  for (int c = 0; c < n; ++c) {
    if (!fixed[static_cast<std::size_t>(c)]) {
      diagonal += K.coeff(c, c);
      ++free_count;
    }
  }
  diagonal /= free_count;
  for (int c = 0; c < K.outerSize(); ++c) {
    for (SpMat::InnerIterator it(K, c); it; ++it) {
      if (fixed[static_cast<std::size_t>(c)] || fixed[static_cast<std::size_t>(it.row())]) {
        it.valueRef() = it.row() == c ? diagonal : 0.0;
      }
    }
  }
  // A bending load: transverse force on the far end plus gravity.
  VecX b = VecX::Zero(n);
  for (int node = 0; node < mesh.num_nodes(); ++node) {
    if (fixed[3 * std::size_t(node)]) continue;
    b[3 * node + 2] = -1.0;
    if (mesh.nodes(node, 1) > (dims[1] - 0.5) * grid.voxel_size) b[3 * node] += 50.0;
  }
  std::printf("%d nodes, %d unknowns, %ld non-zeros\n", mesh.num_nodes(), n, static_cast<long>(K.nonZeros()));
  timer.report("mesh + assembly");

  LinearSolverOptions options;
  options.node_positions = std::make_shared<const NodeArray>(mesh.nodes);
  options.pcg_tolerance = 1e-8;
  options.mg_smoother_degree = degree;
  options.mg_coarse_unknowns = coarse;
  MultigridSolver solver(options);
  solver.analyze(K);
  timer.report("pcg-mg analyze");
  std::printf("levels:");
  for (int l = 0; l < solver.num_levels(); ++l) std::printf(" %ld", static_cast<long>(solver.level_unknowns(l)));
  std::printf(" unknowns\n");
  VecX x;
  for (int s = 0; s < solves; ++s) {
    if (!solver.factorize(K, 0.0)) {
      std::printf("factorize failed\n");
      return 1;
    }
    timer.report("pcg-mg factorize");
    x = solver.solve(b);
    char label[64];
    std::snprintf(label, sizeof(label), "pcg-mg solve (%d it)", solver.stats().iterations);
    timer.report(label);
  }
  std::printf("relative residual %.3e (checked: %.3e)\n", solver.stats().relative_residual, relative_residual(K, x, b));

  if (with_cholmod) {
    CholmodSolver direct;
    direct.analyze(K);
    timer.report("cholmod analyze");
    direct.factorize(K, 0.0);
    timer.report("cholmod factorize");
    const VecX reference = direct.solve(b);
    timer.report("cholmod solve");
    std::printf("relative difference pcg-mg vs cholmod %.3e\n", (x - reference).norm() / reference.norm());
  }
  return 0;
}
