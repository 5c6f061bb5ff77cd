#include "topopt/cell_material.hpp"

#include <cmath>
#include <functional>

#include "core/errors.hpp"

namespace msfab {

namespace {

constexpr double kLn10 = 2.302585092994046;

// The unit-cube normalization shared with gamut/material_space.hpp.
struct UnitScale {
  double E0, decades;
  double modulus(double u) const { return E0 * std::pow(10.0, (u - 1) * decades); }
  double modulus_rate() const { return decades * kLn10; }  // (dE/du) / E
  double modulus_unit(double E) const { return 1 + std::log10(E / E0) / decades; }
};

int voigt_size(int dim) { return dim == 3 ? 6 : 3; }

// Compliance of an isotropic (or, with G free, cubic) material:
// S_ii = 1/E, S_ij = -nu/E (normal block), S_shear = 1/G.
void add_cubic_compliance(int dim, double E, double nu, double G, MatX& S) {
  const int normals = dim == 3 ? 3 : 2, m = voigt_size(dim);
  S = MatX::Zero(m, m);
  for (int i = 0; i < normals; ++i) {
    for (int j = 0; j < normals; ++j) S(i, j) = -nu / E;
    S(i, i) = 1 / E;
  }
  for (int i = normals; i < m; ++i) S(i, i) = 1 / G;
}
// dS/dE, dS/dnu, dS/dG of the above.
void cubic_compliance_derivatives(int dim, double E, double nu, double G, MatX& dE, MatX& dnu, MatX& dG) {
  const int normals = dim == 3 ? 3 : 2, m = voigt_size(dim);
  dE = MatX::Zero(m, m), dnu = MatX::Zero(m, m), dG = MatX::Zero(m, m);
  for (int i = 0; i < normals; ++i) {
    for (int j = 0; j < normals; ++j) dE(i, j) = nu / (E * E), dnu(i, j) = -1 / E;
    dE(i, i) = -1 / (E * E), dnu(i, i) = 0;
  }
  for (int i = normals; i < m; ++i) dG(i, i) = -1 / (G * G);
}

class CubicModel : public CellMaterialModel {
 public:
  CubicModel(int dim, UnitScale scale, const GamutLevelSet* ls) : dim_(dim), scale_(scale), ls_(ls) {}
  std::string space() const override { return dim_ == 3 ? "cubic3d" : "cubic2d"; }
  std::vector<std::string> names() const override { return {"E", "nu", "G", "rho"}; }
  int dimension() const override { return dim_; }
  VecX raw(const VecX& p) const override {
    VecX r(4);
    r << scale_.modulus(p[0]), nu(p[1]), scale_.modulus(p[2]), p[3];
    return r;
  }
  bool has_constraint() const override { return true; }
  double constraint(const VecX& p, VecX* g) const override { return ls_->smooth_value(p, g); }
  VecX initial_point(double rho) const override;

 protected:
  void compliance(const VecX& p, MatX& S, std::vector<MatX>& dS) const override {
    const VecX r = raw(p);
    add_cubic_compliance(dim_, r[0], r[1], r[2], S);
    MatX dE, dnu, dG;
    cubic_compliance_derivatives(dim_, r[0], r[1], r[2], dE, dnu, dG);
    dS = {dE * r[0] * scale_.modulus_rate(), dnu * nu_range(), dG * r[2] * scale_.modulus_rate(),
          MatX::Zero(S.rows(), S.cols())};
  }
  double nu_range() const { return dim_ == 3 ? 1.5 : 2.0; }
  double nu(double u) const { return -1 + u * nu_range(); }

  int dim_;
  UnitScale scale_;
  const GamutLevelSet* ls_;
};

// Starts from the gamut point nearest to (rho, rho-scaled moduli) found by
// walking down the level set's gradient.
VecX descend_into(const VecX& start, const std::function<double(const VecX&, VecX*)>& phi) {
  VecX p = start;
  for (int it = 0; it < 200; ++it) {
    VecX g;
    const double v = phi(p, &g);
    if (v <= -1e-3) break;
    if (g.squaredNorm() < 1e-20) break;
    p -= (v + 2e-3) * g / g.squaredNorm();
    p = p.cwiseMax(1e-3).cwiseMin(1 - 1e-3);
  }
  return p;
}

VecX CubicModel::initial_point(double rho) const {
  VecX p(4);
  // Voigt-like guess: E ~ rho E0 (on the log scale), nu 0.3, G ~ rho E0 / 2.6.
  const double E = std::max(rho, 1e-3) * scale_.E0;
  p << scale_.modulus_unit(E), (0.3 + 1) / nu_range(), scale_.modulus_unit(E / 2.6), rho;
  p = p.cwiseMax(1e-3).cwiseMin(1 - 1e-3);
  return descend_into(p, [&](const VecX& q, VecX* g) { return constraint(q, g); });
}

const std::vector<std::string> kOrthotropicNames = {"Ex", "Ey", "nu_xy", "G", "rho"};

class OrthotropicModel : public CellMaterialModel {
 public:
  OrthotropicModel(UnitScale scale, const GamutLevelSet* ls) : scale_(scale), ls_(ls) {}
  std::string space() const override { return "orthotropic2d"; }
  std::vector<std::string> names() const override { return kOrthotropicNames; }
  VoigtBoundModes bound_modes() const override { return VoigtBoundModes::orthotropic2d; }
  int dimension() const override { return 2; }
  VecX raw(const VecX& p) const override {
    VecX r(5);
    r << scale_.modulus(p[0]), scale_.modulus(p[1]), -1 + 2 * p[2], scale_.modulus(p[3]), p[4];
    return r;
  }
  bool has_constraint() const override { return true; }
  double constraint(const VecX& p, VecX* g) const override { return ls_->smooth_value(p, g); }
  VecX initial_point(double rho) const override {
    VecX p(5);
    const double E = std::max(rho, 1e-3) * scale_.E0;
    p << scale_.modulus_unit(E), scale_.modulus_unit(E), (0.3 + 1) / 2, scale_.modulus_unit(E / 2.6), rho;
    p = p.cwiseMax(1e-3).cwiseMin(1 - 1e-3);
    return descend_into(p, [&](const VecX& q, VecX* g) { return constraint(q, g); });
  }

 protected:
  void compliance(const VecX& p, MatX& S, std::vector<MatX>& dS) const override {
    const VecX r = raw(p);
    const double Ex = r[0], Ey = r[1], nu = r[2], G = r[3], k = scale_.modulus_rate();
    S = MatX::Zero(3, 3);
    S(0, 0) = 1 / Ex, S(1, 1) = 1 / Ey, S(0, 1) = S(1, 0) = -nu / Ex, S(2, 2) = 1 / G;
    dS.assign(5, MatX::Zero(3, 3));
    dS[0](0, 0) = -k / Ex, dS[0](0, 1) = dS[0](1, 0) = k * nu / Ex;  // d/du0 with dEx/du0 = k Ex
    dS[1](1, 1) = -k / Ey;
    dS[2](0, 1) = dS[2](1, 0) = -2 / Ex;
    dS[3](2, 2) = -k / G;
  }

 private:
  UnitScale scale_;
  const GamutLevelSet* ls_;
};

// Square-symmetric cells inside an orthotropic gamut: the gamut's slice
// Ex = Ey. Its feasible set is a subset of the orthotropic space's in the
// same level set by construction, so the two spaces can be compared on one
// gamut (Fig. 3-16), and its optimum is a feasible start for the
// orthotropic run. The design records the orthotropic point, so it maps
// with the orthotropic gamut's structures.
class CubicSliceModel : public CubicModel {
 public:
  CubicSliceModel(UnitScale scale, const GamutLevelSet* ls) : CubicModel(2, scale, ls) {}
  std::string space() const override { return "cubic2d_slice"; }
  double constraint(const VecX& p, VecX* g) const override {
    VecX go;
    const double value = ls_->smooth_value(orthotropic_point(p), g ? &go : nullptr);
    if (g) {
      g->resize(4);
      (*g) << go[0] + go[1], go[2], go[3], go[4];
    }
    return value;
  }
  std::string design_space() const override { return "orthotropic2d"; }
  std::vector<std::string> design_names() const override { return kOrthotropicNames; }
  void design_row(const VecX& p, VecX& unit, VecX& raw_row) const override {
    unit = orthotropic_point(p);
    const VecX r = raw(p);
    raw_row.resize(5);
    raw_row << r[0], r[0], r[1], r[2], r[3];
  }
  // An orthotropic point's nearest slice point (Ex and Ey are log-scaled:
  // their mean is the geometric mean of the moduli).
  VecX parameters_of_design_unit(const VecX& unit) const override {
    VecX p(4);
    p << 0.5 * (unit[0] + unit[1]), unit[2], unit[3], unit[4];
    return p;
  }

 private:
  static VecX orthotropic_point(const VecX& p) {
    VecX q(5);
    q << p[0], p[0], p[1], p[2], p[3];
    return q;
  }
};

// Isotropic cells inside a cubic gamut: G tied to E and nu.
class IsotropicModel : public CubicModel {
 public:
  using CubicModel::CubicModel;
  std::string space() const override { return dim_ == 3 ? "isotropic3d" : "isotropic2d"; }
  std::vector<std::string> names() const override { return {"E", "nu", "rho"}; }
  VecX raw(const VecX& p) const override {
    VecX r(3);
    r << scale_.modulus(p[0]), nu(p[1]), p[2];
    return r;
  }
  double constraint(const VecX& p, VecX* g) const override {
    const VecX q = cubic_point(p);
    VecX gc;
    const double value = ls_->smooth_value(q, g ? &gc : nullptr);
    if (g) {
      const double dG_dnu = -nu_range() / ((1 + nu(p[1])) * kLn10 * scale_.decades);  // d uG / d p1
      g->resize(3);
      (*g) << gc[0] + gc[2], gc[1] + gc[2] * dG_dnu, gc[3];
    }
    return value;
  }
  VecX initial_point(double rho) const override {
    VecX p(3);
    p << scale_.modulus_unit(std::max(rho, 1e-3) * scale_.E0), (0.3 + 1) / nu_range(), rho;
    p = p.cwiseMax(1e-3).cwiseMin(1 - 1e-3);
    return descend_into(p, [&](const VecX& q, VecX* g) { return constraint(q, g); });
  }

 protected:
  // The cubic-space point of an isotropic one: uG = uE - log10(2 (1 + nu)) / decades.
  VecX cubic_point(const VecX& p) const {
    VecX q(4);
    q << p[0], p[1], p[0] - std::log10(2 * (1 + nu(p[1]))) / scale_.decades, p[2];
    return q;
  }
  void compliance(const VecX& p, MatX& S, std::vector<MatX>& dS) const override {
    const double E = scale_.modulus(p[0]), v = nu(p[1]), G = E / (2 * (1 + v));
    add_cubic_compliance(dim_, E, v, G, S);
    MatX dE, dnu, dG;
    cubic_compliance_derivatives(dim_, E, v, G, dE, dnu, dG);
    // dG/dE = G / E, dG/dnu = -G / (1 + nu).
    dS = {(dE + dG * G / E) * E * scale_.modulus_rate(), (dnu - dG * G / (1 + v)) * nu_range(),
          MatX::Zero(S.rows(), S.cols())};
  }
};

// Isotropic, nu fixed; an explicit gamut E <= rho^3 E0 (thesis §3.6.2).
class AnalyticModel : public CellMaterialModel {
 public:
  AnalyticModel(int dim, UnitScale scale, double nu) : dim_(dim), scale_(scale), nu_(nu) {}
  std::string space() const override { return dim_ == 3 ? "analytic3d" : "analytic2d"; }
  std::vector<std::string> names() const override { return {"E", "rho"}; }
  int dimension() const override { return dim_; }
  VecX raw(const VecX& p) const override {
    VecX r(2);
    r << scale_.modulus(p[0]), p[1];
    return r;
  }
  bool has_constraint() const override { return true; }
  double constraint(const VecX& p, VecX* g) const override {
    const double e = scale_.modulus(p[0]) / scale_.E0;
    if (g) {
      g->resize(2);
      (*g) << e * scale_.modulus_rate(), -3 * p[1] * p[1];
    }
    return e - p[1] * p[1] * p[1];
  }
  VecX initial_point(double rho) const override {
    VecX p(2);
    // Just inside the boundary E = rho^3 E0 (and above the box's floor).
    p << scale_.modulus_unit(std::max(0.9 * std::pow(rho, 3), std::pow(10.0, -scale_.decades + 1e-3)) * scale_.E0), rho;
    return p;
  }

 protected:
  void compliance(const VecX& p, MatX& S, std::vector<MatX>& dS) const override {
    const double E = scale_.modulus(p[0]);
    add_cubic_compliance(dim_, E, nu_, E / (2 * (1 + nu_)), S);
    dS = {-S * scale_.modulus_rate(), MatX::Zero(S.rows(), S.cols())};  // S ~ 1/E
  }

 private:
  int dim_;
  UnitScale scale_;
  double nu_;
};

class SimpModel : public CellMaterialModel {
 public:
  SimpModel(int dim, double E0, double nu, double penalty, double E_min_ratio)
      : dim_(dim), E0_(E0), nu_(nu), p_(penalty), Emin_(E_min_ratio * E0) {}
  std::string space() const override { return dim_ == 3 ? "simp3d" : "simp2d"; }
  std::vector<std::string> names() const override { return {"rho"}; }
  int dimension() const override { return dim_; }
  VecX raw(const VecX& p) const override { return p; }
  VecX initial_point(double rho) const override { return VecX::Constant(1, rho); }
  double modulus(double rho) const { return Emin_ + std::pow(rho, p_) * (E0_ - Emin_); }

 protected:
  void compliance(const VecX& p, MatX& S, std::vector<MatX>& dS) const override {
    const double E = modulus(p[0]);
    const double dE = p_ * std::pow(p[0], p_ - 1) * (E0_ - Emin_);
    add_cubic_compliance(dim_, E, nu_, E / (2 * (1 + nu_)), S);
    dS = {-S * dE / E};
  }

 private:
  int dim_;
  double E0_, nu_, p_, Emin_;
};

}  // namespace

void CellMaterialModel::tensor(const VecX& p, MatX& C, std::vector<MatX>* dC) const {
  MatX S;
  std::vector<MatX> dS;
  compliance(p, S, dS);
  C = S.inverse();
  C = 0.5 * (C + C.transpose());
  if (!dC) return;
  dC->resize(dS.size());
  for (std::size_t k = 0; k < dS.size(); ++k) (*dC)[k] = -C * dS[k] * C;
}

void CellMaterialModel::set_voigt_bound(MatX stiff, MatX soft) {
  const int m = voigt_size(dimension());
  if (stiff.rows() != m || soft.rows() != m)
    throw InputError("material space " + space() + ": the Voigt bound needs " + std::to_string(m) + " x " +
                     std::to_string(m) + " base-material tensors");
  bound_ = VoigtBound(std::move(stiff), std::move(soft), bound_modes());
}

VecX CellMaterialModel::bound_constraints(const VecX& p, MatX* jacobian) const {
  if (!bound_.active()) return VecX();
  MatX C;
  std::vector<MatX> dC;
  tensor(p, C, jacobian ? &dC : nullptr);
  return bound_.evaluate(C, p[density_index()], jacobian ? &dC : nullptr, density_index(), jacobian);
}

double CellMaterialModel::constraint(const VecX& p, VecX* gradient) const {
  if (gradient) *gradient = VecX::Zero(p.size());
  return -1.0;
}

double CellMaterialModel::density(const VecX& p, VecX* gradient) const {
  if (gradient) *gradient = VecX::Unit(p.size(), density_index());
  return p[density_index()];
}

std::vector<std::string> cell_material_spaces() {
  return {"cubic3d",    "cubic2d",    "orthotropic2d", "cubic2d_slice", "isotropic2d", "isotropic3d",
          "analytic2d", "analytic3d", "simp2d",        "simp3d",        "family3d"};
}

bool needs_family_grid(const std::string& space) { return space == "family3d"; }

std::string required_gamut_space(const std::string& space) {
  if (space == "cubic3d" || space == "cubic2d" || space == "orthotropic2d") return space;
  if (space == "isotropic2d") return "cubic2d";
  if (space == "cubic2d_slice") return "orthotropic2d";
  if (space == "isotropic3d") return "cubic3d";
  return "";
}

MatX isotropic_voigt(int dimension, double E, double nu) {
  MatX S;
  add_cubic_compliance(dimension, E, nu, E / (2 * (1 + nu)), S);
  return S.inverse();
}

std::unique_ptr<CellMaterialModel> make_cell_material_model(const CellMaterialSettings& s) {
  if (!(s.E_stiff > 0) || !(s.decades > 0)) throw InputError("material space: E_stiff and decades must be > 0");
  const UnitScale scale{s.E_stiff, s.decades};
  const std::string& sp = s.space;
  const std::string gamut = required_gamut_space(sp);
  if (!gamut.empty()) {
    if (!s.level_set) throw InputError("material space " + sp + " needs a gamut artifact of space " + gamut);
    const int want = gamut == "orthotropic2d" ? 5 : 4;
    if (s.level_set->dimension() != want)
      throw InputError("material space " + sp + ": the gamut level set has " +
                       std::to_string(s.level_set->dimension()) + " dimensions, expected " + std::to_string(want));
  }
  if (needs_family_grid(sp))
    throw InputError("material space " + sp + " is made from a family's structure grid (family:)");
  if (sp == "cubic3d") return std::make_unique<CubicModel>(3, scale, s.level_set);
  if (sp == "cubic2d") return std::make_unique<CubicModel>(2, scale, s.level_set);
  if (sp == "orthotropic2d") return std::make_unique<OrthotropicModel>(scale, s.level_set);
  if (sp == "cubic2d_slice") return std::make_unique<CubicSliceModel>(scale, s.level_set);
  if (sp == "isotropic3d") return std::make_unique<IsotropicModel>(3, scale, s.level_set);
  if (sp == "isotropic2d") return std::make_unique<IsotropicModel>(2, scale, s.level_set);
  const double nu_hi = sp.back() == 'd' && sp[sp.size() - 2] == '3' ? 0.5 : 1.0;
  if (!(s.nu > -1 && s.nu < nu_hi))
    throw InputError("material space " + sp + ": nu must be in (-1, " +
                     (nu_hi == 0.5 ? std::string("0.5") : std::string("1")) + ")");
  if (sp == "analytic3d") return std::make_unique<AnalyticModel>(3, scale, s.nu);
  if (sp == "analytic2d") return std::make_unique<AnalyticModel>(2, scale, s.nu);
  if (!(s.penalty >= 1)) throw InputError("material space " + sp + ": penalty must be >= 1");
  if (!(s.E_min_ratio > 0 && s.E_min_ratio < 1))
    throw InputError("material space " + sp + ": E_min_ratio must be in (0, 1)");
  if (sp == "simp3d") return std::make_unique<SimpModel>(3, s.E_stiff, s.nu, s.penalty, s.E_min_ratio);
  if (sp == "simp2d") return std::make_unique<SimpModel>(2, s.E_stiff, s.nu, s.penalty, s.E_min_ratio);
  std::string choices;
  for (const auto& c : cell_material_spaces()) choices += (choices.empty() ? "" : ", ") + c;
  throw InputError("material space '" + sp + "': expected one of " + choices);
}

}  // namespace msfab
