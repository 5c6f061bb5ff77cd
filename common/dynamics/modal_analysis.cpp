#include "dynamics/modal_analysis.hpp"

#include <Eigen/Eigenvalues>
#include <algorithm>
#include <cmath>
#include <cstdint>
#include <sstream>
#include <string>

#include "core/errors.hpp"
#include "dynamics/mass_matrix.hpp"
#include "fem/elastic_assembler.hpp"
#include "solve/cholmod_solver.hpp"

namespace msfab {

namespace {

constexpr double kTwoPi = 6.283185307179586476925286766559;

// The rows and columns of A whose map entry is >= 0, renumbered by the map.
// The map is increasing on the kept indices, so column order and sorted
// row order survive and the result is built directly in compressed form.
SpMat restrict_symmetric(const SpMat& A, const std::vector<int>& map, int kept) {
  SpMat R(kept, kept);
  std::vector<int> col_ptr(1, 0), rows;
  std::vector<double> values;
  rows.reserve(static_cast<size_t>(A.nonZeros()));
  values.reserve(static_cast<size_t>(A.nonZeros()));
  for (int j = 0; j < A.outerSize(); ++j) {
    if (map[j] < 0) continue;
    for (SpMat::InnerIterator it(A, j); it; ++it) {
      const int r = map[it.row()];
      if (r < 0) continue;
      rows.push_back(r);
      values.push_back(it.value());
    }
    col_ptr.push_back(static_cast<int>(rows.size()));
  }
  R.resizeNonZeros(static_cast<Eigen::Index>(rows.size()));
  std::copy(col_ptr.begin(), col_ptr.end(), R.outerIndexPtr());
  std::copy(rows.begin(), rows.end(), R.innerIndexPtr());
  std::copy(values.begin(), values.end(), R.valuePtr());
  return R;
}

// Start vectors from a fixed integer hash (splitmix64), so they are the same
// on every platform and standard library.
MatX start_block(Eigen::Index n, Eigen::Index columns, std::uint64_t salt) {
  MatX X(n, columns);
  for (Eigen::Index c = 0; c < columns; ++c)
    for (Eigen::Index i = 0; i < n; ++i) {
      std::uint64_t z =
          (static_cast<std::uint64_t>(c) << 40) ^ static_cast<std::uint64_t>(i) ^ (salt * 0x9E3779B97F4A7C15ull);
      z += 0x9E3779B97F4A7C15ull;
      z = (z ^ (z >> 30)) * 0xBF58476D1CE4E5B9ull;
      z = (z ^ (z >> 27)) * 0x94D049BB133111EBull;
      z ^= z >> 31;
      X(i, c) = static_cast<double>(z >> 11) * (2.0 / 9007199254740992.0) - 1.0;
    }
  return X;
}

// An M-orthonormal basis V (with MV = M V kept alongside) grown one vector at
// a time by two passes of classical Gram-Schmidt in the M inner product.
class MBasis {
 public:
  MBasis(const SpMat& M, Eigen::Index n, Eigen::Index capacity) : M_(M), V_(n, capacity), MV_(n, capacity) {}

  Eigen::Index size() const { return size_; }
  Eigen::Index capacity() const { return V_.cols(); }
  auto V() const { return V_.leftCols(size_); }
  auto MV() const { return MV_.leftCols(size_); }
  void clear() { size_ = 0; }

  // Appends the normalized part of b orthogonal to the basis; returns false
  // (and appends nothing) when b lies in the span to round-off.
  bool add(VecX b) {
    if (size_ >= capacity()) return false;
    VecX Mb = M_ * b;
    const double original = std::sqrt(std::max(b.dot(Mb), 0.0));
    if (!(original > 0) || !std::isfinite(original)) return false;
    for (int pass = 0; pass < 2 && size_ > 0; ++pass) {
      const VecX c = MV().transpose() * b;
      b.noalias() -= V() * c;
    }
    Mb = M_ * b;
    const double norm = std::sqrt(std::max(b.dot(Mb), 0.0));
    if (!(norm > 1e-10 * original)) return false;
    V_.col(size_) = b / norm;
    MV_.col(size_) = Mb / norm;
    ++size_;
    return true;
  }

 private:
  const SpMat& M_;
  MatX V_, MV_;
  Eigen::Index size_ = 0;
};

// Relative residual ||k - lambda m|| / ||k|| (see ModalResult::residuals).
double relative_residual(const VecX& k, const VecX& m, double lambda, bool rigid, double scale) {
  const double denominator = rigid ? scale * m.norm() : k.norm();
  const double r = (k - lambda * m).norm();
  return denominator > 0 ? r / denominator : r;
}

// Diagonal DOF weightings for the canonical basis of a repeated eigenvalue:
// first diag(3, 2, 1) on the x, y, z displacement of every node; then, to
// split what that leaves tied (identical disconnected bodies), the same
// times a weight growing along a generic direction in space.
std::vector<VecX> canonical_weights(const std::vector<int>& free_dofs, const NodeArray* positions) {
  const Eigen::Index nf = static_cast<Eigen::Index>(free_dofs.size());
  std::vector<VecX> w(1, VecX(nf));
  for (Eigen::Index i = 0; i < nf; ++i) w[0](i) = 3.0 - free_dofs[static_cast<size_t>(i)] % 3;
  if (positions && positions->rows() > 0) {
    const Vec3 lo = positions->colwise().minCoeff().transpose(), hi = positions->colwise().maxCoeff().transpose();
    const Vec3 centre = 0.5 * (lo + hi);
    const double radius = std::max(0.5 * (hi - lo).norm(), 1e-300);
    const Vec3 direction = Vec3(1.0, 2.0, 3.0).normalized();
    w.emplace_back(nf);
    for (Eigen::Index i = 0; i < nf; ++i) {
      const int node = free_dofs[static_cast<size_t>(i)] / 3;
      const double s = (positions->row(node).transpose() - centre).dot(direction) / radius;
      w[1](i) = w[0](i) * (1.0 + 0.5 * s);
    }
  }
  return w;
}

// Orthogonal rotation of the columns of X (M-orthonormal, MX = M X) onto the
// eigenvectors of Q = sym(X^T diag(w) M X), largest Q first; groups of
// equal Q are resolved by the next weighting.
MatX canonical_rotation(const MatX& X, const MatX& MX, const std::vector<VecX>& weights, size_t level) {
  MatX Q = X.transpose() * weights[level].asDiagonal() * MX;
  Q = 0.5 * (Q + Q.transpose()).eval();
  Eigen::SelfAdjointEigenSolver<MatX> eig(Q);
  MatX R = eig.eigenvectors().rowwise().reverse();
  const VecX q = eig.eigenvalues().reverse();
  if (level + 1 < weights.size()) {
    const double tie = 1e-8 * q.cwiseAbs().maxCoeff();
    for (Eigen::Index g = 0; g < q.size();) {
      Eigen::Index h = g + 1;
      while (h < q.size() && q(h - 1) - q(h) <= tie) ++h;
      if (h - g > 1) {
        const MatX Rg = R.middleCols(g, h - g);
        R.middleCols(g, h - g) = Rg * canonical_rotation(X * Rg, MX * Rg, weights, level + 1);
      }
      g = h;
    }
  }
  return R;
}

void check_options(const ModalOptions& o) {
  auto bad = [](const std::string& what) { throw InputError("modal analysis options: " + what); };
  if (o.num_modes < 1) bad("num_modes must be at least 1");
  if (!(o.rigid_threshold >= 0) || !std::isfinite(o.rigid_threshold)) bad("rigid_threshold must be >= 0");
  if (!std::isnan(o.shift) && !std::isfinite(o.shift)) bad("shift must be finite (or NaN for automatic)");
  if (!(o.shift_fraction > 0) || !std::isfinite(o.shift_fraction)) bad("shift_fraction must be > 0");
  if (!(o.tolerance > 0) || !(o.tolerance < 1)) bad("tolerance must be in (0, 1)");
  if (o.max_cycles < 1) bad("max_cycles must be at least 1");
  if (o.block_size < 0) bad("block_size must be >= 0 (0 = automatic)");
  if (o.krylov_blocks < 2) bad("krylov_blocks must be at least 2");
  if (!(o.repeated_tolerance >= 0) || !(o.repeated_tolerance < 1)) bad("repeated_tolerance must be in [0, 1)");
}

void check_system(const SpMat& K, const SpMat& M, const std::vector<char>& fixed, const NodeArray* rest_positions) {
  const Eigen::Index n = K.rows();
  if (K.cols() != n || M.rows() != n || M.cols() != n)
    throw InputError("modal analysis: K is " + std::to_string(K.rows()) + "x" + std::to_string(K.cols()) +
                     " and M is " + std::to_string(M.rows()) + "x" + std::to_string(M.cols()) +
                     "; both must be square of the same size");
  if (n % 3 != 0) throw InputError("modal analysis: " + std::to_string(n) + " DOFs is not 3 per node");
  if (rest_positions && 3 * rest_positions->rows() != n)
    throw InputError("modal analysis: " + std::to_string(rest_positions->rows()) + " node positions for " +
                     std::to_string(n) + " DOFs");
  if (!fixed.empty() && static_cast<Eigen::Index>(fixed.size()) != n)
    throw InputError("modal analysis: " + std::to_string(fixed.size()) + " fixed-DOF flags for " + std::to_string(n) +
                     " DOFs");
}

// Factorizes A = K - sigma M into `solver` and returns sigma: the given
// shift, or an automatic one below zero moved down tenfold until A is
// positive definite. The solver checks its solves against A, so the caller
// keeps A alive as long as the solver.
double factorize_shifted(const SpMat& Kf, const SpMat& Mf, const ModalOptions& options, double scale, SpMat& A,
                         CholmodSolver& solver) {
  const bool automatic = std::isnan(options.shift);
  double sigma = automatic ? -options.shift_fraction * scale : options.shift;
  A = Kf - sigma * Mf;
  solver.analyze(A);
  for (int attempt = 0;; ++attempt) {
    if (solver.factorize(A)) return sigma;
    if (!automatic || attempt == 6) {
      std::ostringstream msg;
      msg << "modal analysis: K - sigma M is not positive definite for sigma = " << sigma
          << (automatic ? " (after lowering the automatic shift 6 times)" : "")
          << "; the shift must lie below the lowest eigenvalue";
      throw NumericalError(msg.str());
    }
    sigma *= 10.0;
    A = Kf - sigma * Mf;  // same pattern: only values change
  }
}

// Ritz pairs of the pencil: values, vectors X and their products K X, M X.
struct RitzPairs {
  VecX values;
  MatX vectors, K, M;
};

// One cycle of the block Krylov method: the M-orthonormal basis of X and
// (K - sigma M)^-1 M applied to it up to krylov_blocks deep, then
// Rayleigh-Ritz on the pencil (V^T K V, V^T M V); the lowest p pairs.
RitzPairs krylov_ritz_pairs(const SpMat& Kf, const SpMat& Mf, CholmodSolver& solver, const MatX& X, int p,
                            int krylov_blocks, int cycle, Eigen::Index& basis_size, int& operator_applications) {
  const Eigen::Index nf = Kf.rows();
  MBasis basis(Mf, nf, std::min<Eigen::Index>(nf, Eigen::Index(p) * krylov_blocks));
  Eigen::Index block_begin = 0;
  for (Eigen::Index c = 0; c < X.cols(); ++c) basis.add(X.col(c));
  for (int depth = 1; depth < krylov_blocks && basis.size() < basis.capacity(); ++depth) {
    const Eigen::Index block_end = basis.size();
    if (block_end == block_begin) break;  // the Krylov space is exhausted
    for (Eigen::Index c = block_begin; c < block_end; ++c) {
      VecX y = solver.solve(basis.MV().col(c));
      ++operator_applications;
      basis.add(std::move(y));
    }
    block_begin = block_end;
  }

  const Eigen::Index m = basis.size();
  basis_size = m;
  const MatX KV = Kf * basis.V();
  MatX Kr = basis.V().transpose() * KV;
  MatX Mr = basis.V().transpose() * basis.MV();
  Kr = 0.5 * (Kr + Kr.transpose()).eval();
  Mr = 0.5 * (Mr + Mr.transpose()).eval();
  Eigen::GeneralizedSelfAdjointEigenSolver<MatX> dense(Kr, Mr);
  if (dense.info() != Eigen::Success)
    throw NumericalError("modal analysis: the projected eigenproblem failed in cycle " + std::to_string(cycle));
  const Eigen::Index keep = std::min<Eigen::Index>(m, p);
  const MatX Y = dense.eigenvectors().leftCols(keep);
  RitzPairs ritz;
  ritz.values = dense.eigenvalues().head(keep);
  ritz.vectors = basis.V() * Y;
  ritz.K = KV * Y;
  ritz.M = basis.MV() * Y;
  return ritz;
}

// Relative residuals of the reported Ritz pairs and of those just past the
// last one with nearly the same eigenvalue: they may join its repeated
// group in the canonical rotation, so they must converge as well.
VecX checked_residuals(const RitzPairs& ritz, const std::vector<int>& reported, double rigid_below, double scale) {
  std::vector<int> checked = reported;
  const double last = ritz.values(reported.back());
  for (Eigen::Index i = reported.back() + 1; i < ritz.values.size(); ++i) {
    const bool rigid_pair = last < rigid_below && ritz.values(i) < rigid_below;
    if (!rigid_pair && !(std::abs(ritz.values(i) - last) <= 1e-3 * std::abs(last))) break;
    checked.push_back(static_cast<int>(i));
  }
  VecX residuals(static_cast<Eigen::Index>(checked.size()));
  for (size_t r = 0; r < checked.size(); ++r) {
    const int i = checked[r];
    residuals(static_cast<Eigen::Index>(r)) =
        relative_residual(ritz.K.col(i), ritz.M.col(i), ritz.values(i), ritz.values(i) < rigid_below, scale);
  }
  return residuals;
}

// The reported Ritz pairs as the result's modes on all n DOFs (fixed ones
// zero), each with the sign rule below, and their frequencies and residuals.
void store_modes(const RitzPairs& ritz, const std::vector<int>& reported, const std::vector<int>& free_dofs,
                 Eigen::Index n, double rigid_below, double scale, ModalResult& result) {
  const int k = static_cast<int>(reported.size());
  const int nf = static_cast<int>(free_dofs.size());
  result.eigenvalues.resize(k);
  result.frequencies.resize(k);
  result.residuals.resize(k);
  result.modes = MatX::Zero(n, k);
  for (int r = 0; r < k; ++r) {
    const int i = reported[static_cast<size_t>(r)];
    VecX x = ritz.vectors.col(i);
    // Sign: the first entry within round-off of the largest magnitude is
    // positive (ties are common on symmetric meshes).
    const double largest = x.cwiseAbs().maxCoeff();
    for (int j = 0; j < nf; ++j)
      if (std::abs(x(j)) >= (1.0 - 1e-8) * largest) {
        if (x(j) < 0) x = -x;
        break;
      }
    const double lambda = ritz.values(i);
    result.eigenvalues(r) = lambda;
    result.frequencies(r) = std::sqrt(std::max(lambda, 0.0)) / kTwoPi;
    result.residuals(r) = relative_residual(ritz.K.col(i), ritz.M.col(i), lambda, lambda < rigid_below, scale);
    for (int j = 0; j < nf; ++j) result.modes(free_dofs[static_cast<size_t>(j)], r) = x(j);
  }
}

// Canonical bases of repeated eigenvalues. A group may run past the last
// reported mode, so the Ritz pairs that follow are taken in while their
// eigenvalues still agree.
void canonicalize_repeated(const SpMat& Kf, const SpMat& Mf, const std::vector<int>& reported,
                           const std::vector<int>& free_dofs, const NodeArray* rest_positions,
                           double repeated_tolerance, double rigid_below, RitzPairs& ritz) {
  const Eigen::Index available = ritz.values.size();
  const Eigen::Index nf = ritz.vectors.rows();
  auto same = [&](int a, int b) {
    const double la = ritz.values(a), lb = ritz.values(b);
    if (la < rigid_below || lb < rigid_below) return la < rigid_below && lb < rigid_below;
    return std::abs(la - lb) <= repeated_tolerance * std::max(std::abs(la), std::abs(lb));
  };
  std::vector<int> extended = reported;
  while (static_cast<Eigen::Index>(extended.back()) + 1 < available && same(extended.back(), extended.back() + 1))
    extended.push_back(extended.back() + 1);
  const std::vector<VecX> weights = canonical_weights(free_dofs, rest_positions);
  for (size_t g = 0; g < extended.size();) {
    size_t h = g + 1;
    while (h < extended.size() && same(extended[h - 1], extended[h])) ++h;
    const Eigen::Index size = static_cast<Eigen::Index>(h - g);
    if (size > 1) {
      MatX Xg(nf, size), MXg(nf, size);
      for (Eigen::Index c = 0; c < size; ++c) {
        Xg.col(c) = ritz.vectors.col(extended[g + c]);
        MXg.col(c) = ritz.M.col(extended[g + c]);
      }
      const MatX XR = Xg * canonical_rotation(Xg, MXg, weights, 0);
      for (Eigen::Index c = 0; c < size; ++c) {
        const int i = extended[g + c];
        ritz.vectors.col(i) = XR.col(c);
        ritz.K.col(i) = Kf * ritz.vectors.col(i);
        ritz.M.col(i) = Mf * ritz.vectors.col(i);
        ritz.values(i) = ritz.vectors.col(i).dot(ritz.K.col(i)) / ritz.vectors.col(i).dot(ritz.M.col(i));
      }
    }
    g = h;
  }
}

}  // namespace

ModalResult modal_analysis(const SpMat& K, const SpMat& M, const std::vector<char>& fixed, const ModalOptions& options,
                           const NodeArray* rest_positions) {
  check_options(options);
  check_system(K, M, fixed, rest_positions);
  const Eigen::Index n = K.rows();

  std::vector<int> map(static_cast<size_t>(n), -1), free_dofs;
  for (Eigen::Index i = 0; i < n; ++i)
    if (fixed.empty() || !fixed[static_cast<size_t>(i)]) {
      map[static_cast<size_t>(i)] = static_cast<int>(free_dofs.size());
      free_dofs.push_back(static_cast<int>(i));
    }
  const int nf = static_cast<int>(free_dofs.size());
  const int k = options.num_modes;
  if (k > nf)
    throw InputError("modal analysis: num_modes " + std::to_string(k) + " exceeds the " + std::to_string(nf) +
                     " free DOFs");
  const SpMat Kf = restrict_symmetric(K, map, nf);
  const SpMat Mf = restrict_symmetric(M, map, nf);

  ModalResult result;
  const double trace_m = Mf.diagonal().sum(), trace_k = Kf.diagonal().sum();
  if (!(trace_m > 0) || !(trace_k > 0) || !std::isfinite(trace_m) || !std::isfinite(trace_k))
    throw InputError("modal analysis: stiffness and mass must have positive diagonals (traces " +
                     std::to_string(trace_k) + ", " + std::to_string(trace_m) + ")");
  const double scale = trace_k / trace_m;
  result.stiffness_scale = scale;
  const double rigid_below = options.rigid_threshold * scale;

  // Factorize K - sigma M, moving an automatic shift down until it is SPD.
  LinearSolverOptions solver_options;
  solver_options.threads = options.threads;
  SpMat shifted;  // K - sigma M, referred to by the solver
  CholmodSolver solver(solver_options);
  const double sigma = factorize_shifted(Kf, Mf, options, scale, shifted, solver);
  result.shift = sigma;

  const int wanted = std::min(nf, k + (options.skip_rigid ? 6 : 0));
  int p = options.block_size > 0 ? options.block_size : std::max(2 * wanted, wanted + 6);
  p = std::min(std::max(p, wanted), nf);

  MatX X = start_block(nf, p, 1);
  RitzPairs ritz;
  std::vector<int> reported;
  VecX residuals;
  std::vector<std::string> history;
  std::vector<double> max_residuals;
  bool converged = false;
  for (int cycle = 1; cycle <= options.max_cycles && !converged; ++cycle) {
    result.cycles = cycle;
    Eigen::Index m = 0;  // the basis' size
    ritz = krylov_ritz_pairs(Kf, Mf, solver, X, p, options.krylov_blocks, cycle, m, result.operator_applications);
    const Eigen::Index keep = ritz.values.size();

    // The first k Ritz pairs above the rigid threshold (or simply the first k).
    reported.clear();
    int rigid = 0;
    for (Eigen::Index i = 0; i < keep && static_cast<int>(reported.size()) < k; ++i) {
      if (options.skip_rigid && ritz.values(i) < rigid_below) {
        ++rigid;
        continue;
      }
      reported.push_back(static_cast<int>(i));
    }
    result.rigid_modes_skipped = rigid;
    if (static_cast<int>(reported.size()) < k) {
      // More rigid modes than the block allows for (several disconnected
      // bodies): widen the block with fresh start vectors and go on.
      if (p >= nf)
        throw NumericalError("modal analysis: only " + std::to_string(reported.size()) +
                             " non-rigid modes exist among the " + std::to_string(nf) + " free DOFs");
      const int wider = std::min(nf, p + rigid + k);
      MatX Xw(nf, wider);
      Xw.leftCols(keep) = ritz.vectors;
      Xw.rightCols(wider - keep) = start_block(nf, wider - keep, 2 + cycle);
      X = std::move(Xw);
      p = wider;
      history.push_back("cycle " + std::to_string(cycle) + ": block widened to " + std::to_string(p));
      continue;
    }

    residuals = checked_residuals(ritz, reported, rigid_below, scale);
    std::ostringstream line;
    line << "cycle " << cycle << ": max residual " << residuals.maxCoeff();
    history.push_back(line.str());
    // Accepted at the tolerance, or at the round-off floor: a residual
    // within 100x the tolerance that has not fallen by 1% in 20 cycles
    // (the shifted factorization of a free, stiff body stalls near 1e-8).
    max_residuals.push_back(residuals.maxCoeff());
    const size_t c = max_residuals.size();
    const bool stalled = c > 20 && max_residuals[c - 1] <= 100 * options.tolerance &&
                         max_residuals[c - 1] > 0.99 * max_residuals[c - 21];
    converged = residuals.maxCoeff() <= options.tolerance || m == nf || stalled;
    X = ritz.vectors;
  }
  if (!converged) {
    std::ostringstream msg;
    msg << "modal analysis did not reach relative residual " << options.tolerance << " in " << options.max_cycles
        << " cycles (block " << p << ", shift " << sigma << "):";
    const size_t from = history.size() > 5 ? history.size() - 5 : 0;
    for (size_t i = from; i < history.size(); ++i) msg << (i > from ? "; " : " ") << history[i];
    throw NumericalError(msg.str());
  }

  if (options.repeated_tolerance > 0)
    canonicalize_repeated(Kf, Mf, reported, free_dofs, rest_positions, options.repeated_tolerance, rigid_below, ritz);

  store_modes(ritz, reported, free_dofs, n, rigid_below, scale, result);
  return result;
}

double modal_analysis_peak_bytes(double elements, double dofs, const ModalOptions& options) {
  const double wanted = options.num_modes + (options.skip_rigid ? 6 : 0);
  const double width = options.block_size > 0 ? options.block_size : std::max(2 * wanted, wanted + 6);
  return 12e3 * elements + 0.7e3 * std::pow(elements, 4.0 / 3.0) +
         8.0 * dofs * (3.0 * options.krylov_blocks + 6.0) * width;
}

ModalResult modal_analysis(const HexMesh& mesh, const std::vector<double>& density, const std::vector<char>& fixed,
                           const ModalOptions& options) {
  ElasticAssembler assembler(mesh);
  SpMat K = assembler.pattern();
  const double energy = assembler.evaluate(assembler.rest_positions(), nullptr, &K);
  if (!std::isfinite(energy)) throw InputError("modal analysis: the rest configuration has inverted elements");
  const SpMat M = expand_to_dofs(scalar_mass_matrix(mesh, density));
  return modal_analysis(K, M, fixed, options, &mesh.nodes);
}

}  // namespace msfab
