#include "gamut/space_label.hpp"

#include "io/artifact.hpp"
#include "io/hdf5_file.hpp"

namespace msfab {

void write_space_label(H5File& f, const SpaceLabel& label) {
  f.write_attribute("/", "space", label.space);
  f.write_attribute("/", "property_names", format_name_list(label.property_names));
  f.write_attribute("/", "E_stiff", label.E_stiff);
  f.write_attribute("/", "decades", label.decades);
}

SpaceLabel read_space_label(const H5File& f) {
  SpaceLabel label;
  label.space = f.read_string_attribute("/", "space");
  label.property_names = parse_name_list(f.read_string_attribute("/", "property_names"));
  label.E_stiff = f.read_attribute<double>("/", "E_stiff");
  label.decades = f.read_attribute<double>("/", "decades");
  return label;
}

}  // namespace msfab
