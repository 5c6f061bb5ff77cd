#include "ddfem/coarsening_options.hpp"

namespace msfab {

void add_coarsening_options(CLI::App& app, CoarseningRequest& request, bool element_option) {
  app.add_option("--coarsen", request.level, "coarsening levels: 0 (fine), 1 (2x2x2 blocks), 2 (4x4x4)")
      ->check(CLI::Range(0, 2));
  app.add_option("--coarse-material", request.material,
                 "ddfem (needs --database), naive, averaged, homogenized or galerkin")
      ->check(CLI::IsMember({"ddfem", "naive", "averaged", "homogenized", "galerkin"}));
  app.add_option("--database", request.database, "coarse_db artifact from msfab-ddfem-build");
  app.add_option("--coarse-fallback", request.fallback,
                 "ddfem: blocks the database holds no fit for (e.g. with void children) are coarsened naive "
                 "(default) or galerkin (each fine voxel integrated over the coarse field, void empty)")
      ->check(CLI::IsMember({"naive", "galerkin"}));
  if (element_option)
    app.add_option("--coarse-element", request.element,
                   "trilinear (the thesis's) or enhanced (three condensed bubble modes: no bending locking); "
                   "default: the database's element for ddfem, trilinear otherwise")
        ->check(CLI::IsMember({"trilinear", "enhanced"}));
}

}  // namespace msfab
