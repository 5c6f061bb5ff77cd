#include "solve/component_multigrid.hpp"

#include <algorithm>
#include <numeric>
#include <stdexcept>

#include "solve/hex_lattice.hpp"
#include "solve/multigrid_cycle.hpp"
#include "solve/sparse_ops.hpp"

namespace msfab {
namespace {

using namespace hex_lattice;

using namespace multigrid_cycle;

// Rows [begin, end) of a block matrix built range by range: per row its
// sorted columns and 9 values per block.
struct RowRange {
  std::vector<int> count, column;
  std::vector<double> values;
};

// Joins row ranges (in order) into M and sets its diagonal slots. Every row
// must hold its diagonal block.
void join_ranges(int rows, std::vector<RowRange>& ranges, BlockMatrix& M) {
  M.rows = rows;
  M.row_start.assign(std::size_t(rows) + 1, 0);
  std::size_t blocks = 0;
  bool with_values = false;  // a pattern alone leaves M.values empty
  for (const RowRange& r : ranges) {
    blocks += r.column.size();
    with_values = with_values || !r.values.empty();
  }
  M.column.clear();
  M.column.reserve(blocks);
  M.values.clear();
  if (with_values) M.values.reserve(9 * blocks);
  int row = 0;
  for (RowRange& r : ranges) {
    for (int c : r.count) {
      M.row_start[std::size_t(row) + 1] = M.row_start[std::size_t(row)] + c;
      ++row;
    }
    M.column.insert(M.column.end(), r.column.begin(), r.column.end());
    M.values.insert(M.values.end(), r.values.begin(), r.values.end());
    r = RowRange{};
  }
  M.diagonal.assign(std::size_t(rows), -1);
  for (int i = 0; i < rows; ++i) {
    const auto begin = M.column.begin() + M.row_start[std::size_t(i)];
    const auto end = M.column.begin() + M.row_start[std::size_t(i) + 1];
    const auto it = std::lower_bound(begin, end, i);
    if (it == end || *it != i) throw std::logic_error("component multigrid: a row without its diagonal block");
    M.diagonal[std::size_t(i)] = static_cast<int>(it - M.column.begin());
  }
}

// Splits [0, n) into contiguous ranges, one per thread of the team, runs
// body(range index, begin, end) on each; the ranges are joined in order.
template <class Body>
std::vector<RowRange> by_ranges(int n, int threads, Body&& body) {
  const int team = std::max(1, std::min(resolve_thread_count(threads), n / 256 + 1));
  std::vector<RowRange> ranges(static_cast<std::size_t>(team));
#pragma omp parallel for schedule(static, 1) num_threads(team)
  for (int t = 0; t < team; ++t) {
    const int begin = static_cast<int>(std::int64_t(n) * t / team),
              end = static_cast<int>(std::int64_t(n) * (t + 1) / team);
    body(ranges[std::size_t(t)], begin, end);
  }
  return ranges;
}

// Sorts a row's columns and carries their 9-value blocks along.
void sort_row(std::vector<int>& column, std::vector<double>& values, std::vector<int>& order, RowRange& out) {
  order.resize(column.size());
  std::iota(order.begin(), order.end(), 0);
  std::sort(order.begin(), order.end(), [&](int a, int b) { return column[std::size_t(a)] < column[std::size_t(b)]; });
  out.count.push_back(static_cast<int>(column.size()));
  for (int o : order) {
    out.column.push_back(column[std::size_t(o)]);
    out.values.insert(out.values.end(), values.begin() + 9 * o, values.begin() + 9 * o + 9);
  }
}

}  // namespace

BlockMatrix level1_element_pattern(const MaterialComponents& components, int threads) {
  const ComponentLevel& level1 = components.levels().at(1);
  const int nx = components.nx(), ny = components.ny(), nz = components.nz();
  const int NX = nx / 2, NY = ny / 2, NZ = nz / 2;
  const int rows = level1.copies();
  std::vector<RowRange> ranges = by_ranges(rows, threads, [&](RowRange& out, int begin, int end) {
    std::vector<int> columns;
    // Rows of one lattice point are contiguous: walk points, not copies.
    std::int64_t point = std::upper_bound(level1.first.begin(), level1.first.end(), begin) - level1.first.begin() - 1;
    for (int row = begin; row < end; ++row) {
      while (level1.first[std::size_t(point) + 1] <= row) ++point;
      const int I = static_cast<int>(point % level1.points[0]),
                J = static_cast<int>((point / level1.points[0]) % level1.points[1]),
                K = static_cast<int>(point / (std::int64_t(level1.points[0]) * level1.points[1]));
      columns.clear();
      // The level-1 elements around the point, and the point's corner in each.
      for (int a = 0; a < 8; ++a) {
        const int EI = I - corner_x(a), EJ = J - corner_y(a), EK = K - corner_z(a);
        if (EI < 0 || EJ < 0 || EK < 0 || EI >= NX || EJ >= NY || EK >= NZ) continue;
        for (int pos = 0; pos < 8; ++pos) {
          const int i = 2 * EI + (pos & 1), j = 2 * EJ + (pos >> 1 & 1), k = 2 * EK + (pos >> 2 & 1);
          if (components.element_copy(i, j, k, a) != row) continue;
          for (int b = 0; b < 8; ++b) columns.push_back(components.element_copy(i, j, k, b));
        }
      }
      columns.push_back(row);  // a copy no free unknown reaches still has its diagonal
      std::sort(columns.begin(), columns.end());
      columns.erase(std::unique(columns.begin(), columns.end()), columns.end());
      // The pattern only: level1() allocates the values once.
      out.count.push_back(static_cast<int>(columns.size()));
      out.column.insert(out.column.end(), columns.begin(), columns.end());
    }
  });
  BlockMatrix M;
  join_ranges(rows, ranges, M);
  return M;
}

void component_galerkin_product(const BlockMatrix& fine, const std::vector<char>& fine_decoupled,
                                const ComponentTransfer& transfer, BlockMatrix& coarse, int threads,
                                const std::vector<int>* fine_upper) {
  const int rows = transfer.coarse_copies();
  if (transfer.fine_rows() != fine.rows)
    throw std::invalid_argument("component_galerkin_product: transfer and matrix sizes differ");
  std::vector<RowRange> ranges = by_ranges(rows, threads, [&](RowRange& out, int begin, int end) {
    std::vector<int> marker(std::size_t(rows), -1), columns, order;
    std::vector<double> values;
    for (int C = begin; C < end; ++C) {
      columns.clear();
      values.clear();
      for (int t = transfer.child_start[std::size_t(C)]; t < transfer.child_start[std::size_t(C) + 1]; ++t) {
        const int i = transfer.child[std::size_t(t)];
        const double wi = transfer.child_weight[std::size_t(t)];
        const char* di = fine_decoupled.data() + 3 * std::size_t(i);
        for (int slot = fine.row_start[std::size_t(i)]; slot < fine.row_start[std::size_t(i) + 1]; ++slot) {
          const int j = fine.column[std::size_t(slot)];
          const char* dj = fine_decoupled.data() + 3 * std::size_t(j);
          double block[9];
          read_block(fine, fine_upper, i, slot, block);
          for (int r = 0; r < 3; ++r)
            for (int q = 0; q < 3; ++q)
              if (di[r] || dj[q]) block[3 * r + q] = 0.0;
          for (int u = transfer.parent_start[std::size_t(j)]; u < transfer.parent_start[std::size_t(j) + 1]; ++u) {
            const int D = transfer.parent[std::size_t(u)];
            const double w = wi * transfer.parent_weight[std::size_t(u)];
            int& index = marker[std::size_t(D)];
            if (index < 0) {
              index = static_cast<int>(columns.size());
              columns.push_back(D);
              values.resize(values.size() + 9, 0.0);
            }
            double* target = values.data() + 9 * std::size_t(index);
            for (int e = 0; e < 9; ++e) target[e] += w * block[e];
          }
        }
      }
      if (marker[std::size_t(C)] < 0) {  // keep the diagonal block
        marker[std::size_t(C)] = static_cast<int>(columns.size());
        columns.push_back(C);
        values.resize(values.size() + 9, 0.0);
      }
      for (int D : columns) marker[std::size_t(D)] = -1;
      sort_row(columns, values, order, out);
    }
  });
  join_ranges(rows, ranges, coarse);
  fill_empty_diagonal(coarse);
}

void fill_empty_diagonal(BlockMatrix& M, const std::vector<int>* upper) {
  const auto diagonal = [&](int i) { return M.values.data() + stored_block(upper, M.diagonal[std::size_t(i)]); };
  double sum = 0.0;
  std::int64_t count = 0;
  for (int i = 0; i < M.rows; ++i)
    for (int d = 0; d < 3; ++d)
      if (const double v = diagonal(i)[4 * d]; v > 0) sum += v, ++count;
  const double scale = count > 0 ? sum / double(count) : 1.0;
  for (int i = 0; i < M.rows; ++i)
    for (int d = 0; d < 3; ++d) {
      double& v = diagonal(i)[4 * d];
      if (v == 0.0) v = scale;
    }
}

struct ComponentMultigrid::Level {
  BlockMatrix matrix;
  std::vector<int> upper;  // level 1 of a large grid: matrix.values holds its upper blocks (upper_block_numbering)
  std::vector<char> decoupled;
  ChebyshevSmoother smoother;
  VecX rhs, solution, residual;
};

ComponentMultigrid::ComponentMultigrid(std::shared_ptr<const MaterialComponents> components, int smoother_degree,
                                       int threads, int upper_level_blocks)
    : components_(std::move(components)),
      smoother_degree_(smoother_degree),
      threads_(threads),
      upper_level_blocks_(upper_level_blocks) {
  const int count = static_cast<int>(components_->levels().size()) - 1;
  if (count < 1) throw std::invalid_argument("ComponentMultigrid: the components have no level 1");
  for (int l = 0; l < count; ++l) levels_.push_back(std::make_unique<Level>());
  levels_.front()->matrix = level1_element_pattern(*components_, threads_);
}

ComponentMultigrid::~ComponentMultigrid() = default;

BlockMatrix& ComponentMultigrid::level1() {
  Level& first = *levels_.front();
  BlockMatrix& M = first.matrix;
  // Level 1 of a large grid is the biggest matrix of set-up: assembled by
  // its upper blocks, it never exists in full. (Not where it is also the
  // coarsest level, which is factored from full storage; that level is
  // small.)
  const bool upper = M.num_blocks() > upper_level_blocks_ && levels_.size() > 1;
  if (upper && first.upper.empty()) first.upper = upper_block_numbering(M, threads_);
  if (M.values.empty()) M.values.assign(9 * (upper ? upper_block_count(M) : std::size_t(M.num_blocks())), 0.0);
  return M;
}

const std::vector<int>* ComponentMultigrid::level1_upper() const {
  const Level& first = *levels_.front();
  return first.upper.empty() ? nullptr : &first.upper;
}

const BlockMatrix& ComponentMultigrid::level_matrix(int level) const { return levels_.at(std::size_t(level))->matrix; }

bool ComponentMultigrid::factorize() {
  const auto upper_of = [](const Level& level) { return level.upper.empty() ? nullptr : &level.upper; };
  fill_empty_diagonal(levels_.front()->matrix, upper_of(*levels_.front()));
  for (std::size_t l = 0; l < levels_.size(); ++l) {
    Level& level = *levels_[l];
    const std::vector<int>* upper = upper_of(level);
    level.decoupled = decoupled_unknowns(level.matrix, threads_, upper);
    if (l + 1 == levels_.size()) break;
    component_galerkin_product(level.matrix, level.decoupled, components_->transfers()[l + 1], levels_[l + 1]->matrix,
                               threads_, upper);
    const int degree = (l == 0 ? 1 : kCoarseDegreeFactor) * smoother_degree_;
    // A level too large to keep in double is held by the smoother's upper
    // blocks in single precision; set-up refills the double values.
    const bool large = level.matrix.num_blocks() > upper_level_blocks_;
    // An upper-held level's numbering is released once its smoother is set up.
    const bool set = upper ? level.smoother.setup(level.matrix, degree, threads_, std::move(level.upper))
                           : level.smoother.setup(level.matrix, degree, threads_,
                                                  large ? SmootherValues::single_upper : SmootherValues::single);
    if (!set) return false;
    if (large) std::vector<double>().swap(level.matrix.values);
  }
  const BlockMatrix& last = levels_.back()->matrix;
  if (!coarse_analyzed_ || coarsest_.rows() != last.unknowns() ||
      coarsest_.nonZeros() != 9 * Eigen::Index(last.num_blocks())) {
    coarsest_ = sparse_pattern(last);
    copy_to_sparse(last, coarsest_);
    coarse_solver_.analyzePattern(coarsest_);
    coarse_analyzed_ = true;
  } else {
    copy_to_sparse(last, coarsest_);
  }
  coarse_solver_.factorize(coarsest_);
  return coarse_solver_.info() == Eigen::Success;
}

void ComponentMultigrid::cycle(std::size_t index, const VecX& rhs, VecX& solution) {
  // The component levels: their smoothers, the component transfers over the
  // unknowns that are not decoupled, the sparse Cholesky on the coarsest.
  struct Levels : multigrid_cycle::SmoothedLevels<decltype(levels_)> {
    ComponentMultigrid& s;
    auto free_in(std::size_t i) const {
      const Level& level = *s.levels_[i];
      return [&level](int row, int d) { return !level.decoupled[3 * std::size_t(row) + std::size_t(d)]; };
    }
    bool is_coarsest(std::size_t i) const { return i + 1 == s.levels_.size(); }
    void solve_coarsest(std::size_t, const VecX& b, VecX& x) { x = s.coarse_solver_.solve(b); }
    void restrict_to_coarse(std::size_t i, const VecX& r, VecX& coarse_rhs) {
      component_restrict(s.components_->transfers()[i + 1], r, free_in(i), coarse_rhs, s.threads_);
    }
    void add_prolongation(std::size_t i, const VecX& coarse_x, VecX& x) {
      component_add_prolongation(s.components_->transfers()[i + 1], coarse_x, free_in(i), x, s.threads_);
    }
  } levels{{levels_}, *this};
  multigrid_cycle::cycle(levels, index, rhs, solution);
}

}  // namespace msfab
