#include "material/green_anisotropic.hpp"

#include <Eigen/Eigenvalues>

#include "core/errors.hpp"
#include "material/voigt.hpp"

namespace msfab {
namespace {

// flat(voigt_to_stress(s)) = T s.
Eigen::Matrix<double, 9, 6> stress_unflattening() {
  Eigen::Matrix<double, 9, 6> T;
  for (int c = 0; c < 6; ++c) T.col(c) = flat(voigt_to_stress(Vec6::Unit(c)));
  return T;
}

// flat(A X) = left_product(A) flat(X), column-major flattening.
Mat9 left_product(const Mat3& A) {
  Mat9 M = Mat9::Zero();
  for (int j = 0; j < 3; ++j) M.block<3, 3>(3 * j, 3 * j) = A;
  return M;
}

// flat(X B) = right_product(B) flat(X).
Mat9 right_product(const Mat3& B) {
  Mat9 M;
  for (int j = 0; j < 3; ++j)
    for (int k = 0; k < 3; ++k) M.block<3, 3>(3 * j, 3 * k) = B(k, j) * Mat3::Identity();
  return M;
}

// C finite, symmetric and positive semidefinite, or InputError.
const Mat6& checked_semidefinite(const Mat6& C) {
  if (!C.allFinite()) throw InputError("green_anisotropic: stiffness matrix C is not finite");
  const double scale = C.cwiseAbs().maxCoeff();
  if ((C - C.transpose()).cwiseAbs().maxCoeff() > 1e-10 * scale)
    throw InputError("green_anisotropic: stiffness matrix C is not symmetric");
  const Mat6 symmetric = 0.5 * (C + C.transpose());
  const double smallest = Eigen::SelfAdjointEigenSolver<Mat6>(symmetric, Eigen::EigenvaluesOnly).eigenvalues()[0];
  if (smallest < -1e-10 * scale)
    throw InputError("green_anisotropic: stiffness matrix C is not positive semidefinite (eigenvalue " +
                     std::to_string(smallest) + ")");
  return C;
}

}  // namespace

GreenAnisotropic::GreenAnisotropic(const Mat6& C) : StiffnessMaterial(checked_semidefinite(C)) {}

void GreenAnisotropic::evaluate(const Mat3& F, double* psi, Mat3* P, Mat9* dPdF) const {
  const Vec6 e = strain_to_voigt(0.5 * (F.transpose() * F - Mat3::Identity()));
  const Vec6 s = C_ * e;
  if (psi) *psi = 0.5 * e.dot(s);
  const Mat3 S = voigt_to_stress(s);
  if (P) *P = F * S;
  if (dPdF) {
    // dP = dF S + F dS, dS = voigt_to_stress(C de), de = strain_to_voigt(F^T dF).
    // Coefficient-based (lazy) products: a chain of these sizes would go
    // through Eigen's general matrix product, whose packing cost 70% of this
    // Hessian (the matched DDFEM materials evaluate it at every point).
    static const Eigen::Matrix<double, 9, 6> T = stress_unflattening();
    static const Eigen::Matrix<double, 6, 9> B = voigt_strain_operator();
    const Eigen::Matrix<double, 6, 9> strain_of_dF = B.lazyProduct(left_product(F.transpose()));
    const Eigen::Matrix<double, 9, 6> stress_to_dP = left_product(F).lazyProduct(T);
    const Eigen::Matrix<double, 6, 9> dS = C_.lazyProduct(strain_of_dF);
    *dPdF = right_product(S);
    dPdF->noalias() += stress_to_dP.lazyProduct(dS);
  }
}

}  // namespace msfab
