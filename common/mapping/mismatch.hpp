#pragma once
// Boundary mismatch between neighbouring microstructures and its greedy
// minimization (thesis §3.5, steps 2-3).
//
// The design's cells form a regular grid; each cell is filled with one
// "entry": a voxel cell of vx x vy x vz ids (a structure, its half-shifted
// variant, or a uniform fill for forced empty / solid cells). Two cells that
// share a face touch along a layer of voxel pairs; a pair whose ids differ
// is a mismatch. Faces on the outside of the grid have no neighbour and
// count nothing.
//
// I_i counts the mismatching pairs on all faces of cell i, so a mismatching
// pair counts once for each of its two cells, and the total I = sum_i I_i
// (over every cell, fixed ones included) is twice the number of mismatching
// voxel pairs. Changing cell i alone changes I by exactly 2 * (change of I_i).
#include <cstdint>
#include <string>
#include <vector>

namespace msfab {

// The design grid as the mismatch energy sees it: cells numbered
// i + nx (j + ny k) (nz = 1 in 2D) and their face neighbours.
struct FaceGrid {
  int dimension = 2;
  int nx = 1, ny = 1, nz = 1;

  std::int64_t cells() const { return std::int64_t(nx) * ny * nz; }
  int faces() const { return 2 * dimension; }
  // The cell across face f = 2 axis + side (side 0: lower, 1: upper), or -1
  // outside the grid.
  std::int64_t neighbour(std::int64_t cell, int face) const;
};

// The periodic translate out(x, y, z) = ids((x + sx) mod nx, (y + sy) mod ny,
// (z + sz) mod nz) of a cell stored x fastest.
std::vector<int> periodic_shift(const std::vector<int>& ids, int nx, int ny, int nz, int sx, int sy, int sz);
// The extra exemplar of §3.5: translated by half the cell along every axis
// (nx/2, ny/2, nz/2, rounded down; nz = 1 leaves z alone). Periodic
// homogenization gives it the same properties; its boundary differs.
std::vector<int> half_shifted(const std::vector<int>& ids, int nx, int ny, int nz);

// The boundary layers of every entry. Face f = 2 axis + side holds the ids
// of the voxel layer at that side, indexed by the two other coordinates
// (axis x: y + vy z; axis y: x + vx z; axis z: x + vx y), so the lower
// cell's upper face and the upper cell's lower face line up element by
// element.
class FaceTable {
 public:
  FaceTable(int vx, int vy, int vz, int dimension);

  // A voxel cell, x fastest (vx * vy * vz ids in 0..255). Returns its entry.
  int add(const std::vector<int>& ids);
  // A cell filled with one id (forced empty: 0, forced solid: 1).
  int add_uniform(int id);

  int entries() const { return entries_; }
  int dimension() const { return dimension_; }
  int face_size(int axis) const { return face_size_[axis]; }
  const std::uint8_t* face(int entry, int f) const { return &data_[std::size_t(entry) * stride_ + face_offset_[f]]; }
  // Differing voxel pairs between `lower`'s upper face and `upper`'s lower
  // face along `axis`.
  std::int64_t mismatch(int lower, int upper, int axis) const;
  // Pairs of the same faces that are void (id 0) on both sides.
  std::int64_t void_pairs(int lower, int upper, int axis) const;

 private:
  int vx_, vy_, vz_, dimension_;
  int face_size_[3] = {0, 0, 0};
  std::size_t face_offset_[6] = {0, 0, 0, 0, 0, 0};
  std::size_t stride_ = 0;
  int entries_ = 0;
  std::vector<std::uint8_t> data_;
};

// The total mismatch after each accepted move, [0] the initial value.
struct DescentReport {
  std::int64_t initial = 0, final = 0;
  std::int64_t moves = 0;             // accepted changes
  std::int64_t evaluations = 0;       // cells whose options were all tried
  std::vector<std::int64_t> history;  // moves + 1 totals, strictly decreasing
  std::vector<std::int64_t> changed;  // moves + 1 cells, [0] = -1
  double seconds = 0;
};

// Which entry each cell may take: cell c's options are
// options[offsets[c]] .. options[offsets[c + 1] - 1] (entries of the table),
// at least one per cell; a cell with one option is fixed.
//
// With a void-pair cost c > 0 the energy is not the mismatch alone: a pair
// that is void on both sides costs c of a mismatching pair, so that two
// cells that share little material no longer count as a perfect fit (for
// c < 1 this is (1 - c) mismatch - c solid-solid pairs + a constant per
// face). Energies are then in sixteenths of a pair: 16 mismatch +
// round(16 c) void pairs; c = 0 keeps I the plain mismatch.
class MismatchProblem {
 public:
  MismatchProblem(FaceGrid grid, FaceTable table, std::vector<std::int64_t> offsets, std::vector<std::int32_t> options,
                  double void_pair_cost = 0);

  const FaceGrid& grid() const { return grid_; }
  const FaceTable& table() const { return table_; }
  std::int64_t option_count(std::int64_t cell) const { return offsets_[cell + 1] - offsets_[cell]; }
  int entry(std::int64_t cell, int option) const { return options_[std::size_t(offsets_[cell] + option)]; }

  // The option index of every cell (into its own list).
  const std::vector<std::int32_t>& choice() const { return choice_; }
  // Sets one cell's option and refreshes the energies it touches.
  void assign(std::int64_t cell, int option);
  // Every cell an option drawn from a hash of (seed, cell): the same for a
  // seed whatever the thread count or the order cells are visited in.
  void randomize(std::uint64_t seed);
  // Every cell its option 0: the nearest candidate, as stored.
  void start_nearest();

  // I_i under the current choice (cached).
  std::int64_t energy(std::int64_t cell) const { return energy_[std::size_t(cell)]; }
  // I = sum_i I_i.
  std::int64_t total() const;
  // I_i if `cell` took `option` and every other cell kept its choice.
  std::int64_t energy_with(std::int64_t cell, int option) const;
  // Every I_i from scratch (parallel over cells).
  void recompute_energies();

  // The voxel pairs across faces between cells under the current choice,
  // each pair once: differing, void on both sides, and the rest (the same
  // material on both sides: solid contact).
  struct FacePairs {
    std::int64_t mismatch = 0, both_void = 0, contact = 0;
  };
  FacePairs face_pairs() const;

  // The greedy descent of §3.5: cells in a priority list by I_i (largest
  // first, then lower index); the top cell takes the option that lowers I the
  // most (ties: the lowest option index, i.e. the nearest candidate) or, if
  // none lowers it, leaves the list; a cell whose neighbour changed re-enters
  // it. Stops when the list is empty: no single-cell change lowers I.
  DescentReport descend();

 private:
  std::int64_t pair_mismatch(int entry, int face, std::int64_t other) const;

  int void_cost16_ = 0;  // round(16 c); 0: I is the mismatch

  FaceGrid grid_;
  FaceTable table_;
  std::vector<std::int64_t> offsets_;
  std::vector<std::int32_t> options_;
  std::vector<std::int32_t> choice_;
  std::vector<std::int64_t> energy_;
};

// The descent from several starts, the lowest final mismatch kept (ties:
// the earlier start). One greedy descent stops in the first local minimum
// it meets, and where options form groups that fit among themselves (every
// structure fits its own copies; half-shifted exemplars fit each other) a
// random start freezes patches of each group whose borders no single-cell
// move can mend. Start 0 is randomize(seed), so one start is the plain
// descent; start 1 the nearest candidate everywhere (neighbours with close
// targets then share structures); start s >= 2 randomize(hash_seed(seed, s)).
// Each descent is sequential, so the result depends on the seed only. The
// problem is left at the kept start's local minimum.
struct MultiStartReport {
  DescentReport kept;  // the kept start's descent
  int kept_start = 0;
  std::vector<std::int64_t> finals;  // final mismatch of every start
  double seconds = 0;                // all starts' descents
};
MultiStartReport descend_from_starts(MismatchProblem& problem, std::uint64_t seed, int starts);

// splitmix64-based hash of (seed, index): a reproducible stream per index.
std::uint64_t hash_seed(std::uint64_t seed, std::uint64_t index);

}  // namespace msfab
