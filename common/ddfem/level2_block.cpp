#include "ddfem/level2_block.hpp"

#include <sstream>
#include <stdexcept>

#include "core/errors.hpp"
#include "material/neo_hookean.hpp"

namespace msfab {

int level1_point_of(int q, int* child) {
  const Vec3 chi = hex8::gauss_rule(4).points[q];
  int c = 0, k = 0;
  for (int a = 0; a < 3; ++a) {
    const int upper = chi[a] > 0;
    // The child spans [-1, 0] or [0, 1]; its local coordinate in [-1, 1].
    const double local = 2.0 * chi[a] + (upper ? -1.0 : 1.0);
    c = 2 * c + upper;
    k = 2 * k + (local > 0);
  }
  *child = c;
  return k;
}

std::vector<int> level2_voxel_ids(const std::array<const CoarseMaterialFit*, 8>& children) {
  std::vector<int> ids(64, 0);
  for (int c = 0; c < 8; ++c) {
    if (!children[c]) continue;
    for (int v = 0; v < 8; ++v) {
      // Child c and its voxel v both in hex8 bit order (x is bit 2).
      const int i = 2 * (c >> 2 & 1) + (v >> 2 & 1), j = 2 * (c >> 1 & 1) + (v >> 1 & 1), k = 2 * (c & 1) + (v & 1);
      ids[i + 4 * (j + 4 * k)] = children[c]->material_ids[v];
    }
  }
  return ids;
}

FineBlock make_block_of_coarse_materials(const std::array<const CoarseMaterialFit*, 8>& children,
                                         const BlockMaterials& ids, double child_size, int context) {
  BlockMaterials shape{};  // 1 where a child has an element
  for (int c = 0; c < 8; ++c) {
    if (!children[c]) {
      if (ids[c] != 0) throw std::invalid_argument("level-2 block: a void child needs id 0");
      continue;
    }
    if (!children[c]->fitted || children[c]->points() != 8) {
      std::ostringstream os;
      os << "level-2 block: child " << c << " is not a fitted level-1 coarse material";
      throw InputError(os.str());
    }
    shape[c] = 1;
  }
  if (is_all_void(shape)) throw InputError("level-2 block: all eight children are void");
  // Geometry and topology of a 2 x 2 x 2 voxel block (void children left
  // out); the materials are replaced by the children's fitted ones below.
  const std::vector<MaterialPtr> shape_only = {nullptr, std::make_shared<NeoHookean>(1.0, 0.3)};
  FineBlock block = make_fine_block(shape, shape_only, child_size, 4, context);
  block.material_ids = ids;
  block.child_material.assign(8, nullptr);
  HexMesh& mesh = block.voxels.mesh;
  mesh.materials.clear();
  // One entry per child (a void child's is never referenced).
  for (int c = 0; c < 8; ++c)
    mesh.materials.push_back(children[c] ? coarse_quadrature_materials(*children[c]) : QuadratureMaterials{});
  // Children fitted with a centre term need the element centre as a ninth
  // point: geometry 1 (all elements are the same cube).
  // Children fitted for the element with bubble modes are that element here too.
  bool enhanced = false;
  for (int c = 0; c < 8; ++c) enhanced = enhanced || (children[c] && children[c]->enhanced);
  if (enhanced)
    mesh.geometries.at(0) = hex8::enhanced_element_geometry(mesh.element_rest_positions(0), hex8::gauss_rule(2));
  const hex8::ElementGeometry gauss = mesh.geometries.at(0);
  mesh.geometries.push_back(hex8::with_centre_point(gauss, mesh.element_rest_positions(0)));
  for (int e = 0; e < mesh.num_elements(); ++e) {
    const int c = block.child_of_element(e);
    mesh.element_material[e] = c;
    mesh.element_tag[e] = ids[c];
    mesh.element_geometry[e] = mesh.materials[c].at_point.size() == gauss.weight.size() ? 0 : 1;
  }
  for (int q = 0; q < block.coarse_points(); ++q) {
    int c = 0;
    const int k = level1_point_of(q, &c);
    block.point_mu0[q] = children[c] ? children[c]->mu0[k] : 0.0;
    block.point_lambda0[q] = children[c] ? children[c]->lambda0[k] : 0.0;
  }
  return block;
}

}  // namespace msfab
