#pragma once
// Argument checks shared by the LinearSolver implementations, so that every
// solver reports a misuse of analyze() / factorize() / solve() the same way.
#include <cstdint>
#include <string>

#include "core/types.hpp"

namespace msfab {

// Throws std::invalid_argument "<solver>::analyze: matrix is RxC, not square".
void require_square(const SpMat& A, const std::string& solver);

// For factorize(): throws std::logic_error if analyze() has not run
// (analyzed_size < 0), std::invalid_argument if A's size or sparsity pattern
// (pattern_fingerprint) differs from the one given to analyze().
void require_analyzed_pattern(const SpMat& A, Eigen::Index analyzed_size, std::uint64_t analyzed_pattern,
                              const std::string& solver);

// For solve(): throws std::invalid_argument unless b has n entries.
void require_rhs_size(const VecX& b, Eigen::Index n, const std::string& solver);

}  // namespace msfab
