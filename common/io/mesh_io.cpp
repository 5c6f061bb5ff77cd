#include "io/mesh_io.hpp"

#include "core/errors.hpp"
#include "io/xdmf.hpp"

namespace msfab {

void write_hex_mesh(H5File& file, const std::string& group, const HexMesh& mesh) {
  using IntRows = Eigen::Matrix<int, Eigen::Dynamic, 8, Eigen::RowMajor>;
  IntRows conn(mesh.num_elements(), 8);
  for (int e = 0; e < mesh.num_elements(); ++e)
    for (int i = 0; i < 8; ++i) conn(e, i) = mesh.elements[e][i];
  H5WriteOptions big;
  big.gzip_level = mesh.num_elements() > 4096 ? 4 : 0;
  file.write_matrix(group + "/nodes", mesh.nodes, big);
  file.write_attribute(group + "/nodes", "units", "m");
  file.write_matrix(group + "/elements", conn, big);
  file.write_matrix(group + "/elements_vtk", hex_connectivity_to_vtk_order(conn), big);
  file.write_vector(group + "/element_tag", mesh.element_tag, big);
}

StoredHexMesh read_hex_mesh(const H5File& file, const std::string& group) {
  StoredHexMesh m;
  const auto nodes = file.read_matrix<double>(group + "/nodes", 3);
  m.nodes = nodes;
  const auto conn = file.read_matrix<int>(group + "/elements", 8);
  m.elements.resize(conn.rows());
  for (int e = 0; e < conn.rows(); ++e)
    for (int i = 0; i < 8; ++i) {
      const int n = conn(e, i);
      if (n < 0 || n >= nodes.rows())
        throw InputError(file.path() + ": " + group + "/elements references node " + std::to_string(n) +
                         " but there are " + std::to_string(nodes.rows()) + " nodes");
      m.elements[e][i] = n;
    }
  m.element_tag = file.read_vector<int>(group + "/element_tag");
  return m;
}

}  // namespace msfab
