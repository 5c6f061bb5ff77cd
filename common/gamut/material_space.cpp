#include "gamut/material_space.hpp"

#include <algorithm>
#include <cmath>

#include "core/errors.hpp"

namespace msfab {

MaterialSpace::MaterialSpace(MaterialSpaceKind kind, double E_stiff, double decades)
    : kind_(kind), E_stiff_(E_stiff), decades_(decades) {
  if (!(E_stiff > 0) || !(decades > 0)) throw InputError("material space: E_stiff and decades must be > 0");
}

MaterialSpaceKind MaterialSpace::parse_kind(const std::string& name) {
  if (name == "cubic3d") return MaterialSpaceKind::cubic3d;
  if (name == "cubic2d") return MaterialSpaceKind::cubic2d;
  if (name == "orthotropic2d") return MaterialSpaceKind::orthotropic2d;
  throw InputError("material space '" + name + "': expected cubic3d, cubic2d or orthotropic2d");
}

int MaterialSpace::dimension() const { return kind_ == MaterialSpaceKind::orthotropic2d ? 5 : 4; }

std::vector<std::string> MaterialSpace::names() const {
  if (kind_ == MaterialSpaceKind::orthotropic2d) return {"Ex", "Ey", "nu_xy", "G", "rho"};
  return {"E", "nu", "G", "rho"};
}

bool MaterialSpace::is_modulus(int i) const {
  if (kind_ == MaterialSpaceKind::orthotropic2d) return i == 0 || i == 1 || i == 3;
  return i == 0 || i == 2;
}

VecX MaterialSpace::properties(const Mat6& C, double rho) const {
  if (kind_ != MaterialSpaceKind::cubic3d) throw std::logic_error("MaterialSpace::properties: a 2D space");
  const CubicModuli m = cubic_moduli(C);
  VecX p(4);
  p << m.E, m.nu, m.G, rho;
  return p;
}

bool MaterialSpace::clamp_to_box(VecX& unit) {
  bool inside = true;
  for (Eigen::Index a = 0; a < unit.size(); ++a) {
    if (!(unit[a] >= -1e-9 && unit[a] <= 1 + 1e-9)) inside = false;
    unit[a] = std::clamp(unit[a], 0.0, 1.0);
  }
  return inside;
}

VecX MaterialSpace::cell_properties(const Mat6& C, double rho) const {
  if (kind_ == MaterialSpaceKind::cubic3d) return properties(C, rho);
  return properties_2d(plane_block(C), rho);
}

VecX MaterialSpace::properties_2d(const Mat3& C, double rho) const {
  if (kind_ == MaterialSpaceKind::cubic3d) throw std::logic_error("MaterialSpace::properties_2d: a 3D space");
  const Mat3 S = C.inverse();
  if (kind_ == MaterialSpaceKind::orthotropic2d) {
    VecX p(5);
    p << 1 / S(0, 0), 1 / S(1, 1), -S(0, 1) / S(0, 0), 1 / S(2, 2), rho;
    return p;
  }
  // Square symmetry: average the two axes.
  const double s11 = 0.5 * (S(0, 0) + S(1, 1));
  VecX p(4);
  p << 1 / s11, -S(0, 1) / s11, 1 / S(2, 2), rho;
  return p;
}

VecX MaterialSpace::properties_with_gradient(const MatX& C, double rho, std::vector<MatX>* dC) const {
  const int m = kind_ == MaterialSpaceKind::cubic3d ? 6 : 3;
  if (C.rows() != m || C.cols() != m)
    throw std::invalid_argument("MaterialSpace::properties_with_gradient: wrong size");
  // The values come from the readers above, so the two cannot drift apart.
  const VecX p = m == 6 ? properties(Mat6(C), rho) : properties_2d(Mat3(C), rho);
  if (!dC) return p;
  const int n = dimension();
  dC->assign(n, MatX::Zero(m, m));
  if (kind_ == MaterialSpaceKind::cubic3d) {
    // cubic_moduli(): C11, C12, C44 as means over the symmetric entries.
    const CubicModuli c = cubic_moduli(C);
    const double a = c.C11, b = c.C12, s = a + b;
    const double dE_da = ((a + 2 * b) + (a - b)) / s - c.E / s, dE_db = (-(a + 2 * b) + 2 * (a - b)) / s - c.E / s;
    const double dnu_da = -b / (s * s), dnu_db = a / (s * s);
    for (int i = 0; i < 3; ++i) {
      (*dC)[0](i, i) = dE_da / 3, (*dC)[1](i, i) = dnu_da / 3;
      (*dC)[2](3 + i, 3 + i) = 1.0 / 3;
    }
    for (auto [i, j] : {std::pair{0, 1}, {0, 2}, {1, 2}}) (*dC)[0](i, j) = dE_db / 3, (*dC)[1](i, j) = dnu_db / 3;
    return p;
  }
  // Through the compliance S = C^-1: dS = -S dC S, so d/dC = -S (d/dS) S.
  const MatX S = C.inverse();
  std::vector<MatX> dS(n - 1, MatX::Zero(3, 3));
  if (kind_ == MaterialSpaceKind::orthotropic2d) {
    dS[0](0, 0) = -p[0] * p[0];
    dS[1](1, 1) = -p[1] * p[1];
    dS[2](0, 1) = -1 / S(0, 0), dS[2](0, 0) = S(0, 1) / (S(0, 0) * S(0, 0));
    dS[3](2, 2) = -p[3] * p[3];
  } else {
    const double s11 = 0.5 * (S(0, 0) + S(1, 1));
    dS[0](0, 0) = dS[0](1, 1) = -0.5 / (s11 * s11);
    dS[1](0, 1) = -1 / s11, dS[1](0, 0) = dS[1](1, 1) = 0.5 * S(0, 1) / (s11 * s11);
    dS[2](2, 2) = -p[2] * p[2];
  }
  for (int i = 0; i < n - 1; ++i) (*dC)[i] = -S.transpose() * dS[i] * S.transpose();
  return p;
}

template <class Density, class Modulus, class Poisson>
VecX MaterialSpace::map_coordinates(const VecX& x, const char* what, Density density, Modulus modulus,
                                    Poisson poisson) const {
  if (x.size() != dimension()) throw std::invalid_argument(std::string("MaterialSpace::") + what + ": wrong dimension");
  VecX y(x.size());
  for (int i = 0; i < x.size(); ++i)
    y[i] = i == x.size() - 1 ? density(x[i]) : is_modulus(i) ? modulus(x[i]) : poisson(x[i]);
  return y;
}

VecX MaterialSpace::unit_derivative(const VecX& raw) const {
  return map_coordinates(
      raw, "unit_derivative", [](double) { return 1.0; }, [&](double E) { return 1 / (E * std::log(10.0) * decades_); },
      [&](double) { return 1 / (nu_high() - nu_low()); });
}

Mat6 MaterialSpace::tensor_3d(const VecX& raw) const {
  if (kind_ != MaterialSpaceKind::cubic3d || raw.size() != 4) throw std::logic_error("MaterialSpace::tensor_3d");
  const double E = raw[0], nu = raw[1], G = raw[2];
  // Cubic compliance: S11 = 1/E, S12 = -nu/E, S44 = 1/G.
  Mat6 S = Mat6::Zero();
  for (int i = 0; i < 3; ++i) {
    for (int j = 0; j < 3; ++j) S(i, j) = -nu / E;
    S(i, i) = 1 / E;
    S(3 + i, 3 + i) = 1 / G;
  }
  return S.inverse();
}

Mat3 MaterialSpace::tensor_2d(const VecX& raw) const {
  Mat3 S = Mat3::Zero();
  if (kind_ == MaterialSpaceKind::orthotropic2d && raw.size() == 5) {
    S(0, 0) = 1 / raw[0];
    S(1, 1) = 1 / raw[1];
    S(0, 1) = S(1, 0) = -raw[2] / raw[0];
    S(2, 2) = 1 / raw[3];
  } else if (kind_ == MaterialSpaceKind::cubic2d && raw.size() == 4) {
    S(0, 0) = S(1, 1) = 1 / raw[0];
    S(0, 1) = S(1, 0) = -raw[1] / raw[0];
    S(2, 2) = 1 / raw[2];
  } else {
    throw std::logic_error("MaterialSpace::tensor_2d");
  }
  return S.inverse();
}

VecX MaterialSpace::normalize(const VecX& raw) const {
  return map_coordinates(
      raw, "normalize", [](double rho) { return rho; },
      [&](double E) { return 1 + std::log10(E / E_stiff_) / decades_; },
      [&](double nu) { return (nu - nu_low()) / (nu_high() - nu_low()); });
}

VecX MaterialSpace::denormalize(const VecX& u) const {
  return map_coordinates(
      u, "denormalize", [](double rho) { return rho; },
      [&](double unit) { return E_stiff_ * std::pow(10.0, (unit - 1) * decades_); },
      [&](double unit) { return nu_low() + unit * (nu_high() - nu_low()); });
}

}  // namespace msfab
