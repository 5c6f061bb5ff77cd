#include "gamut/microstructure_set.hpp"

#include <algorithm>
#include <cmath>
#include <sstream>

#include "core/errors.hpp"
#include "io/artifact.hpp"
#include "material/linear_isotropic.hpp"

namespace msfab {
namespace {

std::string at(const std::string& group, const std::string& name) {
  return group == "/" ? "/" + name : group + "/" + name;
}

[[noreturn]] void bad(const H5File& f, const std::string& field, const std::string& problem) {
  throw InputError(f.path() + ": " + field + ": " + problem);
}

void write_grid(H5File& f, const std::string& g, const StructureGrid& grid, std::size_t items) {
  if (grid.names.size() != grid.axes.size() || grid.points() != items)
    throw std::logic_error("write_microstructure_set: the parameter grid does not match the structures");
  const std::string gg = at(g, "grid");
  f.create_group(gg);
  std::string names;
  for (const auto& name : grid.names) names += (names.empty() ? "" : ",") + name;
  f.write_attribute(gg, "names", names);
  f.write_attribute(gg, "order", "structure i is the grid point whose indices, first axis slowest, spell i");
  for (std::size_t a = 0; a < grid.axes.size(); ++a) f.write_vector(at(gg, "axis" + std::to_string(a)), grid.axes[a]);
}

StructureGrid read_grid(const H5File& f, const std::string& g, std::size_t items) {
  StructureGrid grid;
  const std::string gg = at(g, "grid");
  std::stringstream names(f.read_string_attribute(gg, "names"));
  for (std::string name; std::getline(names, name, ',');) grid.names.push_back(name);
  if (grid.names.empty() || grid.names.size() > 3) bad(f, gg + " names", "expected 1 to 3 axis names");
  for (std::size_t a = 0; a < grid.names.size(); ++a) {
    const std::string field = at(gg, "axis" + std::to_string(a));
    std::vector<double> axis = f.read_vector<double>(field);
    if (axis.empty()) bad(f, field, "is empty");
    for (std::size_t i = 0; i < axis.size(); ++i)
      if (!std::isfinite(axis[i]) || (i > 0 && !(axis[i] > axis[i - 1])))
        bad(f, field, "values must be finite and strictly increasing");
    grid.axes.push_back(std::move(axis));
  }
  if (grid.points() != items)
    bad(f, gg,
        "the grid has " + std::to_string(grid.points()) + " points but the set " + std::to_string(items) +
            " structures");
  return grid;
}

}  // namespace

std::size_t StructureGrid::points() const {
  if (axes.empty()) return 0;
  std::size_t n = 1;
  for (const auto& a : axes) n *= a.size();
  return n;
}

std::size_t StructureGrid::item(const std::vector<int>& index) const {
  if (index.size() != axes.size()) throw std::logic_error("StructureGrid::item: one index per axis");
  std::size_t i = 0;
  for (std::size_t a = 0; a < axes.size(); ++a) {
    if (index[a] < 0 || std::size_t(index[a]) >= axes[a].size()) throw std::logic_error("StructureGrid::item: index");
    i = i * axes[a].size() + std::size_t(index[a]);
  }
  return i;
}

const char* step_name(SampleStep step) {
  switch (step) {
    case SampleStep::initial: return "initial";
    case SampleStep::discrete: return "discrete";
    case SampleStep::continuous: return "continuous";
    case SampleStep::void_variant: return "void_variant";
    case SampleStep::directed: return "directed";
    case SampleStep::targeted: return "targeted";
  }
  return "?";
}

std::vector<MaterialPtr> base_palette(const MicrostructureSet& set) {
  std::vector<MaterialPtr> palette = {nullptr, std::make_shared<LinearIsotropic>(set.stiff.E, set.stiff.nu)};
  if (!set.soft_is_void) palette.push_back(std::make_shared<LinearIsotropic>(set.soft.E, set.soft.nu));
  return palette;
}

std::uint64_t voxel_hash(const std::vector<int>& ids) {
  std::uint64_t h = 1469598103934665603ULL;
  for (int v : ids) h = (h ^ static_cast<std::uint64_t>(v)) * 1099511628211ULL;
  return h;
}

int bits_per_voxel(int max_id) {
  int bits = 1;
  while ((1 << bits) <= max_id) ++bits;
  return bits;
}

std::vector<std::uint8_t> pack_voxels(const std::vector<int>& ids, int bits) {
  std::vector<std::uint8_t> bytes((ids.size() * bits + 7) / 8, 0);
  for (std::size_t v = 0; v < ids.size(); ++v)
    for (int b = 0; b < bits; ++b)
      if (ids[v] >> b & 1) {
        const std::size_t bit = v * bits + b;
        bytes[bit / 8] |= static_cast<std::uint8_t>(1u << (bit % 8));
      }
  return bytes;
}

std::vector<int> unpack_voxels(const std::uint8_t* bytes, std::size_t voxels, int bits) {
  std::vector<int> ids(voxels, 0);
  for (std::size_t v = 0; v < voxels; ++v)
    for (int b = 0; b < bits; ++b) {
      const std::size_t bit = v * bits + b;
      if (bytes[bit / 8] >> (bit % 8) & 1) ids[v] |= 1 << b;
    }
  return ids;
}

void write_microstructure_set(H5File& f, const std::string& g, const MicrostructureSet& set) {
  const std::size_t n = set.items.size();
  if (n == 0) throw std::logic_error("write_microstructure_set: no structures");
  const std::size_t voxels = std::size_t(set.nx) * set.ny * set.nz;
  const int d = static_cast<int>(set.property_names.size());
  const int bits = bits_per_voxel(set.soft_is_void ? 1 : 2);
  const std::size_t row = (voxels * bits + 7) / 8;
  std::vector<std::uint8_t> packed(n * row);
  std::vector<double> props(n * d), unit(n * d), C(n * 36);
  std::vector<std::int32_t> cycle(n), step(n);
  std::vector<std::int64_t> parent(n);
  for (std::size_t i = 0; i < n; ++i) {
    const Microstructure& m = set.items[i];
    if (m.ids.size() != voxels || m.properties.size() != d || m.unit.size() != d)
      throw std::logic_error("write_microstructure_set: structure " + std::to_string(i) + " has the wrong size");
    const std::vector<std::uint8_t> p = pack_voxels(m.ids, bits);
    std::copy(p.begin(), p.end(), packed.begin() + i * row);
    for (int a = 0; a < d; ++a) props[i * d + a] = m.properties[a], unit[i * d + a] = m.unit[a];
    for (int r = 0; r < 6; ++r)
      for (int c = 0; c < 6; ++c) C[i * 36 + 6 * r + c] = m.C(r, c);
    cycle[i] = m.cycle;
    step[i] = static_cast<std::int32_t>(m.step);
    parent[i] = m.parent;
  }
  if (g != "/" && !f.exists(g)) f.create_group(g);
  f.write_attribute(g, "space", set.space);
  f.write_attribute(g, "property_names", [&] {
    std::string s;
    for (const auto& name : set.property_names) s += (s.empty() ? "" : ",") + name;
    return s;
  }());
  f.write_attribute(g, "E_stiff", set.E_stiff);
  f.write_attribute(g, "decades", set.decades);
  f.write_attribute(g, "stiff_E", set.stiff.E);
  f.write_attribute(g, "stiff_nu", set.stiff.nu);
  f.write_attribute(g, "soft_is_void", static_cast<std::int32_t>(set.soft_is_void));
  if (!set.soft_is_void) {
    f.write_attribute(g, "soft_E", set.soft.E);
    f.write_attribute(g, "soft_nu", set.soft.nu);
  }
  f.write_vector(at(g, "size"), std::vector<std::int32_t>{set.nx, set.ny, set.nz});
  f.write_dataset(at(g, "voxels"), packed, {hsize_t(n), hsize_t(row)});
  f.write_attribute(at(g, "voxels"), "bits_per_voxel", static_cast<std::int32_t>(bits));
  f.write_attribute(
      at(g, "voxels"), "order",
      "per structure: ids x fastest (i + nx (j + ny k)), bits_per_voxel bits each, least significant first");
  f.write_attribute(at(g, "voxels"), "ids", set.soft_is_void ? "0 void, 1 stiff" : "0 void, 1 stiff, 2 soft");
  f.write_dataset(at(g, "properties"), props, {hsize_t(n), hsize_t(d)});
  f.write_dataset(at(g, "unit_properties"), unit, {hsize_t(n), hsize_t(d)});
  f.write_dataset(at(g, "C"), C, {hsize_t(n), 6, 6});
  f.write_attribute(at(g, "C"), "order", "Voigt xx, yy, zz, yz, xz, xy; engineering shear; 2D cells: plane strain");
  f.write_vector(at(g, "cycle"), cycle);
  f.write_vector(at(g, "step"), step);
  f.write_attribute(at(g, "step"), "meaning",
                    "0 initial, 1 discrete, 2 continuous, 3 void variant, 4 directed, 5 targeted");
  f.write_vector(at(g, "parent"), parent);
  if (!set.grid.empty()) write_grid(f, g, set.grid, n);
}

MicrostructureSet read_microstructure_set(const H5File& f, const std::string& g) {
  MicrostructureSet set;
  set.space = f.read_string_attribute(g, "space");
  if (set.space != "cubic3d" && set.space != "cubic2d" && set.space != "orthotropic2d")
    bad(f, g + " space", "'" + set.space + "' is not cubic3d, cubic2d or orthotropic2d");
  std::stringstream names(f.read_string_attribute(g, "property_names"));
  for (std::string name; std::getline(names, name, ',');) set.property_names.push_back(name);
  set.E_stiff = f.read_attribute<double>(g, "E_stiff");
  set.decades = f.read_attribute<double>(g, "decades");
  set.stiff.E = f.read_attribute<double>(g, "stiff_E");
  set.stiff.nu = f.read_attribute<double>(g, "stiff_nu");
  set.soft_is_void = f.read_attribute<std::int32_t>(g, "soft_is_void") != 0;
  if (!set.soft_is_void) {
    set.soft.E = f.read_attribute<double>(g, "soft_E");
    set.soft.nu = f.read_attribute<double>(g, "soft_nu");
  }
  const std::vector<std::int32_t> size = f.read_vector<std::int32_t>(at(g, "size"));
  if (size.size() != 3 || size[0] < 1 || size[1] < 1 || size[2] < 1) bad(f, at(g, "size"), "expected 3 positive sizes");
  set.nx = size[0], set.ny = size[1], set.nz = size[2];
  const std::size_t voxels = std::size_t(set.nx) * set.ny * set.nz;
  const int bits = f.read_attribute<std::int32_t>(at(g, "voxels"), "bits_per_voxel");
  if (bits < 1 || bits > 8) bad(f, at(g, "voxels") + " bits_per_voxel", "must be 1..8");
  const NdArray<std::uint8_t> packed = f.read_dataset<std::uint8_t>(at(g, "voxels"));
  const std::size_t row = (voxels * bits + 7) / 8;
  if (packed.shape.size() != 2 || packed.shape[1] != row)
    bad(f, at(g, "voxels"), "expected rows of " + std::to_string(row) + " bytes");
  const std::size_t n = packed.shape[0];
  const int d = static_cast<int>(set.property_names.size());
  const MatX props = f.read_matrix<double>(at(g, "properties"), d);
  const MatX unit = f.read_matrix<double>(at(g, "unit_properties"), d);
  const NdArray<double> C = f.read_dataset<double>(at(g, "C"));
  const std::vector<std::int32_t> cycle = f.read_vector<std::int32_t>(at(g, "cycle"));
  const std::vector<std::int32_t> step = f.read_vector<std::int32_t>(at(g, "step"));
  const std::vector<std::int64_t> parent = f.read_vector<std::int64_t>(at(g, "parent"));
  if (std::size_t(props.rows()) != n || std::size_t(unit.rows()) != n || C.values.size() != n * 36 ||
      cycle.size() != n || step.size() != n || parent.size() != n)
    bad(f, g, "the datasets disagree on the number of structures (" + std::to_string(n) + " voxel rows)");
  set.items.resize(n);
  for (std::size_t i = 0; i < n; ++i) {
    Microstructure& m = set.items[i];
    m.ids = unpack_voxels(&packed.values[i * row], voxels, bits);
    m.properties = props.row(i).transpose();
    m.unit = unit.row(i).transpose();
    for (int r = 0; r < 6; ++r)
      for (int c = 0; c < 6; ++c) m.C(r, c) = C.values[i * 36 + 6 * r + c];
    m.cycle = cycle[i];
    if (step[i] < 0 || step[i] > 5) bad(f, at(g, "step"), "value " + std::to_string(step[i]) + " is not 0..5");
    m.step = static_cast<SampleStep>(step[i]);
    m.parent = parent[i];
  }
  if (f.exists(at(g, "grid"))) set.grid = read_grid(f, g, n);
  return set;
}

void write_microstructures_artifact(const std::string& path, const MicrostructureSet& set,
                                    const std::string& executable, const std::string& config_text,
                                    const std::vector<std::string>& inputs, std::uint64_t seed) {
  ArtifactWriter out(path, kMicrostructuresSchema, kMicrostructuresSchemaVersion, executable, config_text, inputs,
                     seed);
  write_microstructure_set(out.file(), "/", set);
  out.commit();
}

MicrostructureSet read_microstructures_artifact(const std::string& path) {
  const ArtifactReader in(path, kMicrostructuresSchema, kMicrostructuresSchemaVersion);
  return read_microstructure_set(in.file(), "/");
}

}  // namespace msfab
