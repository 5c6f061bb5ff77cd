#pragma once
// XDMF sidecars so ParaView opens hex-mesh results stored in an artifact:
// the .xmf file holds only XML that points at datasets in the .h5 file.
#include <Eigen/Core>
#include <array>
#include <cstddef>
#include <stdexcept>
#include <string>
#include <vector>

#include "io/hdf5_file.hpp"

namespace msfab {

// Hex node numbering. The toolkit numbers the corners of a hexahedron as in
// thesis Table 2.1 (xi slowest, zeta fastest):
//   node = 4*x + 2*y + z   for the corner (x, y, z) of the unit cube.
// VTK/XDMF "Hexahedron" wants the bottom face counter-clockwise, then the top:
//   (0,0,0) (1,0,0) (1,1,0) (0,1,0)  (0,0,1) (1,0,1) (1,1,1) (0,1,1).
// kToolkitNodeAtVtkCorner[v] is the toolkit node that goes to VTK position v.
inline constexpr std::array<int, 8> kToolkitNodeAtVtkCorner = {0, 4, 6, 2, 1, 5, 7, 3};

// Reorders an (n_elems, 8) connectivity from toolkit order to VTK order.
template <class Derived>
typename Derived::PlainObject hex_connectivity_to_vtk_order(const Eigen::MatrixBase<Derived>& toolkit) {
  if (toolkit.cols() != 8) {
    throw std::invalid_argument("hex connectivity needs 8 columns, got " + std::to_string(toolkit.cols()));
  }
  typename Derived::PlainObject vtk(toolkit.rows(), toolkit.cols());
  for (int v = 0; v < 8; ++v) vtk.col(v) = toolkit.col(kToolkitNodeAtVtkCorner[v]);
  return vtk;
}

// The sidecar of an artifact: "x.h5" -> "x.xmf" (any other name gets
// ".xmf" appended), and the artifact's file name as the sidecar refers to it.
std::string xdmf_sidecar_path(const std::string& h5_path);
std::string file_name_of(const std::string& path);

// A field on nodes or cells. The dataset has shape (n) for a scalar or
// (n, components) otherwise.
struct XdmfField {
  std::string name;     // as shown in ParaView
  std::string dataset;  // HDF5 path, e.g. "/displacement"
  int components = 1;   // 1 scalar, 3 vector, 6 symmetric tensor, 9 tensor
  H5Dtype dtype = H5Dtype::kFloat64;
};

struct XdmfHexMesh {
  std::string h5_file;               // relative to the .xmf's folder, e.g. "result.h5"
  std::string nodes_dataset;         // (n_nodes, 3) float64
  std::string connectivity_dataset;  // (n_elems, 8), VTK corner order (see above)
  std::size_t n_nodes = 0;
  std::size_t n_elems = 0;
  H5Dtype connectivity_dtype = H5Dtype::kInt32;
};

// One grid with the given node and cell fields. Written atomically
// (io/atomic_file.hpp); throws std::runtime_error on I/O failure and
// std::invalid_argument for an unsupported component count.
void write_hex_mesh_xdmf(const std::string& xmf_path, const XdmfHexMesh& mesh,
                         const std::vector<XdmfField>& node_fields, const std::vector<XdmfField>& cell_fields);

struct XdmfTimeStep {
  double time = 0.0;
  std::vector<XdmfField> node_fields;
  std::vector<XdmfField> cell_fields;
};

// A temporal collection: one grid per step, every step pointing at the same
// node and connectivity datasets (nothing is duplicated in the .h5).
void write_hex_mesh_time_series_xdmf(const std::string& xmf_path, const XdmfHexMesh& mesh,
                                     const std::vector<XdmfTimeStep>& steps);

}  // namespace msfab
