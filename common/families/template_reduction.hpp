#pragma once
// Reduced template parameters by principal component regression (thesis
// §3.3, Fig. 3-9c, Appendix A). A family's template fitted to each member
// gives one full parameter vector per member; most of their spread is a few
// directions, and only some of those change the material. We
//
//   1. centre the members' parameters on their mean (the base template),
//   2. keep the principal components explaining `variance_kept` of the
//      spread,
//   3. regress the members' properties (log10 E, ν) linearly on the
//      component scores,
//   4. take as reduced direction j the parameter-space gradient of property
//      j's regression (within the kept components), orthogonalized against
//      the earlier ones,
//   5. scale each direction to the members' extent along it: r_j = +1 and
//      -1 are the extreme members' projections (the "plus" and "minus"
//      templates of Appendix A).
//
// So the first reduced parameter mostly moves Young's modulus and the
// second Poisson's ratio, as the thesis reports for its families.
#include <vector>

#include "core/types.hpp"

namespace msfab {

struct ReducedTemplate {
  VecX base;                // mean fitted parameters (r = 0)
  std::vector<VecX> plus;   // parameters at r_j = +1
  std::vector<VecX> minus;  // parameters at r_j = -1
  // Predicted change of (log10 E, ν) per unit r_j by the regression
  // (column j): the direction the properties move along.
  MatX property_slope;               // 2 x reduced
  int components = 0;                // principal components kept
  double explained_variance = 0;     // fraction of the parameter spread they hold
  double regression_r2[2] = {0, 0};  // R^2 of log10 E and of ν on the kept scores
};

struct ReductionOptions {
  int reduced = 2;
  double variance_kept = 0.99;
};

// `parameters`: members x p; `properties`: members x 2 (log10 E relative to
// the stiff material, ν). InputError for fewer than 3 members, mismatched
// rows or reduced < 1.
ReducedTemplate reduce_template_parameters(const MatX& parameters, const MatX& properties,
                                           const ReductionOptions& options = {});

// Appendix A's interpolation: for each r_j in [-1, 1], move from the base
// towards plus_j (r_j > 0) or minus_j (r_j < 0) by |r_j|; the moves add.
// InputError for an r_j outside [-1, 1] or too many reduced parameters.
VecX reduced_to_parameters(const ReducedTemplate& reduced, const std::vector<double>& r);

}  // namespace msfab
