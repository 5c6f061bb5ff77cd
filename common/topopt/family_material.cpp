#include "topopt/family_material.hpp"

#include <algorithm>
#include <cmath>

#include "core/errors.hpp"
#include "gamut/material_space.hpp"
#include "homog/elastic_tensor.hpp"
#include "topopt/grid_interpolant.hpp"

namespace msfab {
namespace {

// The eigenvalues of a cubic Voigt tensor: hydrostatic C11 + 2 C12 (once),
// deviatoric C11 - C12 (twice), shear C44 (three times), from the moduli
// averaged over their copies (round-off asymmetry of a homogenized tensor
// does not matter).
Eigen::Vector3d cubic_eigenvalues(const Mat6& C) {
  const CubicModuli m = cubic_moduli(C);
  return {m.C11 + 2 * m.C12, m.C11 - m.C12, m.C44};
}

class FamilyGridModel : public CellMaterialModel {
 public:
  FamilyGridModel(StructureGrid grid, GridInterpolant table, MaterialSpace space, bool derived_density)
      : grid_(std::move(grid)), table_(std::move(table)), space_(space), derived_density_(derived_density) {}

  std::string space() const override { return "family3d"; }
  std::vector<std::string> names() const override {
    std::vector<std::string> n = grid_.names;
    n.push_back("rho");
    return n;
  }
  int dimension() const override { return 3; }
  std::vector<std::string> family_names() const override { return grid_.names; }

  // The half-sizes (piecewise linear between the grid's values) and rho.
  VecX raw(const VecX& p) const override {
    const int k = axes();
    VecX r(k + 1);
    for (int a = 0; a < k; ++a) {
      const std::vector<double>& axis = grid_.axes[std::size_t(a)];
      const int n = int(axis.size());
      if (n == 1) {
        r[a] = axis[0];
        continue;
      }
      const double x = std::clamp(p[a], 0.0, 1.0) * (n - 1);
      const int i = std::min(int(std::floor(x)), n - 2);
      r[a] = axis[std::size_t(i)] + (x - i) * (axis[std::size_t(i) + 1] - axis[std::size_t(i)]);
    }
    r[k] = p[k];
    return r;
  }

  bool has_constraint() const override { return !derived_density_; }
  double constraint(const VecX& p, VecX* gradient) const override {
    if (derived_density_) return CellMaterialModel::constraint(p, gradient);
    const double phi = family_density(p, gradient) - p[axes()];
    if (gradient) (*gradient)[axes()] = -1;
    return phi;
  }
  bool derives_density() const override { return derived_density_; }
  double density(const VecX& p, VecX* gradient) const override {
    return derived_density_ ? family_density(p, gradient) : CellMaterialModel::density(p, gradient);
  }

  // The member mix whose solid fraction is nearest rho, on a 21-point scan
  // per axis, with rho just above the family's so the start is feasible.
  VecX initial_point(double rho) const override {
    const int k = axes();
    const int steps = 20;
    int total = 1;
    for (int a = 0; a < k; ++a) total *= steps + 1;
    VecX best, t(k), v;
    double best_gap = 1e300;
    for (int i = 0; i < total; ++i) {
      int rest = i;
      for (int a = k; a-- > 0;)
        t[a] = std::clamp(double(rest % (steps + 1)) / steps, 1e-3, 1 - 1e-3), rest /= steps + 1;
      table_.evaluate(t, v);
      if (std::abs(v[3] - rho) < best_gap) best_gap = std::abs(v[3] - rho), best = t;
    }
    table_.evaluate(best, v);
    VecX p(k + 1);
    p << best, std::min(1.0, v[3] + 1e-3);
    return p;
  }

  void tensor(const VecX& p, MatX& C, std::vector<MatX>* dC = nullptr) const override {
    const int k = axes();
    VecX v;
    MatX dv;
    table_.evaluate(p.head(k), v, dC ? &dv : nullptr);
    const Eigen::Vector3d lambda(std::exp(v[0]), std::exp(v[1]), std::exp(v[2]));
    C = cubic_from_eigenvalues(lambda);
    if (!dC) return;
    dC->assign(std::size_t(k) + 1, MatX::Zero(6, 6));
    for (int a = 0; a < k; ++a)
      (*dC)[std::size_t(a)] = cubic_from_eigenvalues(lambda.cwiseProduct(dv.col(a).head<3>()));
  }

  std::string design_space() const override { return "cubic3d"; }
  std::vector<std::string> design_names() const override { return space_.names(); }
  void design_row(const VecX& p, VecX& unit, VecX& raw_row) const override {
    MatX C;
    tensor(p, C);
    raw_row = space_.properties(Mat6(C), p[axes()]);
    unit = space_.normalize(raw_row);
  }

 protected:
  void compliance(const VecX&, MatX&, std::vector<MatX>&) const override {
    throw std::logic_error("FamilyGridModel: the stiffness is interpolated, not inverted");
  }

 private:
  int axes() const { return table_.axes(); }
  // The members' solid fraction interpolated at p's family parameters; the
  // gradient's rho entry is 0.
  double family_density(const VecX& p, VecX* gradient) const {
    VecX v;
    MatX dv;
    table_.evaluate(p.head(axes()), v, gradient ? &dv : nullptr);
    if (gradient) {
      *gradient = VecX::Zero(p.size());
      gradient->head(axes()) = dv.row(3).transpose();
    }
    return v[3];
  }
  // Linear in the eigenvalues, so it also maps their derivatives.
  static MatX cubic_from_eigenvalues(const Eigen::Vector3d& l) {
    return cubic_tensor((l[0] + 2 * l[1]) / 3, (l[0] - l[1]) / 3, l[2]);
  }

  StructureGrid grid_;
  GridInterpolant table_;
  MaterialSpace space_;
  bool derived_density_;
};

}  // namespace

std::unique_ptr<CellMaterialModel> make_family_material_model(const MicrostructureSet& set, const std::string& path,
                                                              bool derived_density) {
  if (set.grid.empty())
    throw InputError(path +
                     ": the structures are not a parameter grid (/grid missing; make them with "
                     "msfab-family-generate and a `grid:` config)");
  if (set.space != "cubic3d") throw InputError(path + ": space " + set.space + ", the family3d space needs cubic3d");
  const int rho = static_cast<int>(set.property_names.size()) - 1;
  if (rho < 0 || set.property_names.back() != "rho") throw InputError(path + ": property_names: the last must be rho");
  MatX values(Eigen::Index(set.items.size()), 4);
  for (std::size_t i = 0; i < set.items.size(); ++i) {
    const Microstructure& m = set.items[i];
    const Eigen::Vector3d l = cubic_eigenvalues(m.C);
    if (!(l.minCoeff() > 0) || !l.allFinite())
      throw InputError(path + ": /C: structure " + std::to_string(i) +
                       " has no positive definite C^H (not homogenized, or a floating piece)");
    values.row(Eigen::Index(i)) << std::log(l[0]), std::log(l[1]), std::log(l[2]), m.properties[rho];
  }
  std::vector<int> sizes;
  for (const auto& axis : set.grid.axes) sizes.push_back(int(axis.size()));
  return std::make_unique<FamilyGridModel>(set.grid, GridInterpolant(sizes, values),
                                           MaterialSpace(MaterialSpaceKind::cubic3d, set.E_stiff, set.decades),
                                           derived_density);
}

}  // namespace msfab
