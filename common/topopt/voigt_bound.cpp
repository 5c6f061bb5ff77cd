#include "topopt/voigt_bound.hpp"

#include <cmath>

#include "core/errors.hpp"

namespace msfab {

namespace {

// Directions of the orthotropic normal block: 8, 22.5 degrees apart, admit
// a negative eigenvalue of at most tan^2(11.25 deg) = 4% of the positive one
// (voigt_bound.hpp).
constexpr int kOrthotropicDirections = 8;

// Hydrostatic, deviatoric and shear unit modes of a Voigt vector.
std::vector<VecX> cubic_modes(int m) {
  const int normals = m == 6 ? 3 : 2;
  VecX hydro = VecX::Zero(m), dev = VecX::Zero(m), shear = VecX::Zero(m);
  for (int i = 0; i < normals; ++i) hydro[i] = 1 / std::sqrt(double(normals));
  dev[0] = 1 / std::sqrt(2.0), dev[1] = -1 / std::sqrt(2.0);
  shear[normals] = 1;
  return {hydro, dev, shear};
}

// Orthotropic 2D: the shear mode, and the normal block's quadratic form in
// kOrthotropicDirections directions evenly spread over 180 degrees.
std::vector<VecX> orthotropic_modes() {
  std::vector<VecX> modes(1, VecX::Unit(3, 2));
  for (int k = 0; k < kOrthotropicDirections; ++k) {
    const double t = M_PI * k / kOrthotropicDirections;
    VecX v = VecX::Zero(3);
    v[0] = std::cos(t), v[1] = std::sin(t);
    modes.push_back(v);
  }
  return modes;
}

}  // namespace

VoigtBound::VoigtBound(MatX stiff, MatX soft, VoigtBoundModes modes)
    : stiff_(std::move(stiff)), soft_(std::move(soft)) {
  const Eigen::Index m = stiff_.rows();
  if ((m != 3 && m != 6) || stiff_.cols() != m || soft_.rows() != m || soft_.cols() != m)
    throw InputError("Voigt bound: the stiff and soft tensors must both be 3 x 3 (2D) or 6 x 6 (3D)");
  if (modes == VoigtBoundModes::orthotropic2d && m != 3)
    throw InputError("Voigt bound: the orthotropic modes are 2D (3 x 3 tensors)");
  if (!stiff_.allFinite() || !soft_.allFinite()) throw InputError("Voigt bound: a tensor entry is not finite");
  const Eigen::SelfAdjointEigenSolver<MatX> es(0.5 * (stiff_ + stiff_.transpose()));
  if (!(es.eigenvalues().minCoeff() > 0)) throw InputError("Voigt bound: the stiff tensor is not positive definite");
  const Eigen::SelfAdjointEigenSolver<MatX> ed(0.5 * (stiff_ - soft_ + (stiff_ - soft_).transpose()));
  if (ed.eigenvalues().minCoeff() < -1e-12 * es.eigenvalues().maxCoeff())
    throw InputError("Voigt bound: the soft tensor is stiffer than the stiff one in some mode");
  mode_vectors_ = modes == VoigtBoundModes::cubic ? cubic_modes(int(m)) : orthotropic_modes();
  for (const VecX& v : mode_vectors_) mode_scale_.push_back(v.dot(stiff_ * v));
}

int VoigtBound::count() const { return active() ? int(mode_vectors_.size()) : 0; }

VecX VoigtBound::evaluate(const MatX& C, double rho, const std::vector<MatX>* dC, int rho_index, MatX* jacobian) const {
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
  for (int i = 0; i < n; ++i) g[i] = -mode_vectors_[i].dot(B * mode_vectors_[i]) / mode_scale_[i];
  for (int k = 0; jacobian && k < params; ++k) {
    const MatX D = dB(k);
    for (int i = 0; i < n; ++i) (*jacobian)(i, k) = -mode_vectors_[i].dot(D * mode_vectors_[i]) / mode_scale_[i];
  }
  return g;
}

}  // namespace msfab
