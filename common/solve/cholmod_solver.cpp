#include "solve/cholmod_solver.hpp"

#include <cholmod.h>
#include <omp.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstring>
#include <mutex>
#include <stdexcept>
#include <string>

#include "core/errors.hpp"
#include "core/timing.hpp"
#include "solve/blas_threads.hpp"
#include "solve/solver_checks.hpp"
#include "solve/sparse_ops.hpp"

namespace msfab {

namespace {

// Debian's CHOLMOD 3 (SuiteSparse 5) opens OpenMP regions with a fixed
// num_threads(4) in the supernodal numeric factorization, whatever the
// caller's thread count, and the OpenMP build of OpenBLAS opens its own
// regions inside them. On two cores that oversubscription is ruinous: a
// bridge of 21 627 unknowns took 3.37 s per factorization with two threads
// against 0.27 s with one (docs/solvers.md, "CHOLMOD threads"); a
// single-threaded caller spent a third of a Newmark step waking threads.
// So CHOLMOD always runs on one thread: with dynamic adjustment on,
// libgomp caps the fixed requests at omp_get_max_threads(), here 1, and
// OpenBLAS is asked for one thread too (planning more than libgomp then
// grants makes it wait forever). Every setting is restored afterwards, so
// the caller's own parallel kernels keep their threads.
class CholmodThreadScope {
 public:
  CholmodThreadScope() : dynamic_(omp_get_dynamic()) { omp_set_dynamic(1); }
  ~CholmodThreadScope() { omp_set_dynamic(dynamic_); }
  CholmodThreadScope(const CholmodThreadScope&) = delete;
  CholmodThreadScope& operator=(const CholmodThreadScope&) = delete;

 private:
  OmpThreads threads_{1};
  int dynamic_;
  SingleThreadedBlas blas_;  // OpenBLAS on one thread for the scope too
};

// METIS keeps its random-number state in globals: two threads ordering at
// once disturb each other's orderings, and with them the round-off of every
// solve. One ordering at a time keeps results reproducible.
std::mutex& metis_mutex() {
  static std::mutex m;
  return m;
}

// A CHOLMOD view of Eigen's arrays (no copy). stype = -1 tells CHOLMOD to
// read only the lower triangle of the full symmetric matrix.
cholmod_sparse lower_triangle_view(const SpMat& A) {
  cholmod_sparse view;
  std::memset(&view, 0, sizeof(view));
  view.nrow = static_cast<size_t>(A.rows());
  view.ncol = static_cast<size_t>(A.cols());
  view.nzmax = static_cast<size_t>(A.isCompressed() ? A.nonZeros() : A.outerIndexPtr()[A.cols()]);
  view.p = const_cast<int*>(A.outerIndexPtr());
  view.i = const_cast<int*>(A.innerIndexPtr());
  view.nz = A.isCompressed() ? nullptr : const_cast<int*>(A.innerNonZeroPtr());
  view.x = const_cast<double*>(A.valuePtr());
  view.z = nullptr;
  view.stype = -1;
  view.itype = CHOLMOD_INT;
  view.xtype = CHOLMOD_REAL;
  view.dtype = CHOLMOD_DOUBLE;
  view.sorted = 1;  // Eigen keeps inner indices sorted
  view.packed = A.isCompressed() ? 1 : 0;
  return view;
}

cholmod_dense dense_view(const double* data, Eigen::Index rows, Eigen::Index cols) {
  cholmod_dense view;
  std::memset(&view, 0, sizeof(view));
  view.nrow = static_cast<size_t>(rows);
  view.ncol = static_cast<size_t>(cols);
  view.nzmax = static_cast<size_t>(rows * cols);
  view.d = static_cast<size_t>(rows);
  view.x = const_cast<double*>(data);
  view.z = nullptr;
  view.xtype = CHOLMOD_REAL;
  view.dtype = CHOLMOD_DOUBLE;
  return view;
}

std::string status_text(int status) {
  switch (status) {
    case CHOLMOD_OK: return "ok";
    case CHOLMOD_NOT_INSTALLED: return "method not installed";
    case CHOLMOD_OUT_OF_MEMORY: return "out of memory";
    case CHOLMOD_TOO_LARGE: return "integer overflow (problem too large for 32-bit indices)";
    case CHOLMOD_INVALID: return "invalid input";
    case CHOLMOD_GPU_PROBLEM: return "GPU problem";
    case CHOLMOD_NOT_POSDEF: return "matrix not positive definite";
    case CHOLMOD_DSMALL: return "tiny diagonal entry";
    default: return "status " + std::to_string(status);
  }
}

}  // namespace

// Owns every CHOLMOD allocation; destroyed in reverse order of need.
struct CholmodSolver::Cholmod {
  cholmod_common common;
  cholmod_factor* factor = nullptr;
  // Solution and workspace reused by cholmod_solve2 across solves.
  cholmod_dense* x = nullptr;
  cholmod_dense* y = nullptr;
  cholmod_dense* e = nullptr;
  Eigen::Index n = -1;  // -1: not analyzed
  std::uint64_t pattern = 0;
  double factor_nonzeros = 0.0;
  bool factor_ready = false;

  Cholmod() {
    cholmod_start(&common);
    common.supernodal = CHOLMOD_SUPERNODAL;  // BLAS-3 kernels on dense supernodes
    common.final_ll = 1;
    // Failures are reported through our exceptions and return values.
    common.print = 0;
    // An indefinite Hessian is expected in Newton's method; stop at the first
    // bad pivot instead of finishing a useless factorization.
    common.quick_return_if_not_posdef = 1;
  }
  ~Cholmod() {
    free_factor();
    cholmod_finish(&common);
  }
  Cholmod(const Cholmod&) = delete;
  Cholmod& operator=(const Cholmod&) = delete;

  void free_factor() {
    if (x) cholmod_free_dense(&x, &common);
    if (y) cholmod_free_dense(&y, &common);
    if (e) cholmod_free_dense(&e, &common);
    if (factor) cholmod_free_factor(&factor, &common);
    factor_ready = false;
  }

  void use_ordering(int ordering) {
    common.nmethods = 1;
    common.method[0].ordering = ordering;
    common.postorder = 1;
  }
};

CholmodSolver::CholmodSolver(const LinearSolverOptions& options)
    : cholmod_(std::make_unique<Cholmod>()), options_(options) {
  validate_linear_solver_options(options);
  if (options.indefinite) {
    // CHOLMOD's LDL^T is simplicial only; it runs to the end on negative
    // pivots and stops at a zero one.
    cholmod_->common.supernodal = CHOLMOD_SIMPLICIAL;
    cholmod_->common.final_ll = 0;
    cholmod_->common.quick_return_if_not_posdef = 0;
  }
}

CholmodSolver::~CholmodSolver() = default;

double CholmodSolver::factor_nonzeros() const { return cholmod_->factor_nonzeros; }

void CholmodSolver::reset_analysis() {
  cholmod_->free_factor();
  cholmod_->n = -1;
  factorized_ = nullptr;
  last_.clear();
  stats_ = LinearSolveStats{};
}

void CholmodSolver::analyze(const SpMat& A) {
  const auto start = std::chrono::steady_clock::now();
  require_square(A, "CholmodSolver");
  Cholmod& c = *cholmod_;
  reset_analysis();

  if (A.rows() > 0) {
    cholmod_sparse view = lower_triangle_view(A);
    std::lock_guard<std::mutex> lock(metis_mutex());
    c.use_ordering(CHOLMOD_METIS);
    c.factor = cholmod_analyze(&view, &c.common);
    if (c.factor == nullptr || c.common.status < CHOLMOD_OK) {
      if (c.factor) cholmod_free_factor(&c.factor, &c.common);
      c.use_ordering(CHOLMOD_AMD);
      c.factor = cholmod_analyze(&view, &c.common);
    }
    if (c.factor == nullptr || c.common.status < CHOLMOD_OK) {
      const int status = c.common.status;
      c.free_factor();
      throw NumericalError("CHOLMOD symbolic analysis of a " + std::to_string(A.rows()) + "x" +
                           std::to_string(A.cols()) + " matrix failed: " + status_text(status) +
                           (status == CHOLMOD_TOO_LARGE || status == CHOLMOD_OUT_OF_MEMORY
                                ? "; use the 'pcg' linear solver for systems this large"
                                : ""));
    }
    ordering_ = c.factor->ordering == CHOLMOD_METIS ? "metis" : c.factor->ordering == CHOLMOD_AMD ? "amd" : "other";
    c.factor_nonzeros = c.common.lnz;
  } else {
    ordering_ = "none";
    c.factor_nonzeros = 0.0;
  }
  c.n = A.rows();
  c.pattern = pattern_fingerprint(A);
  stats_.analyze_seconds = seconds_since(start);
}

void CholmodSolver::analyze_with_last(const SpMat& A, const std::vector<int>& last) {
  const auto start = std::chrono::steady_clock::now();
  require_square(A, "CholmodSolver");
  const int n = static_cast<int>(A.rows());
  std::vector<char> is_last(std::size_t(n), 0);
  for (int i : last) {
    if (i < 0 || i >= n) throw InputError("CholmodSolver: unknown " + std::to_string(i) + " out of range");
    if (is_last[std::size_t(i)]) throw InputError("CholmodSolver: unknown " + std::to_string(i) + " listed twice");
    is_last[std::size_t(i)] = 1;
  }
  Cholmod& c = *cholmod_;
  reset_analysis();

  // The others' ordering, on their own submatrix.
  std::vector<int> others;
  others.reserve(std::size_t(n) - last.size());
  for (int i = 0; i < n; ++i)
    if (!is_last[std::size_t(i)]) others.push_back(i);
  std::vector<int> perm;
  perm.reserve(std::size_t(n));
  std::lock_guard<std::mutex> lock(metis_mutex());
  if (!others.empty()) {
    Eigen::PermutationMatrix<Eigen::Dynamic, Eigen::Dynamic, int> to_front(n);
    {
      std::vector<int> order = others;
      order.insert(order.end(), last.begin(), last.end());
      for (int k = 0; k < n; ++k) to_front.indices()[order[std::size_t(k)]] = k;
    }
    const int m = static_cast<int>(others.size());
    SpMat permuted;
    permuted = A.selfadjointView<Eigen::Lower>().twistedBy(to_front);
    const SpMat interior = permuted.topLeftCorner(m, m);
    cholmod_sparse view = lower_triangle_view(interior);
    std::vector<int> interior_perm(static_cast<std::size_t>(m));
    int ok = cholmod_metis(&view, nullptr, 0, 1, interior_perm.data(), &c.common);
    if (!ok) ok = cholmod_amd(&view, nullptr, 0, interior_perm.data(), &c.common);
    if (!ok)
      throw NumericalError("CHOLMOD ordering of a " + std::to_string(m) +
                           "-unknown block failed: " + status_text(c.common.status));
    for (int k : interior_perm) perm.push_back(others[std::size_t(k)]);
  }
  perm.insert(perm.end(), last.begin(), last.end());

  if (n > 0) {
    cholmod_sparse view = lower_triangle_view(A);
    c.common.nmethods = 1;
    c.common.method[0].ordering = CHOLMOD_GIVEN;
    c.common.postorder = 0;  // a postorder could move the last unknowns
    c.factor = cholmod_analyze_p(&view, perm.data(), nullptr, 0, &c.common);
    if (c.factor == nullptr || c.common.status < CHOLMOD_OK) {
      const int status = c.common.status;
      c.free_factor();
      throw NumericalError("CHOLMOD symbolic analysis with given ordering failed: " + status_text(status));
    }
    const int* P = static_cast<const int*>(c.factor->Perm);
    for (std::size_t k = 0; k < last.size(); ++k)
      if (P[std::size_t(n) - last.size() + k] != last[k])
        throw NumericalError("CHOLMOD did not keep the given unknowns last");
    c.factor_nonzeros = c.common.lnz;
  }
  ordering_ = "given unknowns last";
  last_ = last;
  c.n = A.rows();
  c.pattern = pattern_fingerprint(A);
  stats_.analyze_seconds = seconds_since(start);
}

MatX CholmodSolver::trailing_factor() const {
  const Cholmod& c = *cholmod_;
  if (!c.factor_ready) throw NumericalError("CHOLMOD trailing factor without a valid factorization");
  const int k = static_cast<int>(last_.size());
  MatX T = MatX::Zero(k, k);
  if (k == 0) return T;
  const cholmod_factor* L = c.factor;
  const int n = static_cast<int>(L->n), first = n - k;
  const double* x = static_cast<const double*>(L->x);
  if (L->is_super) {
    const int* super = static_cast<const int*>(L->super);
    const int* pi = static_cast<const int*>(L->pi);
    const int* px = static_cast<const int*>(L->px);
    const int* rows = static_cast<const int*>(L->s);
    for (std::size_t s = 0; s < L->nsuper; ++s) {
      const int k1 = super[s], k2 = super[s + 1];
      if (k2 <= first) continue;
      const int nrows = pi[s + 1] - pi[s];
      for (int j = std::max(k1, first); j < k2; ++j)
        for (int r = j - k1; r < nrows; ++r) {
          const int row = rows[pi[s] + r];
          if (row >= first) T(row - first, j - first) = x[px[s] + std::ptrdiff_t(j - k1) * nrows + r];
        }
    }
  } else {
    if (!L->is_ll) throw NumericalError("CHOLMOD trailing factor: expected an LL^T factor");
    const int* p = static_cast<const int*>(L->p);
    const int* i = static_cast<const int*>(L->i);
    const int* nz = static_cast<const int*>(L->nz);
    for (int j = first; j < n; ++j)
      for (int q = p[j]; q < p[j] + nz[j]; ++q)
        if (i[q] >= first) T(i[q] - first, j - first) = x[q];
  }
  return T;
}

bool CholmodSolver::factorize(const SpMat& A, double shift) {
  const auto start = std::chrono::steady_clock::now();
  Cholmod& c = *cholmod_;
  require_analyzed_pattern(A, c.n, c.pattern, "CholmodSolver");
  c.factor_ready = false;
  factorized_ = nullptr;
  stats_.positive_definite = false;
  negative_pivots_ = 0;

  if (c.n > 0) {
    cholmod_sparse view = lower_triangle_view(A);
    double beta[2] = {shift, 0.0};  // CHOLMOD factors A + beta[0] * I
    const CholmodThreadScope one_thread;
    const int ok = cholmod_factorize_p(&view, beta, nullptr, 0, c.factor, &c.common);
    const int status = c.common.status;
    if (status < CHOLMOD_OK || (!ok && status != CHOLMOD_NOT_POSDEF)) {
      throw NumericalError("CHOLMOD numeric factorization failed: " + status_text(status));
    }
    if (c.factor->minor < c.factor->n || (status == CHOLMOD_NOT_POSDEF && !options_.indefinite)) {
      stats_.factorize_seconds = seconds_since(start);
      return false;
    }
    if (!c.factor->is_ll) {  // D sits on the diagonal of the simplicial factor
      const int* p = static_cast<const int*>(c.factor->p);
      const double* x = static_cast<const double*>(c.factor->x);
      for (std::size_t j = 0; j < c.factor->n; ++j) negative_pivots_ += x[p[j]] < 0;
    }
  }
  c.factor_ready = true;
  factorized_ = &A;
  shift_ = shift;
  stats_.positive_definite = negative_pivots_ == 0;
  stats_.factorize_seconds = seconds_since(start);
  return true;
}

VecX CholmodSolver::solve(const VecX& b) {
  const auto start = std::chrono::steady_clock::now();
  Cholmod& c = *cholmod_;
  if (!c.factor_ready) {
    throw NumericalError(
        "CHOLMOD solve without a valid factorization (the last factorize() found the matrix "
        "not positive definite, or none was done); factorize with a larger shift first");
  }
  require_rhs_size(b, c.n, "CholmodSolver");
  VecX x = VecX::Zero(c.n);
  if (c.n > 0) {
    cholmod_dense rhs = dense_view(b.data(), b.size(), 1);
    const CholmodThreadScope one_thread;
    if (!cholmod_solve2(CHOLMOD_A, c.factor, &rhs, nullptr, &c.x, nullptr, &c.y, &c.e, &c.common)) {
      throw NumericalError("CHOLMOD triangular solves failed: " + status_text(c.common.status));
    }
    x = Eigen::Map<const VecX>(static_cast<const double*>(c.x->x), c.n);
  }
  stats_.iterations = 0;
  stats_.relative_residual = relative_residual(*factorized_, x, b, shift_, options_.threads);
  stats_.solve_seconds = seconds_since(start);
  if (!std::isfinite(stats_.relative_residual)) {
    throw NumericalError("CHOLMOD solve produced a non-finite solution (relative residual " +
                         std::to_string(stats_.relative_residual) + ")");
  }
  return x;
}

MatX CholmodSolver::solve_columns(const MatX& B) {
  const auto start = std::chrono::steady_clock::now();
  Cholmod& c = *cholmod_;
  if (!c.factor_ready)
    throw NumericalError("CHOLMOD solve without a valid factorization; factorize with a larger shift first");
  if (B.rows() != c.n)
    throw std::invalid_argument("CholmodSolver: right-hand sides have " + std::to_string(B.rows()) +
                                " rows, expected " + std::to_string(c.n));
  MatX X = MatX::Zero(c.n, B.cols());
  if (c.n > 0 && B.cols() > 0) {
    cholmod_dense rhs = dense_view(B.data(), B.rows(), B.cols());
    // Its own workspace: c.x and c.y are sized for one column.
    cholmod_dense *x = nullptr, *y = nullptr, *e = nullptr;
    const CholmodThreadScope one_thread;
    const int ok = cholmod_solve2(CHOLMOD_A, c.factor, &rhs, nullptr, &x, nullptr, &y, &e, &c.common);
    if (ok) X = Eigen::Map<const MatX>(static_cast<const double*>(x->x), c.n, B.cols());
    cholmod_free_dense(&x, &c.common);
    cholmod_free_dense(&y, &c.common);
    cholmod_free_dense(&e, &c.common);
    if (!ok) throw NumericalError("CHOLMOD triangular solves failed: " + status_text(c.common.status));
  }
  stats_.iterations = 0;
  stats_.relative_residual = 0;
  // Checked on the sum of the columns: one mat-vec instead of one per
  // column still catches a failed or non-finite solve.
  if (B.cols() > 0 && c.n > 0)
    stats_.relative_residual = relative_residual(*factorized_, X.rowwise().sum(), B.rowwise().sum(), shift_, 1);
  stats_.solve_seconds = seconds_since(start);
  if (!std::isfinite(stats_.relative_residual))
    throw NumericalError("CHOLMOD solve produced a non-finite solution (relative residual " +
                         std::to_string(stats_.relative_residual) + ")");
  return X;
}

}  // namespace msfab
