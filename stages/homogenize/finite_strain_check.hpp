#pragma once
// The finite-strain check of msfab-homogenize (`finite_strain` section):
// the cell under uniaxial stress at the given strains with its own
// (Neo-Hookean) materials, against the uniaxial response of its linear C^H
// (thesis §3.3: Poisson's ratio 16% off at 7% strain on average).
#include <optional>
#include <string>
#include <vector>

#include "cell_input.hpp"
#include "homog/finite_strain_cell.hpp"
#include "io/config.hpp"

namespace msfab {

struct FiniteStrainCheck {
  int axis = 0;
  std::vector<double> strains;
  FiniteStrainOptions options;
  // Filled by run_finite_strain_check:
  std::vector<UniaxialStrainPoint> points;
  double linear_nu[2] = {0, 0};  // -S(l, axis) / S(axis, axis) of C^H, lateral axes in order
  double linear_E = 0;           // 1 / S(axis, axis)
  double seconds = 0;
};

// The `finite_strain` section, or nothing when it is absent.
std::optional<FiniteStrainCheck> read_finite_strain_check(const Config& config);

// Runs the check on `in` with C^H = C; prints the table.
void run_finite_strain_check(FiniteStrainCheck& check, const CellInput& in, const Mat6& C);

}  // namespace msfab
