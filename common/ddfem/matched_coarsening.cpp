#include "ddfem/matched_coarsening.hpp"

#include <Eigen/Eigenvalues>
#include <algorithm>
#include <cmath>
#include <limits>

#include "core/errors.hpp"
#include "ddfem/baseline_coarsening.hpp"
#include "ddfem/windowed_stiffness.hpp"
#include "material/voigt.hpp"

namespace msfab {
namespace {

// The fixed point stops when the element's uniform response is within this
// of C^H (relative, Frobenius): far below the error of any coarse model.
constexpr double kResponseTolerance = 1e-6;
// The fixed point's steps before Newton takes over (it converges in 3 on a
// random 4^3 block), Newton's steps, and its finite-difference step.
constexpr int kFixedPointSteps = 10;
constexpr int kMaxNewtonSteps = 20;
constexpr double kJacobianStep = 1e-7;
// A residual above this is a congruence that failed, not a small error: an
// error, not a silent stop.
constexpr double kAcceptedResidual = 1e-4;

Mat6 spd_sqrt(const Mat6& M) { return Eigen::SelfAdjointEigenSolver<Mat6>(M).operatorSqrt(); }

// The SPD S with S A S = B (A, B SPD).
Mat6 congruence_to(const Mat6& A, const Mat6& B) {
  const Eigen::SelfAdjointEigenSolver<Mat6> eig(A);
  const Mat6 half = eig.operatorSqrt(), inverse_half = eig.operatorInverseSqrt();
  const Mat6 S = inverse_half * spd_sqrt(half * B * half) * inverse_half;
  return 0.5 * (S + S.transpose());
}

}  // namespace

Mat6 uniform_strain_response(const hex8::ElementGeometry& geo, const std::vector<Mat6>& C) {
  if (static_cast<int>(C.size()) != geo.size())
    throw std::invalid_argument("uniform_strain_response: one stiffness per quadrature point expected");
  // A uniform strain e is the same at every point; with bubble amplitudes a
  // the strain at q is e + H_q a, and at rest the energy is quadratic:
  //   1/2 sum_q w_q (e + H_q a)^T C_q (e + H_q a).
  // Minimizing over a condenses the bubbles: A V = sum w C - P^T Q^-1 P.
  Mat6 sum = Mat6::Zero();
  Eigen::Matrix<double, 9, 6> P = Eigen::Matrix<double, 9, 6>::Zero();
  Mat9 Q = Mat9::Zero();
  double volume = 0;
  for (int q = 0; q < geo.size(); ++q) {
    sum += geo.weight[q] * C[q];
    volume += geo.weight[q];
    if (!geo.has_enhanced_modes()) continue;
    // Amplitude (i, k) (displacement component i, bubble k) adds
    // e_i (grad bubble_k)^T to the displacement gradient.
    Eigen::Matrix<double, 6, 9> H;
    for (int i = 0; i < 3; ++i)
      for (int k = 0; k < 3; ++k) {
        Mat3 M = Mat3::Zero();
        M.row(i) = geo.enhanced[q].row(k);
        H.col(3 * i + k) = strain_to_voigt(M);
      }
    P += geo.weight[q] * H.transpose() * C[q];
    Q += geo.weight[q] * H.transpose() * C[q] * H;
  }
  Mat6 A = sum;
  if (geo.has_enhanced_modes()) A -= P.transpose() * Q.ldlt().solve(P);
  A /= volume;
  return 0.5 * (A + A.transpose());
}

hex8::NodeMatrix unit_cube() {
  hex8::NodeMatrix X;
  for (int c = 0; c < 8; ++c) X.row(c) = Vec3(c >> 2 & 1, c >> 1 & 1, c & 1).transpose();
  return X;
}

Mat6 element_uniform_response(const std::vector<Mat6>& C, int n, bool enhanced) {
  const hex8::NodeMatrix X = unit_cube();
  const hex8::QuadratureRule rule = hex8::gauss_rule(n);
  if (static_cast<int>(C.size()) != rule.size())
    throw std::invalid_argument("element_uniform_response: one stiffness per quadrature point expected");
  return uniform_strain_response(enhanced ? hex8::enhanced_element_geometry(X, rule) : hex8::element_geometry(X, rule),
                                 C);
}

Mat6 fit_uniform_response(const CoarseMaterialFit& fit) {
  const hex8::NodeMatrix X = unit_cube();
  const QuadratureMaterials m = coarse_quadrature_materials(fit);
  std::vector<Mat6> C;
  for (const MaterialPtr& p : m.at_point) C.push_back(rest_voigt_stiffness(*p));
  return uniform_strain_response(coarse_element_geometry(coarse_fit_geometry(X, fit.points(), fit.enhanced), X, m), C);
}

double stiffness_distance(const Mat6& A, const Mat6& B) {
  const Eigen::GeneralizedSelfAdjointEigenSolver<Mat6> eig(A, B, Eigen::EigenvaluesOnly);
  if (eig.info() != Eigen::Success || !(eig.eigenvalues().minCoeff() > 0))
    return std::numeric_limits<double>::infinity();
  return std::sqrt(eig.eigenvalues().array().log().square().mean());
}

Mat6 rest_voigt_stiffness(const Material& material) {
  const Mat9 D = material.stress_derivative(Mat3::Identity());
  Mat6 C;
  for (int j = 0; j < 6; ++j) {
    const Mat3 eps = voigt_to_strain(Vec6::Unit(j));
    const Vec9 dP = D * Eigen::Map<const Vec9>(eps.data());
    C.col(j) = stress_to_voigt(Eigen::Map<const Mat3>(dP.data()));
  }
  return 0.5 * (C + C.transpose());
}

namespace {

// The 21 independent entries of a symmetric 6 x 6 matrix, and back.
using Vec21 = Eigen::Matrix<double, 21, 1>;
Vec21 symmetric_entries(const Mat6& M) {
  Vec21 v;
  for (int i = 0, k = 0; i < 6; ++i)
    for (int j = i; j < 6; ++j) v[k++] = M(i, j);
  return v;
}
Mat6 symmetric_matrix(const Vec21& v) {
  Mat6 M;
  for (int i = 0, k = 0; i < 6; ++i)
    for (int j = i; j < 6; ++j, ++k) M(i, j) = M(j, i) = v[k];
  return M;
}

std::vector<Mat6> congruent(const std::vector<Mat6>& C, const Mat6& S) {
  std::vector<Mat6> out;
  out.reserve(C.size());
  for (const Mat6& Cq : C) out.push_back(S * Cq * S);
  return out;
}

// Newton on the symmetric S of one more congruence, S C_q S, for the
// equations A(S) = target (21 of them, 21 unknowns), from S = I; the
// Jacobian by forward differences (21 more responses, each a 9 x 9
// condensation). For the cells on which the fixed point converges slowly.
std::vector<Mat6> newton_to_response(std::vector<Mat6> C, const hex8::ElementGeometry& geo, const Mat6& target,
                                     int* iterations, double* r) {
  const double scale = target.norm();
  auto residual = [&](const std::vector<Mat6>& Cs) {
    return Vec21(symmetric_entries(uniform_strain_response(geo, Cs) - target) / scale);
  };
  Vec21 F = residual(C);
  for (int it = 0; it < kMaxNewtonSteps && F.norm() > kResponseTolerance; ++it, ++*iterations) {
    Eigen::Matrix<double, 21, 21> J;
    for (int k = 0; k < 21; ++k) {
      const Mat6 S = Mat6::Identity() + symmetric_matrix(kJacobianStep * Vec21::Unit(k));
      J.col(k) = (residual(congruent(C, S)) - F) / kJacobianStep;
    }
    const Vec21 step = J.colPivHouseholderQr().solve(-F);
    // Backtracking on the residual's norm; S stays near I, so S C_q S stays
    // positive definite.
    bool decreased = false;
    for (double t = 1; t > 1e-9 && !decreased; t *= 0.5) {
      std::vector<Mat6> trial = congruent(C, Mat6::Identity() + symmetric_matrix(t * step));
      const Vec21 Ft = residual(trial);
      if ((decreased = Ft.norm() < F.norm())) {
        C = std::move(trial);
        F = Ft;
      }
    }
    if (!decreased) break;  // no decrease left
  }
  *r = (uniform_strain_response(geo, C) - target).norm() / scale;
  return C;
}

}  // namespace

std::vector<Mat6> congruent_to_response(std::vector<Mat6> C, const hex8::ElementGeometry& geo, const Mat6& target,
                                        int* iterations, double* residual) {
  double r = 0;
  int it = 0;
  for (;; ++it) {
    const Mat6 A = uniform_strain_response(geo, C);
    r = (A - target).norm() / target.norm();
    if (r <= kResponseTolerance || it == kFixedPointSteps) break;
    const Mat6 S = congruence_to(A, target);
    for (Mat6& Cq : C) Cq = S * Cq * S;
  }
  // The fixed point converges linearly, on some high-contrast cells at a
  // rate of 0.8 per step (measured at level 1 with a windowed target: 50
  // steps left 6e-5); Newton finishes those.
  if (r > kResponseTolerance) C = newton_to_response(std::move(C), geo, target, &it, &r);
  if (!(r <= kAcceptedResidual))
    throw NumericalError("matched coarsening: the congruence leaves the element's uniform response " +
                         std::to_string(r) + " (relative) from its target stiffness");
  if (iterations) *iterations = it;
  if (residual) *residual = r;
  return C;
}

namespace {

std::vector<Mat6> matched_point_stiffness_to(const std::vector<MaterialPtr>& palette, const std::vector<int>& ids,
                                             int n, bool enhanced, const Mat6* target, int* iterations,
                                             double* residual) {
  if (static_cast<int>(ids.size()) != n * n * n)
    throw std::invalid_argument("matched_point_stiffness: n^3 ids expected");
  std::vector<Mat6> C;
  for (int id : ids) {
    if (id <= 0 || id >= static_cast<int>(palette.size()) || !palette[id])
      throw InputError("matched coarsening: fine material id " + std::to_string(id) +
                       " is not a solid palette material");
    C.push_back(lame_C(palette[id]->shear_modulus(), palette[id]->lame_lambda()));
  }
  const hex8::NodeMatrix X = unit_cube();
  const hex8::QuadratureRule rule = hex8::gauss_rule(n);
  return congruent_to_response(std::move(C),
                               enhanced ? hex8::enhanced_element_geometry(X, rule) : hex8::element_geometry(X, rule),
                               target ? *target : block_homogenized_stiffness(palette, ids, n), iterations, residual);
}

}  // namespace

std::vector<Mat6> matched_point_stiffness(const std::vector<MaterialPtr>& palette, const std::vector<int>& ids, int n,
                                          bool enhanced, int* iterations, double* residual) {
  return matched_point_stiffness_to(palette, ids, n, enhanced, nullptr, iterations, residual);
}

QuadratureMaterials matched_block_materials(const std::vector<MaterialPtr>& palette, const std::vector<int>& ids, int n,
                                            bool enhanced, const Mat6* target) {
  if (!solid_mixed_block(ids)) return naive_block(palette, ids, n);
  int iterations = 0;
  const std::vector<Mat6> C = matched_point_stiffness_to(palette, ids, n, enhanced, target, &iterations, nullptr);
  // Already matched (the enhanced element at level 1 with the cell's C^H):
  // the naive materials themselves, which evaluate faster.
  if (iterations == 0) return naive_block(palette, ids, n);
  QuadratureMaterials m;
  for (const Mat6& Cq : C) m.at_point.push_back(homogenized_block_material(Cq));
  return m;
}

Mat6 cell_windowed_stiffness(const VoxelGrid& fine, const std::vector<MaterialPtr>& palette, const CoarseGrid& cells,
                             const std::vector<int>& ids, int cell, int margin, bool* unresolved) {
  *unresolved = false;
  const std::array<int, 3> v = cells.first_voxel(cell);
  try {
    return windowed_stiffness(fine, palette, v[0], v[1], v[2], cells.fine_per_cell(), margin);
  } catch (const NumericalError&) {
    *unresolved = true;
    return block_homogenized_stiffness(palette, ids, cells.fine_per_cell());
  }
}

QuadratureMaterials windowed_matched_cell(const VoxelGrid& fine, const std::vector<MaterialPtr>& palette,
                                          const CoarseGrid& cells, const CoarseGrid* level1, bool enhanced, int margin,
                                          int cell, bool* unresolved) {
  *unresolved = false;
  const int combination = cells.cell_combination.at(cell);
  if (combination < 0) throw std::invalid_argument("windowed_matched_cell: the cell is void");
  const ChildIds& child = cells.combinations[combination];
  const int n = cells.fine_per_cell();
  const std::vector<int> ids = level1 ? block_level2(child, level1->combinations) : block_level1(child);
  if (!solid_mixed_block(ids)) return naive_block(palette, ids, n);
  const Mat6 A = cell_windowed_stiffness(fine, palette, cells, ids, cell, margin, unresolved);
  return matched_block_materials(palette, ids, n, enhanced, &A);
}

CoarseMaterialLookup matched_coarsening(const std::vector<MaterialPtr>& palette, bool enhanced) {
  return [palette, enhanced](const ChildIds& child) {
    return matched_block_materials(palette, block_level1(child), 2, enhanced);
  };
}

CoarseMaterialLookup matched_coarsening(const std::vector<MaterialPtr>& palette, const CoarseGrid& level1,
                                        bool enhanced) {
  if (level1.level != 1) throw InputError("matched level-2 coarsening needs a level-1 grid");
  return [palette, combos = level1.combinations, enhanced](const ChildIds& child) {
    return matched_block_materials(palette, block_level2(child, combos), 4, enhanced);
  };
}

}  // namespace msfab
