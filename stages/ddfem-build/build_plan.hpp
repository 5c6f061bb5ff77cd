#pragma once
// What one run of the database builder fits, and how the fits become a
// database: at level 1 the cube-symmetry orbits of the palette's
// combinations, at level 2 the final representatives of the hierarchy over
// a level-1 database (thesis §2.3.5).
#include <cstdint>
#include <functional>
#include <string>
#include <vector>

#include "build_options.hpp"
#include "checkpoint.hpp"
#include "ddfem/fine_block.hpp"

namespace msfab {

struct BuildPlan {
  CoarseDatabase db;                                  // palette; at level 2 also level1 and hierarchy
  std::vector<std::int64_t> items;                    // what to fit, increasing
  std::vector<std::int64_t> item_of;                  // level 1: per combination code, its orbit's representative
  int points = 8;                                     // quadrature points of each fit
  std::string fingerprint;                            // the inputs a checkpoint must agree on besides the config
  std::function<FineBlock(std::int64_t item)> block;  // the block fitted for an item
  // Void children of an item's block (0..8). A block with void children
  // may stay unfitted (coarsened naively online); one with 8 is no element
  // and is not fitted at all (level 2's all-void arrangement).
  std::function<int(std::int64_t item)> void_children;
};

// Level 1: the palette's n^8 combinations grouped into orbits of the 48
// cube symmetries (or one orbit each without symmetry).
BuildPlan plan_level1(const BuildOptions& options);
// Level 2: reads options.base_database (InputError if it is not a level-1
// database of fitted materials) and builds the hierarchy.
// check_memory(bytes, what, remedy) is called with the pair candidates'
// features and search state before the hierarchy is built (it throws to
// refuse; StageContext::check_memory).
using MemoryCheck = std::function<void(double, const std::string&, const std::string&)>;
BuildPlan plan_level2(const BuildOptions& options, const MemoryCheck& check_memory);

// The finished database from the fits of every item. NumericalError if an
// item could not be fitted.
CoarseDatabase assemble_database(BuildPlan plan, const FittedOrbits& done);

}  // namespace msfab
