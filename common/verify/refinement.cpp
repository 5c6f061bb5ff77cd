#include "verify/refinement.hpp"

#include <algorithm>
#include <array>
#include <cmath>

#include "core/errors.hpp"
#include "verify/solid_pieces.hpp"

namespace msfab {

namespace {

CellGrid refined_grid(const CellGrid& coarse, int r) {
  if (coarse.dimension() != 3) throw InputError("the full-resolution model needs a 3D grid");
  if (r < 1) throw InputError("voxels per cell must be >= 1");
  return CellGrid(3, coarse.nx() * r, coarse.ny() * r, coarse.nz() * r, coarse.h() / r);
}

struct Weighted {
  std::int64_t node;
  double weight;
};

}  // namespace

CellRefinement::CellRefinement(const CellGrid& coarse, int resolution)
    : coarse_(coarse), fine_(refined_grid(coarse, resolution)), r_(resolution) {}

std::int64_t CellRefinement::fine_node_of(std::int64_t coarse_node) const {
  const auto c = coarse_.node_coords(coarse_node);
  return fine_.node_index(c[0] * r_, c[1] * r_, c[2] * r_);
}

CellRefinement::Entity CellRefinement::entity(std::int64_t fine_node) const {
  const auto f = fine_.node_coords(fine_node);
  int q[3], spanned[3], n_spanned = 0;
  double t[3];
  for (int a = 0; a < 3; ++a) {
    q[a] = f[a] / r_;
    const int m = f[a] % r_;
    t[a] = double(m) / r_;
    if (m != 0) spanned[n_spanned++] = a;
  }
  Entity e;
  e.corners = 1 << n_spanned;
  for (int b = 0; b < e.corners; ++b) {
    int c[3] = {q[0], q[1], q[2]};
    double w = 1.0;
    for (int s = 0; s < n_spanned; ++s) {
      const int a = spanned[s];
      const bool upper = (b >> s) & 1;
      c[a] += upper ? 1 : 0;
      w *= upper ? t[a] : 1.0 - t[a];
    }
    e.node[b] = coarse_.node_index(c[0], c[1], c[2]);
    e.weight[b] = w;
  }
  return e;
}

std::vector<char> CellRefinement::material_nodes(const std::vector<char>& voxel_material) const {
  if (std::int64_t(voxel_material.size()) != fine_.cells())
    throw std::invalid_argument("material_nodes: one flag per fine cell");
  return solid_nodes(fine_, voxel_material);
}

bool CellRefinement::on_faces_of(std::int64_t coarse_node, std::int64_t fine_node) const {
  const auto c = coarse_.node_coords(coarse_node);
  const auto f = fine_.node_coords(fine_node);
  const int n[3] = {coarse_.nx(), coarse_.ny(), coarse_.nz()};
  bool on_boundary = false;
  for (int a = 0; a < 3; ++a) {
    if (c[a] == 0 || c[a] == n[a]) {
      on_boundary = true;
      if (f[a] == c[a] * r_) return true;
    }
  }
  return !on_boundary;
}

std::vector<std::int64_t> CellRefinement::nearest_material(std::int64_t coarse_node,
                                                           const std::vector<char>& node_material,
                                                           int max_distance) const {
  const std::int64_t p = fine_node_of(coarse_node);
  if (node_material[std::size_t(p)]) return {p};
  const auto c = fine_.node_coords(p);
  const int N[3] = {fine_.nx(), fine_.ny(), fine_.nz()};
  std::vector<std::int64_t> out;
  for (int d = 1; d <= max_distance && out.empty(); ++d) {
    int lo[3], hi[3];
    for (int a = 0; a < 3; ++a) lo[a] = std::max(0, c[a] - d), hi[a] = std::min(N[a], c[a] + d);
    for (int k = lo[2]; k <= hi[2]; ++k)
      for (int j = lo[1]; j <= hi[1]; ++j)
        for (int i = lo[0]; i <= hi[0]; ++i) {
          const int dist = std::max({std::abs(i - c[0]), std::abs(j - c[1]), std::abs(k - c[2])});
          if (dist != d) continue;
          const std::int64_t x = fine_.node_index(i, j, k);
          if (node_material[std::size_t(x)] && on_faces_of(coarse_node, x)) out.push_back(x);
        }
  }
  return out;
}

CellRefinement::Supports CellRefinement::refine_supports(const std::vector<char>& coarse_fixed,
                                                         const std::vector<char>& node_material) const {
  if (std::int64_t(coarse_fixed.size()) != coarse_.unknowns())
    throw std::invalid_argument("refine_supports: one flag per coarse unknown");
  Supports s;
  s.fixed.assign(std::size_t(fine_.unknowns()), 0);
  std::vector<Eigen::Triplet<double, int>> triplets;
  for (std::int64_t x = 0; x < fine_.nodes(); ++x) {
    const Entity e = entity(x);
    for (int a = 0; a < 3; ++a) {
      bool all = true;
      for (int b = 0; b < e.corners && all; ++b) all = coarse_fixed[std::size_t(e.node[b] * 3 + a)] != 0;
      if (!all) continue;
      s.fixed[std::size_t(x * 3 + a)] = 1;
      for (int b = 0; b < e.corners; ++b)
        if (e.weight[b] != 0) triplets.emplace_back(int(x * 3 + a), int(e.node[b] * 3 + a), e.weight[b]);
    }
  }
  // A point support on a fine node that only void touches would hold
  // nothing: the solid next to it would float on the void's stiffness.
  const int n[3] = {coarse_.nx(), coarse_.ny(), coarse_.nz()};
  for (std::int64_t cn = 0; cn < coarse_.nodes(); ++cn) {
    const auto c = coarse_.node_coords(cn);
    for (int a = 0; a < 3; ++a) {
      if (!coarse_fixed[std::size_t(cn * 3 + a)]) continue;
      bool alone = true;
      for (int axis = 0; axis < 3 && alone; ++axis)
        for (int step : {-1, 1}) {
          int q[3] = {c[0], c[1], c[2]};
          q[axis] += step;
          if (q[axis] < 0 || q[axis] > n[axis]) continue;
          if (coarse_fixed[std::size_t(coarse_.node_index(q[0], q[1], q[2]) * 3 + a)]) alone = false;
        }
      if (!alone) continue;
      ++s.point_supports;
      if (node_material[std::size_t(fine_node_of(cn))]) continue;
      const std::vector<std::int64_t> near = nearest_material(cn, node_material, r_ / 2);
      if (near.empty()) {
        ++s.lost_point_supports;
        continue;
      }
      ++s.moved_point_supports;
      for (std::int64_t x : near) {
        if (s.fixed[std::size_t(x * 3 + a)]) continue;
        s.fixed[std::size_t(x * 3 + a)] = 1;
        triplets.emplace_back(int(x * 3 + a), int(cn * 3 + a), 1.0);
      }
    }
  }
  s.values.resize(fine_.unknowns(), coarse_.unknowns());
  s.values.setFromTriplets(triplets.begin(), triplets.end());
  return s;
}

VecX CellRefinement::refine_forces(const VecX& coarse_force, const std::vector<char>& node_material,
                                   const std::string& what, LoadStats* stats) const {
  if (coarse_force.size() != coarse_.unknowns())
    throw std::invalid_argument("refine_forces: one entry per coarse unknown");
  LoadStats st;
  std::vector<char> loaded(std::size_t(coarse_.nodes()), 0);
  for (std::int64_t cn = 0; cn < coarse_.nodes(); ++cn)
    loaded[std::size_t(cn)] = coarse_force.segment(cn * 3, 3).squaredNorm() > 0 ? 1 : 0;
  const int N[3] = {fine_.nx(), fine_.ny(), fine_.nz()};
  auto in_loaded_region = [&](int i, int j, int k) {
    if (i < 0 || j < 0 || k < 0 || i > N[0] || j > N[1] || k > N[2]) return false;
    const Entity e = entity(fine_.node_index(i, j, k));
    for (int b = 0; b < e.corners; ++b)
      if (!loaded[std::size_t(e.node[b])]) return false;
    return true;
  };
  // The trapezoid rule's weight of a fine node in the loaded region: halved
  // along every axis where the region ends at the node, so a coarse load
  // that is the consistent load of a uniform traction becomes (up to
  // lumping) the same uniform traction on the fine nodes.
  auto trapezoid = [&](int i, int j, int k) {
    double m = 1.0;
    for (int a = 0; a < 3; ++a) {
      int lo[3] = {i, j, k}, hi[3] = {i, j, k};
      --lo[a], ++hi[a];
      if (in_loaded_region(lo[0], lo[1], lo[2]) != in_loaded_region(hi[0], hi[1], hi[2])) m *= 0.5;
    }
    return m;
  };
  VecX fine_force = VecX::Zero(fine_.unknowns());
  std::vector<char> received(std::size_t(fine_.nodes()), 0);
  std::vector<Weighted> footprint, patch, volume;
  for (std::int64_t cn = 0; cn < coarse_.nodes(); ++cn) {
    if (!loaded[std::size_t(cn)]) continue;
    ++st.loaded_nodes;
    const std::int64_t p = fine_node_of(cn);
    const auto c = fine_.node_coords(p);
    footprint.clear(), patch.clear(), volume.clear();
    // The hat function's support: fine nodes less than one cell away.
    int lo[3], hi[3];
    for (int a = 0; a < 3; ++a) lo[a] = std::max(0, c[a] - r_ + 1), hi[a] = std::min(N[a], c[a] + r_ - 1);
    bool only_own_node = true;
    for (int k = lo[2]; k <= hi[2]; ++k)
      for (int j = lo[1]; j <= hi[1]; ++j)
        for (int i = lo[0]; i <= hi[0]; ++i) {
          const std::int64_t x = fine_.node_index(i, j, k);
          const double w = (1.0 - std::abs(i - c[0]) / double(r_)) * (1.0 - std::abs(j - c[1]) / double(r_)) *
                           (1.0 - std::abs(k - c[2]) / double(r_));
          const Entity e = entity(x);
          bool all_loaded = true;
          for (int b = 0; b < e.corners && all_loaded; ++b) all_loaded = loaded[std::size_t(e.node[b])] != 0;
          const bool material = node_material[std::size_t(x)] != 0;
          if (all_loaded) {
            if (x != p) only_own_node = false;
            if (material) footprint.push_back({x, w * trapezoid(i, j, k)});
          }
          if (material && on_faces_of(cn, x)) patch.push_back({x, w});
          if (material) volume.push_back({x, w});
        }
    const std::vector<Weighted>* use = &footprint;
    if (only_own_node) {
      ++st.point_loads;
      use = &patch;
    }
    if (use->empty() && use != &patch) use = &patch, ++st.fallbacks;
    if (use->empty()) use = &volume, ++st.fallbacks;
    if (use->empty()) {
      const auto q = coarse_.node_coords(cn);
      throw InputError(what + ": the force at grid node [" + std::to_string(q[0]) + ", " + std::to_string(q[1]) + ", " +
                       std::to_string(q[2]) + "] finds no material within one cell in the full-resolution model");
    }
    double total = 0;
    for (const Weighted& x : *use) total += x.weight;
    const Vec3 F = coarse_force.segment<3>(cn * 3);
    for (const Weighted& x : *use) {
      fine_force.segment<3>(x.node * 3) += (x.weight / total) * F;
      received[std::size_t(x.node)] = 1;
    }
  }
  st.fine_nodes = std::count(received.begin(), received.end(), char(1));
  if (stats) *stats = st;
  return fine_force;
}

}  // namespace msfab
