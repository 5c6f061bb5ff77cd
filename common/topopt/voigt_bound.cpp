#include "topopt/voigt_bound.hpp"

#include <cmath>

#include "core/errors.hpp"

namespace msfab {

namespace {

// Hydrostatic, deviatoric and shear unit modes of a Voigt vector.
std::vector<VecX> cubic_modes(int m) {
  const int normals = m == 6 ? 3 : 2;
  VecX hydro = VecX::Zero(m), dev = VecX::Zero(m), shear = VecX::Zero(m);
  for (int i = 0; i < normals; ++i) hydro[i] = 1 / std::sqrt(double(normals));
  dev[0] = 1 / std::sqrt(2.0), dev[1] = -1 / std::sqrt(2.0);
  shear[normals] = 1;
  return {hydro, dev, shear};
}

}  // namespace

VoigtBound::VoigtBound(MatX stiff, MatX soft, VoigtBoundModes modes)
    : stiff_(std::move(stiff)), soft_(std::move(soft)), modes_(modes) {
  const Eigen::Index m = stiff_.rows();
  if ((m != 3 && m != 6) || stiff_.cols() != m || soft_.rows() != m || soft_.cols() != m)
    throw InputError("Voigt bound: the stiff and soft tensors must both be 3 x 3 (2D) or 6 x 6 (3D)");
  if (modes_ == VoigtBoundModes::orthotropic2d && m != 3)
    throw InputError("Voigt bound: the orthotropic modes are 2D (3 x 3 tensors)");
  if (!stiff_.allFinite() || !soft_.allFinite()) throw InputError("Voigt bound: a tensor entry is not finite");
  const Eigen::SelfAdjointEigenSolver<MatX> es(0.5 * (stiff_ + stiff_.transpose()));
  if (!(es.eigenvalues().minCoeff() > 0)) throw InputError("Voigt bound: the stiff tensor is not positive definite");
  const Eigen::SelfAdjointEigenSolver<MatX> ed(0.5 * (stiff_ - soft_ + (stiff_ - soft_).transpose()));
  if (ed.eigenvalues().minCoeff() < -1e-12 * es.eigenvalues().maxCoeff())
    throw InputError("Voigt bound: the soft tensor is stiffer than the stiff one in some mode");
  if (modes_ == VoigtBoundModes::cubic) {
    mode_vectors_ = cubic_modes(int(m));
    for (const VecX& v : mode_vectors_) mode_scale_.push_back(v.dot(stiff_ * v));
  } else {
    mode_scale_ = {stiff_(2, 2), stiff_(0, 0), stiff_(1, 1), stiff_(0, 0) * stiff_(1, 1)};
  }
}

int VoigtBound::count() const {
  if (!active()) return 0;
  return modes_ == VoigtBoundModes::cubic ? 3 : 4;
}

VecX VoigtBound::evaluate(const MatX& C, double rho, const std::vector<MatX>* dC, int rho_index,
                          MatX* jacobian) const {
  const int n = count();
  VecX g(n);
  if (n == 0) return g;
  const MatX B = rho * stiff_ + (1 - rho) * soft_ - C;
  const MatX dB_drho = stiff_ - soft_;
  const int params = dC ? int(dC->size()) : 0;
  if (jacobian) {
    if (!dC || rho_index < 0 || rho_index >= params)
      throw std::logic_error("VoigtBound::evaluate: a Jacobian needs dC and the index of rho");
    jacobian->setZero(n, params);
  }
  // dB/dp_k: -dC_k, plus (C_s - C_w) for rho.
  auto dB = [&](int k) -> MatX {
    MatX d = -(*dC)[k];
    if (k == rho_index) d += dB_drho;
    return d;
  };
  if (modes_ == VoigtBoundModes::cubic) {
    for (int i = 0; i < n; ++i) g[i] = -mode_vectors_[i].dot(B * mode_vectors_[i]) / mode_scale_[i];
    for (int k = 0; jacobian && k < params; ++k) {
      const MatX D = dB(k);
      for (int i = 0; i < n; ++i) (*jacobian)(i, k) = -mode_vectors_[i].dot(D * mode_vectors_[i]) / mode_scale_[i];
    }
    return g;
  }
  // Orthotropic 2D: shear, the two normal diagonals, the normal block's determinant.
  const double a = B(0, 0), b = B(0, 1), d = B(1, 1);
  g << -B(2, 2) / mode_scale_[0], -a / mode_scale_[1], -d / mode_scale_[2], -(a * d - b * b) / mode_scale_[3];
  if (jacobian) {
    for (int k = 0; k < params; ++k) {
      const MatX D = dB(k);
      (*jacobian)(0, k) = -D(2, 2) / mode_scale_[0];
      (*jacobian)(1, k) = -D(0, 0) / mode_scale_[1];
      (*jacobian)(2, k) = -D(1, 1) / mode_scale_[2];
      (*jacobian)(3, k) = -(D(0, 0) * d + a * D(1, 1) - 2 * b * D(0, 1)) / mode_scale_[3];
    }
  }
  return g;
}

}  // namespace msfab
