#pragma once
// The objective S(p, u) of the two-scale topology optimization (thesis
// Eq. 3.5-3.9) and its adjoint gradient with respect to the design
// variables.
//
//   S = sum_l w_l C_l(u_l) + w_M (sum_i rho_i V_i - M)^2 + w_r sum_i (rho_i - rho^_i)^2 V_i
//
// with u_l = K(p)^-1 f_l per load case and C_l either the compliance
// u^T K u (Eq. 3.9) or the target deformation (u - u^)^T D (u - u^)
// (Eq. 3.8). The design variables q are the unit parameters of the design
// cells; p = filter(q) are what the cells are made of. Cells outside the
// design domain are forced empty (a void stiffness) or solid (the stiff base
// material).
#include <cstdint>
#include <memory>
#include <string>
#include <vector>

#include "core/types.hpp"
#include "topopt/cell_filter.hpp"
#include "topopt/cell_material.hpp"
#include "topopt/design_artifact.hpp"
#include "topopt/grid_elasticity.hpp"

namespace msfab {

enum class ElasticObjective { compliance, target };

struct LoadCase {
  std::string name;
  double weight = 1.0;
  ElasticObjective objective = ElasticObjective::compliance;
  VecX force;          // per unknown
  VecX prescribed;     // per unknown; read at fixed unknowns only (empty: zeros)
  VecX target;         // target: u^ per unknown
  VecX target_weight;  // target: the diagonal of D per unknown (0 = free)
};

struct MassTerms {
  double total_weight = 0;  // w_M; 0 disables the total-mass term
  double total_target = 0;  // M (in rho * volume)
  double local_weight = 0;  // w_r; 0 disables the local terms
  VecX local_target;        // rho^ per grid cell
};

struct TopologySetup {
  CellGrid grid;
  std::vector<CellRole> roles;  // per grid cell
  // The mesh the elasticity is solved on: the design grid itself
  // (elements_per_cell 1), or m^3 hexahedra per design cell, each taking its
  // cell's stiffness (fem_grid, m = elements_per_cell): one trilinear
  // hexahedron per cell locks in bending, and the design then promises a
  // stiffness its homogenized model on a finer mesh does not have
  // (docs/topopt.md, "Elements per cell"). `fixed` and the loads' vectors
  // are per unknown of this mesh.
  int elements_per_cell = 1;
  CellGrid fem_grid;        // read when elements_per_cell > 1
  std::vector<char> fixed;  // per unknown (of the FEM mesh)
  std::vector<LoadCase> loads;
  MassTerms mass;
  double filter_radius = 0;  // in cells; <= 1: none
  MatX solid_C, empty_C;     // Voigt stiffness of forced-solid and forced-empty cells
  std::string solver = "auto";
  LinearSolverOptions solver_options;
};

struct ObjectiveValue {
  double total = 0;              // S
  double elastic = 0;            // the weighted elasticity terms
  double mass = 0;               // the mass terms
  std::vector<double> per_load;  // C_l (unweighted)
};

class TopologyObjective {
 public:
  // Takes the model by reference; it must outlive the objective. InputError
  // for inconsistent sizes, loads on nothing, a compliance load with nonzero
  // prescribed displacements (u^T K u then grows with stiffness).
  TopologyObjective(TopologySetup setup, const CellMaterialModel& model);

  const CellGrid& grid() const { return setup_.grid; }
  const CellMaterialModel& model() const { return model_; }
  const TopologySetup& setup() const { return setup_; }
  const CellFilter& filter() const { return filter_; }
  // Grid cell of each design variable row.
  const std::vector<std::int64_t>& design_cells() const { return design_cells_; }
  Eigen::Index variables() const { return Eigen::Index(design_cells_.size()) * model_.parameters(); }

  // S at design variables q (design cells x parameters); with `gradient`,
  // dS/dq of the same shape.
  ObjectiveValue evaluate(const MatX& q, MatX* gradient);
  // The physical parameters p = filter(q); where the model derives rho
  // from the other parameters (CellMaterialModel::derives_density), p's rho
  // column is that, not the filtered q.
  MatX physical(const MatX& q) const;
  // Total mass sum rho_i V_i of a design (forced-solid cells count rho = 1).
  double mass(const MatX& q) const;
  // d mass / d q (the shape of q).
  MatX mass_gradient(const MatX& q) const;
  // Every grid cell's Voigt stiffness at physical parameters p (the upper
  // triangle, CellGrid::pair_index order): design cells the model's,
  // forced cells the solid's or the void's. NumericalError where a cell's
  // stiffness is not finite.
  MatX cell_pairs(const MatX& p) const;
  // The value of the last evaluate().
  const ObjectiveValue& last_value() const { return value_; }
  // Displacements of the last evaluate(), one per load case, per unknown
  // of the FEM mesh.
  const std::vector<VecX>& displacements() const { return u_; }
  // The mesh they live on (the design grid unless elements_per_cell > 1).
  const CellGrid& fem_grid() const { return setup_.elements_per_cell > 1 ? setup_.fem_grid : setup_.grid; }
  // Load case l's displacement at the design grid's nodes.
  VecX grid_displacement(std::size_t l) const;
  GridElasticity& elasticity() { return *fem_; }

 private:
  TopologySetup setup_;
  const CellMaterialModel& model_;
  std::vector<std::int64_t> design_cells_;
  CellFilter filter_;
  std::unique_ptr<GridElasticity> fem_;
  std::vector<std::int64_t> fem_parent_;  // per FEM cell, its design grid cell (elements_per_cell > 1)
  // Holds the nodes that only forced-empty cells touch: their ersatz
  // stiffness (void_stiffness of the solid) moves nothing the objective
  // reads, and left free they make the multigrid preconditioners indefinite
  // (the gripper plate on 4^3 hexahedra per cell: CG met r' M^-1 r < 0 at
  // the start, where CHOLMOD solved the same matrix).
  void hold_void_nodes();
  // d/dp of a function of the physical parameters, carried back to the
  // design variables: through rho = density(p) where derived, then through
  // the filter.
  MatX to_variables(const MatX& p, MatX grad_p) const;
  // The state of the last evaluation.
  void compute_state(const MatX& q);
  MatX gradient_from_state();
  bool has_state_ = false;
  MatX last_q_, p_;
  ObjectiveValue value_;
  std::vector<VecX> u_;
};

}  // namespace msfab
