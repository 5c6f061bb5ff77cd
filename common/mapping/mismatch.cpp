#include "mapping/mismatch.hpp"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstring>
#include <set>
#include <stdexcept>
#include <utility>

#include "cli/progress.hpp"

namespace msfab {

std::int64_t FaceGrid::neighbour(std::int64_t cell, int face) const {
  const int axis = face / 2;
  const int step = face % 2 == 0 ? -1 : 1;
  const std::int64_t i = cell % nx, j = (cell / nx) % ny, k = cell / (std::int64_t(nx) * ny);
  switch (axis) {
    case 0: return (i + step < 0 || i + step >= nx) ? -1 : cell + step;
    case 1: return (j + step < 0 || j + step >= ny) ? -1 : cell + step * std::int64_t(nx);
    default: return (k + step < 0 || k + step >= nz) ? -1 : cell + step * std::int64_t(nx) * ny;
  }
}

std::vector<int> periodic_shift(const std::vector<int>& ids, int nx, int ny, int nz, int sx, int sy, int sz) {
  if (ids.size() != std::size_t(nx) * ny * nz) throw std::invalid_argument("periodic_shift: wrong voxel count");
  auto wrap = [](int v, int n) { return ((v % n) + n) % n; };
  std::vector<int> out(ids.size());
  for (int z = 0; z < nz; ++z)
    for (int y = 0; y < ny; ++y)
      for (int x = 0; x < nx; ++x)
        out[x + std::size_t(nx) * (y + std::size_t(ny) * z)] =
            ids[wrap(x + sx, nx) + std::size_t(nx) * (wrap(y + sy, ny) + std::size_t(ny) * wrap(z + sz, nz))];
  return out;
}

std::vector<int> half_shifted(const std::vector<int>& ids, int nx, int ny, int nz) {
  return periodic_shift(ids, nx, ny, nz, nx / 2, ny / 2, nz / 2);
}

// ---------------------------------------------------------------------------
// FaceTable

FaceTable::FaceTable(int vx, int vy, int vz, int dimension) : vx_(vx), vy_(vy), vz_(vz), dimension_(dimension) {
  if (vx < 1 || vy < 1 || vz < 1 || (dimension != 2 && dimension != 3) || (dimension == 2 && vz != 1))
    throw std::invalid_argument("FaceTable: bad cell size or dimension");
  face_size_[0] = vy * vz, face_size_[1] = vx * vz, face_size_[2] = dimension == 3 ? vx * vy : 0;
  for (int f = 0; f < 2 * dimension; ++f) {
    face_offset_[f] = stride_;
    stride_ += std::size_t(face_size_[f / 2]);
  }
}

int FaceTable::add(const std::vector<int>& ids) {
  if (ids.size() != std::size_t(vx_) * vy_ * vz_) throw std::invalid_argument("FaceTable::add: wrong voxel count");
  const std::size_t base = data_.size();
  data_.resize(base + stride_);
  auto at = [&](int x, int y, int z) {
    const int id = ids[x + std::size_t(vx_) * (y + std::size_t(vy_) * z)];
    if (id < 0 || id > 255) throw std::invalid_argument("FaceTable::add: voxel id outside 0..255");
    return static_cast<std::uint8_t>(id);
  };
  for (int side = 0; side < 2; ++side) {
    std::uint8_t* fx = &data_[base + face_offset_[side]];
    const int x = side == 0 ? 0 : vx_ - 1;
    for (int z = 0; z < vz_; ++z)
      for (int y = 0; y < vy_; ++y) fx[y + vy_ * z] = at(x, y, z);
    std::uint8_t* fy = &data_[base + face_offset_[2 + side]];
    const int y = side == 0 ? 0 : vy_ - 1;
    for (int z = 0; z < vz_; ++z)
      for (int x2 = 0; x2 < vx_; ++x2) fy[x2 + vx_ * z] = at(x2, y, z);
    if (dimension_ == 3) {
      std::uint8_t* fz = &data_[base + face_offset_[4 + side]];
      const int z = side == 0 ? 0 : vz_ - 1;
      for (int y2 = 0; y2 < vy_; ++y2)
        for (int x2 = 0; x2 < vx_; ++x2) fz[x2 + vx_ * y2] = at(x2, y2, z);
    }
  }
  return entries_++;
}

int FaceTable::add_uniform(int id) { return add(std::vector<int>(std::size_t(vx_) * vy_ * vz_, id)); }

std::int64_t FaceTable::mismatch(int lower, int upper, int axis) const {
  const std::uint8_t* a = face(lower, 2 * axis + 1);
  const std::uint8_t* b = face(upper, 2 * axis);
  const int n = face_size_[axis];
  // Eight voxels at a time: a byte of a ^ b is nonzero where the ids
  // differ; fold each byte's bits into its lowest bit and add those up.
  constexpr std::uint64_t kLow = 0x0101010101010101ull;
  std::int64_t count = 0;
  int k = 0;
  for (; k + 8 <= n; k += 8) {
    std::uint64_t x, y;
    std::memcpy(&x, a + k, 8);
    std::memcpy(&y, b + k, 8);
    x ^= y;
    x |= x >> 4;
    x |= x >> 2;
    x |= x >> 1;
    count += std::int64_t(((x & kLow) * kLow) >> 56);
  }
  for (; k < n; ++k) count += a[k] != b[k];
  return count;
}

std::int64_t FaceTable::void_pairs(int lower, int upper, int axis) const {
  const std::uint8_t* a = face(lower, 2 * axis + 1);
  const std::uint8_t* b = face(upper, 2 * axis);
  const int n = face_size_[axis];
  // As in mismatch(): a byte of a | b is zero where both ids are 0.
  constexpr std::uint64_t kLow = 0x0101010101010101ull;
  std::int64_t count = 0;
  int k = 0;
  for (; k + 8 <= n; k += 8) {
    std::uint64_t x, y;
    std::memcpy(&x, a + k, 8);
    std::memcpy(&y, b + k, 8);
    x |= y;
    x |= x >> 4;
    x |= x >> 2;
    x |= x >> 1;
    count += 8 - std::int64_t(((x & kLow) * kLow) >> 56);
  }
  for (; k < n; ++k) count += (a[k] | b[k]) == 0;
  return count;
}

// ---------------------------------------------------------------------------
// MismatchProblem

std::uint64_t hash_seed(std::uint64_t seed, std::uint64_t index) {
  auto splitmix = [](std::uint64_t x) {
    x += 0x9E3779B97F4A7C15ull;
    x = (x ^ (x >> 30)) * 0xBF58476D1CE4E5B9ull;
    x = (x ^ (x >> 27)) * 0x94D049BB133111EBull;
    return x ^ (x >> 31);
  };
  return splitmix(splitmix(seed) ^ splitmix(index ^ 0x5851F42D4C957F2Dull));
}

MismatchProblem::MismatchProblem(FaceGrid grid, FaceTable table, std::vector<std::int64_t> offsets,
                                 std::vector<std::int32_t> options, double void_pair_cost)
    : grid_(grid), table_(std::move(table)), offsets_(std::move(offsets)), options_(std::move(options)) {
  if (!(void_pair_cost >= 0 && void_pair_cost <= 1))
    throw std::invalid_argument("MismatchProblem: the void-pair cost must lie in [0, 1]");
  void_cost16_ = int(std::lround(16 * void_pair_cost));
  const std::int64_t cells = grid_.cells();
  if (grid_.dimension != table_.dimension()) throw std::invalid_argument("MismatchProblem: dimensions differ");
  if (std::int64_t(offsets_.size()) != cells + 1 || offsets_[0] != 0 ||
      offsets_.back() != std::int64_t(options_.size()))
    throw std::invalid_argument("MismatchProblem: offsets must have cells + 1 entries spanning the options");
  for (std::int64_t c = 0; c < cells; ++c)
    if (option_count(c) < 1) throw std::invalid_argument("MismatchProblem: a cell without options");
  for (std::int32_t e : options_)
    if (e < 0 || e >= table_.entries()) throw std::invalid_argument("MismatchProblem: option is not a table entry");
  choice_.assign(std::size_t(cells), 0);
  energy_.assign(std::size_t(cells), 0);
  recompute_energies();
}

std::int64_t MismatchProblem::pair_mismatch(int entry, int face, std::int64_t other) const {
  const int other_entry = this->entry(other, choice_[std::size_t(other)]);
  const int axis = face / 2;
  const int lower = face % 2 == 1 ? entry : other_entry, upper = face % 2 == 1 ? other_entry : entry;
  if (void_cost16_ == 0) return table_.mismatch(lower, upper, axis);
  return 16 * table_.mismatch(lower, upper, axis) + void_cost16_ * table_.void_pairs(lower, upper, axis);
}

MismatchProblem::FacePairs MismatchProblem::face_pairs() const {
  FacePairs p;
  const std::int64_t cells = grid_.cells();
  for (std::int64_t c = 0; c < cells; ++c) {
    const int e = entry(c, choice_[std::size_t(c)]);
    for (int axis = 0; axis < grid_.dimension; ++axis) {
      const std::int64_t n = grid_.neighbour(c, 2 * axis + 1);
      if (n < 0) continue;
      const int o = entry(n, choice_[std::size_t(n)]);
      const std::int64_t differ = table_.mismatch(e, o, axis), both_void = table_.void_pairs(e, o, axis);
      p.mismatch += differ;
      p.both_void += both_void;
      p.contact += table_.face_size(axis) - differ - both_void;
    }
  }
  return p;
}

std::int64_t MismatchProblem::energy_with(std::int64_t cell, int option) const {
  const int e = entry(cell, option);
  std::int64_t sum = 0;
  for (int f = 0; f < grid_.faces(); ++f) {
    const std::int64_t n = grid_.neighbour(cell, f);
    if (n >= 0) sum += pair_mismatch(e, f, n);
  }
  return sum;
}

void MismatchProblem::recompute_energies() {
  const std::int64_t cells = grid_.cells();
#pragma omp parallel for schedule(static)
  for (std::int64_t c = 0; c < cells; ++c) energy_[std::size_t(c)] = energy_with(c, choice_[std::size_t(c)]);
}

std::int64_t MismatchProblem::total() const {
  std::int64_t sum = 0;
  const std::int64_t cells = grid_.cells();
#pragma omp parallel for reduction(+ : sum) schedule(static)
  for (std::int64_t c = 0; c < cells; ++c) sum += energy_[std::size_t(c)];
  return sum;
}

void MismatchProblem::assign(std::int64_t cell, int option) {
  if (option < 0 || option >= option_count(cell)) throw std::out_of_range("MismatchProblem::assign: no such option");
  const int old_entry = entry(cell, choice_[std::size_t(cell)]), new_entry = entry(cell, option);
  for (int f = 0; f < grid_.faces(); ++f) {
    const std::int64_t n = grid_.neighbour(cell, f);
    if (n < 0) continue;
    const std::int64_t change = pair_mismatch(new_entry, f, n) - pair_mismatch(old_entry, f, n);
    energy_[std::size_t(n)] += change;
    energy_[std::size_t(cell)] += change;
  }
  choice_[std::size_t(cell)] = option;
}

void MismatchProblem::randomize(std::uint64_t seed) {
  const std::int64_t cells = grid_.cells();
#pragma omp parallel for schedule(static)
  for (std::int64_t c = 0; c < cells; ++c) {
    const std::int64_t n = option_count(c);
    choice_[std::size_t(c)] = n > 1 ? std::int32_t(hash_seed(seed, std::uint64_t(c)) % std::uint64_t(n)) : 0;
  }
  recompute_energies();
}

void MismatchProblem::start_nearest() {
  std::fill(choice_.begin(), choice_.end(), 0);
  recompute_energies();
}

DescentReport MismatchProblem::descend() {
  const auto start = std::chrono::steady_clock::now();
  DescentReport report;
  std::int64_t total_now = total();
  report.initial = total_now;
  report.history.push_back(total_now);
  report.changed.push_back(-1);

  // The priority list: (-I_i, i), so the largest energy comes first and
  // equal energies go by cell index. Only cells that could still lower I
  // are in it: more than one option and I_i > 0.
  std::set<std::pair<std::int64_t, std::int64_t>> queue;
  auto movable = [&](std::int64_t c) { return option_count(c) > 1 && energy_[std::size_t(c)] > 0; };
  for (std::int64_t c = 0; c < grid_.cells(); ++c)
    if (movable(c)) queue.emplace(-energy_[std::size_t(c)], c);

  Progress progress("mismatch descent", 0);
  while (!queue.empty()) {
    const std::int64_t cell = queue.begin()->second;
    queue.erase(queue.begin());
    ++report.evaluations;
    progress.tick();
    const std::int64_t current = energy_[std::size_t(cell)];
    int best = choice_[std::size_t(cell)];
    std::int64_t best_energy = current;
    for (int o = 0; o < option_count(cell); ++o) {
      if (o == choice_[std::size_t(cell)]) continue;
      const std::int64_t e = energy_with(cell, o);
      if (e < best_energy) best = o, best_energy = e;
    }
    if (best_energy >= current) continue;  // no option lowers I: the cell leaves the list

    // The neighbours' energies change: take them out under their old keys,
    // put them back (re-evaluated later) under the new ones.
    for (int f = 0; f < grid_.faces(); ++f) {
      const std::int64_t n = grid_.neighbour(cell, f);
      if (n >= 0 && movable(n)) queue.erase({-energy_[std::size_t(n)], n});
    }
    assign(cell, best);
    for (int f = 0; f < grid_.faces(); ++f) {
      const std::int64_t n = grid_.neighbour(cell, f);
      if (n >= 0 && movable(n)) queue.emplace(-energy_[std::size_t(n)], n);
    }
    // `cell` itself now has its best option for these neighbours; it comes
    // back when one of them changes.
    total_now -= 2 * (current - best_energy);
    report.history.push_back(total_now);
    report.changed.push_back(cell);
    ++report.moves;
  }
  progress.done();
  report.final = total_now;
  report.seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  return report;
}

MultiStartReport descend_from_starts(MismatchProblem& problem, std::uint64_t seed, int starts) {
  if (starts < 1) throw std::invalid_argument("descend_from_starts: needs at least one start");
  MultiStartReport out;
  std::vector<std::int32_t> kept_choice;
  for (int s = 0; s < starts; ++s) {
    if (s == 1)
      problem.start_nearest();
    else
      problem.randomize(s == 0 ? seed : hash_seed(seed, std::uint64_t(s)));
    DescentReport report = problem.descend();
    out.seconds += report.seconds;
    out.finals.push_back(report.final);
    if (s == 0 || report.final < out.kept.final) {
      out.kept = std::move(report);
      out.kept_start = s;
      if (starts > 1) kept_choice = problem.choice();
    }
  }
  if (starts > 1 && out.kept_start != starts - 1) {
    for (std::int64_t c = 0; c < problem.grid().cells(); ++c) problem.assign(c, kept_choice[std::size_t(c)]);
  }
  return out;
}

}  // namespace msfab
