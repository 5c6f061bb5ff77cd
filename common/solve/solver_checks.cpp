#include "solve/solver_checks.hpp"

#include <stdexcept>

#include "solve/sparse_ops.hpp"

namespace msfab {

void require_square(const SpMat& A, const std::string& solver) {
  if (A.rows() != A.cols()) {
    throw std::invalid_argument(solver + "::analyze: matrix is " + std::to_string(A.rows()) + "x" +
                                std::to_string(A.cols()) + ", not square");
  }
}

void require_analyzed_pattern(const SpMat& A, Eigen::Index analyzed_size, std::uint64_t analyzed_pattern,
                              const std::string& solver) {
  if (analyzed_size < 0) throw std::logic_error(solver + "::factorize called before analyze");
  if (A.rows() != analyzed_size || A.cols() != analyzed_size || pattern_fingerprint(A) != analyzed_pattern) {
    throw std::invalid_argument(solver + "::factorize: the matrix pattern differs from the one given to analyze()");
  }
}

void require_rhs_size(const VecX& b, Eigen::Index n, const std::string& solver) {
  if (b.size() != n) {
    throw std::invalid_argument(solver + "::solve: right-hand side has " + std::to_string(b.size()) +
                                " entries, matrix has " + std::to_string(n) + " rows");
  }
}

}  // namespace msfab
