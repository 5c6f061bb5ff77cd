#include "mapping/mapped_artifact.hpp"

#include <stdexcept>

#include "core/errors.hpp"
#include "io/artifact.hpp"

namespace msfab {
namespace {

// Empty string when the sizes agree, else what is wrong.
std::string size_problem(const MappedDesign& m) {
  if (m.dimension != 2 && m.dimension != 3) return "dimension must be 2 or 3";
  if (m.nx < 1 || m.ny < 1 || m.nz < 1 || (m.dimension == 2 && m.nz != 1)) return "bad cell grid";
  if (m.vx < 1 || m.vy < 1 || m.vz < 1 || (m.dimension == 2 && m.vz != 1)) return "bad voxels per cell";
  if (m.tiling < 1 || m.tiling > kMaxTiling)
    return "attribute tiling is " + std::to_string(m.tiling) + " (expected 1.." + std::to_string(kMaxTiling) + ")";
  const std::size_t n = std::size_t(m.cells());
  if (m.roles.size() != n) return "/cells/role must have one entry per cell";
  if (m.structure.size() != n) return "/cells/structure must have one entry per cell";
  if (m.shift.size() != n) return "/cells/shift must have one entry per cell";
  if (m.distance.size() != n) return "/cells/distance must have one entry per cell";
  if (!m.property_gap.empty() && m.property_gap.size() != n) return "/cells/property_gap must have one entry per cell";
  if (m.candidates.size() != n) return "/cells/candidates must have one entry per cell";
  if (m.mismatch.size() != n) return "/cells/mismatch must have one entry per cell";
  if (m.history.empty() || m.history.size() != m.history_cell.size())
    return "/history/mismatch and /history/cell must have the same, nonzero length";
  for (std::size_t c = 0; c < n; ++c) {
    if (m.shift[c] > 1) return "/cells/shift holds a value other than 0 and 1";
    if ((m.roles[c] == CellRole::design) != (m.structure[c] >= 0))
      return "/cells/structure must be >= 0 exactly for design cells (cell " + std::to_string(c) + ")";
  }
  return {};
}

}  // namespace

void write_mapped_artifact(const std::string& path, const MappedDesign& m, const std::string& executable,
                           const std::string& config_text, const std::vector<std::string>& inputs, std::uint64_t seed) {
  if (const std::string problem = size_problem(m); !problem.empty())
    throw std::invalid_argument("write_mapped_artifact: " + problem);
  ArtifactWriter out(path, kMappedSchema, kMappedSchemaVersion, executable, config_text, inputs, seed);
  H5File& f = out.file();
  f.write_attribute("/", "space", m.space);
  f.write_attribute("/", "property_names", format_name_list(m.property_names));
  f.write_attribute("/", "dimension", static_cast<std::int32_t>(m.dimension));
  f.write_attribute("/", "grid", std::vector<std::int32_t>{m.nx, m.ny, m.nz});
  f.write_attribute("/", "cell_size", m.cell_size);
  f.write_attribute("/", "cell_voxels", std::vector<std::int32_t>{m.vx, m.vy, m.vz});
  f.write_attribute("/", "tiling", static_cast<std::int32_t>(m.tiling));
  f.write_attribute("/", "candidates_k", static_cast<std::int32_t>(m.k));
  f.write_attribute("/", "radius", m.radius);
  f.write_attribute("/", "half_shift", static_cast<std::int32_t>(m.half_shift));
  f.write_attribute("/", "max_distance", m.max_distance);
  f.write_attribute("/", "initial_mismatch", m.history.front());
  f.write_attribute("/", "final_mismatch", m.history.back());
  f.write_attribute("/", "void_pair_cost", m.void_pair_cost);
  f.write_attribute("/", "mismatch_pairs", m.mismatch_pairs);
  f.write_attribute("/", "void_pairs", m.void_pairs);
  f.write_attribute("/", "contact_pairs", m.contact_pairs);
  f.write_attribute("/", "evaluations", m.evaluations);
  f.write_attribute("/", "seconds", m.seconds);

  H5WriteOptions packed;
  packed.gzip_level = 4;
  std::vector<std::uint8_t> roles(m.roles.size());
  for (std::size_t i = 0; i < roles.size(); ++i) roles[i] = static_cast<std::uint8_t>(m.roles[i]);
  f.write_vector("/cells/role", roles, packed);
  f.write_attribute("/cells/role", "meaning", "0 design, 1 forced empty, 2 forced solid");
  f.write_vector("/cells/structure", m.structure, packed);
  f.write_attribute("/cells/structure", "meaning",
                    "index into the input msfab.microstructures set; -1 for forced empty or solid cells");
  f.write_vector("/cells/shift", m.shift, packed);
  f.write_attribute("/cells/shift", "meaning",
                    "1: the exemplar translated periodically by (nx/2, ny/2, nz/2) voxels; 0: as stored");
  f.write_vector("/cells/distance", m.distance, packed);
  f.write_attribute("/cells/distance", "meaning",
                    "Euclidean distance between the structure's and the cell's normalized properties");
  f.write_attribute("/cells/distance", "units", "1");
  if (!m.property_gap.empty()) {
    f.write_vector("/cells/property_gap", m.property_gap, packed);
    f.write_attribute("/cells/property_gap", "meaning",
                      "|C(structure) - C(target)|_F / |C(target)|_F, C the space's stiffness of the raw properties");
    f.write_attribute("/cells/property_gap", "units", "1");
  }
  f.write_vector("/cells/candidates", m.candidates, packed);
  f.write_attribute("/cells/candidates", "meaning", "candidate structures of the cell (each with its variants)");
  f.write_vector("/cells/mismatch", m.mismatch, packed);
  f.write_attribute("/cells/mismatch", "meaning",
                    "I_i: boundary voxels of the cell whose id differs from the voxel across the face");
  f.write_vector("/history/mismatch", m.history, packed);
  f.write_attribute("/history/mismatch", "meaning", "total mismatch I = sum of I_i; [0] initial, then after each move");
  f.write_vector("/history/cell", m.history_cell, packed);
  f.write_attribute("/history/cell", "meaning", "the cell each move changed; [0] = -1");
  out.commit();
}

MappedDesign read_mapped_artifact(const std::string& path) {
  const ArtifactReader in(path, kMappedSchema, kMappedSchemaVersion);
  const H5File& f = in.file();
  MappedDesign m;
  m.space = f.read_string_attribute("/", "space");
  m.property_names = parse_name_list(f.read_string_attribute("/", "property_names"));
  m.dimension = f.read_attribute<std::int32_t>("/", "dimension");
  const auto grid = f.read_attribute_vector<std::int32_t>("/", "grid");
  const auto voxels = f.read_attribute_vector<std::int32_t>("/", "cell_voxels");
  if (grid.size() != 3) throw InputError(path + ": attribute grid must have 3 entries");
  if (voxels.size() != 3) throw InputError(path + ": attribute cell_voxels must have 3 entries");
  m.nx = grid[0], m.ny = grid[1], m.nz = grid[2];
  m.vx = voxels[0], m.vy = voxels[1], m.vz = voxels[2];
  // Artifacts written before tilings existed hold one structure per cell.
  if (f.has_attribute("/", "tiling")) m.tiling = f.read_attribute<std::int32_t>("/", "tiling");
  m.cell_size = f.read_attribute<double>("/", "cell_size");
  m.k = f.read_attribute<std::int32_t>("/", "candidates_k");
  m.radius = f.read_attribute<double>("/", "radius");
  m.half_shift = f.read_attribute<std::int32_t>("/", "half_shift") != 0;
  m.max_distance = f.read_attribute<double>("/", "max_distance");
  // Artifacts written before the void-pair cost: plain mismatch, pairs not recorded.
  if (f.has_attribute("/", "void_pair_cost")) {
    m.void_pair_cost = f.read_attribute<double>("/", "void_pair_cost");
    m.mismatch_pairs = f.read_attribute<std::int64_t>("/", "mismatch_pairs");
    m.void_pairs = f.read_attribute<std::int64_t>("/", "void_pairs");
    m.contact_pairs = f.read_attribute<std::int64_t>("/", "contact_pairs");
  }
  m.evaluations = f.read_attribute<std::int64_t>("/", "evaluations");
  m.seconds = f.read_attribute<double>("/", "seconds");
  const auto roles = f.read_vector<std::uint8_t>("/cells/role");
  for (std::uint8_t r : roles) {
    if (r > 2) throw InputError(path + ": /cells/role holds " + std::to_string(r) + " (expected 0, 1 or 2)");
    m.roles.push_back(static_cast<CellRole>(r));
  }
  m.structure = f.read_vector<std::int32_t>("/cells/structure");
  m.shift = f.read_vector<std::uint8_t>("/cells/shift");
  m.distance = f.read_vector<double>("/cells/distance");
  if (f.exists("/cells/property_gap")) m.property_gap = f.read_vector<double>("/cells/property_gap");
  m.candidates = f.read_vector<std::int32_t>("/cells/candidates");
  m.mismatch = f.read_vector<std::int64_t>("/cells/mismatch");
  m.history = f.read_vector<std::int64_t>("/history/mismatch");
  m.history_cell = f.read_vector<std::int64_t>("/history/cell");
  if (const std::string problem = size_problem(m); !problem.empty()) throw InputError(path + ": " + problem);
  return m;
}

}  // namespace msfab
