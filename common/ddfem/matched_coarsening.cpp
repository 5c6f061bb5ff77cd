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
constexpr int kMaxIterations = 50;

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
  return uniform_strain_response(enhanced ? hex8::enhanced_element_geometry(X, rule) : hex8::element_geometry(X, rule), C);
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

std::vector<Mat6> congruent_to_response(std::vector<Mat6> C, const hex8::ElementGeometry& geo, const Mat6& target,
                                        int* iterations, double* residual) {
  double r = 0;
  int it = 0;
  for (;; ++it) {
    const Mat6 A = uniform_strain_response(geo, C);
    r = (A - target).norm() / target.norm();
    if (r <= kResponseTolerance || it == kMaxIterations) break;
    const Mat6 S = congruence_to(A, target);
    for (Mat6& Cq : C) Cq = S * Cq * S;
  }
  if (iterations) *iterations = it;
  if (residual) *residual = r;
  return C;
}

namespace {

bool solid_and_mixed(const std::vector<int>& ids) {
  return std::find(ids.begin(), ids.end(), 0) == ids.end() &&
         std::any_of(ids.begin(), ids.end(), [&](int id) { return id != ids[0]; });
}

std::vector<Mat6> matched_point_stiffness_to(const std::vector<MaterialPtr>& palette, const std::vector<int>& ids,
                                             int n, bool enhanced, const Mat6* target, int* iterations,
                                             double* residual) {
  if (static_cast<int>(ids.size()) != n * n * n) throw std::invalid_argument("matched_point_stiffness: n^3 ids expected");
  std::vector<Mat6> C;
  for (int id : ids) {
    if (id <= 0 || id >= static_cast<int>(palette.size()) || !palette[id])
      throw InputError("matched coarsening: fine material id " + std::to_string(id) + " is not a solid palette material");
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

QuadratureMaterials matched_block_materials(const std::vector<MaterialPtr>& palette, const std::vector<int>& ids,
                                            int n, bool enhanced, const Mat6* target) {
  if (!solid_and_mixed(ids)) return naive_block(palette, ids, n);
  int iterations = 0;
  const std::vector<Mat6> C = matched_point_stiffness_to(palette, ids, n, enhanced, target, &iterations, nullptr);
  // Already matched (the enhanced element at level 1 with the cell's C^H):
  // the naive materials themselves, which evaluate faster.
  if (iterations == 0) return naive_block(palette, ids, n);
  QuadratureMaterials m;
  for (const Mat6& Cq : C) m.at_point.push_back(homogenized_block_material(Cq));
  return m;
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
  if (!solid_and_mixed(ids)) return naive_block(palette, ids, n);
  const int I = cell % cells.nx, J = (cell / cells.nx) % cells.ny, K = cell / (cells.nx * cells.ny);
  try {
    const Mat6 A = windowed_stiffness(fine, palette, n * I, n * J, n * K, n, margin);
    return matched_block_materials(palette, ids, n, enhanced, &A);
  } catch (const NumericalError&) {
    *unresolved = true;
    return matched_block_materials(palette, ids, n, enhanced);
  }
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
