// Speed against error of the two periodic cell solvers (direct sparse
// Cholesky, matrix-free multigrid CG) on three kinds of cell, at several
// resolutions, multigrid tolerances and smoother degrees. Each row
// homogenizes one cell; the error is |C - C_ref| / |C_ref| (Frobenius)
// against the direct solver at the same resolution (up to 32^3) or the
// multigrid solver at tolerance 1e-11 (beyond).
//
//   bench_cell_solver [--sizes 16,24,32,64] [--tolerances 1e-5,1e-6,1e-8]
//                     [--degrees 2] [--kinds random,sphere,frame,cubic-random]
//                     [--coarsest 64,512] [--solvers multigrid,direct]
//                     [--symmetries none,cyclic,mirror,both] [--no-direct]
//                     [--batch K]
//
// --batch K: instead of the table, the throughput a gamut sampler sees:
// K different cells of each kind and size (seeds 1..K) homogenized with
// the default options, one cell per thread on all threads, with the
// symmetry reductions and without them, in the same run.
//
// Symmetries: none solves the six cases on the whole cell, cyclic two
// cases (cubic cells), mirror the cases on one octant (cells invariant
// under the three reflections; the solver then runs on the octant), both
// two cases on the octant. Modes a cell does not have are skipped.
//
// Prints a Markdown table. Timings are wall-clock with the OpenMP default
// thread count (set OMP_NUM_THREADS).
#include <omp.h>

#include <algorithm>
#include <chrono>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <random>
#include <sstream>
#include <string>
#include <vector>

#include "gamut/structure_ops.hpp"
#include "homog/periodic_homogenization.hpp"
#include "material/linear_isotropic.hpp"

using namespace msfab;

namespace {

template <class T>
std::vector<T> parse_list(const char* text) {
  std::vector<T> out;
  std::stringstream ss(text);
  std::string item;
  while (std::getline(ss, item, ',')) {
    std::stringstream is(item);
    T value;
    is >> value;
    out.push_back(value);
  }
  return out;
}

// random: two phases (E 1e6 / 1e3, nu 0.45) voxel by voxel, the gamut
// issue's contrast at its worst (no smooth geometry). sphere: a soft sphere
// of radius 0.3 in the stiff phase. frame: three orthogonal bars of the
// stiff phase in void (void stiffness 1e-6). cubic-random: random with
// its fundamental domain mirrored (a gamut structure's symmetry). sphere,
// frame and cubic-random are cubic, so they also run with two cell
// problems instead of six (HomogenizationOptions::use_symmetry).
// mirror-random: random mirrored into the three reflections only (an
// orthotropic structure's symmetry: one octant, six cases).
VoxelGrid make_cell(const std::string& kind, int n, unsigned seed = 7) {
  VoxelGrid g(n, n, n, 1.0 / n, 1);
  std::mt19937 rng(seed);
  for (int k = 0; k < n; ++k)
    for (int j = 0; j < n; ++j)
      for (int i = 0; i < n; ++i) {
        const Vec3 x = g.voxel_center(i, j, k) - Vec3(0.5, 0.5, 0.5);
        int& id = g.at(i, j, k);
        if (kind == "random" || kind == "cubic-random" || kind == "mirror-random") id = 1 + int(rng() % 2);
        if (kind == "sphere") id = x.norm() < 0.3 ? 2 : 1;
        if (kind == "frame") {
          const double a = std::abs(x[0]), b = std::abs(x[1]), c = std::abs(x[2]), w = 1.0 / 6;
          id = ((a < w && b < w) || (b < w && c < w) || (a < w && c < w)) ? 1 : 0;
        }
      }
  if (kind == "cubic-random") mirror_fundamental_domain(g);
  if (kind == "mirror-random") mirror_fundamental_domain(g, CellSymmetry::orthotropic);
  return g;
}

std::string format_error(double e) {
  char text[32];
  std::snprintf(text, sizeof text, "%.1e", e);
  return text;
}

}  // namespace

int main(int argc, char** argv) {
  std::vector<int> sizes = {16, 24, 32, 64};
  std::vector<double> tolerances = {1e-5, 1e-6, 1e-8};
  std::vector<int> degrees = {2};
  std::vector<int> coarsest = {PeriodicMultigridOptions{}.coarsest_nodes};
  std::vector<std::string> kinds = {"random", "sphere", "frame"};
  std::vector<std::string> solvers = {"matrix-free"};
  std::vector<std::string> symmetries = {"none", "cyclic", "mirror", "both"};
  int batch = 0;
  bool direct = true;
  for (int a = 1; a < argc; ++a) {
    const bool more = a + 1 < argc;
    if (!std::strcmp(argv[a], "--sizes") && more)
      sizes = parse_list<int>(argv[++a]);
    else if (!std::strcmp(argv[a], "--tolerances") && more)
      tolerances = parse_list<double>(argv[++a]);
    else if (!std::strcmp(argv[a], "--degrees") && more)
      degrees = parse_list<int>(argv[++a]);
    else if (!std::strcmp(argv[a], "--coarsest") && more)
      coarsest = parse_list<int>(argv[++a]);
    else if (!std::strcmp(argv[a], "--kinds") && more)
      kinds = parse_list<std::string>(argv[++a]);
    else if (!std::strcmp(argv[a], "--solvers") && more)
      solvers = parse_list<std::string>(argv[++a]);
    else if (!std::strcmp(argv[a], "--symmetries") && more)
      symmetries = parse_list<std::string>(argv[++a]);
    else if (!std::strcmp(argv[a], "--batch") && more)
      batch = std::atoi(argv[++a]);
    else if (!std::strcmp(argv[a], "--no-direct"))
      direct = false;
    else {
      std::fprintf(stderr,
                   "usage: %s [--sizes L] [--tolerances L] [--degrees L] [--kinds L] [--coarsest L] [--solvers L] "
                   "[--symmetries L] [--batch K] [--no-direct]\n",
                   argv[0]);
      return 2;
    }
  }
  const std::vector<MaterialPtr> palette = {nullptr, std::make_shared<LinearIsotropic>(1e6, 0.45),
                                            std::make_shared<LinearIsotropic>(1e3, 0.45)};
  if (batch > 0) {
    std::printf(
        "| cell | n | cells | threads | symmetry | seconds | cells/s | max rel. difference of C "
        "|\n|---|---|---|---|---|---|---|---|\n");
    for (const std::string& kind : kinds)
      for (int n : sizes) {
        std::vector<VoxelGrid> cells;
        for (int c = 0; c < batch; ++c) cells.push_back(make_cell(kind, n, 1 + c));
        std::vector<Mat6> reference(batch);
        // whole: six cases on the whole cell; cyclic: two cases on the whole
        // cell (the default before the octant, cubic cells only); reduced: the default.
        for (const std::string mode : {"whole", "cyclic", "reduced"}) {
          if (mode == "cyclic" && !has_cubic_symmetry(cells[0])) continue;
          HomogenizationOptions o;
          o.threads = 1;
          o.use_symmetry = mode != "whole";
          o.use_mirror_symmetry = mode == "reduced";
          std::vector<Mat6> C(batch);
          const auto start = std::chrono::steady_clock::now();
#pragma omp parallel for schedule(dynamic, 1)
          for (int c = 0; c < batch; ++c) C[c] = homogenize(cells[c], palette, o).C;
          const double seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
          double difference = 0;
          for (int c = 0; c < batch; ++c)
            if (mode == "whole")
              reference[c] = C[c];
            else
              difference = std::max(difference, (C[c] - reference[c]).norm() / reference[c].norm());
          const char* label = mode == "whole"    ? "whole cell, 6 cases"
                              : mode == "cyclic" ? "whole cell, 2 cases (cyclic)"
                                                 : "default (octant; 2 cases if cubic)";
          std::printf("| %s | %d | %d | %d | %s | %.3f | %.3g | %s |\n", kind.c_str(), n, batch, omp_get_max_threads(),
                      label, seconds, batch / seconds,
                      mode == "whole" ? "(reference)" : format_error(difference).c_str());
          std::fflush(stdout);
        }
      }
    return 0;
  }
  std::printf(
      "| cell | n | solver | domain | tolerance | degree | coarsest nodes | cases solved | CG iterations | seconds | "
      "cells/s | rel. error of C | speed-up vs direct |\n");
  std::printf("|---|---|---|---|---|---|---|---|---|---|---|---|---|\n");
  for (const std::string& kind : kinds)
    for (int n : sizes) {
      const VoxelGrid cell = make_cell(kind, n);
      HomogenizationOptions reference_options;
      Mat6 C_ref;
      double direct_seconds = 0;
      reference_options.use_symmetry = false;
      reference_options.use_mirror_symmetry = false;
      if (direct && n <= 32) {
        reference_options.solver = "cholmod";
        const HomogenizationResult r = homogenize(cell, palette, reference_options);
        C_ref = r.C;
        direct_seconds = r.seconds;
        std::printf("| %s | %d | direct | cell | | | | 6 | | %.3f | %.3g | (reference) | |\n", kind.c_str(), n,
                    r.seconds, 1 / r.seconds);
      } else {
        reference_options.solver = "matrix-free";
        reference_options.tolerance = 1e-11;
        C_ref = homogenize(cell, palette, reference_options).C;
      }
      std::fflush(stdout);
      const bool cubic = has_cubic_symmetry(cell), mirrored = has_symmetry(cell, CellSymmetry::orthotropic);
      for (const std::string& symmetry : symmetries) {
        if ((symmetry == "cyclic" && !cubic) || (symmetry == "mirror" && !mirrored) ||
            (symmetry == "both" && !(cubic && mirrored)))
          continue;
        for (const std::string& solver : solvers)
          for (int degree : degrees)
            for (double tolerance : tolerances)
              for (int coarse : coarsest) {
                if (solver == "cholmod" &&
                    (degree != degrees[0] || tolerance != tolerances[0] || coarse != coarsest[0]))
                  continue;  // the direct solver has none of these knobs
                HomogenizationOptions o;
                o.solver = solver;
                o.tolerance = tolerance;
                o.multigrid_smoother_degree = degree;
                o.use_symmetry = symmetry == "cyclic" || symmetry == "both";
                o.use_mirror_symmetry = symmetry == "mirror" || symmetry == "both";
                o.multigrid_coarsest_nodes = coarse;
                const HomogenizationResult r = homogenize(cell, palette, o);
                std::printf("| %s | %d | %s | %s |", kind.c_str(), n, r.solver.c_str(), r.octant ? "octant" : "cell");
                if (r.solver == "matrix-free")
                  std::printf(" %.0e | %d | %s |", tolerance, degree, r.octant ? "" : std::to_string(coarse).c_str());
                else
                  std::printf(" | | |");
                std::printf(" %d | %s | %.3f | %.3g | %.1e |", r.symmetric_cases ? 2 : 6,
                            r.solver == "matrix-free" ? std::to_string(r.iterations).c_str() : "", r.seconds,
                            1 / r.seconds, (r.C - C_ref).norm() / C_ref.norm());
                if (direct_seconds > 0)
                  std::printf(" %.1f |\n", direct_seconds / r.seconds);
                else
                  std::printf(" |\n");
                std::fflush(stdout);
              }
      }
    }
  return 0;
}
