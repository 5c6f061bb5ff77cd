// Homogenizes a two-layer laminate cell with msfab and compares the stiffness
// across the layers with the exact laminate value, C*_zzzz = <1/(lambda + 2 mu)>^-1
// (in-plane strains are fixed by the macroscopic strain, the normal stress is
// continuous across the layers). Prints both and exits 1 if they differ.
#include <cmath>
#include <cstdio>
#include <memory>

#include "homog/periodic_homogenization.hpp"
#include "material/linear_isotropic.hpp"

int main() {
  using namespace msfab;
  const double E1 = 1.0e6, E2 = 1.0e7, nu = 0.3;
  VoxelGrid cell(2, 2, 4, 1.0e-3, 1);
  for (int k = 2; k < 4; ++k)
    for (int j = 0; j < 2; ++j)
      for (int i = 0; i < 2; ++i) cell.at(i, j, k) = 2;
  const std::vector<MaterialPtr> palette{nullptr, std::make_shared<LinearIsotropic>(E1, nu),
                                         std::make_shared<LinearIsotropic>(E2, nu)};
  const HomogenizationResult r = homogenize(cell, palette);
  auto p_modulus = [&](double E) { return E * (1 - nu) / ((1 + nu) * (1 - 2 * nu)); };
  const double exact = 1.0 / (0.5 / p_modulus(E1) + 0.5 / p_modulus(E2));
  const double relative = std::abs(r.C(2, 2) - exact) / exact;
  std::printf("laminate C_zzzz: msfab %.12e, exact %.12e, relative difference %.2e\n", r.C(2, 2), exact, relative);
  return relative < 1e-9 ? 0 : 1;
}
