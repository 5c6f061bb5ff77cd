#include "verify/design_refinement.hpp"

#include "verify/refinement.hpp"

namespace msfab {

void refine_fem_mesh(TopologySetup& setup, int m) {
  if (m == 1) return;
  const CellRefinement refinement(setup.grid, m);
  const CellGrid& coarse = setup.grid;
  const CellGrid& fine = refinement.fine();
  const int dim = coarse.dimension();
  // Every cell carries stiffness (forced-empty cells an ersatz one), so
  // every node has material.
  const std::vector<char> node_material = refinement.material_nodes(std::vector<char>(std::size_t(fine.cells()), 1));
  const CellRefinement::Supports supports = refinement.refine_supports(setup.fixed, node_material);
  for (LoadCase& l : setup.loads) {
    l.force = refinement.refine_forces(l.force, node_material, "load case '" + l.name + "'");
    if (l.prescribed.size() == coarse.unknowns()) l.prescribed = supports.values * l.prescribed;
    if (l.target.size() == coarse.unknowns()) {
      VecX target = VecX::Zero(fine.unknowns()), weight = VecX::Zero(fine.unknowns());
      for (std::int64_t node = 0; node < coarse.nodes(); ++node) {
        const std::int64_t f = refinement.fine_node_of(node);
        for (int c = 0; c < dim; ++c) {
          target[f * dim + c] = l.target[node * dim + c];
          weight[f * dim + c] = l.target_weight[node * dim + c];
        }
      }
      l.target = std::move(target);
      l.target_weight = std::move(weight);
    }
  }
  setup.fixed = supports.fixed;
  setup.fem_grid = fine;
  setup.elements_per_cell = m;
}

}  // namespace msfab
