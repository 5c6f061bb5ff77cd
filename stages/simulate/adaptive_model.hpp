#pragma once
// Adaptive coarsening for msfab-simulate (--target-error; docs/ddfem.md,
// "Adaptive coarsening"): from solves of the uniform level-2 and level-1
// models, the level of every level-2 cell (fine, level 1 or level 2) is
// chosen so that the estimated error meets the target, and the scene is
// meshed with those levels, hanging nodes constrained. After the mixed solve
// its error is estimated a posteriori against the Richardson extrapolation
// of the two uniform solutions; with --posterior-check a miss tightens the
// choice and solves again.
#include <string>

#include "coarse_model.hpp"
#include "ddfem/adaptive_levels.hpp"
#include "ddfem/mixed_level_mesh.hpp"
#include "solve/newton.hpp"

namespace msfab {

struct AdaptiveModel {
  MixedLevelMesh mixed;
  StaticConditions conditions;        // on the unknowns
  LevelErrors level_errors{};         // estimated errors of the uniform models
  double level_difference = 0;        // D: mean-vertex distance between the level-1 and level-2 solutions
  std::vector<CellErrorModel> cells;  // energy shares and element counts per level-2 cell
  VecX extrapolated;                  // fine-node displacements u1 + (u1 - u2) / (2^p - 1), p = 1
  double choice_target = 0;           // the target the levels were chosen for (tightened by misses)
  LevelChoice choice;
  int cells_refined_for_conditions = 0;  // level-2 cells set to level 0 so that no fixed node hangs
  double seconds = 0;                    // estimate, choice and mesh (not the solves)
  // The materials of level-1 and level-2 cells: the uniform models' own,
  // looked up again only for a block they do not hold.
  CoarseMaterialLookup level1_materials, level2_materials;
};

// Mixed solves before the a-posteriori check gives up (the one with the
// smallest estimate stands).
constexpr int kMaxAdaptiveSolves = 3;

// The uniform level-1 model of the scene with the materials of `level1_db`:
// the level-2 model's database's own (compressed) level-1 base, or a
// level-1 database checked to stand in for it (--level1-database). The
// level-1 cells of the adaptive model take the same materials.
CoarseModel level1_model_of(const Scene& scene, const VoxelMesh& fine, const CoarseModel& level2,
                            const CoarseDatabase& level1_db);

// Positions (3 per node) to start Newton from on a finer model whose rest
// nodes are the rows of `rest`: the coarser uniform model `from`'s solution
// x_from interpolated to them (uniform_displacement_at).
VecX start_from(const CoarseModel& from, const VecX& x_from, const NodeArray& rest);

// `level2` / `level1` are the uniform models and x2 / x1 their solutions
// (positions); `level1_db` the database level1 was built with.
AdaptiveModel build_adaptive_model(const Scene& scene, const VoxelMesh& fine, const StaticConditions& fine_conditions,
                                   const CoarseModel& level2, const VecX& x2, const CoarseModel& level1, const VecX& x1,
                                   const CoarseDatabase& level1_db, double target_error);

// Re-chooses the levels of `model` for `choice_target` (below the target the
// previous choice was made for, after its a-posteriori check missed) and
// meshes them again; no cell ends coarser than in the previous choice.
void rechoose_adaptive_levels(AdaptiveModel& model, const Scene& scene, const VoxelMesh& fine,
                              const StaticConditions& fine_conditions, const CoarseModel& level2, double choice_target);

// The a-posteriori error estimate of a solution of `model` (`u_on_fine`, from
// adaptive_displacement_on_fine): its mean-vertex distance from the
// extrapolated fine displacement. It equals the a-priori estimate for a
// uniform level-1 or level-2 choice and, unlike it, sees errors that cells
// of different levels make together (interfaces, errors of one sign).
double a_posteriori_error(const VoxelMesh& fine, const AdaptiveModel& model, const VecX& u_on_fine);

// After a refinement: a bound on the error of the finer solve from how far
// it moved from the coarser one. With rho the ratio of their a-priori
// estimates (the reduction the finer choice was made for), e_fine <= rho
// e_coarse and e_coarse <= change + e_fine give e_fine <= rho / (1 - rho)
// change (the saturation assumption of two-solution estimates). Unlike the
// distance from the extrapolated solution it does not carry the
// extrapolation's own error, which dominates where the two uniform levels
// err in different directions (docs/ddfem.md). +inf where rho > 1/2,
// where the factor is too sensitive to the predicted ratio (layers1, whose
// level-1 cells are no better than its level-2 ones, was underestimated at
// rho = 0.78).
double refinement_error_bound(const VoxelMesh& fine, const VecX& finer_on_fine, double finer_predicted,
                              const VecX& coarser_on_fine, double coarser_predicted);

// The a-posteriori estimate of a mixed solve kept by --posterior-check: 0
// for a choice of fine cells only (the fine model itself), else the smaller
// of a_posteriori_error and, from the second solve on, the
// refinement_error_bound against the previous solve (`previous_on_fine`,
// null for the first solve, with its predicted error and number).
struct PosteriorEstimate {
  double value = 0;
  std::string source;    // what `value` is, for the log; or why there is none
  bool measured = true;  // false: no estimate of this kind here (`source` says why)
  // The estimated error itself as displacements at the fine nodes, where
  // the estimate is a field that says where the error sits (fine Newton
  // steps); empty otherwise.
  VecX error_field = VecX();
};
PosteriorEstimate posterior_estimate(const VoxelMesh& fine, const AdaptiveModel& model, const VecX& on_fine,
                                     const VecX* previous_on_fine, double previous_predicted, int previous_solve);

// Re-chooses the levels of `model` after its solve (`on_fine`, fine-node
// displacements) missed `target_error` by the estimate `measured`, whose
// error field says how the error splits between the level-1 and level-2
// cells: the two level errors are calibrated by it
// (calibrated_level_errors, with the field's fine strain energy per
// level-2 cell; the spread over the cells stays the a-priori one) and the
// levels refined from the current ones to meet the target itself.
// Returns false, changing nothing, where the estimate has no field or the
// calibrated errors refine no cell.
bool rechoose_where_measured(AdaptiveModel& model, const Scene& scene, const VoxelMesh& fine,
                             const StaticConditions& fine_conditions, const CoarseModel& level2, const VecX& on_fine,
                             const PosteriorEstimate& measured, double target_error);

// The a-posteriori estimate by the fine model itself (--posterior-estimate
// newton): the mean-vertex size of one Newton step of the fine model from
// the mixed solution (`on_fine`, displacements at the fine nodes). That step
// is the remaining error up to second order, whatever its origin, including
// error the two uniform levels share, which their difference cannot see
// (docs/ddfem.md). 0 for a choice of fine cells only. Where the fine
// tangent at the mixed solution is indefinite, the step is the exact one
// (MINRES) and a second step from where it lands is added: one step
// amplifies the soft directions (1.2-1.3x the true error), two are within
// 16% on bridge_arch, holes3 and twisting. Not `measured` where the steps
// do not lower the potential one after the other, or the second is not
// shorter than the first (they then head for
// another equilibrium: skeleton at 0.02 measured 19x its true error), where
// an element is inverted, or where the exact step cannot be taken (a mesh
// too large for a direct factorization without the lattice multigrid: a
// regularized step measured less than half the true error on bridge_arch).
PosteriorEstimate fine_newton_estimate(const VoxelMesh& fine, const ElasticAssembler& fine_assembler,
                                       const StaticConditions& fine_conditions, const NewtonOptions& options,
                                       const AdaptiveModel& model, const VecX& on_fine);

// The solution of the adaptive model (positions of the unknowns) as
// displacements at the fine mesh's nodes, for the error against the fine
// solution.
VecX adaptive_displacement_on_fine(const Scene& scene, const VoxelMesh& fine, const AdaptiveModel& model,
                                   const ElasticAssembler& assembler, const VecX& x);

// The adaptive model's mesh, conditions and solution with one entry per mesh
// node (hanging nodes: interpolated positions, no force or condition), as the
// result artifact stores them.
struct AdaptiveResultOnMesh {
  VoxelMesh mesh;
  StaticConditions conditions;
  NewtonResult newton;
};
AdaptiveResultOnMesh adaptive_result_on_mesh(const AdaptiveModel& model, const ElasticAssembler& assembler,
                                             const NewtonResult& result);

// An adaptive run (msfab-simulate --target-error): the uniform level-2 and
// level-1 solves, the level choice, the mixed solve and, with
// `posterior_check`, its a-posteriori check and re-choices (at most
// kMaxAdaptiveSolves mixed solves). The solves are ranked by their
// estimates (kept_solve): an extrapolated estimate is raised to the fine
// Newton estimate of a solve that refines it. docs/ddfem.md, "Adaptive
// coarsening".
struct AdaptiveRunOptions {
  double target = 0;             // the mean-vertex error to meet
  bool posterior_check = false;  // solve again, finer, while the estimate misses the target
  bool newton_estimate = false;  // estimate by fine Newton steps where the fine tangent allows
};
struct AdaptiveRun {
  AdaptiveModel model;          // the kept mixed model
  NewtonResult result;          // its solve
  double uniform_seconds = 0;   // the uniform level-2 and level-1 solves the estimate comes from
  double rejected_seconds = 0;  // mixed solves not kept
  int solves = 0;               // mixed solves
  double estimate = 0;          // the kept solve's a-posteriori estimate, as ranked
  std::string estimate_source;  // what that estimate is
};
AdaptiveRun solve_adaptively(const Scene& scene, const VoxelMesh& fine, const StaticConditions& fine_conditions,
                             const CoarseModel& coarse, const CoarseDatabase& level1_db,
                             const AdaptiveRunOptions& options);

}  // namespace msfab
