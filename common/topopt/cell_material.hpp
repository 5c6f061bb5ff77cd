#pragma once
// How a cell's material parameters become its stiffness, and which
// parameters are achievable (thesis §3.4, §3.6.2, Fig. 3-16).
//
// The optimizer works on parameters normalized to [0, 1] (the unit cube of
// gamut/material_space.hpp: moduli on a log scale, Poisson's ratios
// linearly, rho as is), so every space has the same box bounds and the
// gamut level set is queried directly. Each model gives the cell's Voigt
// stiffness C(p) (3 x 3 in 2D: in-plane constants, a plate of unit
// thickness; 6 x 6 in 3D), its derivatives dC/dp_k, the stiff-material
// fraction rho that counts as mass, and an optional constraint Phi(p) <= 0.
//
//   space          parameters          stiffness                    constraint
//   cubic3d/2d     E, nu, G, rho       cubic compliance             gamut level set
//   orthotropic2d  Ex, Ey, nu_xy, G, rho orthotropic compliance     gamut level set
//   isotropic2d/3d E, nu, rho          G = E / (2 (1 + nu))         the cubic gamut at that G
//   cubic2d_slice  E, nu, G, rho       cubic compliance             an orthotropic gamut at Ex = Ey
//   analytic2d/3d  E, rho              isotropic, nu fixed          E / E0 - rho^3 <= 0 (§3.6.2)
//   simp2d/3d      rho                 E = Emin + rho^p (E0 - Emin) none (a volume constraint instead)
//   family3d       the family's own, rho  interpolated between members rho >= the members' (family_material.hpp)
//
// Every C is the inverse of a compliance S that is linear in a few raw
// properties, so dC/dp_k = -C (dS/dp_k) C exactly.
#include <memory>
#include <string>
#include <vector>

#include "core/types.hpp"
#include "gamut/level_set.hpp"
#include "topopt/voigt_bound.hpp"

namespace msfab {

class CellMaterialModel {
 public:
  virtual ~CellMaterialModel() = default;
  virtual std::string space() const = 0;
  virtual std::vector<std::string> names() const = 0;
  int parameters() const { return static_cast<int>(names().size()); }
  virtual int dimension() const = 0;
  // Voigt stiffness at unit parameters p; with dC, also dC/dp_k for every k.
  // By default the inverse of compliance(); a model that interpolates C
  // directly (the family spaces) overrides this instead.
  virtual void tensor(const VecX& p, MatX& C, std::vector<MatX>* dC = nullptr) const;
  // Raw parameters (moduli in Pa) of unit parameters.
  virtual VecX raw(const VecX& p) const = 0;
  // Index of rho (the mass fraction) among the parameters.
  int density_index() const { return parameters() - 1; }
  // Phi(p) <= 0 marks achievable parameters; models without a constraint
  // return false from has_constraint().
  virtual bool has_constraint() const { return false; }
  virtual double constraint(const VecX& p, VecX* gradient) const;
  // A point to start from: inside the constraint where there is one.
  virtual VecX initial_point(double rho) const = 0;
  // Whether rho is a function of the other parameters (a family cell that
  // holds exactly its members' mix of material) rather than a free
  // parameter tied to them by Phi. The objective then overwrites the rho
  // column of its physical parameters with density(p), and the model has
  // no constraint, so a density filter on the parameters keeps the problem
  // separable over the cells (topopt/cell_mma.hpp). By default rho is free
  // and density(p) is p's rho.
  virtual bool derives_density() const { return false; }
  // rho at p; with `gradient`, d rho / d p (rho's own entry 0 where derived).
  virtual double density(const VecX& p, VecX* gradient) const;

  // What the design artifact records for a cell: space, property names and
  // the unit and raw rows. By default the parameters themselves; a family
  // space records the cubic3d material its cell interpolates, so the mapper
  // and the checks compare it with structures like any gamut design.
  virtual std::string design_space() const { return space(); }
  virtual std::vector<std::string> design_names() const { return names(); }
  virtual void design_row(const VecX& p, VecX& unit, VecX& raw_row) const { unit = p, raw_row = raw(p); }
  // The parameters of a design row's unit values (design_names() order), to
  // start from a stored design: the inverse of design_row where one exists,
  // else the nearest parameters. By default the row itself.
  virtual VecX parameters_of_design_unit(const VecX& unit) const { return unit; }
  // A family space's own parameters (the first parameters of every cell;
  // raw() gives their values); empty elsewhere.
  virtual std::vector<std::string> family_names() const { return {}; }

  // The Voigt bound C(p) <= rho C_stiff + (1 - rho) C_soft (voigt_bound.hpp)
  // as bound_conditions() more per-cell conditions g(p) <= 0; none unless
  // set (the gamut spaces, from the gamut artifact's base materials:
  // Gamut::bound_stiff, bound_soft).
  // InputError on tensors of the wrong size for the space's dimension.
  void set_voigt_bound(MatX stiff, MatX soft);
  int bound_conditions() const { return bound_.count(); }
  // The conditions at p, with d g / d p (bound_conditions() x parameters()).
  VecX bound_constraints(const VecX& p, MatX* jacobian) const;

 protected:
  // S(p) and dS/dp_k (m x m each).
  virtual void compliance(const VecX& p, MatX& S, std::vector<MatX>& dS) const = 0;
  // Which conditions express the bound for this space's symmetry.
  virtual VoigtBoundModes bound_modes() const { return VoigtBoundModes::cubic; }

 private:
  VoigtBound bound_;
};

struct CellMaterialSettings {
  std::string space;                         // see the table above
  double E_stiff = 1.0;                      // E0: the stiffest base material, normalizes moduli
  double decades = 4.0;                      // log-scale span of the moduli
  double nu = 0.3;                           // analytic and simp: the fixed Poisson's ratio
  double penalty = 3.0;                      // simp: p
  double E_min_ratio = 1e-9;                 // simp: Emin / E0
  const GamutLevelSet* level_set = nullptr;  // gamut spaces and isotropic: the (cubic) gamut
};

// InputError for an unknown space, a missing level set where one is
// needed, or a level set of the wrong dimension. The family spaces are made
// from their structure grid by make_family_material_model
// (topopt/family_material.hpp).
std::unique_ptr<CellMaterialModel> make_cell_material_model(const CellMaterialSettings& settings);

// The spaces make_cell_material_model accepts.
std::vector<std::string> cell_material_spaces();

// Whether a design space reads a family's structure grid (`family:`).
bool needs_family_grid(const std::string& space);

// The gamut space whose artifact a design space needs ("" for none):
// isotropic2d -> cubic2d, isotropic3d -> cubic3d, cubic2d_slice ->
// orthotropic2d, a gamut space -> itself.
std::string required_gamut_space(const std::string& space);

// Isotropic Voigt stiffness (in-plane constants in 2D) of a solid cell.
MatX isotropic_voigt(int dimension, double E, double nu);

}  // namespace msfab
