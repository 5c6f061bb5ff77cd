#include "io/xdmf.hpp"

#include <cstdio>
#include <cstdlib>
#include <sstream>

#include "io/atomic_file.hpp"

namespace msfab {

std::string xdmf_sidecar_path(const std::string& h5_path) {
  const auto dot = h5_path.rfind(".h5");
  return (dot != std::string::npos && dot + 3 == h5_path.size()) ? h5_path.substr(0, dot) + ".xmf" : h5_path + ".xmf";
}

std::string file_name_of(const std::string& path) {
  const auto slash = path.rfind('/');
  return slash == std::string::npos ? path : path.substr(slash + 1);
}

namespace {

std::string xml_escape(const std::string& text) {
  std::string out;
  for (char c : text) {
    switch (c) {
      case '&': out += "&amp;"; break;
      case '<': out += "&lt;"; break;
      case '>': out += "&gt;"; break;
      case '"': out += "&quot;"; break;
      case '\'': out += "&apos;"; break;
      default: out += c;
    }
  }
  return out;
}

// Shortest decimal text that reads back as the same double.
std::string exact_decimal(double value) {
  char text[32];
  for (int digits = 15; digits <= 17; ++digits) {
    std::snprintf(text, sizeof(text), "%.*g", digits, value);
    if (std::strtod(text, nullptr) == value) break;
  }
  return text;
}

std::string number_type(H5Dtype dtype) {
  switch (dtype) {
    case H5Dtype::kFloat64: return "NumberType=\"Float\" Precision=\"8\"";
    case H5Dtype::kInt32: return "NumberType=\"Int\" Precision=\"4\"";
    case H5Dtype::kInt64: return "NumberType=\"Int\" Precision=\"8\"";
    case H5Dtype::kUInt8: return "NumberType=\"UChar\" Precision=\"1\"";
    case H5Dtype::kUInt64: return "NumberType=\"UInt\" Precision=\"8\"";
  }
  throw std::logic_error("unknown H5Dtype");
}

const char* attribute_type(const XdmfField& field) {
  switch (field.components) {
    case 1: return "Scalar";
    case 3: return "Vector";
    case 6: return "Tensor6";
    case 9: return "Tensor";
  }
  throw std::invalid_argument("XDMF field '" + field.name + "' has " + std::to_string(field.components) +
                              " components; supported are 1, 3, 6 and 9");
}

void data_item(std::ostream& out, const std::string& indent, const std::string& dimensions, H5Dtype dtype,
               const std::string& h5_file, const std::string& dataset) {
  out << indent << "<DataItem Dimensions=\"" << dimensions << "\" " << number_type(dtype) << " Format=\"HDF\">"
      << xml_escape(h5_file) << ":" << xml_escape(dataset) << "</DataItem>\n";
}

void mesh_elements(std::ostream& out, const std::string& indent, const XdmfHexMesh& mesh) {
  out << indent << "<Topology TopologyType=\"Hexahedron\" NumberOfElements=\"" << mesh.n_elems
      << "\" NodesPerElement=\"8\">\n";
  data_item(out, indent + "  ", std::to_string(mesh.n_elems) + " 8", mesh.connectivity_dtype, mesh.h5_file,
            mesh.connectivity_dataset);
  out << indent << "</Topology>\n";
  out << indent << "<Geometry GeometryType=\"XYZ\">\n";
  data_item(out, indent + "  ", std::to_string(mesh.n_nodes) + " 3", H5Dtype::kFloat64, mesh.h5_file,
            mesh.nodes_dataset);
  out << indent << "</Geometry>\n";
}

void field(std::ostream& out, const std::string& indent, const XdmfField& f, const char* center, std::size_t count,
           const std::string& h5_file) {
  const char* type = attribute_type(f);
  std::string dimensions = std::to_string(count);
  if (f.components > 1) dimensions += " " + std::to_string(f.components);
  out << indent << "<Attribute Name=\"" << xml_escape(f.name) << "\" AttributeType=\"" << type << "\" Center=\""
      << center << "\">\n";
  data_item(out, indent + "  ", dimensions, f.dtype, h5_file, f.dataset);
  out << indent << "</Attribute>\n";
}

void uniform_grid(std::ostream& out, const std::string& indent, const std::string& name, const XdmfHexMesh& mesh,
                  const double* time, const std::vector<XdmfField>& node_fields,
                  const std::vector<XdmfField>& cell_fields) {
  out << indent << "<Grid Name=\"" << xml_escape(name) << "\" GridType=\"Uniform\">\n";
  const std::string inner = indent + "  ";
  if (time != nullptr) out << inner << "<Time Value=\"" << exact_decimal(*time) << "\"/>\n";
  mesh_elements(out, inner, mesh);
  for (const XdmfField& f : node_fields) field(out, inner, f, "Node", mesh.n_nodes, mesh.h5_file);
  for (const XdmfField& f : cell_fields) field(out, inner, f, "Cell", mesh.n_elems, mesh.h5_file);
  out << indent << "</Grid>\n";
}

const char* kHeader =
    "<?xml version=\"1.0\" ?>\n"
    "<!DOCTYPE Xdmf SYSTEM \"Xdmf.dtd\" []>\n"
    "<Xdmf Version=\"3.0\">\n"
    "  <Domain>\n";
const char* kFooter =
    "  </Domain>\n"
    "</Xdmf>\n";

}  // namespace

void write_hex_mesh_xdmf(const std::string& xmf_path, const XdmfHexMesh& mesh,
                         const std::vector<XdmfField>& node_fields, const std::vector<XdmfField>& cell_fields) {
  std::ostringstream out;
  out << kHeader;
  uniform_grid(out, "    ", "mesh", mesh, nullptr, node_fields, cell_fields);
  out << kFooter;
  write_file_atomically(xmf_path, out.str());
}

void write_hex_mesh_time_series_xdmf(const std::string& xmf_path, const XdmfHexMesh& mesh,
                                     const std::vector<XdmfTimeStep>& steps) {
  std::ostringstream out;
  out << kHeader;
  out << "    <Grid Name=\"time_series\" GridType=\"Collection\" CollectionType=\"Temporal\">\n";
  for (std::size_t i = 0; i < steps.size(); ++i) {
    uniform_grid(out, "      ", "step_" + std::to_string(i), mesh, &steps[i].time, steps[i].node_fields,
                 steps[i].cell_fields);
  }
  out << "    </Grid>\n";
  out << kFooter;
  write_file_atomically(xmf_path, out.str());
}

}  // namespace msfab
