#pragma once
// Whether a microstructure set belongs to the gamut a design was optimized
// in. Structure properties alone cannot tell: two gamuts of the same base
// material share space, names and normalization, and mapping a design to
// the other one's structures silently gives the wrong objects. The
// artifacts' `inputs` attributes (path and SHA-256) can: the design lists
// its gamut, the gamut lists its structures.
#include <string>

namespace msfab {

// Nothing to check for a design whose inputs list the set itself
// (msfab-assign). Otherwise InputError naming both files when the design's
// gamut (its first input of schema msfab.gamut, if that file is still there
// unchanged) was built from other structures than `structures_path` and
// the set is not derived from them either (a set whose own inputs list
// them: msfab-fill-targets, msfab-homogenize). Where the gamut cannot be
// found or has changed since the design was written, a warning and no
// check.
void check_set_belongs_to_design(const std::string& design_path, const std::string& structures_path);

}  // namespace msfab
