#include "fem/hex_element.hpp"

#include <Eigen/Cholesky>
#include <algorithm>
#include <cmath>

namespace msfab {
namespace {

using Mat9x24 = Eigen::Matrix<double, 9, 24>;
using Mat24x9 = Eigen::Matrix<double, 24, 9>;

// flat(A G^T) = M flat(A) with M = bubble_map(G), column-major flattening:
// entry (i + 3j, i + 3l) of M is G(j, l). M is never formed; these are its
// products (a dense 9 x 9 M cost about 6x the flops).
//
// M^T X: row block l (rows 3l..3l+2) is sum_j G(j, l) row block j of X.
template <int C>
Eigen::Matrix<double, 9, C> bubble_map_transpose_times(const Mat3& G, const Eigen::Matrix<double, 9, C>& X) {
  Eigen::Matrix<double, 9, C> R;
  for (int l = 0; l < 3; ++l)
    R.template middleRows<3>(3 * l) = G(0, l) * X.template middleRows<3>(0) + G(1, l) * X.template middleRows<3>(3) +
                                      G(2, l) * X.template middleRows<3>(6);
  return R;
}
// H M: column block m is sum_n G(n, m) column block n of H.
Mat9 times_bubble_map(const Mat9& H, const Mat3& G) {
  Mat9 R;
  for (int m = 0; m < 3; ++m)
    R.middleCols<3>(3 * m) = G(0, m) * H.middleCols<3>(0) + G(1, m) * H.middleCols<3>(3) + G(2, m) * H.middleCols<3>(6);
  return R;
}

Mat3 point_gradient(const hex8::ElementGeometry& geo, const hex8::NodeMatrix& x, int q, const Mat3& A) {
  Mat3 F = hex8::deformation_gradient(x, geo.dNdX[q]);
  if (geo.has_enhanced_modes()) F.noalias() += A * geo.enhanced[q].transpose();
  return F;
}

// H B for the 9x24 map B from nodal positions to flat F (three non-zeros
// per column of B: dF(a, c)/dx_i(a) = dN_i/dX_c).
Mat9x24 times_b(const Mat9& H, const hex8::NodeMatrix& D) {
  Mat9x24 HB;
  for (int i = 0; i < 8; ++i)
    for (int a = 0; a < 3; ++a)
      HB.col(3 * i + a) = H.col(a) * D(i, 0) + H.col(a + 3) * D(i, 1) + H.col(a + 6) * D(i, 2);
  return HB;
}

// The element with bubble amplitudes A: energy, and optionally the
// gradient and Hessian in the nodal positions and the blocks that couple
// them with A (r_A = dE/dA, K_AA, and K_Au when `coupling`; the bubbles'
// own Newton needs only the first two).
struct EnhancedTerms {
  Vec9 r_A = Vec9::Zero();
  Mat9 K_AA = Mat9::Zero();
  Eigen::Matrix<double, 9, 24> K_Au = Eigen::Matrix<double, 9, 24>::Zero();
  bool coupling = true;
};

double evaluate_with(const hex8::ElementGeometry& geo, const QuadratureMaterials& mat, const hex8::NodeMatrix& x,
                     const Mat3& A, Vec24* gradient, Mat24* hessian, EnhancedTerms* bubbles) {
  double e = 0;
  if (gradient) gradient->setZero();
  if (hessian) hessian->setZero();
  const bool coupling = bubbles && bubbles->coupling;
  if (bubbles) *bubbles = EnhancedTerms{}, bubbles->coupling = coupling;
  const bool need_P = gradient || bubbles, need_H = hessian || bubbles;
  Mat3 P;
  Mat9 H;
  for (int q = 0; q < geo.size(); ++q) {
    const Material* material = mat.at(q);
    if (!material) continue;
    const hex8::NodeMatrix& D = geo.dNdX[q];
    const Mat3 F = point_gradient(geo, x, q, A);
    double psi;
    material->evaluate(F, &psi, need_P ? &P : nullptr, need_H ? &H : nullptr);
    if (!std::isfinite(psi)) return kInfiniteEnergy;
    const double w = geo.weight[q];
    e += w * psi;
    if (gradient) {
      // dE/dx_i = w P dN_i/dX
      const Eigen::Matrix<double, 3, 8> G = w * P * D.transpose();
      for (int i = 0; i < 8; ++i) gradient->segment<3>(3 * i) += G.col(i);
    }
    if (bubbles) {
      const Mat3& G = geo.enhanced[q];
      bubbles->r_A += w * flat(P * G);  // M^T flat(P)
      bubbles->K_AA.noalias() += w * bubble_map_transpose_times<9>(G, times_bubble_map(H, G));
    }
    if (!hessian && !coupling) continue;
    // With B three non-zeros per column, w B^T H B costs ~2.4k flops per
    // point instead of ~7k.
    const Mat9x24 HB = times_b(H, D);
    if (hessian)
      for (int j = 0; j < 8; ++j) {
        const double d0 = w * D(j, 0), d1 = w * D(j, 1), d2 = w * D(j, 2);
        for (int b = 0; b < 3; ++b) hessian->row(3 * j + b) += d0 * HB.row(b) + d1 * HB.row(b + 3) + d2 * HB.row(b + 6);
      }
    if (coupling) bubbles->K_Au.noalias() += w * bubble_map_transpose_times<24>(geo.enhanced[q], HB);
  }
  return e;
}

// K_AA factored, made definite by a shift if it is not (a bubble mode
// without stiffness, or a state past a material instability).
Eigen::LDLT<Mat9> definite_factor(const Mat9& K) {
  Eigen::LDLT<Mat9> f(K);
  const double scale = std::max(K.diagonal().cwiseAbs().maxCoeff(), 1e-300);
  for (double shift = 1e-10 * scale;
       f.info() != Eigen::Success || !f.isPositive() || f.vectorD().minCoeff() <= 1e-14 * scale; shift *= 10) {
    f.compute(K + shift * Mat9::Identity());
    if (shift > scale) break;
  }
  return f;
}

// Below this Newton step (relative to the element's size) the bubbles'
// problem is in Newton's quadratic regime and the energy decrease a step
// brings, ~(step / h)^2 of the energy scale (1e-14 here), is at the
// energy's own round-off: full steps are taken without a line search.
constexpr double kRoundOffStep = 1e-7;
// Amplitudes are converged when the step is this small against the
// element's size: ~1e3 above the round-off of the amplitudes themselves
// (eps times h), and their energy error ~1e-26 of the energy scale.
constexpr double kConvergedStep = 1e-13;

// The bubble amplitudes that minimize the element energy at nodal
// positions x: Newton from the amplitudes A passed in (from `second_start`,
// then from A = 0, where the element is inverted there). It stops when the
// residual has fallen 1e-12 of its start, the Newton decrement (the
// decrease a full step predicts) is below 1e-14 of the energy, or the step
// is below kConvergedStep of the element's size. Steps above kRoundOffStep
// are backtracked on the energy; smaller ones are taken whole, since there
// the energies compared differ by their round-off (the line search then
// halved up to 40 times before giving up: on the fibre bar at level 1 a
// fifth of the Newton steps did, and those stalls made 85% of the
// element's evaluations). Each accepted trial's terms are those of the
// next iteration. The gradient error left is second order in the last step
// (the condensed gradient is corrected to first order in r_A). Returns
// false if the element is inverted at A = 0.
bool condense_bubbles(const hex8::ElementGeometry& geo, const QuadratureMaterials& mat, const hex8::NodeMatrix& x,
                      Mat3& A, double& energy, int* evaluations = nullptr, const Mat3* second_start = nullptr) {
  int count = 1;  // evaluations of the element's terms, reported in `evaluations`
  const auto done = [&](bool finite) {
    if (evaluations) *evaluations = count;
    return finite;
  };
  EnhancedTerms t;
  t.coupling = false;
  energy = evaluate_with(geo, mat, x, A, nullptr, nullptr, &t);
  if (!std::isfinite(energy) && second_start && *second_start != A) {
    A = *second_start;
    energy = evaluate_with(geo, mat, x, A, nullptr, nullptr, &t);
    ++count;
  }
  if (!std::isfinite(energy) && !A.isZero(0.0)) {
    A.setZero();
    energy = evaluate_with(geo, mat, x, A, nullptr, nullptr, &t);
    ++count;
  }
  if (!std::isfinite(energy)) return done(false);
  double volume = 0;
  for (double w : geo.weight) volume += w;
  const double size = std::cbrt(volume);
  const double r0 = t.r_A.norm();
  EnhancedTerms trial_terms;
  trial_terms.coupling = false;
  for (int it = 0; it < 30 && t.r_A.norm() > 1e-12 * r0; ++it) {
    const Vec9 step = -definite_factor(t.K_AA).solve(t.r_A);
    const double slope = t.r_A.dot(step);
    if (-slope <= 1e-14 * std::abs(energy)) break;
    const double step_size = step.cwiseAbs().maxCoeff();
    if (step_size <= kConvergedStep * size) break;
    const bool whole = step_size <= kRoundOffStep * size;
    double s = 1.0, trial = kInfiniteEnergy;
    Mat3 B;
    for (int k = 0; k < 40; ++k, s *= 0.5) {
      B = A + s * Eigen::Map<const Mat3>(step.data());
      trial = evaluate_with(geo, mat, x, B, nullptr, nullptr, &trial_terms);
      ++count;
      if (std::isfinite(trial) && (whole || trial <= energy + 1e-4 * s * slope)) break;
    }
    if (!(std::isfinite(trial) && (whole || trial <= energy))) break;  // round-off: no decrease left
    A = B;
    energy = trial;
    std::swap(t, trial_terms);
  }
  return done(true);
}

}  // namespace

double hex_energy(const hex8::ElementGeometry& geo, const QuadratureMaterials& mat, const hex8::NodeMatrix& x) {
  if (geo.has_enhanced_modes()) return hex_evaluate(geo, mat, x, nullptr, nullptr);
  double e = 0;
  for (int q = 0; q < geo.size(); ++q) {
    const Material* material = mat.at(q);
    if (!material) continue;
    double psi;
    material->evaluate(hex8::deformation_gradient(x, geo.dNdX[q]), &psi, nullptr, nullptr);
    if (!std::isfinite(psi)) return kInfiniteEnergy;
    e += geo.weight[q] * psi;
  }
  return e;
}

double hex_evaluate(const hex8::ElementGeometry& geo, const QuadratureMaterials& mat, const hex8::NodeMatrix& x,
                    Vec24* gradient, Mat24* hessian, BubbleState* bubbles) {
  if (!geo.has_enhanced_modes()) return evaluate_with(geo, mat, x, Mat3::Zero(), gradient, hessian, nullptr);
  Mat3 A = Mat3::Zero();
  double energy = 0;
  // Where the amplitudes were condensed at these very positions (a Newton
  // iteration's assembly after its line search accepted them) they are
  // reused; elsewhere the condensation starts from their first-order
  // prediction, which Newton finishes in about one step.
  const bool reuse = bubbles && bubbles->condensed && bubbles->at == x;
  if (reuse) {
    A = bubbles->A;
    energy = bubbles->energy;
    bubbles->evaluations = 0;
  } else {
    if (bubbles) A = bubbles->has_model ? bubbles->predicted(x) : bubbles->A;
    if (!condense_bubbles(geo, mat, x, A, energy, bubbles ? &bubbles->evaluations : nullptr,
                          bubbles && bubbles->has_model ? &bubbles->A : nullptr)) {
      if (bubbles) bubbles->condensed = false;
      return kInfiniteEnergy;
    }
    if (bubbles) {
      bubbles->A = A;
      bubbles->at = x;
      bubbles->energy = energy;
      bubbles->condensed = true;
    }
  }
  if (!gradient && !hessian) return energy;
  EnhancedTerms t;
  energy = evaluate_with(geo, mat, x, A, gradient, hessian, &t);
  // Static condensation: E(x) = min_A E(x, A), so dE/dx = E_x - K_xA K_AA^-1 r_A
  // (r_A ~ 0 at the minimum) and d2E/dx2 = K_xx - K_xA K_AA^-1 K_Ax.
  const Eigen::LDLT<Mat9> K_AA = definite_factor(t.K_AA);
  const Mat24x9 coupling = t.K_Au.transpose();
  const Mat9x24 sensitivity = K_AA.solve(t.K_Au);  // -dA/dx at the minimum
  if (gradient) gradient->noalias() -= coupling * K_AA.solve(t.r_A);
  if (hessian) hessian->noalias() -= coupling * sensitivity;
  if (bubbles) {
    bubbles->sensitivity = sensitivity;
    bubbles->model_A = A;
    bubbles->model_at = x;
    bubbles->has_model = true;
  }
  return energy;
}

Mat3 BubbleState::predicted(const hex8::NodeMatrix& x) const {
  Vec24 dx;
  for (int i = 0; i < 8; ++i)
    for (int a = 0; a < 3; ++a) dx[3 * i + a] = x(i, a) - model_at(i, a);
  const Vec9 dA = -sensitivity * dx;
  return model_A + Eigen::Map<const Mat3>(dA.data());
}

bool hex_condensed_bubbles(const hex8::ElementGeometry& geo, const QuadratureMaterials& mat, const hex8::NodeMatrix& x,
                           Mat3& A) {
  A.setZero();
  if (!geo.has_enhanced_modes()) return std::isfinite(hex_energy(geo, mat, x));
  double energy;
  return condense_bubbles(geo, mat, x, A, energy);
}

}  // namespace msfab
