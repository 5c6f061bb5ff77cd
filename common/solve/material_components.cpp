#include "solve/material_components.hpp"

#include <algorithm>
#include <string>

#include "core/errors.hpp"
#include "solve/hex_lattice.hpp"
#include "solve/sparse_ops.hpp"

namespace msfab {
namespace {

using namespace hex_lattice;

// What one coarse lattice point contributes: its pieces' first voxels, and
// per child copy (fine copies whose lattice point lies within one fine
// spacing) the piece it falls in and its trilinear weight.
struct PointPieces {
  std::vector<std::int64_t> representative;
  struct Child {
    int piece;
    int copy;
    float weight;
  };
  std::vector<Child> children;
};

// Labels the pieces of solid voxels in the box [lo, lo + size) of the grid
// (clipped), voxels connected when they share a corner, in scan order of
// their first voxel (x fastest). label: one entry per voxel of the clipped
// box, -1 for void. Returns the first voxel of each piece.
std::vector<std::int64_t> label_box(const int n[3], const std::vector<char>& solid, const int lo_in[3], int size,
                                    int lo[3], int dims[3], std::vector<int>& label, std::vector<int>& stack) {
  for (int a = 0; a < 3; ++a) {
    lo[a] = std::max(lo_in[a], 0);
    dims[a] = std::max(0, std::min(lo_in[a] + size, n[a]) - lo[a]);
  }
  const std::size_t volume = std::size_t(dims[0]) * dims[1] * dims[2];
  label.assign(volume, -1);
  std::vector<std::int64_t> firsts;
  const auto voxel = [&](int x, int y, int z) {
    return (lo[0] + x) + std::int64_t(n[0]) * ((lo[1] + y) + std::int64_t(n[1]) * (lo[2] + z));
  };
  for (int z = 0; z < dims[2]; ++z)
    for (int y = 0; y < dims[1]; ++y)
      for (int x = 0; x < dims[0]; ++x) {
        const std::size_t local = x + std::size_t(dims[0]) * (y + std::size_t(dims[1]) * z);
        if (label[local] >= 0 || !solid[std::size_t(voxel(x, y, z))]) continue;
        const int piece = static_cast<int>(firsts.size());
        firsts.push_back(voxel(x, y, z));
        label[local] = piece;
        stack.assign(1, static_cast<int>(local));
        while (!stack.empty()) {
          const int v = stack.back();
          stack.pop_back();
          const int vx = v % dims[0], vy = (v / dims[0]) % dims[1], vz = v / (dims[0] * dims[1]);
          for (int dz = -1; dz <= 1; ++dz)
            for (int dy = -1; dy <= 1; ++dy)
              for (int dx = -1; dx <= 1; ++dx) {
                const int wx = vx + dx, wy = vy + dy, wz = vz + dz;
                if (wx < 0 || wy < 0 || wz < 0 || wx >= dims[0] || wy >= dims[1] || wz >= dims[2]) continue;
                const int w = wx + dims[0] * (wy + dims[1] * wz);
                if (label[std::size_t(w)] >= 0 || !solid[std::size_t(voxel(wx, wy, wz))]) continue;
                label[std::size_t(w)] = piece;
                stack.push_back(w);
              }
        }
      }
  return firsts;
}

// The next coarser level of `fine` and the transfer between them.
void coarsen(const int n[3], const std::vector<char>& solid, const ComponentLevel& fine, int threads,
             ComponentLevel& coarse, ComponentTransfer& transfer) {
  const int s = fine.spacing;
  coarse.spacing = 2 * s;
  for (int a = 0; a < 3; ++a)
    coarse.points[a] = fine.points[a] / 2 + 1;  // up to the first even point at or beyond the last
  const std::int64_t points = coarse.num_points();
  std::vector<PointPieces> pieces(static_cast<std::size_t>(points));
  const int team = resolve_thread_count(threads);
#pragma omp parallel num_threads(team)
  {
    std::vector<int> label, stack;
#pragma omp for schedule(dynamic, 64)
    for (std::int64_t P = 0; P < points; ++P) {
      const int I[3] = {static_cast<int>(P % coarse.points[0]),
                        static_cast<int>((P / coarse.points[0]) % coarse.points[1]),
                        static_cast<int>(P / (std::int64_t(coarse.points[0]) * coarse.points[1]))};
      // The support of the coarse hat: one coarse spacing either side.
      const int lo_in[3] = {2 * s * (I[0] - 1), 2 * s * (I[1] - 1), 2 * s * (I[2] - 1)};
      int lo[3], dims[3];
      std::vector<std::int64_t> firsts = label_box(n, solid, lo_in, 4 * s, lo, dims, label, stack);
      PointPieces& out = pieces[std::size_t(P)];
      std::vector<int> used(firsts.size(), 0);
      for (int dz = -1; dz <= 1; ++dz)
        for (int dy = -1; dy <= 1; ++dy)
          for (int dx = -1; dx <= 1; ++dx) {
            const int q[3] = {2 * I[0] + dx, 2 * I[1] + dy, 2 * I[2] + dz};
            if (q[0] < 0 || q[1] < 0 || q[2] < 0 || q[0] >= fine.points[0] || q[1] >= fine.points[1] ||
                q[2] >= fine.points[2])
              continue;
            const float weight = (dx ? 0.5f : 1.0f) * (dy ? 0.5f : 1.0f) * (dz ? 0.5f : 1.0f);
            const std::int64_t Q = fine.point(q[0], q[1], q[2]);
            for (int c = fine.first[std::size_t(Q)]; c < fine.first[std::size_t(Q) + 1]; ++c) {
              const std::int64_t v = fine.representative[std::size_t(c)];
              if (v < 0) continue;
              const int x = static_cast<int>(v % n[0]) - lo[0], y = static_cast<int>((v / n[0]) % n[1]) - lo[1],
                        z = static_cast<int>(v / (std::int64_t(n[0]) * n[1])) - lo[2];
              if (x < 0 || y < 0 || z < 0 || x >= dims[0] || y >= dims[1] || z >= dims[2])
                throw std::logic_error("material components: a piece reaches outside its coarse support");
              const int piece = label[std::size_t(x) + std::size_t(dims[0]) * (y + std::size_t(dims[1]) * z)];
              if (piece < 0) throw std::logic_error("material components: a piece's voxel is void");
              out.children.push_back({piece, c, weight});
              used[std::size_t(piece)] = 1;
            }
          }
      // Pieces no finer copy reaches carry nothing: no copy for them.
      std::vector<int> renumber(firsts.size(), -1);
      for (std::size_t k = 0; k < firsts.size(); ++k)
        if (used[k]) {
          renumber[k] = static_cast<int>(out.representative.size());
          out.representative.push_back(firsts[k]);
        }
      for (auto& child : out.children) child.piece = renumber[std::size_t(child.piece)];
    }
  }
  coarse.first.assign(std::size_t(points) + 1, 0);
  for (std::int64_t P = 0; P < points; ++P)
    coarse.first[std::size_t(P) + 1] =
        coarse.first[std::size_t(P)] + static_cast<int>(pieces[std::size_t(P)].representative.size());
  const int copies = coarse.copies();
  coarse.representative.resize(std::size_t(copies));
  transfer.child_start.assign(std::size_t(copies) + 1, 0);
  for (std::int64_t P = 0; P < points; ++P) {
    const PointPieces& p = pieces[std::size_t(P)];
    std::copy(p.representative.begin(), p.representative.end(),
              coarse.representative.begin() + coarse.first[std::size_t(P)]);
    for (const auto& child : p.children)
      ++transfer.child_start[std::size_t(coarse.first[std::size_t(P)] + child.piece) + 1];
  }
  for (int c = 0; c < copies; ++c) transfer.child_start[std::size_t(c) + 1] += transfer.child_start[std::size_t(c)];
  transfer.child.resize(std::size_t(transfer.child_start.back()));
  transfer.child_weight.resize(transfer.child.size());
  {
    std::vector<int> cursor(transfer.child_start.begin(), transfer.child_start.end() - 1);
    for (std::int64_t P = 0; P < points; ++P)
      for (const auto& child : pieces[std::size_t(P)].children) {
        const int slot = cursor[std::size_t(coarse.first[std::size_t(P)] + child.piece)]++;
        transfer.child[std::size_t(slot)] = child.copy;
        transfer.child_weight[std::size_t(slot)] = child.weight;
      }
  }
  // The transpose, parents of each fine copy in coarse copy order.
  const int fine_copies = fine.copies();
  transfer.parent_start.assign(std::size_t(fine_copies) + 1, 0);
  for (int c : transfer.child) ++transfer.parent_start[std::size_t(c) + 1];
  for (int f = 0; f < fine_copies; ++f)
    transfer.parent_start[std::size_t(f) + 1] += transfer.parent_start[std::size_t(f)];
  transfer.parent.resize(transfer.child.size());
  transfer.parent_weight.resize(transfer.child.size());
  std::vector<int> cursor(transfer.parent_start.begin(), transfer.parent_start.end() - 1);
  for (int C = 0; C < copies; ++C)
    for (int t = transfer.child_start[std::size_t(C)]; t < transfer.child_start[std::size_t(C) + 1]; ++t) {
      const int slot = cursor[std::size_t(transfer.child[std::size_t(t)])]++;
      transfer.parent[std::size_t(slot)] = C;
      transfer.parent_weight[std::size_t(slot)] = transfer.child_weight[std::size_t(t)];
    }
}

}  // namespace

MaterialComponents::MaterialComponents(int nx, int ny, int nz, const std::vector<char>& solid, int coarse_copies,
                                       int threads)
    : n_{nx, ny, nz}, solid_(solid) {
  for (int a = 0; a < 3; ++a)
    if (n_[a] < 2 || n_[a] % 2 != 0)
      throw InputError("material components: a grid of " + std::to_string(nx) + " x " + std::to_string(ny) + " x " +
                       std::to_string(nz) + " voxels cannot be coarsened (every dimension must be even)");
  if (std::int64_t(solid_.size()) != std::int64_t(nx) * ny * nz)
    throw std::invalid_argument("MaterialComponents: one solid flag per voxel");
  if (coarse_copies < 1) throw InputError("material components: coarse_copies must be at least 1");

  // Level 0: the grid's nodes that touch a solid voxel, one copy each (in
  // node order), represented by one such voxel. Nodes only void touches get
  // no copy: the fine level carries unknowns only where there is material.
  ComponentLevel grid;
  grid.spacing = 1;
  for (int a = 0; a < 3; ++a) grid.points[a] = n_[a] + 1;
  const std::int64_t nodes = grid.num_points();
  if (nodes > (std::int64_t(1) << 31) - 1) throw InputError("material components: more than 2^31 grid nodes");
  std::vector<std::int64_t> touching(std::size_t(nodes), -1);
  chunked_for(nodes, threads, [&](Eigen::Index begin, Eigen::Index end) {
    for (Eigen::Index p = begin; p < end; ++p) {
      const int i = static_cast<int>(p % (nx + 1)), j = static_cast<int>((p / (nx + 1)) % (ny + 1)),
                k = static_cast<int>(p / (std::int64_t(nx + 1) * (ny + 1)));
      for (int a = 0; a < 8 && touching[std::size_t(p)] < 0; ++a) {
        const int vi = i - corner_x(a), vj = j - corner_y(a), vk = k - corner_z(a);
        if (vi < 0 || vj < 0 || vk < 0 || vi >= nx || vj >= ny || vk >= nz) continue;
        const std::int64_t v = vi + std::int64_t(nx) * (vj + std::int64_t(ny) * vk);
        if (solid_[std::size_t(v)]) touching[std::size_t(p)] = v;
      }
    }
  });
  grid.first.resize(std::size_t(nodes) + 1);
  grid.first[0] = 0;
  for (std::int64_t p = 0; p < nodes; ++p)
    grid.first[std::size_t(p) + 1] = grid.first[std::size_t(p)] + (touching[std::size_t(p)] >= 0 ? 1 : 0);
  grid.representative.reserve(std::size_t(grid.copies()));
  for (std::int64_t v : touching)
    if (v >= 0) grid.representative.push_back(v);
  std::vector<std::int64_t>().swap(touching);
  levels_.push_back(std::move(grid));
  for (;;) {
    const ComponentLevel& fine = levels_.back();
    ComponentLevel coarse;
    ComponentTransfer transfer;
    coarsen(n_, solid_, fine, threads, coarse, transfer);
    const bool first = levels_.size() == 1;
    const int fine_copies = first ? 0 : fine.copies();
    levels_.push_back(std::move(coarse));
    transfers_.push_back(std::move(transfer));
    const ComponentLevel& added = levels_.back();
    if (added.copies() <= coarse_copies) break;
    if (!first && 10 * std::int64_t(added.copies()) > 9 * std::int64_t(fine_copies)) break;
    if (added.points[0] <= 2 && added.points[1] <= 2 && added.points[2] <= 2) break;
  }
}

int MaterialComponents::element_copy(int i, int j, int k, int corner) const {
  if (!solid_[std::size_t(i + std::int64_t(n_[0]) * (j + std::int64_t(n_[1]) * k))]) return -1;
  // The voxel's own corner nearest the level-1 corner has that point among
  // its parents; parents are listed z, y, x outermost to innermost over the
  // node's enclosing level-1 points (one per even coordinate, two per odd).
  const int ax = corner_x(corner), ay = corner_y(corner), az = corner_z(corner);
  const int p[3] = {i + ax, j + ay, k + az};
  const int target[3] = {i / 2 + ax, j / 2 + ay, k / 2 + az};
  const ComponentLevel& grid = levels_[0];
  const ComponentLevel& level1 = levels_[1];
  const int node = grid.first[std::size_t(grid.point(p[0], p[1], p[2]))];  // its copy: the voxel is solid
  const ComponentTransfer& t = transfers_[0];
  const std::int64_t point = level1.point(target[0], target[1], target[2]);
  for (int s = t.parent_start[std::size_t(node)]; s < t.parent_start[std::size_t(node) + 1]; ++s) {
    const int c = t.parent[std::size_t(s)];
    if (c >= level1.first[std::size_t(point)] && c < level1.first[std::size_t(point) + 1]) return c;
  }
  throw std::logic_error("material components: a solid voxel's corner has no copy at its level-1 corner");
}

}  // namespace msfab
