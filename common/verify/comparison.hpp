#pragma once
// Homogenized against full-resolution displacements at the coarse nodes
// (thesis Table 3.1: mean vertex displacement and its mean difference).
#include <cstdint>
#include <vector>

#include "core/types.hpp"
#include "verify/refinement.hpp"

namespace msfab {

// Per coarse node: how the fine displacement was sampled there.
enum class SampleKind : std::uint8_t {
  skipped = 0,     // not compared: no material near it, or only empty cells touch it
  coincident = 1,  // the fine node at the coarse node's position
  nearest = 2,     // the mean of the nearest fine nodes with material (refinement.hpp)
};

struct DisplacementComparison {
  std::int64_t compared = 0;     // coarse nodes compared
  std::int64_t nearest = 0;      // of those, sampled off the node (void there)
  double mean_homogenized = 0;   // mean |u_hom| over the compared nodes
  double mean_full = 0;          // mean |u_full|
  double mean_difference = 0;    // mean |u_full - u_hom|
  double relative = 0;           // mean_difference / mean_homogenized (0 when both vanish)
  MatX sampled;                  // coarse nodes x 3, the fine displacement sampled (0 where skipped)
  std::vector<SampleKind> kind;  // per coarse node
};

// `coarse_active`: per coarse node, 0 to leave it out (a node only empty
// cells touch is void in both models). Fine nodes are searched up to half a
// cell away (resolution / 2).
DisplacementComparison compare_displacements(const CellRefinement& refinement, const VecX& u_homogenized,
                                             const VecX& u_full, const std::vector<char>& fine_node_material,
                                             const std::vector<char>& coarse_active);

// |E_full - E_hom| / E_hom (0 when both vanish).
double relative_difference(double homogenized, double full);

}  // namespace msfab
