#include "topopt/design_artifact.hpp"

#include "core/errors.hpp"
#include "io/artifact.hpp"
#include "io/field_table.hpp"
#include "io/xdmf.hpp"

namespace msfab {

bool is_gamut_space(const std::string& space) {
  return space == "cubic3d" || space == "cubic2d" || space == "orthotropic2d";
}

namespace {
using HistoryEntry = DesignHistoryEntry;
const FieldOf<HistoryEntry> kHistoryFields[] = {
    MSFAB_FIELD(HistoryEntry, iteration), MSFAB_FIELD(HistoryEntry, objective), MSFAB_FIELD(HistoryEntry, elastic),
    MSFAB_FIELD(HistoryEntry, max_violation), MSFAB_FIELD(HistoryEntry, seconds)};

void check_sizes(const Design& d, const std::string& where) {
  auto fail = [&](const std::string& what) { throw InputError(where + ": " + what); };
  if (d.dimension != 2 && d.dimension != 3) fail("dimension must be 2 or 3");
  if (d.nx < 1 || d.ny < 1 || d.nz < 1 || (d.dimension == 2 && d.nz != 1)) fail("bad grid size");
  const Eigen::Index n = d.cells(), p = Eigen::Index(d.property_names.size());
  if (d.unit.rows() != n || d.unit.cols() != p) fail("/cells/unit must be cells x properties");
  if (d.raw.rows() != n || d.raw.cols() != p) fail("/cells/raw must be cells x properties");
  if (Eigen::Index(d.roles.size()) != n) fail("/cells/role must have one entry per cell");
  if (d.phi.size() != n) fail("/cells/phi must have one entry per cell");
  if (d.displacement.size() != 0 && (d.displacement.rows() != d.nodes() || d.displacement.cols() != d.dimension))
    fail("/nodes/displacement must be nodes x dimension");
  if (!d.unit.allFinite() || !d.raw.allFinite()) fail("non-finite cell parameters");
  const Eigen::Index k = Eigen::Index(d.family_names.size());
  if (k > 0 &&
      (d.family_unit.rows() != n || d.family_unit.cols() != k || d.family_raw.rows() != n || d.family_raw.cols() != k))
    fail("/family/unit and /family/raw must be cells x family parameters");
  if (k > 0 && (!d.family_unit.allFinite() || !d.family_raw.allFinite())) fail("non-finite family parameters");
}
// Hexahedra for ParaView: a 2D design becomes a slab one cell thick.
void write_mesh(H5File& f, const Design& d) {
  const int nz = d.dimension == 3 ? d.nz : 1;
  const std::int64_t px = d.nx + 1, py = d.ny + 1, pz = nz + 1;
  Eigen::Matrix<double, Eigen::Dynamic, 3, Eigen::RowMajor> nodes(px * py * pz, 3), u(px * py * pz, 3);
  u.setZero();
  for (std::int64_t k = 0; k < pz; ++k)
    for (std::int64_t j = 0; j < py; ++j)
      for (std::int64_t i = 0; i < px; ++i) {
        const std::int64_t n = i + px * (j + py * k);
        nodes.row(n) << i * d.cell_size, j * d.cell_size, k * d.cell_size;
        if (d.displacement.size() == 0) continue;
        // 2D: both layers carry the in-plane displacement of their node.
        const std::int64_t src = d.dimension == 3 ? n : i + px * j;
        for (int a = 0; a < d.dimension; ++a) u(n, a) = d.displacement(src, a);
      }
  Eigen::Matrix<std::int32_t, Eigen::Dynamic, 8, Eigen::RowMajor> hexes(d.cells(), 8);
  for (std::int64_t k = 0; k < nz; ++k)
    for (std::int64_t j = 0; j < d.ny; ++j)
      for (std::int64_t i = 0; i < d.nx; ++i) {
        const std::int64_t c = i + std::int64_t(d.nx) * (j + std::int64_t(d.ny) * k);
        for (int a = 0; a < 8; ++a) {
          const int v = kToolkitNodeAtVtkCorner[a];  // toolkit corner (v>>2, v>>1 & 1, v & 1)
          hexes(c, a) = std::int32_t((i + (v >> 2 & 1)) + px * ((j + (v >> 1 & 1)) + py * (k + (v & 1))));
        }
      }
  f.write_matrix("/mesh/nodes", nodes);
  f.write_matrix("/mesh/hexes_vtk", hexes);
  if (d.displacement.size() > 0) f.write_matrix("/mesh/displacement", u);
  VecX rho = d.unit.col(d.unit.cols() - 1);
  for (std::int64_t c = 0; c < d.cells(); ++c)
    if (d.roles[c] != CellRole::design) rho[c] = d.roles[c] == CellRole::solid ? 1.0 : 0.0;
  f.write_vector("/mesh/rho", rho);
}

}  // namespace

void write_design_artifact(const std::string& path, const Design& d, const std::string& executable,
                           const std::string& config_text, const std::vector<std::string>& inputs, std::uint64_t seed) {
  check_sizes(d, path);
  ArtifactWriter out(path, kDesignSchema, kDesignSchemaVersion, executable, config_text, inputs, seed);
  H5File& f = out.file();
  write_space_label(f, d);
  f.write_attribute("/", "dimension", static_cast<std::int32_t>(d.dimension));
  f.write_attribute("/", "grid", std::vector<std::int32_t>{d.nx, d.ny, d.nz});
  f.write_attribute("/", "cell_size", d.cell_size);
  f.write_matrix("/cells/unit", d.unit);
  f.write_attribute("/cells/unit", "meaning", "material parameters normalized to the space's unit cube");
  f.write_matrix("/cells/raw", d.raw);
  f.write_attribute("/cells/raw", "units", "moduli in Pa, Poisson's ratios and rho dimensionless");
  std::vector<std::uint8_t> roles(d.roles.size());
  for (std::size_t i = 0; i < roles.size(); ++i) roles[i] = static_cast<std::uint8_t>(d.roles[i]);
  f.write_vector("/cells/role", roles);
  f.write_attribute("/cells/role", "meaning", "0 design, 1 forced empty, 2 forced solid");
  f.write_vector("/cells/phi", d.phi);
  f.write_attribute("/cells/phi", "meaning", "gamut constraint value at the end, <= 0 inside");
  if (d.displacement.size() > 0) {
    f.write_matrix("/nodes/displacement", d.displacement);
    f.write_attribute("/nodes/displacement", "units", "m");
  }
  write_column_fields(f, "/history", d.history, kHistoryFields);
  if (!d.family_names.empty()) {
    f.write_matrix("/family/unit", d.family_unit);
    f.write_attribute("/family/unit", "meaning",
                      "the family grid's parameters, each normalized to [0, 1] along its axis");
    f.write_matrix("/family/raw", d.family_raw);
    f.write_attribute("/family/raw", "meaning", "the family's parameters (beam half-sizes in cell units)");
    f.write_attribute("/family", "names", format_name_list(d.family_names));
  }
  write_mesh(f, d);
  out.commit();
  // The ParaView sidecar.
  const std::string xmf = xdmf_sidecar_path(path);
  XdmfHexMesh xm;
  xm.h5_file = file_name_of(path);
  xm.nodes_dataset = "/mesh/nodes";
  xm.connectivity_dataset = "/mesh/hexes_vtk";
  xm.n_nodes = std::size_t(d.dimension == 3 ? d.nodes() : 2 * d.nodes());
  xm.n_elems = std::size_t(d.cells());
  std::vector<XdmfField> node_fields;
  if (d.displacement.size() > 0) node_fields.push_back({"displacement", "/mesh/displacement", 3, H5Dtype::kFloat64});
  write_hex_mesh_xdmf(xmf, xm, node_fields,
                      {{"rho", "/mesh/rho", 1, H5Dtype::kFloat64}, {"phi", "/cells/phi", 1, H5Dtype::kFloat64}});
}

Design read_design_artifact(const std::string& path) {
  const ArtifactReader in(path, kDesignSchema, kDesignSchemaVersion);
  const H5File& f = in.file();
  Design d;
  static_cast<SpaceLabel&>(d) = read_space_label(f);
  d.dimension = f.read_attribute<std::int32_t>("/", "dimension");
  const auto grid = f.read_attribute_vector<std::int32_t>("/", "grid");
  if (grid.size() != 3) throw InputError(path + ": attribute grid must have 3 entries");
  d.nx = grid[0], d.ny = grid[1], d.nz = grid[2];
  d.cell_size = f.read_attribute<double>("/", "cell_size");
  d.unit = f.read_matrix<double>("/cells/unit");
  d.raw = f.read_matrix<double>("/cells/raw");
  const auto roles = f.read_vector<std::uint8_t>("/cells/role");
  for (std::uint8_t r : roles) {
    if (r > 2) throw InputError(path + ": /cells/role holds " + std::to_string(r) + " (expected 0, 1 or 2)");
    d.roles.push_back(static_cast<CellRole>(r));
  }
  const auto phi = f.read_vector<double>("/cells/phi");
  d.phi = Eigen::Map<const VecX>(phi.data(), Eigen::Index(phi.size()));
  if (f.exists("/nodes/displacement")) d.displacement = f.read_matrix<double>("/nodes/displacement");
  d.history = read_column_fields(f, "/history", kHistoryFields);
  if (f.exists("/family")) {
    d.family_names = parse_name_list(f.read_string_attribute("/family", "names"));
    d.family_unit = f.read_matrix<double>("/family/unit");
    d.family_raw = f.read_matrix<double>("/family/raw");
  }
  check_sizes(d, path);
  return d;
}

}  // namespace msfab
