#include "finite_strain_check.hpp"

#include <spdlog/spdlog.h>

#include <chrono>
#include <cmath>
#include <cstdio>

#include "core/errors.hpp"

namespace msfab {

std::optional<FiniteStrainCheck> read_finite_strain_check(const Config& config) {
  if (!config.has("finite_strain")) return std::nullopt;
  const Config f = config.child("finite_strain");
  FiniteStrainCheck check;
  check.strains = f.get<std::vector<double>>("strains");
  if (check.strains.empty() || check.strains.size() > 100) f.fail("strains", "give 1 to 100 strains");
  for (double e : check.strains)
    if (!(std::isfinite(e) && e != 0 && e > -0.5 && e < 1))
      f.fail("strains", "every strain must be nonzero and in (-0.5, 1) (engineering strain along the axis)");
  check.axis = f.has("axis") ? static_cast<int>(f.one_of("axis", {"x", "y", "z"})[0] - 'x') : 0;
  check.options.max_step = f.get_or<double>("max_step", check.options.max_step);
  if (!(check.options.max_step > 0 && check.options.max_step <= 0.1)) f.fail("max_step", "must be in (0, 0.1]");
  f.check_no_unknown_keys();
  return check;
}

void run_finite_strain_check(FiniteStrainCheck& check, const CellInput& in, const Mat6& C) {
  for (const PaletteEntry& p : in.palette)
    if (p.model != "neo-hookean")
      spdlog::warn("finite_strain: material '{}' is {}: only Neo-Hookean materials change with the strain", p.name,
                   p.model);
  const Mat6 S = C.inverse();
  const int a = check.axis, lat[2] = {(a + 1) % 3, (a + 2) % 3};
  check.linear_E = 1 / S(a, a);
  for (int q = 0; q < 2; ++q) check.linear_nu[q] = -S(lat[q], a) / S(a, a);
  const auto t0 = std::chrono::steady_clock::now();
  check.points = uniaxial_finite_strain(in.cell, in.material_by_id, a, check.strains, check.options);
  check.seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  const char axes[] = "xyz";
  std::printf(
      "  finite strain, uniaxial stress along %c (void removed; %.2f s); linear C^H: E %.6g, nu_%c%c %.4f, nu_%c%c "
      "%.4f\n",
      axes[a], check.seconds, check.linear_E, axes[a], axes[lat[0]], check.linear_nu[0], axes[a], axes[lat[1]],
      check.linear_nu[1]);
  std::printf("    strain    nu_%c%c     nu_%c%c     vs linear   secant E / linear E   Newton its\n", axes[a],
              axes[lat[0]], axes[a], axes[lat[1]]);
  for (const UniaxialStrainPoint& p : check.points) {
    const double rel = 0.5 * (std::abs(p.nu[0] - check.linear_nu[0]) / std::max(std::abs(check.linear_nu[0]), 1e-12) +
                              std::abs(p.nu[1] - check.linear_nu[1]) / std::max(std::abs(check.linear_nu[1]), 1e-12));
    std::printf("    %+.4f   %+.4f   %+.4f   %6.1f%%     %.4f                %d%s\n", p.strain, p.nu[0], p.nu[1],
                100 * rel, p.nominal_stress / p.strain / check.linear_E, p.newton_iterations,
                p.shifted_factorizations > 0 ? " (Hessian shifted: a hinge, or buckled)" : "");
  }
}

}  // namespace msfab
