#include "io/material_config.hpp"

namespace msfab {

double read_youngs_modulus(const Config& m, const std::string& what) { return m.require_positive<double>("E", what); }

double read_poissons_ratio(const Config& m, PoissonRange range) {
  const double hi = range == PoissonRange::Solid ? 0.5 : 1.0;
  return m.require_range<double>("nu", -1.0, hi, Bounds::Open, "Poisson's ratio");
}

ElasticConstants read_elastic_constants(const Config& m, PoissonRange range, std::optional<ElasticConstants> fallback) {
  ElasticConstants c;
  if (fallback && !m.has("E"))
    c.E = m.get_or<double>("E", fallback->E);
  else
    c.E = read_youngs_modulus(m);
  if (fallback && !m.has("nu"))
    c.nu = m.get_or<double>("nu", fallback->nu);
  else
    c.nu = read_poissons_ratio(m, range);
  return c;
}

double read_density(const Config& m, std::optional<double> fallback) {
  if (fallback && !m.has("density")) return m.get_or<double>("density", *fallback);
  return m.require_positive<double>("density", "density (kg/m^3)");
}

}  // namespace msfab
