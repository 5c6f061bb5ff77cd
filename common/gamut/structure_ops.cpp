#include "gamut/structure_ops.hpp"

#include <algorithm>
#include <cstdlib>
#include <map>
#include <string>
#include <vector>

#include "core/errors.hpp"

namespace msfab {
namespace {

bool is_2d(const VoxelGrid& c) { return c.nz == 1; }

void require_symmetric_shape(const VoxelGrid& c) {
  if (c.nx != c.ny || (c.nz != c.nx && c.nz != 1))
    throw InputError("cubic symmetry needs a cubic (n x n x n) or square (n x n x 1) cell, got " +
                     std::to_string(c.nx) + " x " + std::to_string(c.ny) + " x " + std::to_string(c.nz));
}

// Face-connected pieces of voxels for which `member` holds; for each, the
// set of axes along which it wraps around the periodic cell. A piece wraps
// along an axis when a voxel is reached twice with unwrapped positions
// that differ along that axis. With periodic false, voxels connect only
// inside the cell (what a cell next to another structure keeps); no piece
// then wraps.
struct Pieces {
  std::vector<int> piece;                  // per voxel, -1 if not a member
  std::vector<std::array<bool, 3>> wraps;  // per piece
  std::vector<int> size;
};
template <class Member>
Pieces face_pieces(const VoxelGrid& c, Member member, bool periodic = true) {
  const int dims = is_2d(c) ? 2 : 3;
  const int n[3] = {c.nx, c.ny, c.nz};
  Pieces p;
  p.piece.assign(c.size(), -1);
  std::vector<std::array<int, 3>> offset(c.size());  // unwrapped cell shift of each visited voxel
  std::vector<int> stack;
  for (std::size_t start = 0; start < c.size(); ++start) {
    if (p.piece[start] >= 0 || !member(c.ids[start])) continue;
    const int id = static_cast<int>(p.wraps.size());
    p.wraps.push_back({false, false, false});
    p.size.push_back(0);
    p.piece[start] = id;
    offset[start] = {0, 0, 0};
    stack.assign(1, static_cast<int>(start));
    while (!stack.empty()) {
      const int v = stack.back();
      stack.pop_back();
      ++p.size[id];
      const int idx[3] = {v % c.nx, (v / c.nx) % c.ny, v / (c.nx * c.ny)};
      for (int a = 0; a < dims; ++a)
        for (int step : {-1, 1}) {
          int q[3] = {idx[0], idx[1], idx[2]};
          std::array<int, 3> off = offset[v];
          q[a] += step;
          if (q[a] < 0 || q[a] >= n[a]) {
            if (!periodic) continue;
            off[a] += q[a] < 0 ? -1 : 1;
          }
          q[a] = wrap_periodic(q[a], n[a]);
          const int w = static_cast<int>(c.index(q[0], q[1], q[2]));
          if (!member(c.ids[w])) continue;
          if (p.piece[w] < 0) {
            p.piece[w] = id;
            offset[w] = off;
            stack.push_back(w);
          } else {
            for (int b = 0; b < 3; ++b)
              if (offset[w][b] != off[b]) p.wraps[id][b] = true;
          }
        }
    }
  }
  return p;
}

}  // namespace

std::array<int, 3> fundamental_voxel(const VoxelGrid& c, int i, int j, int k, CellSymmetry symmetry) {
  std::array<int, 3> f{std::min(i, c.nx - 1 - i), std::min(j, c.ny - 1 - j), std::min(k, c.nz - 1 - k)};
  if (symmetry == CellSymmetry::orthotropic) return f;
  if (is_2d(c)) {
    if (f[0] > f[1]) std::swap(f[0], f[1]);
  } else {
    std::sort(f.begin(), f.end());
  }
  return f;
}

void mirror_fundamental_domain(VoxelGrid& c, CellSymmetry symmetry) {
  if (symmetry == CellSymmetry::cubic) require_symmetric_shape(c);
  for (int k = 0; k < c.nz; ++k)
    for (int j = 0; j < c.ny; ++j)
      for (int i = 0; i < c.nx; ++i) {
        const auto f = fundamental_voxel(c, i, j, k, symmetry);
        c.at(i, j, k) = c.at(f[0], f[1], f[2]);
      }
}

bool has_symmetry(const VoxelGrid& c, CellSymmetry symmetry) {
  if (symmetry == CellSymmetry::cubic && (c.nx != c.ny || (c.nz != c.nx && c.nz != 1))) return false;
  for (int k = 0; k < c.nz; ++k)
    for (int j = 0; j < c.ny; ++j)
      for (int i = 0; i < c.nx; ++i) {
        const auto f = fundamental_voxel(c, i, j, k, symmetry);
        if (c.at(i, j, k) != c.at(f[0], f[1], f[2])) return false;
      }
  return true;
}

bool has_cubic_symmetry(const VoxelGrid& c) { return has_symmetry(c, CellSymmetry::cubic); }

int paint_beam(VoxelGrid& c, const Vec3& a, const Vec3& b, double radius, int id) {
  const Vec3 ab = b - a;
  const double len2 = ab.squaredNorm();
  int changed = 0;
  for (int k = 0; k < c.nz; ++k)
    for (int j = 0; j < c.ny; ++j)
      for (int i = 0; i < c.nx; ++i) {
        const Vec3 x(i + 0.5, j + 0.5, k + 0.5);
        const double t = len2 > 0 ? std::clamp((x - a).dot(ab) / len2, 0.0, 1.0) : 0.0;
        if ((x - (a + t * ab)).norm() <= radius && c.at(i, j, k) != id) {
          c.at(i, j, k) = id;
          ++changed;
        }
      }
  return changed;
}

std::vector<std::uint8_t> face_connector(const VoxelGrid& c, int half_width, int depth) {
  const bool flat = is_2d(c);
  if (c.nx != c.ny || (!flat && c.nz != c.nx))
    throw InputError("face connector: the cell must be cubic (or square in 2D)");
  const int n = c.nx;
  if (half_width < 1 || depth < 1 || 2 * half_width > n || 2 * depth > n)
    throw InputError("face connector: need half_width >= 1, depth >= 1, both at most half the cell (" +
                     std::to_string(n) + " voxels)");
  // |2i + 1 - n| < 2w: the 2w central indices (odd n: 2w - 1).
  auto central = [&](int i) { return std::abs(2 * i + 1 - n) < 2 * half_width; };
  auto outer = [&](int i) { return i < depth || i >= n - depth; };
  std::vector<std::uint8_t> mask(c.size(), 0);
  for (int k = 0; k < c.nz; ++k)
    for (int j = 0; j < c.ny; ++j)
      for (int i = 0; i < c.nx; ++i) {
        const bool on = flat ? (outer(i) && central(j)) || (outer(j) && central(i))
                             : (outer(i) && central(j) && central(k)) || (outer(j) && central(i) && central(k)) ||
                                   (outer(k) && central(i) && central(j));
        mask[c.index(i, j, k)] = on;
      }
  return mask;
}

int add_axis_backbone(VoxelGrid& c, int half_width) {
  const bool flat = is_2d(c);
  if (c.nx != c.ny || (!flat && c.nz != c.nx))
    throw InputError("axis backbone: the cell must be cubic (or square in 2D)");
  const int n = c.nx;
  if (half_width < 1 || 2 * half_width > n)
    throw InputError("axis backbone: half_width must be 1.." + std::to_string(n / 2) + " voxels");
  auto central = [&](int i) { return std::abs(2 * i + 1 - n) < 2 * half_width; };
  int changed = 0;
  std::size_t a_beam_voxel = 0;
  for (int k = 0; k < c.nz; ++k)
    for (int j = 0; j < c.ny; ++j)
      for (int i = 0; i < c.nx; ++i) {
        const bool on = flat ? central(i) || central(j)
                             : (central(j) && central(k)) || (central(i) && central(k)) || (central(i) && central(j));
        if (!on) continue;
        const std::size_t v = c.index(i, j, k);
        a_beam_voxel = v;
        if (c.ids[v] != 1) c.ids[v] = 1, ++changed;
      }
  // Joined to the beams through faces inside the cell, not across its
  // periodic boundary: in a mapped object the neighbour across a face is
  // another structure, so material joined to the backbone only through the
  // cell's own periodic image would float there. The three beams cross at
  // the centre, so they are one piece.
  const Pieces solid = face_pieces(
      c, [](int id) { return id != 0; }, false);
  const int backbone = solid.piece[a_beam_voxel];
  for (std::size_t v = 0; v < c.size(); ++v)
    if (solid.piece[v] >= 0 && solid.piece[v] != backbone) c.ids[v] = 0, ++changed;
  return changed;
}

CleanupReport clean_structure(VoxelGrid& c) {
  CleanupReport report;
  const int dims = is_2d(c) ? 2 : 3;
  // 1. Solid pieces that do not wrap along every axis carry no load.
  const Pieces solid = face_pieces(c, [](int id) { return id != 0; });
  for (std::size_t v = 0; v < c.size(); ++v) {
    const int p = solid.piece[v];
    if (p < 0) continue;
    bool all = true;
    for (int a = 0; a < dims; ++a) all &= solid.wraps[p][a];
    if (!all) c.ids[v] = 0, ++report.removed_voxels;
  }
  // 2. Void pieces that wrap along no axis are enclosed cavities (3D only:
  // in a 2D cell every hole of a lattice is enclosed, and holes are what a
  // 2D structure is made of).
  if (dims == 2) return report;
  const Pieces cavity = face_pieces(c, [](int id) { return id == 0; });
  std::vector<std::map<int, int>> around(cavity.wraps.size());
  std::vector<bool> enclosed(cavity.wraps.size());
  for (std::size_t p = 0; p < cavity.wraps.size(); ++p) {
    bool any = false;
    for (int a = 0; a < dims; ++a) any |= cavity.wraps[p][a];
    enclosed[p] = !any;
  }
  const int n[3] = {c.nx, c.ny, c.nz};
  for (std::size_t v = 0; v < c.size(); ++v) {
    const int p = cavity.piece[v];
    if (p < 0 || !enclosed[p]) continue;
    const int idx[3] = {int(v % c.nx), int((v / c.nx) % c.ny), int(v / (std::size_t(c.nx) * c.ny))};
    for (int a = 0; a < dims; ++a)
      for (int step : {-1, 1}) {
        int q[3] = {idx[0], idx[1], idx[2]};
        q[a] = wrap_periodic(q[a] + step, n[a]);
        const int id = c.at(q[0], q[1], q[2]);
        if (id != 0) ++around[p][id];
      }
  }
  for (std::size_t v = 0; v < c.size(); ++v) {
    const int p = cavity.piece[v];
    if (p < 0 || !enclosed[p] || around[p].empty()) continue;
    const auto best = std::max_element(around[p].begin(), around[p].end(),
                                       [](const auto& x, const auto& y) { return x.second < y.second; });
    c.ids[v] = best->first;
    ++report.filled_voxels;
  }
  return report;
}

std::int64_t thin_feature_voxels(const VoxelGrid& c, int width) {
  if (width <= 1) return 0;
  const int wz = is_2d(c) ? 1 : width;
  if (width > c.nx || width > c.ny || wz > c.nz) return static_cast<std::int64_t>(c.size());
  std::vector<std::uint8_t> covered(c.size(), 0);
  // Each window origin whose window is uniformly solid or uniformly void
  // covers its voxels.
  for (int k = 0; k < c.nz; ++k)
    for (int j = 0; j < c.ny; ++j)
      for (int i = 0; i < c.nx; ++i) {
        const bool solid = c.at(i, j, k) != 0;
        bool uniform = true;
        for (int dk = 0; dk < wz && uniform; ++dk)
          for (int dj = 0; dj < width && uniform; ++dj)
            for (int di = 0; di < width && uniform; ++di)
              uniform = (c.at(wrap_periodic(i + di, c.nx), wrap_periodic(j + dj, c.ny), wrap_periodic(k + dk, c.nz)) !=
                         0) == solid;
        if (!uniform) continue;
        for (int dk = 0; dk < wz; ++dk)
          for (int dj = 0; dj < width; ++dj)
            for (int di = 0; di < width; ++di)
              covered[c.index(wrap_periodic(i + di, c.nx), wrap_periodic(j + dj, c.ny), wrap_periodic(k + dk, c.nz))] =
                  1;
      }
  std::int64_t thin = 0;
  for (std::uint8_t v : covered) thin += v == 0;
  return thin;
}

}  // namespace msfab
