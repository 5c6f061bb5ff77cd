#include "gamut/gamut_artifact.hpp"

#include "core/errors.hpp"
#include "io/artifact.hpp"

namespace msfab {

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
  std::vector<std::int32_t> cycle, samples, discrete, continuous;
  std::vector<double> cover, seconds;
  for (const GamutCycle& c : g.history) {
    cycle.push_back(c.cycle), samples.push_back(c.samples), discrete.push_back(c.discrete_added);
    continuous.push_back(c.continuous_added), cover.push_back(c.coverage), seconds.push_back(c.seconds);
  }
  if (!cycle.empty()) {
    f.write_vector("/history/cycle", cycle);
    f.write_vector("/history/samples", samples);
    f.write_vector("/history/discrete_added", discrete);
    f.write_vector("/history/continuous_added", continuous);
    f.write_vector("/history/coverage", cover);
    f.write_vector("/history/seconds", seconds);
  }
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
  if (f.exists("/history/cycle")) {
    const auto cycle = f.read_vector<std::int32_t>("/history/cycle");
    const auto samples = f.read_vector<std::int32_t>("/history/samples");
    const auto discrete = f.read_vector<std::int32_t>("/history/discrete_added");
    const auto continuous = f.read_vector<std::int32_t>("/history/continuous_added");
    const auto cover = f.read_vector<double>("/history/coverage");
    const auto seconds = f.read_vector<double>("/history/seconds");
    for (std::size_t i = 0; i < cycle.size(); ++i)
      g.history.push_back({cycle[i], samples.at(i), discrete.at(i), continuous.at(i), cover.at(i), seconds.at(i)});
  }
  return g;
}

}  // namespace msfab
