// msfab-ddfem-compress: keep k representative coarse materials of a DDFEM
// database (thesis §2.3.4).
//
//   1. read the full database
//   2. feature vector per coarse material: log-energies on common
//      deformations of the coarse element
//   3. farthest-point sampling to k representatives (Eq. 2.10 distance)
//   4. look every combination up to its nearest representative and write
//      the compressed `msfab.coarse_db` (parameters of the representatives
//      only, plus the lookup table)
#include <spdlog/spdlog.h>

#include <cstdio>
#include <filesystem>

#include "cli/stage_app.hpp"
#include "core/errors.hpp"
#include "ddfem/db_compression.hpp"

using namespace msfab;

namespace {
constexpr const char* kDefaults = R"(
representatives: 64     # k
deformations: 64        # common deformations in the feature vectors
strain: 0.05            # their strain magnitude
seed: 3                 # draws the deformations and the first representative
corner_moves: false     # add the 24 single-corner moves to the features (where in a block its stiffness sits)
)";
}

int main(int argc, char** argv) {
  StageApp app("msfab-ddfem-compress", "Compress a DDFEM database to k representative coarse materials (thesis 2.3.4)");
  app.add_common_options();
  app.set_default_config(kDefaults);
  std::string input;
  app.option("--database", input, "full coarse_db from msfab-ddfem-build").required();
  return app.run(argc, argv, [&](StageContext& ctx) {
    const std::string& out = ctx.require_out();
    const int k = ctx.config.require_positive<int>("representatives", "number of representatives");
    const int deformations = ctx.config.require_positive<int>("deformations", "number of common deformations");
    const double strain = ctx.config.require_range<double>("strain", 0.0, 0.5, Bounds::Open, "deformation strain");
    const auto seed = ctx.config.get_or<std::uint64_t>("seed", 3);
    const bool corner_moves = ctx.config.get_or<bool>("corner_moves", false);
    ctx.finish_config();
    ctx.check_out_folder();

    const CoarseDatabase full = read_coarse_db(input);
    if (full.compressed()) throw InputError(input + ": the database is already compressed");
    if (k > static_cast<int>(full.entries.size()))
      throw InputError("representatives = " + std::to_string(k) + " exceeds the " +
                       std::to_string(full.entries.size()) + " coarse materials of " + input);
    // The feature matrix (one energy per material and deformation), twice
    // over, and the deformations themselves.
    ctx.check_memory(16.0 * double(full.entries.size()) * deformations + 192.0 * deformations,
                     std::to_string(deformations) + " deformations of " + std::to_string(full.entries.size()) +
                         " coarse materials (deformations)",
                     "use fewer deformations");
    CompressionReport report;
    const CoarseDatabase small = compress_database(full, k, deformations, strain, seed, &report, corner_moves);
    write_coarse_db(out, small, ctx.config.resolved_text(), ctx.command_line, seed, "msfab-ddfem-compress");
    std::printf("msfab-ddfem-compress: %zu -> %zu coarse materials\n", full.entries.size(), small.entries.size());
    std::printf("  distance to representative (Eq. 2.10): mean %.4f, max %.4f\n", report.mean_distance,
                report.max_distance);
    std::printf("  energy of representative vs own on the common deformations: mean |ratio - 1| = %.4f\n",
                report.mean_energy_error);
    std::printf("  artifact: %s (%.1f kB)\n", out.c_str(), std::filesystem::file_size(out) / 1024.0);
  });
}
