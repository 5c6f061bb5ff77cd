#include "solve/block_matrix.hpp"

#include <algorithm>
#include <stdexcept>
#include <string>

#include "solve/sparse_ops.hpp"

namespace msfab {

namespace {

// Entries of column j occupy [outer[j], column_end(A, j)); uncompressed
// matrices leave gaps after each column.
inline Eigen::Index column_end(const SpMat& A, Eigen::Index j) {
  return A.isCompressed() ? A.outerIndexPtr()[j + 1] : A.outerIndexPtr()[j] + A.innerNonZeroPtr()[j];
}

}  // namespace

BlockMatrix block_pattern(const SpMat& A) {
  if (A.rows() != A.cols() || A.rows() % 3 != 0) {
    throw std::invalid_argument("block_pattern: matrix is " + std::to_string(A.rows()) + "x" +
                                std::to_string(A.cols()) + ", not square with 3 unknowns per node");
  }
  BlockMatrix M;
  M.rows = static_cast<int>(A.rows() / 3);
  M.row_start.assign(static_cast<std::size_t>(M.rows) + 1, 0);
  M.diagonal.assign(static_cast<std::size_t>(M.rows), -1);
  std::vector<int> seen(static_cast<std::size_t>(M.rows), -1);
  std::vector<int> row;
  const int* inner = A.innerIndexPtr();
  for (int i = 0; i < M.rows; ++i) {
    row.clear();
    row.push_back(i);
    seen[i] = i;
    for (int a = 0; a < 3; ++a) {
      const Eigen::Index col = 3 * Eigen::Index(i) + a;
      for (Eigen::Index k = A.outerIndexPtr()[col]; k < column_end(A, col); ++k) {
        const int j = inner[k] / 3;
        if (seen[j] != i) {
          seen[j] = i;
          row.push_back(j);
        }
      }
    }
    std::sort(row.begin(), row.end());
    M.diagonal[i] = M.row_start[i] + static_cast<int>(std::lower_bound(row.begin(), row.end(), i) - row.begin());
    M.column.insert(M.column.end(), row.begin(), row.end());
    M.row_start[i + 1] = static_cast<int>(M.column.size());
  }
  M.values.assign(9 * M.column.size(), 0.0);
  return M;
}

void copy_block_values(const SpMat& A, double shift, BlockMatrix& M, int threads) {
  const int* inner = A.innerIndexPtr();
  const double* source = A.valuePtr();
  parallel_row_ranges(M.rows, resolve_thread_count(threads), [&](int begin, int end) {
    for (int i = begin; i < end; ++i) {
      const int first = M.row_start[i];
      const int last = M.row_start[i + 1];
      double* row_values = M.values.data() + 9 * std::size_t(first);
      std::fill(row_values, row_values + 9 * std::size_t(last - first), 0.0);
      for (int a = 0; a < 3; ++a) {
        const Eigen::Index col = 3 * Eigen::Index(i) + a;
        int slot = first;
        for (Eigen::Index k = A.outerIndexPtr()[col]; k < column_end(A, col); ++k) {
          const int j = inner[k] / 3;
          while (M.column[slot] < j) ++slot;
          // Entry (3j + b, 3i + a) of A is entry (a, b) of block (i, j) by symmetry.
          M.values[9 * std::size_t(slot) + 3 * std::size_t(a) + std::size_t(inner[k] % 3)] = source[k];
        }
      }
      double* diagonal = M.values.data() + 9 * std::size_t(M.diagonal[i]);
      diagonal[0] += shift;
      diagonal[4] += shift;
      diagonal[8] += shift;
    }
  });
}

void block_multiply(const BlockMatrix& M, const VecX& x, VecX& y, int threads) {
  y.resize(M.unknowns());
  parallel_row_ranges(M.rows, resolve_thread_count(threads), [&](int begin, int end) {
    for (int i = begin; i < end; ++i) block_row_product(M, i, x.data(), y.data() + 3 * i);
  });
}

std::size_t upper_block_count(const BlockMatrix& M) {
  std::size_t count = 0;
  for (int i = 0; i < M.rows; ++i) count += std::size_t(M.row_start[std::size_t(i) + 1] - M.diagonal[std::size_t(i)]);
  return count;
}

std::vector<int> upper_block_numbering(const BlockMatrix& M, int threads) {
  std::vector<int> first_upper(std::size_t(M.rows) + 1, 0);
  for (int i = 0; i < M.rows; ++i)
    first_upper[std::size_t(i) + 1] = first_upper[std::size_t(i)] + (M.row_start[i + 1] - M.diagonal[std::size_t(i)]);
  std::vector<int> block_of_slot(std::size_t(M.num_blocks()));
  const long long unmatched = chunked_reduce(M.rows, threads, [&](Eigen::Index begin, Eigen::Index end) {
    long long missing = 0;
    for (Eigen::Index i = begin; i < end; ++i) {
      for (int slot = M.row_start[i]; slot < M.row_start[i + 1]; ++slot) {
        const int j = M.column[std::size_t(slot)];
        if (j >= i) {
          block_of_slot[std::size_t(slot)] = first_upper[std::size_t(i)] + (slot - M.diagonal[std::size_t(i)]);
          continue;
        }
        // Block (j, i) sits in row j, above its diagonal.
        const auto begin_j = M.column.begin() + M.diagonal[std::size_t(j)];
        const auto end_j = M.column.begin() + M.row_start[std::size_t(j) + 1];
        const auto it = std::lower_bound(begin_j, end_j, static_cast<int>(i));
        if (it == end_j || *it != i) {
          ++missing;
          continue;
        }
        block_of_slot[std::size_t(slot)] =
            first_upper[std::size_t(j)] + static_cast<int>(it - M.column.begin()) - M.diagonal[std::size_t(j)];
      }
    }
    return missing;
  });
  if (unmatched != 0) throw std::logic_error("upper_block_numbering: the block pattern is not symmetric");
  return block_of_slot;
}

std::vector<char> decoupled_unknowns(const BlockMatrix& M, int threads, const std::vector<int>* upper) {
  std::vector<char> decoupled(static_cast<std::size_t>(M.unknowns()), 0);
  parallel_row_ranges(M.rows, resolve_thread_count(threads), [&](int begin, int end) {
    double block[9];
    for (int i = begin; i < end; ++i) {
      for (int a = 0; a < 3; ++a) {
        bool coupled = false;
        for (int slot = M.row_start[i]; slot < M.row_start[i + 1] && !coupled; ++slot) {
          read_block(M, upper, i, slot, block);
          const double* m = block + 3 * a;
          const bool diagonal = slot == M.diagonal[i];
          for (int b = 0; b < 3; ++b) {
            if (m[b] != 0.0 && !(diagonal && b == a)) coupled = true;
          }
        }
        decoupled[3 * std::size_t(i) + std::size_t(a)] = coupled ? 0 : 1;
      }
    }
  });
  return decoupled;
}

SpMat sparse_pattern(const BlockMatrix& M) {
  const Eigen::Index n = M.unknowns();
  SpMat S(n, n);
  S.resizeNonZeros(9 * Eigen::Index(M.num_blocks()));
  int* outer = S.outerIndexPtr();
  int* inner = S.innerIndexPtr();
  int position = 0;
  for (int j = 0; j < M.rows; ++j) {
    for (int b = 0; b < 3; ++b) {
      outer[3 * j + b] = position;
      // The pattern is symmetric: block column j holds the blocks of block row j.
      for (int slot = M.row_start[j]; slot < M.row_start[j + 1]; ++slot) {
        for (int a = 0; a < 3; ++a) inner[position++] = 3 * M.column[slot] + a;
      }
    }
  }
  outer[n] = position;
  std::fill(S.valuePtr(), S.valuePtr() + position, 0.0);
  return S;
}

void copy_to_sparse(const BlockMatrix& M, SpMat& S) {
  double* target = S.valuePtr();
  const int* outer = S.outerIndexPtr();
  for (int j = 0; j < M.rows; ++j) {
    const int first = M.row_start[j];
    const int count = M.row_start[j + 1] - first;
    for (int b = 0; b < 3; ++b) {
      double* column = target + outer[3 * j + b];
      // Entry (3i + a, 3j + b) = block (j, i) entry (b, a) by symmetry.
      for (int s = 0; s < count; ++s) {
        const double* m = M.values.data() + 9 * std::size_t(first + s) + 3 * b;
        for (int a = 0; a < 3; ++a) column[3 * s + a] = m[a];
      }
    }
  }
}

}  // namespace msfab
