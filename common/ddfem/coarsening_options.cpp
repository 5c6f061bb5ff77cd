#include "ddfem/coarsening_options.hpp"

namespace msfab {

void add_coarsening_options(StageApp& app, CoarseningRequest& request, bool element_option) {
  app.option("--coarsen", request.level, "coarsening levels: 0 (fine), 1 (2x2x2 blocks), 2 (4x4x4)").in_range(0, 2);
  app.option("--coarse-material", request.material,
             "ddfem (needs --database), naive, averaged, homogenized, galerkin (each fine voxel integrated "
             "over the coarse field, on the points that keep its stiffness), galerkin-full (on all the "
             "voxels' points) or matched (naive materials carried onto the block's homogenized stiffness)")
      .one_of({"ddfem", "naive", "averaged", "homogenized", "galerkin", "galerkin-full", "matched"});
  app.option("--database", request.database, "coarse_db artifact from msfab-ddfem-build");
  app.option("--coarse-fallback", request.fallback,
             "ddfem: blocks the database holds no fit for (e.g. with void children) are coarsened naive "
             "(default), galerkin (each fine voxel integrated over the coarse field, void empty), "
             "galerkin-full (the same on all the voxels' points) or matched")
      .one_of({"naive", "galerkin", "galerkin-full", "matched"});
  app.option("--coarse-check", request.check_tolerance,
             "ddfem: check each solid mixed block's fit against the block's homogenized stiffness and "
             "coarsen it by the matched model where they differ by more than this (RMS log of the "
             "generalized eigenvalues; 0, the default: no check)");
  app.option("--coarse-window", request.window,
             "matched: carry each cell onto its stiffness among this many voxels of its real neighbours "
             "(materials per cell) instead of its periodic C^H; 0, the default: off");
  if (element_option)
    app.option("--coarse-element", request.element,
               "trilinear (the thesis's) or enhanced (three condensed bubble modes: no bending locking); "
               "default: the database's element for ddfem, trilinear otherwise")
        .one_of({"trilinear", "enhanced"});
}

}  // namespace msfab
