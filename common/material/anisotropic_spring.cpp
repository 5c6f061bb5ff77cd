#include "material/anisotropic_spring.hpp"

#include <cmath>
#include <sstream>

#include "core/errors.hpp"

namespace msfab {

AnisotropicSpring::AnisotropicSpring(double C, const Vec3& v) : C_(C) {
  if (!std::isfinite(C) || C < 0.0) {
    std::ostringstream os;
    os.precision(10);
    os << "anisotropic spring stiffness C must be >= 0 and finite, got " << C;
    throw InputError(os.str());
  }
  const double n = v.norm();
  if (!v.allFinite() || !(n > 0.0)) {
    std::ostringstream os;
    os.precision(10);
    os << "anisotropic spring direction v must be finite and nonzero, got (" << v(0) << ", " << v(1) << ", " << v(2)
       << ")";
    throw InputError(os.str());
  }
  v_ = v / n;
}

void AnisotropicSpring::evaluate(const Mat3& F, double* psi, Mat3* P, Mat9* dPdF) const {
  const Vec3 w = F * v_;
  const double l = w.norm();
  if (psi) *psi = C_ * (l - 1.0) * (l - 1.0);
  const bool degenerate = !(l >= kMinStretch);
  const double a = degenerate ? 0.0 : 1.0 - 1.0 / l;
  if (P) *P = (2.0 * C_ * a) * w * v_.transpose();
  if (dPdF) {
    // In the column-major flattening, X -> A X v v^T is the Kronecker product
    // (v v^T) (x) A: 3x3 block (j, k) is v_j v_k A.
    Mat3 A = (degenerate ? 1.0 : a) * Mat3::Identity();
    if (!degenerate) A += (w * w.transpose()) / (l * l * l);
    A *= 2.0 * C_;
    for (int k = 0; k < 3; ++k)
      for (int j = 0; j < 3; ++j) dPdF->block<3, 3>(3 * j, 3 * k) = (v_(j) * v_(k)) * A;
  }
}

}  // namespace msfab
