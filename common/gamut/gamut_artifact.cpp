#include "gamut/gamut_artifact.hpp"

#include "core/errors.hpp"
#include "io/artifact.hpp"
#include "io/field_table.hpp"

namespace msfab {

namespace {
const FieldOf<GamutCycle> kHistoryFields[] = {
    MSFAB_FIELD(GamutCycle, cycle),          MSFAB_FIELD(GamutCycle, samples),
    MSFAB_FIELD(GamutCycle, discrete_added), MSFAB_FIELD(GamutCycle, continuous_added),
    MSFAB_FIELD(GamutCycle, coverage),       MSFAB_FIELD(GamutCycle, seconds)};
}  // namespace

double coverage(const GamutLevelSet& ls) {
  const int d = ls.dimension(), n = ls.cells();
  std::vector<int> index(d, 0);
  long long inside = 0, total = 0;
  const std::vector<double>& phi = ls.values();
  for (std::size_t v = 0; v < phi.size(); ++v) {
    long long flat = static_cast<long long>(v);
    bool in_cube = true;
    for (int a = 0; a < d; ++a) {
      const double x = ls.lower() + (flat % n + 0.5) * ls.spacing();
      flat /= n;
      in_cube &= x >= 0 && x <= 1;
    }
    if (!in_cube) continue;
    ++total;
    inside += phi[v] <= 0;
  }
  return total > 0 ? double(inside) / total : 0.0;
}

void write_gamut_artifact(const std::string& path, const Gamut& g, const std::string& executable,
                          const std::string& config_text, const std::vector<std::string>& inputs, std::uint64_t seed) {
  ArtifactWriter out(path, kGamutSchema, kGamutSchemaVersion, executable, config_text, inputs, seed);
  write_gamut(out.file(), g);
  out.commit();
}

void write_gamut(H5File& f, const Gamut& g) {
  write_space_label(f, g);
  const GamutLevelSet& ls = g.level_set;
  std::vector<hsize_t> shape(ls.dimension(), hsize_t(ls.cells()));
  f.write_dataset("/level_set/phi", ls.values(), shape);
  f.write_attribute("/level_set/phi", "order",
                    "C order over (p_{d-1}, ..., p_0): the first property varies fastest in memory");
  f.write_attribute("/level_set", "dimension", static_cast<std::int32_t>(ls.dimension()));
  f.write_attribute("/level_set", "cells", static_cast<std::int32_t>(ls.cells()));
  f.write_attribute("/level_set", "lower", ls.lower());
  f.write_attribute("/level_set", "spacing", ls.spacing());
  f.write_attribute("/level_set", "padding", ls.padding());
  f.write_attribute(
      "/level_set", "meaning",
      "signed distance in normalized property space, negative inside; node i at lower + (i + 1/2) spacing");
  if (g.bound_stiff.size() > 0) {
    f.write_matrix("/bound/stiff", g.bound_stiff);
    f.write_matrix("/bound/soft", g.bound_soft);
    f.write_attribute("/bound", "meaning",
                      "base-material tensors (Voigt, engineering shear; 2D: plane-strain xx, yy, xy block; soft zero "
                      "for void): every structure has C <= rho stiff + (1 - rho) soft");
  }
  write_column_fields(f, "/history", g.history, kHistoryFields);
}

namespace {

// Artifacts written before the padding was stored used the default radius
// of the implicit function, 1.5 grid spacings.
double read_padding(const H5File& f, const std::string& path) {
  const double padding = f.has_attribute("/level_set", "padding")
                             ? f.read_attribute<double>("/level_set", "padding")
                             : 1.5 * f.read_attribute<double>("/level_set", "spacing");
  if (!(padding >= 0) || !std::isfinite(padding))
    throw InputError(path + ": /level_set attribute padding must be finite and >= 0");
  return padding;
}

MatX read_bound_tensor(const H5File& f, const std::string& path, const std::string& name, int m) {
  const MatX M = f.read_matrix<double>(name, m);
  if (M.rows() != m) throw InputError(path + ": " + name + " must be " + std::to_string(m) + " x " + std::to_string(m));
  if (!M.allFinite()) throw InputError(path + ": " + name + " has a value that is not finite");
  return M;
}

}  // namespace

Gamut read_gamut_artifact(const std::string& path) {
  const ArtifactReader in(path, kGamutSchema, kGamutSchemaVersion);
  const H5File& f = in.file();
  Gamut g;
  static_cast<SpaceLabel&>(g) = read_space_label(f);
  const int d = f.read_attribute<std::int32_t>("/level_set", "dimension");
  if (d != static_cast<int>(g.property_names.size()))
    throw InputError(path + ": /level_set dimension " + std::to_string(d) + " differs from the " +
                     std::to_string(g.property_names.size()) + " property names");
  const NdArray<double> phi = f.read_dataset<double>("/level_set/phi");
  g.level_set = GamutLevelSet::from_values(
      d, f.read_attribute<std::int32_t>("/level_set", "cells"), f.read_attribute<double>("/level_set", "lower"),
      f.read_attribute<double>("/level_set", "spacing"), phi.values, read_padding(f, path));
  if (f.exists("/bound/stiff")) {
    const int m = g.space == "cubic3d" ? 6 : 3;
    g.bound_stiff = read_bound_tensor(f, path, "/bound/stiff", m);
    g.bound_soft = read_bound_tensor(f, path, "/bound/soft", m);
  }
  g.history = read_column_fields(f, "/history", kHistoryFields);
  return g;
}

}  // namespace msfab
