#pragma once
// The isotropic elastic constants of a material entry, read the same way in
// every stage (scene palettes, DDFEM palettes, gamut base materials,
// dynamics materials, the topology optimizer's solid):
//
//   E:       Young's modulus, > 0
//   nu:      Poisson's ratio, in (-1, 0.5) for a solid (in (-1, 1) for the
//            in-plane constants of a 2D material)
//   density: kg/m^3, > 0
#include <optional>
#include <string>

#include "io/config.hpp"

namespace msfab {

struct ElasticConstants {
  double E = 0;
  double nu = 0;
};

// Which range Poisson's ratio lies in: a 3D solid (-1, 0.5), or the in-plane
// constants of a 2D material (-1, 1).
enum class PoissonRange { Solid, InPlane };

// E and nu, both required (or, with fallbacks, optional).
ElasticConstants read_elastic_constants(const Config& m, PoissonRange range = PoissonRange::Solid,
                                        std::optional<ElasticConstants> fallback = std::nullopt);
// Young's modulus alone; `what` names it in the message.
double read_youngs_modulus(const Config& m, const std::string& what = "Young's modulus");
// Poisson's ratio alone.
double read_poissons_ratio(const Config& m, PoissonRange range = PoissonRange::Solid);
// Density: required without a fallback.
double read_density(const Config& m, std::optional<double> fallback = std::nullopt);

}  // namespace msfab
