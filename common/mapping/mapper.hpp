#pragma once
// The microstructure mapper (thesis §3.5) on a design and a microstructure
// set: the steps msfab-map runs, in order (docs/mapping.md).
//
//   check_mapping_inputs(design, design_path, set, set_path);
//   CellCandidates cand = design_candidates(design, set, options.candidates);
//   MismatchProblem problem = mismatch_problem(design, set, cand, options.half_shift);
//   problem.randomize(seed);
//   DescentReport report = problem.descend();
//   MappedDesign mapped = mapped_design(design, set, cand, problem, report, options);
#include <cstdint>
#include <string>

#include "gamut/material_space.hpp"
#include "gamut/microstructure_set.hpp"
#include "io/config.hpp"
#include "mapping/candidates.hpp"
#include "mapping/mapped_artifact.hpp"
#include "mapping/mismatch.hpp"
#include "topopt/design_artifact.hpp"

namespace msfab {

struct MapperOptions {
  CandidateOptions candidates;
  bool half_shift = true;     // also offer each candidate translated by half a cell
  double void_pair_cost = 0;  // MismatchProblem: a both-void pair costs this much of a mismatching one
  double max_distance = 0.1;  // warn about cells whose nearest candidate is farther (normalized units)
};

// The `match` key of msfab-map and msfab-fill-targets: "all" (every
// property of the space, the thesis's choice) or "stiffness" (the density
// left out: CandidateOptions::stiffness_only). Default "all".
bool read_stiffness_only(const Config& config);

// InputError naming the offending file for inputs that cannot be paired:
// a design space that is not a gamut space, different spaces or property
// names, an empty set, a 2D design with 3D structures (or the reverse),
// a design without any cell.
void check_mapping_inputs(const Design& design, const std::string& design_path, const MicrostructureSet& set,
                          const std::string& structures_path);

// Peak memory of steps 1-4 before any export (docs/cli.md, "Memory"): per
// design cell its candidates (index and distance, 12 B each) and their
// face-table options (4 B per candidate and shift); per cell its target
// rows and about 270 B of descent state and mapped result (measured with
// /usr/bin/time: 2.6 GB for 4 M design cells and 16 candidates); per
// structure and shift its six faces at 4 B per face voxel. Candidates that
// `radius` adds beyond k are not counted.
double mapping_peak_bytes(const Design& design, const MicrostructureSet& set, const MapperOptions& options);

// Step 1: the candidates of every design cell (forced empty / solid cells
// get none), by the cells' `unit` rows against the structures' `unit` rows.
CellCandidates design_candidates(const Design& design, const MicrostructureSet& set, const CandidateOptions& options);

// Steps 1-2: every cell's options as entries of a face table. Design cell c's
// option o is candidate o / v of c, half-shifted when o % v == 1, where
// v = 2 with half_shift and 1 without; forced empty cells hold one all-void
// entry, forced solid cells one all-id-1 entry. Starts with option 0 (the
// nearest candidate) everywhere.
MismatchProblem mismatch_problem(const Design& design, const MicrostructureSet& set, const CellCandidates& candidates,
                                 bool half_shift, double void_pair_cost = 0);

// Step 4: the chosen structure, exemplar and distance of every cell.
MappedDesign mapped_design(const Design& design, const MicrostructureSet& set, const CellCandidates& candidates,
                           const MismatchProblem& problem, const DescentReport& report, const MapperOptions& options);

// How far the candidates are from the targets, over design cells.
struct DistanceSummary {
  std::int64_t design_cells = 0;
  std::int64_t far_cells = 0;        // nearest candidate farther than max_distance
  double max_nearest = 0;            // largest distance to the nearest candidate
  double max_chosen = 0;             // largest distance to the structure chosen
  double max_gap = 0, mean_gap = 0;  // property gap (MappedDesign::property_gap) of the chosen structures
};
// |C(a) - C(b)|_F / |C(b)|_F for raw properties a (a structure's) and b (a
// target) of a gamut space (MaterialSpace::tensor_2d / tensor_3d).
double relative_stiffness_gap(const MaterialSpace& space, const VecX& a, const VecX& b);

DistanceSummary summarize_distances(const CellCandidates& candidates, const MappedDesign& mapped, double max_distance);

}  // namespace msfab
