#include "ddfem/fine_block.hpp"

#include <algorithm>
#include <cmath>
#include <sstream>

#include "core/errors.hpp"

namespace msfab {
namespace {

void check_voxel_size(const char* what, double voxel_size) {
  if (voxel_size > 0.0 && std::isfinite(voxel_size)) return;
  std::ostringstream os;
  os << what << ": voxel size must be positive and finite, got " << voxel_size;
  throw InputError(os.str());
}

}  // namespace

bool is_all_void(const BlockMaterials& ids) {
  for (int id : ids)
    if (id != 0) return false;
  return true;
}

bool is_all_solid(const BlockMaterials& ids) {
  for (int id : ids)
    if (id == 0) return false;
  return true;
}

std::string block_name(const BlockMaterials& ids) {
  std::string s = "[";
  for (int c = 0; c < 8; ++c) s += (c ? " " : "") + std::to_string(ids[c]);
  return s + "]";
}

bool FineBlock::has_all_corners() const {
  for (int n : corner_nodes)
    if (n < 0) return false;
  return true;
}

bool FineBlock::all_children_solid() const { return is_all_solid(material_ids); }

int FineBlock::child_of_element(int e) const {
  const int N = voxels_per_edge, n = N + 2 * context;
  const int v = voxels.element_voxel[e];  // x fastest
  const int i = v % n, j = (v / n) % n, k = v / (n * n);
  // Periodic copy: voxel i of the patch is voxel (i - context) mod N of the
  // block, in its lower or upper half.
  auto child = [&](int a) { return ((a - context) % N + N) % N / (N / 2); };
  return 4 * child(i) + 2 * child(j) + child(k);
}

hex8::NodeMatrix FineBlock::coarse_rest_positions() const {
  hex8::NodeMatrix X;
  for (int c = 0; c < 8; ++c) X.row(c) = edge() * Vec3(c >> 2 & 1, c >> 1 & 1, c & 1).transpose();
  return X;
}

hex8::ElementGeometry FineBlock::coarse_geometry() const {
  return hex8::element_geometry(coarse_rest_positions(), hex8::gauss_rule(coarse_points_per_axis));
}

int FineBlock::child_of_point(int q) const {
  const Vec3 chi = hex8::gauss_rule(coarse_points_per_axis).points[q];
  return 4 * (chi.x() > 0) + 2 * (chi.y() > 0) + (chi.z() > 0);
}

int FineBlock::voxel_of_point(int q) const {
  const int N = voxels_per_edge;
  const Vec3 chi = hex8::gauss_rule(coarse_points_per_axis).points[q];
  int voxel[3];
  for (int a = 0; a < 3; ++a) voxel[a] = std::min(N - 1, static_cast<int>(std::floor((chi[a] + 1) * N / 2)));
  return voxel[0] + N * (voxel[1] + N * voxel[2]);
}

int FineBlock::child_of_coarse_point(int q) {
  const Vec3 chi = hex8::gauss_rule(2).points[q];
  return 4 * (chi.x() > 0) + 2 * (chi.y() > 0) + (chi.z() > 0);
}

int FineBlock::lattice_node(int i, int j, int k) const {
  const size_t n = voxels_per_edge + 1 + 2 * size_t(context);
  return voxels.lattice_node[size_t(i + context) + n * (size_t(j + context) + n * size_t(k + context))];
}

namespace {
// A block's frame, before its voxels are set.
FineBlock empty_block(const char* what, double voxel_size, int voxels_per_edge, int coarse_points_per_axis,
                      const BlockMaterials& ids) {
  check_voxel_size(what, voxel_size);
  FineBlock block;
  block.voxel_size = voxel_size;
  block.voxels_per_edge = voxels_per_edge;
  block.coarse_points_per_axis = coarse_points_per_axis;
  block.material_ids = ids;
  block.child_material.assign(8, nullptr);
  return block;
}
}  // namespace

FineBlock make_fine_block(const BlockMaterials& ids, const std::vector<MaterialPtr>& palette, double voxel_size,
                          int coarse_points_per_axis, int context) {
  if (context < 0 || context > 4) {
    std::ostringstream os;
    os << "fine block: context must be 0 (isolated) to 4 voxels, got " << context;
    throw InputError(os.str());
  }
  if (coarse_points_per_axis != 2 && coarse_points_per_axis != 4)
    throw InputError("fine block: the coarse element takes 2 or 4 Gauss points per axis");
  FineBlock block = empty_block("fine block", voxel_size, 2, coarse_points_per_axis, ids);
  block.context = context;
  const int n = 2 + 2 * context;
  VoxelGrid grid(n, n, n, voxel_size, 0);
  grid.origin = Vec3::Constant(-context * voxel_size);
  bool any_solid = false;
  for (int c = 0; c < 8; ++c) {
    const int id = ids[c];
    if (id < 0 || id >= static_cast<int>(palette.size())) {
      std::ostringstream os;
      os << "fine block: material id " << id << " of child " << c << " is outside the palette (size " << palette.size()
         << ")";
      throw InputError(os.str());
    }
    if (id == 0) continue;
    if (!palette[id]) {
      std::ostringstream os;
      os << "fine block: palette entry " << id << " (child " << c << ") has no material";
      throw InputError(os.str());
    }
    any_solid = true;
    block.child_material[c] = palette[id];
  }
  if (!any_solid) throw InputError("fine block: all eight children are void");
  auto child = [&](int a) { return ((a - context) % 2 + 2) % 2; };
  for (int k = 0; k < n; ++k)
    for (int j = 0; j < n; ++j)
      for (int i = 0; i < n; ++i) grid.at(i, j, k) = ids[4 * child(i) + 2 * child(j) + child(k)];
  block.voxels = build_voxel_mesh(grid, palette);
  const HexMesh& mesh = block.voxels.mesh;
  block.core_element.assign(mesh.num_elements(), 0);
  for (int e = 0; e < mesh.num_elements(); ++e) {
    const int v = block.voxels.element_voxel[e];
    const int i = v % n - context, j = (v / n) % n - context, k = v / (n * n) - context;
    block.core_element[e] = i >= 0 && i < 2 && j >= 0 && j < 2 && k >= 0 && k < 2;
  }
  for (int c = 0; c < 8; ++c)
    block.corner_nodes[c] = block.lattice_node(2 * (c >> 2 & 1), 2 * (c >> 1 & 1), 2 * (c & 1));
  for (int q = 0; q < block.coarse_points(); ++q) {
    const MaterialPtr& m = block.child_material[block.child_of_point(q)];
    block.point_mu0.push_back(m ? m->shear_modulus() : 0.0);
    block.point_lambda0.push_back(m ? m->lame_lambda() : 0.0);
  }
  return block;
}

FineBlock make_voxel_block(const std::vector<int>& voxel_ids, const std::vector<MaterialPtr>& palette,
                           double voxel_size, const BlockMaterials& label) {
  constexpr int N = 4;
  if (voxel_ids.size() != size_t(N * N * N)) {
    std::ostringstream os;
    os << "voxel block: needs " << N * N * N << " voxel ids, got " << voxel_ids.size();
    throw InputError(os.str());
  }
  FineBlock block = empty_block("voxel block", voxel_size, N, N, label);
  VoxelGrid grid(N, N, N, voxel_size, 0);
  bool any_solid = false;
  for (int v = 0; v < N * N * N; ++v) {
    const int id = voxel_ids[v];
    if (id < 0 || id >= static_cast<int>(palette.size()) || (id != 0 && !palette[id])) {
      std::ostringstream os;
      os << "voxel block: material id " << id << " of voxel " << v << " is not in the palette (size " << palette.size()
         << ")";
      throw InputError(os.str());
    }
    any_solid = any_solid || id != 0;
    grid.at(v % N, (v / N) % N, v / (N * N)) = id;
  }
  if (!any_solid) throw InputError("voxel block: every voxel is void");
  block.voxels = build_voxel_mesh(grid, palette);
  block.core_element.assign(block.mesh().num_elements(), 1);
  for (int c = 0; c < 8; ++c)
    block.corner_nodes[c] = block.lattice_node(N * (c >> 2 & 1), N * (c >> 1 & 1), N * (c & 1));
  // One Gauss point in each voxel: the 4-point rule's abscissae lie one in
  // each quarter of [-1, 1].
  for (int q = 0; q < block.coarse_points(); ++q) {
    const int id = voxel_ids[block.voxel_of_point(q)];
    block.point_mu0.push_back(id ? palette[id]->shear_modulus() : 0.0);
    block.point_lambda0.push_back(id ? palette[id]->lame_lambda() : 0.0);
  }
  return block;
}

}  // namespace msfab
