#pragma once
// What names a point of a material space in an artifact: the space, its
// properties' names and the normalization of MaterialSpace (E_stiff, the
// number of decades). Gamuts and designs carry it alike, as root
// attributes, so a design can be checked against the gamut it was made in.
#include <string>
#include <vector>

namespace msfab {

class H5File;

struct SpaceLabel {
  std::string space;  // the space's kind name (MaterialSpace, or a SIMP / analytic space of a design)
  std::vector<std::string> property_names;
  double E_stiff = 0, decades = 4;
};

// Root attributes space, property_names, E_stiff and decades.
void write_space_label(H5File& f, const SpaceLabel& label);
SpaceLabel read_space_label(const H5File& f);

}  // namespace msfab
