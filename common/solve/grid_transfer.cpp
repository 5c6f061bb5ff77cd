#include "solve/grid_transfer.hpp"

#include <algorithm>
#include <array>
#include <cstdlib>
#include <string>

#include "core/errors.hpp"
#include "solve/sparse_ops.hpp"

namespace msfab {

namespace {

// A coarse diagonal 3x3 block after the Galerkin sum: made exactly
// symmetric (the sums round differently above and below the diagonal),
// with a decoupled unit row for each unknown nothing interpolates to, which
// keeps the coarse matrix definite.
void finish_diagonal_block(double* block, const bool reached[3]) {
  for (int a = 0; a < 3; ++a) {
    for (int b = a + 1; b < 3; ++b) {
      const double mean = 0.5 * (block[3 * a + b] + block[3 * b + a]);
      block[3 * a + b] = mean;
      block[3 * b + a] = mean;
    }
    if (!reached[a]) block[4 * a] = 1.0;
  }
}

// Lattice offsets (each component in {-1, 0, 1}) are coded as
// (dx+1) + 3 (dy+1) + 9 (dz+1); 13 is (0, 0, 0). With nodes numbered in
// lattice order (x fastest), a code >= 13 means a column node >= the row node.
constexpr int kCenter = 13;

int offset_component(int code, int axis) { return (axis == 0 ? code : axis == 1 ? code / 3 : code / 9) % 3 - 1; }

// A fine node's box of coarse columns in A P: coarse points floor((c-1)/2)
// onward, 3 per axis for an even coordinate c and 2 for an odd one.
int box_extent(int parity_bit) { return parity_bit ? 2 : 3; }
int box_size(int parity) { return box_extent(parity & 1) * box_extent(parity >> 1 & 1) * box_extent(parity >> 2 & 1); }

// Block `slot` of fine row f times `weight`, into `scaled`. P has no row for
// a decoupled unknown, so its diagonal entry is dropped (its off-diagonal
// entries are zero already).
void scaled_fine_block(const BlockMatrix& fine, const std::vector<char>& fine_decoupled, int f, int slot, double weight,
                       double scaled[9]) {
  const double* block = fine.values.data() + 9 * std::size_t(slot);
  for (int a = 0; a < 9; ++a) scaled[a] = weight * block[a];
  if (slot != fine.diagonal[f]) return;
  for (int a = 0; a < 3; ++a) {
    if (fine_decoupled[3 * std::size_t(f) + std::size_t(a)]) scaled[4 * a] = 0.0;
  }
}

struct EntryList {
  int count = 0;
  std::array<std::uint8_t, 27> entry{};
};

// For a fine row node of coordinate parity `parity` and a column node at
// lattice offset `code`: the box entries of the column node's coarse parents.
const std::array<std::array<EntryList, 27>, 8>& parent_box_entries() {
  static const std::array<std::array<EntryList, 27>, 8> table = [] {
    // Per axis: row parity, offset + 1 -> first and last local parent index.
    constexpr int first[2][3] = {{0, 1, 1}, {0, 0, 1}};
    constexpr int last[2][3] = {{1, 1, 2}, {0, 1, 1}};
    std::array<std::array<EntryList, 27>, 8> t{};
    for (int parity = 0; parity < 8; ++parity) {
      const int ex = box_extent(parity & 1), ey = box_extent(parity >> 1 & 1);
      const int px = parity & 1, py = parity >> 1 & 1, pz = parity >> 2 & 1;
      for (int code = 0; code < 27; ++code) {
        const int ox = offset_component(code, 0) + 1, oy = offset_component(code, 1) + 1,
                  oz = offset_component(code, 2) + 1;
        EntryList& list = t[parity][code];
        for (int w = first[pz][oz]; w <= last[pz][oz]; ++w) {
          for (int v = first[py][oy]; v <= last[py][oy]; ++v) {
            for (int u = first[px][ox]; u <= last[px][ox]; ++u) {
              list.entry[static_cast<std::size_t>(list.count++)] = static_cast<std::uint8_t>(u + ex * (v + ey * w));
            }
          }
        }
      }
    }
    return t;
  }();
  return table;
}

// For a fine child at offset code `child` from twice its coarse parent: the
// coarse offset code (relative to that parent) of each entry of the child's box.
const std::array<EntryList, 27>& box_entry_offsets() {
  static const std::array<EntryList, 27> table = [] {
    std::array<EntryList, 27> t{};
    for (int child = 0; child < 27; ++child) {
      std::array<int, 3> extent{}, shift{};
      for (int axis = 0; axis < 3; ++axis) {
        const int delta = offset_component(child, axis);
        extent[axis] = box_extent(delta != 0);
        // The box starts at floor((2C + delta - 1) / 2) = C - 1 (delta <= 0) or C (delta = 1).
        shift[axis] = delta == 1 ? 1 : 0;
      }
      EntryList& list = t[child];
      for (int w = 0; w < extent[2]; ++w) {
        for (int v = 0; v < extent[1]; ++v) {
          for (int u = 0; u < extent[0]; ++u) {
            list.entry[static_cast<std::size_t>(list.count++)] =
                static_cast<std::uint8_t>((u + shift[0]) + 3 * (v + shift[1]) + 9 * (w + shift[2]));
          }
        }
      }
    }
    return t;
  }();
  return table;
}

}  // namespace

int lattice_reach(const NodeLattice& lattice, const BlockMatrix& matrix) {
  int reach = 0;
  for (int f = 0; f < matrix.rows; ++f) {
    const std::array<int, 3>& c = lattice.coords[f];
    for (int slot = matrix.row_start[f]; slot < matrix.row_start[f + 1]; ++slot) {
      const int g = matrix.column[slot];
      const std::array<int, 3>& d = lattice.coords[g];
      const int steps = std::max({std::abs(d[0] - c[0]), std::abs(d[1] - c[1]), std::abs(d[2] - c[2])});
      if (steps > GridTransfer::kMaxCouplingSteps) {
        throw InputError("pcg-mg needs a voxel mesh: the matrix couples nodes " + std::to_string(f) + " and " +
                         std::to_string(g) + ", which are not neighbours on the node lattice (" +
                         std::to_string(steps) + " lattice steps apart, more than the " +
                         std::to_string(GridTransfer::kMaxCouplingSteps) +
                         " elements of mixed sizes reach; is node_positions the rest configuration of this mesh?)");
      }
      reach = std::max(reach, steps);
    }
  }
  return reach;
}

GridTransfer::GridTransfer(const NodeLattice& fine, const NodeLattice& coarse, const BlockMatrix& fine_operator,
                           int reach) {
  const int fine_count = fine.num_nodes();
  const int coarse_count = coarse.num_nodes();
  if (fine_operator.rows != fine_count) {
    throw std::invalid_argument("GridTransfer: the fine operator has " + std::to_string(fine_operator.rows) +
                                " block rows for " + std::to_string(fine_count) + " lattice nodes");
  }

  neighbour_coupled_ = reach <= 1;
  if (!neighbour_coupled_) {
    build_wide_transfer(fine, coarse, fine_operator);
    return;
  }

  // Parents and coordinate parities of the fine nodes; offsets of the fine blocks.
  parent_start_.assign(static_cast<std::size_t>(fine_count) + 1, 0);
  fine_parity_.resize(static_cast<std::size_t>(fine_count));
  box_start_.assign(static_cast<std::size_t>(fine_count) + 1, 0);
  for (int f = 0; f < fine_count; ++f) {
    const std::array<int, 3>& c = fine.coords[f];
    const int parity = (c[0] & 1) | (c[1] & 1) << 1 | (c[2] & 1) << 2;
    fine_parity_[f] = static_cast<std::uint8_t>(parity);
    for (int k = c[2] / 2; k <= (c[2] + 1) / 2; ++k) {
      for (int j = c[1] / 2; j <= (c[1] + 1) / 2; ++j) {
        for (int i = c[0] / 2; i <= (c[0] + 1) / 2; ++i) parent_node_.push_back(coarse.node(i, j, k));
      }
    }
    parent_start_[f + 1] = static_cast<int>(parent_node_.size());
    box_start_[f + 1] = box_start_[f] + box_size(parity);
  }
  fine_block_offset_.resize(static_cast<std::size_t>(fine_operator.num_blocks()));
  for (int f = 0; f < fine_count; ++f) {
    const std::array<int, 3>& c = fine.coords[f];
    for (int slot = fine_operator.row_start[f]; slot < fine_operator.row_start[f + 1]; ++slot) {
      const std::array<int, 3>& d = fine.coords[fine_operator.column[slot]];
      const int dx = d[0] - c[0], dy = d[1] - c[1], dz = d[2] - c[2];
      fine_block_offset_[slot] = static_cast<std::uint8_t>((dx + 1) + 3 * (dy + 1) + 9 * (dz + 1));
    }
  }
  fine_times_p_.assign(9 * static_cast<std::size_t>(box_start_.back()), 0.0);

  // Children of the coarse nodes, in offset order.
  child_start_.assign(static_cast<std::size_t>(coarse_count) + 1, 0);
  for (int p = 0; p < coarse_count; ++p) {
    const std::array<int, 3>& c = coarse.coords[p];
    for (int code = 0; code < 27; ++code) {
      const int dx = offset_component(code, 0), dy = offset_component(code, 1), dz = offset_component(code, 2);
      const int f = fine.node(2 * c[0] + dx, 2 * c[1] + dy, 2 * c[2] + dz);
      if (f < 0) continue;
      child_node_.push_back(f);
      child_weight_.push_back(1.0 / double(1 << (std::abs(dx) + std::abs(dy) + std::abs(dz))));
      child_offset_.push_back(static_cast<std::uint8_t>(code));
    }
    child_start_[p + 1] = static_cast<int>(child_node_.size());
  }

  // Coarse pattern: block (p, q) is stored if a child of p couples to a fine
  // node that q interpolates to.
  const auto& parents = parent_box_entries();
  const auto& box_offsets = box_entry_offsets();
  coarse_.rows = coarse_count;
  coarse_.row_start.assign(static_cast<std::size_t>(coarse_count) + 1, 0);
  coarse_.diagonal.assign(static_cast<std::size_t>(coarse_count), -1);
  std::vector<std::array<int, 27>> slot_of_offset(static_cast<std::size_t>(coarse_count));
  for (int p = 0; p < coarse_count; ++p) {
    std::array<bool, 27> reached{};
    for (int k = child_start_[p]; k < child_start_[p + 1]; ++k) {
      const int f = child_node_[k];
      const EntryList& to_code = box_offsets[child_offset_[k]];
      for (int slot = fine_operator.row_start[f]; slot < fine_operator.row_start[f + 1]; ++slot) {
        const EntryList& entries = parents[fine_parity_[f]][fine_block_offset_[slot]];
        for (int e = 0; e < entries.count; ++e) reached[to_code.entry[entries.entry[e]]] = true;
      }
    }
    reached[kCenter] = true;
    const std::array<int, 3>& c = coarse.coords[p];
    std::array<int, 27>& slots = slot_of_offset[p];
    slots.fill(-1);
    for (int code = 0; code < 27; ++code) {
      if (!reached[code]) continue;
      const int q = coarse.node(c[0] + offset_component(code, 0), c[1] + offset_component(code, 1),
                                c[2] + offset_component(code, 2));
      if (q < 0) throw std::logic_error("GridTransfer: a reached coarse point has no node");
      slots[code] = static_cast<int>(coarse_.column.size());
      if (code == kCenter) coarse_.diagonal[p] = static_cast<int>(coarse_.column.size());
      coarse_.column.push_back(q);
      coarse_block_offset_.push_back(static_cast<std::uint8_t>(code));
    }
    coarse_.row_start[p + 1] = static_cast<int>(coarse_.column.size());
  }
  mirror_slot_.resize(coarse_.column.size());
  for (int p = 0; p < coarse_count; ++p) {
    for (int slot = coarse_.row_start[p]; slot < coarse_.row_start[p + 1]; ++slot) {
      const int q = coarse_.column[slot];
      const int mirror = slot_of_offset[q][static_cast<std::size_t>(26 - coarse_block_offset_[slot])];
      if (mirror < 0) throw std::logic_error("GridTransfer: the coarse pattern is not symmetric");
      mirror_slot_[slot] = mirror;
    }
  }
}

BlockMatrix GridTransfer::coarse_pattern() const {
  BlockMatrix pattern = coarse_;
  pattern.values.assign(9 * pattern.column.size(), 0.0);
  return pattern;
}

void GridTransfer::galerkin_product(const BlockMatrix& fine, const std::vector<char>& fine_decoupled,
                                    BlockMatrix& coarse, int threads) {
  if (!neighbour_coupled_) {
    wide_galerkin_product(fine, fine_decoupled, coarse, threads);
    return;
  }
  const int team = resolve_thread_count(threads);
  const auto& parents = parent_box_entries();
  const auto& box_offsets = box_entry_offsets();

  // A P, row by row: each fine block, scaled by the interpolation weight of
  // its column node, lands on the box entries of that node's parents.
  parallel_row_ranges(fine.rows, team, [&](int begin, int end) {
    for (int f = begin; f < end; ++f) {
      const int parity = fine_parity_[f];
      double* box = fine_times_p_.data() + 9 * std::size_t(box_start_[f]);
      std::fill(box, box + 9 * box_size(parity), 0.0);
      for (int slot = fine.row_start[f]; slot < fine.row_start[f + 1]; ++slot) {
        const EntryList& entries = parents[parity][fine_block_offset_[slot]];
        double scaled[9];
        scaled_fine_block(fine, fine_decoupled, f, slot, 1.0 / entries.count, scaled);  // a power of two: exact
        for (int e = 0; e < entries.count; ++e) {
          double* target = box + 9 * std::size_t(entries.entry[e]);
          for (int a = 0; a < 9; ++a) target[a] += scaled[a];
        }
      }
    }
  });

  // Upper block triangle of P^T (A P), gathering each coarse row from the
  // rows of its children; the diagonal blocks are symmetrized.
  parallel_row_ranges(coarse.rows, team, [&](int begin, int end) {
    double sum[27][9];
    for (int p = begin; p < end; ++p) {
      for (int code = kCenter; code < 27; ++code) std::fill(sum[code], sum[code] + 9, 0.0);
      bool reached[3] = {false, false, false};
      for (int k = child_start_[p]; k < child_start_[p + 1]; ++k) {
        const int f = child_node_[k];
        const double weight = child_weight_[k];
        for (int a = 0; a < 3; ++a) reached[a] = reached[a] || !fine_decoupled[3 * std::size_t(f) + std::size_t(a)];
        const EntryList& to_code = box_offsets[child_offset_[k]];
        const double* box = fine_times_p_.data() + 9 * std::size_t(box_start_[f]);
        for (int e = 0; e < to_code.count; ++e) {
          const int code = to_code.entry[e];
          if (code < kCenter) continue;
          const double* block = box + 9 * e;
          for (int a = 0; a < 9; ++a) sum[code][a] += weight * block[a];
        }
      }
      for (int slot = coarse.row_start[p]; slot < coarse.row_start[p + 1]; ++slot) {
        const int code = coarse_block_offset_[slot];
        if (code < kCenter) continue;
        double* target = coarse.values.data() + 9 * std::size_t(slot);
        std::copy(sum[code], sum[code] + 9, target);
        if (code == kCenter) finish_diagonal_block(target, reached);
      }
    }
  });

  mirror_lower_blocks(coarse, team);
}

void GridTransfer::mirror_lower_blocks(BlockMatrix& coarse, int team) const {
  // Columns ascend within a row (lattice order), so the blocks before the
  // diagonal are the lower triangle: each the transpose of its mirror.
  parallel_row_ranges(coarse.rows, team, [&](int begin, int end) {
    for (int p = begin; p < end; ++p) {
      for (int slot = coarse.row_start[p]; slot < coarse.diagonal[p]; ++slot) {
        const double* source = coarse.values.data() + 9 * std::size_t(mirror_slot_[slot]);
        double* target = coarse.values.data() + 9 * std::size_t(slot);
        for (int a = 0; a < 3; ++a) {
          for (int b = 0; b < 3; ++b) target[3 * a + b] = source[3 * b + a];
        }
      }
    }
  });
}

void GridTransfer::build_wide_transfer(const NodeLattice& fine, const NodeLattice& coarse,
                                       const BlockMatrix& fine_operator) {
  // Parents by the rule of coarsen_lattice_by_injection: the corners of the
  // enclosing coarse cell whose fine point holds a node, all with the same
  // weight; a node with none of them takes the corner at floor(c / 2) alone.
  // Each coarse column then has a row of its own with weight 1 (its
  // injected node, or a node for which it is the only parent), so P has
  // full column rank and P^T A P is definite where A is.
  const int fine_count = fine.num_nodes();
  const int coarse_count = coarse.num_nodes();
  parent_start_.assign(static_cast<std::size_t>(fine_count) + 1, 0);
  for (int f = 0; f < fine_count; ++f) {
    const std::array<int, 3>& c = fine.coords[f];
    for (int k = c[2] / 2; k <= (c[2] + 1) / 2; ++k) {
      for (int j = c[1] / 2; j <= (c[1] + 1) / 2; ++j) {
        for (int i = c[0] / 2; i <= (c[0] + 1) / 2; ++i) {
          if (fine.node(2 * i, 2 * j, 2 * k) < 0) continue;
          const int p = coarse.node(i, j, k);
          if (p < 0) throw std::logic_error("GridTransfer: a coarse point over a fine node has no node");
          parent_node_.push_back(p);
        }
      }
    }
    if (static_cast<int>(parent_node_.size()) == parent_start_[f]) {
      const int p = coarse.node(c[0] / 2, c[1] / 2, c[2] / 2);
      if (p < 0) throw std::logic_error("GridTransfer: a fine node without parents has no floor corner");
      parent_node_.push_back(p);
    }
    parent_start_[f + 1] = static_cast<int>(parent_node_.size());
  }
  // Children: the parents' lists inverted, in fine node order.
  child_start_.assign(static_cast<std::size_t>(coarse_count) + 1, 0);
  for (const int p : parent_node_) ++child_start_[static_cast<std::size_t>(p) + 1];
  for (int p = 0; p < coarse_count; ++p) child_start_[p + 1] += child_start_[p];
  child_node_.resize(parent_node_.size());
  child_weight_.resize(parent_node_.size());
  std::vector<int> next(child_start_.begin(), child_start_.end() - 1);
  for (int f = 0; f < fine_count; ++f) {
    const double weight = 1.0 / (parent_start_[f + 1] - parent_start_[f]);
    for (int e = parent_start_[f]; e < parent_start_[f + 1]; ++e) {
      const int slot = next[static_cast<std::size_t>(parent_node_[e])]++;
      child_node_[slot] = f;
      child_weight_[slot] = weight;
    }
  }
  build_wide_pattern(fine_operator);
}

void GridTransfer::build_wide_pattern(const BlockMatrix& fine_operator) {
  // Block (p, q) is stored if a child of p couples to a fine node that q
  // interpolates to: the same rule as the neighbour tables, found directly.
  const int coarse_count = coarse_nodes();
  coarse_.rows = coarse_count;
  coarse_.row_start.assign(static_cast<std::size_t>(coarse_count) + 1, 0);
  coarse_.diagonal.assign(static_cast<std::size_t>(coarse_count), -1);
  std::vector<char> seen(static_cast<std::size_t>(coarse_count), 0);
  std::vector<int> columns;
  for (int p = 0; p < coarse_count; ++p) {
    columns.assign(1, p);
    seen[p] = 1;
    for (int k = child_start_[p]; k < child_start_[p + 1]; ++k) {
      const int f = child_node_[k];
      for (int slot = fine_operator.row_start[f]; slot < fine_operator.row_start[f + 1]; ++slot) {
        const int g = fine_operator.column[slot];
        for (int e = parent_start_[g]; e < parent_start_[g + 1]; ++e) {
          const int q = parent_node_[e];
          if (seen[q]) continue;
          seen[q] = 1;
          columns.push_back(q);
        }
      }
    }
    std::sort(columns.begin(), columns.end());
    for (const int q : columns) {
      seen[q] = 0;
      if (q == p) coarse_.diagonal[p] = static_cast<int>(coarse_.column.size());
      coarse_.column.push_back(q);
    }
    coarse_.row_start[p + 1] = static_cast<int>(coarse_.column.size());
  }
  mirror_slot_.resize(coarse_.column.size());
  for (int p = 0; p < coarse_count; ++p) {
    for (int slot = coarse_.row_start[p]; slot < coarse_.row_start[p + 1]; ++slot) {
      const int q = coarse_.column[slot];
      const auto row_begin = coarse_.column.begin() + coarse_.row_start[q];
      const auto row_end = coarse_.column.begin() + coarse_.row_start[q + 1];
      const auto found = std::lower_bound(row_begin, row_end, p);
      if (found == row_end || *found != p) throw std::logic_error("GridTransfer: the coarse pattern is not symmetric");
      mirror_slot_[slot] = static_cast<int>(found - coarse_.column.begin());
    }
  }
}

void GridTransfer::wide_galerkin_product(const BlockMatrix& fine, const std::vector<char>& fine_decoupled,
                                         BlockMatrix& coarse, int threads) const {
  const int team = resolve_thread_count(threads);
  const int coarse_count = coarse.rows;
  // Upper block triangle of P^T A P, one coarse row at a time from its
  // children's fine rows: each fine block, weighted by the child's and the
  // column's interpolation weights (powers of two: exact), lands on the
  // column's parents. Rows are independent, so the sums do not depend on the
  // thread count.
  parallel_row_ranges(coarse_count, team, [&](int begin, int end) {
    std::vector<int> slot_of(static_cast<std::size_t>(coarse_count), -1);
    for (int p = begin; p < end; ++p) {
      const int upper = coarse.diagonal[p];
      const int last = coarse.row_start[p + 1];
      for (int slot = upper; slot < last; ++slot) slot_of[coarse.column[slot]] = slot;
      std::fill(coarse.values.data() + 9 * std::size_t(upper), coarse.values.data() + 9 * std::size_t(last), 0.0);
      bool reached[3] = {false, false, false};
      for (int k = child_start_[p]; k < child_start_[p + 1]; ++k) {
        const int f = child_node_[k];
        for (int a = 0; a < 3; ++a) reached[a] = reached[a] || !fine_decoupled[3 * std::size_t(f) + std::size_t(a)];
        for (int slot = fine.row_start[f]; slot < fine.row_start[f + 1]; ++slot) {
          const int g = fine.column[slot];
          const int first_parent = parent_start_[g];
          const int end_parent = parent_start_[g + 1];
          double scaled[9];
          scaled_fine_block(fine, fine_decoupled, f, slot, child_weight_[k] / (end_parent - first_parent), scaled);
          for (int e = first_parent; e < end_parent; ++e) {
            const int q = parent_node_[e];
            if (q < p) continue;
            double* target = coarse.values.data() + 9 * std::size_t(slot_of[q]);
            for (int a = 0; a < 9; ++a) target[a] += scaled[a];
          }
        }
      }
      finish_diagonal_block(coarse.values.data() + 9 * std::size_t(upper), reached);
      for (int slot = upper; slot < last; ++slot) slot_of[coarse.column[slot]] = -1;
    }
  });
  mirror_lower_blocks(coarse, team);
}

void GridTransfer::restrict_to_coarse(const VecX& fine, const std::vector<char>& fine_decoupled, VecX& coarse,
                                      int threads) const {
  coarse.resize(3 * Eigen::Index(coarse_nodes()));
  parallel_row_ranges(coarse_nodes(), resolve_thread_count(threads), [&](int begin, int end) {
    for (int p = begin; p < end; ++p) {
      double sum[3] = {0.0, 0.0, 0.0};
      for (int k = child_start_[p]; k < child_start_[p + 1]; ++k) {
        const std::size_t f = static_cast<std::size_t>(child_node_[k]);
        const double weight = child_weight_[k];
        for (int a = 0; a < 3; ++a) {
          if (!fine_decoupled[3 * f + std::size_t(a)]) sum[a] += weight * fine[Eigen::Index(3 * f) + a];
        }
      }
      for (int a = 0; a < 3; ++a) coarse[3 * Eigen::Index(p) + a] = sum[a];
    }
  });
}

void GridTransfer::add_prolongation(const VecX& coarse, const std::vector<char>& fine_decoupled, VecX& fine,
                                    int threads) const {
  parallel_row_ranges(fine_nodes(), resolve_thread_count(threads), [&](int begin, int end) {
    for (int f = begin; f < end; ++f) {
      const int first = parent_start_[f];
      const int last = parent_start_[f + 1];
      const double weight = 1.0 / (last - first);
      double sum[3] = {0.0, 0.0, 0.0};
      for (int k = first; k < last; ++k) {
        const Eigen::Index p = 3 * Eigen::Index(parent_node_[k]);
        for (int a = 0; a < 3; ++a) sum[a] += coarse[p + a];
      }
      for (int a = 0; a < 3; ++a) {
        if (!fine_decoupled[3 * std::size_t(f) + std::size_t(a)]) fine[3 * Eigen::Index(f) + a] += weight * sum[a];
      }
    }
  });
}

SpMat GridTransfer::prolongation(const std::vector<char>& fine_decoupled) const {
  std::vector<Eigen::Triplet<double, int>> entries;
  for (int f = 0; f < fine_nodes(); ++f) {
    const int first = parent_start_[f];
    const int last = parent_start_[f + 1];
    for (int k = first; k < last; ++k) {
      for (int a = 0; a < 3; ++a) {
        if (fine_decoupled[3 * std::size_t(f) + std::size_t(a)]) continue;
        entries.emplace_back(3 * f + a, 3 * parent_node_[k] + a, 1.0 / (last - first));
      }
    }
  }
  SpMat P(3 * Eigen::Index(fine_nodes()), 3 * Eigen::Index(coarse_nodes()));
  P.setFromTriplets(entries.begin(), entries.end());
  return P;
}

}  // namespace msfab
