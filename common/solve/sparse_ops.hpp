#pragma once
// OpenMP-parallel kernels on symmetric sparse matrices and vectors whose
// results do not depend on the number of threads.
//
// Determinism rule: every reduction is split into fixed-size chunks of
// kReductionChunk entries (independent of the thread count); each chunk's
// partial sum is computed by one thread in index order and the partial sums
// are then added serially in chunk order.
#include <algorithm>
#include <cstdint>
#include <type_traits>
#include <vector>

#include "core/types.hpp"

namespace msfab {

inline constexpr Eigen::Index kReductionChunk = 3072;

// threads > 0: that many OpenMP threads; otherwise the OpenMP default
// (omp_get_max_threads(), i.e. OMP_NUM_THREADS or omp_set_num_threads()).
int resolve_thread_count(int threads);

// Sum of chunk_sum(begin, end) over consecutive chunks [begin, end) of
// [0, n), added in chunk order. chunk_sum returns a double or a fixed-size
// Eigen vector (several sums in one pass) and must return zero for an empty
// range; it may also write to disjoint parts of vectors inside its own range.
template <class ChunkSum>
auto chunked_reduce(Eigen::Index n, int threads, ChunkSum&& chunk_sum) {
  using Value = std::decay_t<decltype(chunk_sum(Eigen::Index{0}, Eigen::Index{0}))>;
  const Eigen::Index chunks = (n + kReductionChunk - 1) / kReductionChunk;
  std::vector<Value> partial(static_cast<std::size_t>(chunks));
  const int team = resolve_thread_count(threads);
#pragma omp parallel for schedule(static) num_threads(team) if (chunks > 1)
  for (Eigen::Index c = 0; c < chunks; ++c) {
    const Eigen::Index begin = c * kReductionChunk;
    const Eigen::Index end = std::min(n, begin + kReductionChunk);
    partial[static_cast<std::size_t>(c)] = chunk_sum(begin, end);
  }
  Value sum = chunk_sum(Eigen::Index{0}, Eigen::Index{0});
  for (const Value& value : partial) sum += value;
  return sum;
}

// body(begin, end) over the same chunks as chunked_reduce, for element-wise
// updates that belong to the same pass.
template <class ChunkBody>
void chunked_for(Eigen::Index n, int threads, ChunkBody&& body) {
  const Eigen::Index chunks = (n + kReductionChunk - 1) / kReductionChunk;
  const int team = resolve_thread_count(threads);
#pragma omp parallel for schedule(static) num_threads(team) if (chunks > 1)
  for (Eigen::Index c = 0; c < chunks; ++c) {
    const Eigen::Index begin = c * kReductionChunk;
    body(begin, std::min(n, begin + kReductionChunk));
  }
}

// a . b, deterministic for any thread count.
double parallel_dot(const VecX& a, const VecX& b, int threads = 0);

// y = (A + shift*I) x for a symmetric A stored with both triangles. Column j
// of A equals row j, so y_j is a gather over column j: no write conflicts, and
// each y_j is summed in the same order whatever the thread count.
void symmetric_spmv(const SpMat& A, const VecX& x, VecX& y, double shift = 0.0, int threads = 0);

// Same product, also returning x . y (the curvature x^T (A + shift I) x that
// conjugate gradients needs) without a second pass over the vectors.
double symmetric_spmv_dot(const SpMat& A, const VecX& x, VecX& y, double shift = 0.0, int threads = 0);

// ||b - (A + shift I) x|| / ||b|| (0 when b = 0 and x = 0).
double relative_residual(const SpMat& A, const VecX& x, const VecX& b, double shift = 0.0, int threads = 0);

// Position of entry (row, col) in A.valuePtr(), or -1 if it is not stored.
// Inner indices are sorted in every Eigen sparse matrix, so this is a
// binary search.
std::int64_t find_entry(const SpMat& A, int row, int col);

// Fingerprint of the sparsity pattern (size, column pointers, row indices);
// solvers compare it to catch values given on a pattern they did not analyze.
std::uint64_t pattern_fingerprint(const SpMat& A);

}  // namespace msfab
