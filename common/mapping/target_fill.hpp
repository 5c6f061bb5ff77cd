#pragma once
// Structures generated at a design's targets (msfab-fill-targets): where no
// structure of the set is close to the stiffness the optimizer asked of a
// cell, one is made by the continuous step of the gamut sampler (thesis
// §3.2.2, Eq. 3.4) aimed at the cell's own target instead of a point just
// outside the gamut, rather than mapping the cell to a far neighbour.
//
//   CellCoverage before = cell_coverage(design, set, k);
//   std::vector<FillTarget> targets = plan_targets(design, set, before, plan);
//   for each target (independent): GeneratedStructure g = generate_at_target(set, target, refine);
//   append_generated(set, targets, generated, round);
//
// The gap of a structure for a cell is |C(structure) - C(target)|_F /
// |C(target)|_F (relative_stiffness_gap), the figure msfab-map reports.
#include <cstdint>
#include <vector>

#include "core/types.hpp"
#include "gamut/continuous_refinement.hpp"
#include "gamut/microstructure_set.hpp"
#include "mapping/candidates.hpp"
#include "topopt/design_artifact.hpp"

namespace msfab {

// Per design cell, the smallest property gap among its candidates (the
// mapper's: design_candidates with the same options) and which structure
// has it; cells that are not design cells hold gap 0, best -1.
struct CellCoverage {
  std::vector<double> gap;
  std::vector<std::int32_t> best;
  std::int64_t design_cells = 0;
  double max_gap = 0, mean_gap = 0;  // over design cells
  std::int64_t above(double limit) const;
};
CellCoverage cell_coverage(const Design& design, const MicrostructureSet& set, const CandidateOptions& candidates);

struct FillPlanOptions {
  double gap = 0.1;              // cells whose best gap exceeds this get a target
  CandidateOptions candidates;   // as cell_coverage's; the starts are among a target's candidates
  int starts = 2;                // refinement starts per target
  double cluster_radius = 0.02;  // unit-cube distance within which cells share a target
  int max_targets = 256;         // the targets of the largest gaps are kept
};

// One structure to generate: the mean unit properties of a group of cells
// (the worst uncovered cell and every uncovered cell within
// cluster_radius of it), and where to start.
struct FillTarget {
  VecX unit, raw;                    // the target's properties (raw: MaterialSpace order, moduli in Pa)
  std::vector<std::int64_t> cells;   // the cells it serves, worst first
  double gap = 0;                    // the set's best gap for the target itself
  std::vector<std::int32_t> starts;  // structures of smallest gap to the target, best first
};
// Groups are formed worst cell first (ties: lower index), so the plan is
// one well-defined list. InputError for bad options.
std::vector<FillTarget> plan_targets(const Design& design, const MicrostructureSet& set, const CellCoverage& coverage,
                                     const FillPlanOptions& options);

struct GeneratedStructure {
  bool found = false;    // a printable structure came out of some start
  std::vector<int> ids;  // voxel ids, the set's layout
  Mat6 C = Mat6::Zero();
  double rho = 0;  // stiff volume fraction
  double gap = 0;  // to the target
  std::int32_t parent = -1;
};

// MMA from each start towards the target's compliance and density
// (refine_structure with the given options; symmetry and void stiffness
// are taken from the set's space and `void_stiffness`), each thresholded
// structure homogenized; the one of smallest gap is returned. Deterministic.
GeneratedStructure generate_at_target(const MicrostructureSet& set, const FillTarget& target,
                                      const ContinuousOptions& options, double void_stiffness);

// Every structure of the set given the face connector (face_connector:
// those voxels made stiff, id 1) and homogenized again, so that any two
// cells of a mapping share a solid patch on their common face; pass the
// mask as ContinuousOptions::frozen_stiff so generated structures carry it
// too. A piece of the connector the structure does not reach stays (it
// bears no load in the cell, but joins its neighbour's). Returns the mask.
std::vector<std::uint8_t> add_face_connector(MicrostructureSet& set, int half_width, int depth, double void_stiffness);

// A generated structure as a fixed-size row of doubles and back, for the
// MPI fan-out (fan_out): found, gap, parent, rho, C (36), ids.
int generated_record_size(const MicrostructureSet& set);
void write_generated_record(const GeneratedStructure& g, double* record);
GeneratedStructure read_generated_record(const MicrostructureSet& set, const double* record);

// Appends, in target order, each found structure whose gap is below its
// target's gap and whose voxels are new to the set (step targeted, cycle
// `round`, parent its start). Returns how many were appended.
int append_generated(MicrostructureSet& set, const std::vector<FillTarget>& targets,
                     const std::vector<GeneratedStructure>& generated, int round);

}  // namespace msfab
