#pragma once
// The Voigt bound as per-cell constraints of the two-scale optimizer.
//
// No arrangement of a stiff material (volume fraction rho, tensor C_s) and
// a soft one (C_w; zero for void) is stiffer than their volume average:
// for every strain e, e^T C^H e <= e^T (rho C_s + (1 - rho) C_w) e (the
// energy of the uniform-strain field bounds the minimum energy). Every
// sampled structure obeys it. A gamut's level set, which lies a padding
// outside its samples and is extrapolated between them, does not: on the
// 2D cantilever of Fig. 3-16 the optimizer placed four cells in five
// beyond it, some with bulk moduli several times the solid's, and the
// design came out stiffer than SIMP with p = 1. The bound removes exactly
// the materials no microstructure can have; it costs nothing achievable.
//
// With B(p) = rho C_s + (1 - rho) C_w - C(p), the bound is B >= 0 (positive
// semi-definite). For the symmetries of the gamut spaces this is a few
// smooth scalar conditions g_i(p) <= 0, each scaled by the solid's
// stiffness in that mode:
//   cubic (2D, 3D; also isotropic): C_s, C_w isotropic and C(p) cubic share
//     the eigenvectors hydrostatic, deviatoric and shear, so B >= 0 is
//     v^T B v >= 0 for those three modes: 3 conditions.
//   orthotropic 2D: the shear mode, and the 2 x 2 normal block's form
//     v^T B v >= 0 for 8 directions v 22.5 degrees apart: 9 conditions,
//     linear in C. A negative eigenvalue of the normal block of at most
//     tan^2(11.25 deg) = 4% of the positive one passes. The exact test
//     (diagonal and determinant >= 0) has a determinant whose gradient
//     vanishes where B's normal block does, at the solid corner (rho = 1,
//     C = C_s), where many cells of a design sit; Ipopt's multipliers did
//     not settle there and every orthotropic run ended at its iteration
//     limit (docs/BENCHMARKS.md, "Fig. 3-16 on one gamut").
#include <vector>

#include "core/types.hpp"

namespace msfab {

enum class VoigtBoundModes { cubic, orthotropic2d };

class VoigtBound {
 public:
  VoigtBound() = default;
  // stiff, soft: m x m Voigt tensors (m = 3: 2D in-plane xx, yy, xy with
  // engineering shear; m = 6: 3D), soft zero for void. InputError on
  // mismatched or non-finite tensors, a stiff tensor that is not positive
  // definite, or a soft one stiffer than the stiff one.
  VoigtBound(MatX stiff, MatX soft, VoigtBoundModes modes);

  bool active() const { return stiff_.size() > 0; }
  int count() const;  // conditions per cell (0 when inactive)

  // g(C, rho) <= 0 per condition; with `jacobian`, dg/dp (count x n) from
  // dC/dp_k (one per parameter) and the index of rho among the parameters.
  VecX evaluate(const MatX& C, double rho, const std::vector<MatX>* dC = nullptr, int rho_index = -1,
                MatX* jacobian = nullptr) const;

 private:
  MatX stiff_, soft_;
  std::vector<VecX> mode_vectors_;  // cubic: the three eigenmodes; orthotropic: shear and 8 directions
  std::vector<double> mode_scale_;  // v^T C_s v per condition
};

}  // namespace msfab
