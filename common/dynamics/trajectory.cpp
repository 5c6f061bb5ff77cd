#include "dynamics/trajectory.hpp"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <stdexcept>
#include <utility>

#include "core/errors.hpp"
#include "io/artifact.hpp"
#include "io/field_table.hpp"
#include "io/mesh_io.hpp"
#include "io/xdmf.hpp"

namespace msfab {

namespace {

// Attribute tables: each field is written and read under one name.
const FieldOf<Trajectory> kTimingFields[] = {{"quasistatic", &Trajectory::seconds_quasistatic},
                                             {"elastic", &Trajectory::seconds_elastic},
                                             {"rigid", &Trajectory::seconds_rigid},
                                             {"total", &Trajectory::seconds_total}};
using Coarsening = TrajectoryCoarsening;
const FieldOf<Coarsening> kCoarseningFields[] = {
    MSFAB_FIELD(Coarsening, level),         MSFAB_FIELD(Coarsening, material), MSFAB_FIELD(Coarsening, database),
    MSFAB_FIELD(Coarsening, element),       MSFAB_FIELD(Coarsening, fallback), MSFAB_FIELD(Coarsening, fallback_blocks),
    MSFAB_FIELD(Coarsening, fine_elements), MSFAB_FIELD(Coarsening, seconds)};
const FieldOf<Coarsening> kCoarseningCheckFields[] = {
    MSFAB_FIELD(Coarsening, check_tolerance), MSFAB_FIELD(Coarsening, checked_blocks),
    MSFAB_FIELD(Coarsening, replaced_blocks), MSFAB_FIELD(Coarsening, window),
    MSFAB_FIELD(Coarsening, unresolved_windows)};
using Comparison = TrajectoryComparison;
const FieldOf<Comparison> kComparisonFields[] = {MSFAB_FIELD(Comparison, reference),
                                                 MSFAB_FIELD(Comparison, error_at_release),
                                                 MSFAB_FIELD(Comparison, error_max),
                                                 MSFAB_FIELD(Comparison, error_mean),
                                                 MSFAB_FIELD(Comparison, error_final),
                                                 MSFAB_FIELD(Comparison, max_center_of_mass_distance),
                                                 MSFAB_FIELD(Comparison, fine_seconds_per_step),
                                                 MSFAB_FIELD(Comparison, seconds_per_step)};

constexpr const char* kSchema = "msfab.trajectory";
constexpr int kSchemaVersion = 1;
constexpr SimulationPhase kPhases[] = {SimulationPhase::kQuasistatic, SimulationPhase::kElastic,
                                       SimulationPhase::kRigid};

std::string frame_group(std::size_t k) {
  char name[32];
  std::snprintf(name, sizeof name, "/frames/%06zu", k);
  return name;
}

// Large meshes are compressed like the mesh group (docs/artifacts.md).
H5WriteOptions options_for_rows(Eigen::Index rows) {
  H5WriteOptions options;
  options.gzip_level = rows > 4096 ? 4 : 0;
  return options;
}

// Event texts are free-form, so one entry per line needs the line break
// (and the escape character itself) escaped.
std::string join_lines(const std::vector<std::string>& items) {
  std::string out;
  for (std::size_t i = 0; i < items.size(); ++i) {
    if (i > 0) out += '\n';
    for (char c : items[i]) {
      if (c == '\\')
        out += "\\\\";
      else if (c == '\n')
        out += "\\n";
      else
        out += c;
    }
  }
  return out;
}

// Inverse of join_lines for a known count, which tells "" (no entries) from
// one empty entry. False if the text is not `count` well-escaped lines.
bool split_lines(const std::string& text, std::size_t count, std::vector<std::string>& items) {
  items.clear();
  if (count == 0) return text.empty();
  items.emplace_back();
  for (std::size_t i = 0; i < text.size(); ++i) {
    const char c = text[i];
    if (c == '\n') {
      items.emplace_back();
    } else if (c == '\\') {
      if (i + 1 >= text.size()) return false;
      const char next = text[++i];
      if (next == '\\')
        items.back() += '\\';
      else if (next == 'n')
        items.back() += '\n';
      else
        return false;
    } else {
      items.back() += c;
    }
  }
  return items.size() == count;
}

void check_trajectory(const Trajectory& t) {
  const Eigen::Index n = t.rest_nodes.rows();
  if (t.element_tag.size() != t.elements.size())
    throw std::invalid_argument("trajectory: " + std::to_string(t.element_tag.size()) + " element tags for " +
                                std::to_string(t.elements.size()) + " elements");
  for (std::size_t e = 0; e < t.elements.size(); ++e)
    for (int node : t.elements[e])
      if (node < 0 || node >= n)
        throw std::invalid_argument("trajectory: element " + std::to_string(e) + " references node " +
                                    std::to_string(node) + " of " + std::to_string(n));
  for (const std::string& name : t.material_names)
    if (name.find(',') != std::string::npos)
      throw std::invalid_argument("trajectory: material name '" + name +
                                  "' contains a comma (names are stored as a comma-separated list)");
  for (std::size_t k = 0; k < t.frames.size(); ++k)
    if (t.frames[k].positions.size() != 3 * n || t.frames[k].velocities.size() != 3 * n)
      throw std::invalid_argument("trajectory: frame " + std::to_string(k) + " has " +
                                  std::to_string(t.frames[k].positions.size()) + " positions and " +
                                  std::to_string(t.frames[k].velocities.size()) + " velocities, expected " +
                                  std::to_string(3 * n));
}

NodeArray as_rows(const VecX& v) { return Eigen::Map<const NodeArray>(v.data(), v.size() / 3, 3); }

VecX as_vector(const MatX& rows) {
  VecX v(rows.size());
  for (Eigen::Index i = 0; i < rows.rows(); ++i)
    for (int a = 0; a < 3; ++a) v[3 * i + a] = rows(i, a);
  return v;
}

template <class T, class F>
void write_sample_column(H5File& f, const std::string& name, const std::vector<TrajectorySample>& samples, F get,
                         const char* units) {
  std::vector<T> column;
  column.reserve(samples.size());
  for (const TrajectorySample& s : samples) column.push_back(static_cast<T>(get(s)));
  const std::string path = "/samples/" + name;
  f.write_vector(path, column);
  if (units != nullptr) f.write_attribute(path, "units", units);
}

template <class F>
void write_sample_vec3(H5File& f, const std::string& name, const std::vector<TrajectorySample>& samples, F get,
                       const char* units) {
  NodeArray rows(Eigen::Index(samples.size()), 3);
  for (std::size_t i = 0; i < samples.size(); ++i) rows.row(Eigen::Index(i)) = get(samples[i]).transpose();
  const std::string path = "/samples/" + name;
  f.write_matrix(path, rows);
  f.write_attribute(path, "units", units);
}

void write_samples(H5File& f, const std::vector<TrajectorySample>& samples) {
  f.create_group("/samples");
  using S = TrajectorySample;
  write_sample_column<double>(
      f, "time", samples, [](const S& s) { return s.time; }, "s");
  write_sample_column<std::int32_t>(
      f, "phase", samples, [](const S& s) { return static_cast<int>(s.phase); }, nullptr);
  std::vector<std::string> names;
  for (SimulationPhase p : kPhases) names.push_back(phase_name(p));
  f.write_attribute("/samples/phase", "names", format_name_list(names));
  write_sample_column<double>(
      f, "kinetic", samples, [](const S& s) { return s.kinetic; }, "J");
  write_sample_column<double>(
      f, "elastic", samples, [](const S& s) { return s.elastic; }, "J");
  write_sample_column<double>(
      f, "gravity", samples, [](const S& s) { return s.gravity; }, "J");
  write_sample_column<double>(
      f, "total", samples, [](const S& s) { return s.total(); }, "J");
  write_sample_vec3(
      f, "center_of_mass", samples, [](const S& s) { return s.center_of_mass; }, "m");
  write_sample_vec3(
      f, "com_velocity", samples, [](const S& s) { return s.com_velocity; }, "m/s");
  write_sample_vec3(
      f, "rotation", samples, [](const S& s) { return s.rotation; }, "rad");
  write_sample_column<std::int32_t>(
      f, "contacts", samples, [](const S& s) { return s.contacts; }, nullptr);
  write_sample_column<std::int32_t>(
      f, "active_contacts", samples, [](const S& s) { return s.active_contacts; }, nullptr);
  write_sample_column<std::int32_t>(
      f, "newton_iterations", samples, [](const S& s) { return s.newton_iterations; }, nullptr);
  write_sample_column<double>(
      f, "max_penetration", samples, [](const S& s) { return s.max_penetration; }, "m");
  write_sample_column<double>(
      f, "seconds", samples, [](const S& s) { return s.seconds; }, "s");
}

// Only for scenes with several bodies: one row per sample, x y z per body.
void write_body_centers(H5File& f, const Trajectory& t) {
  if (t.body_names.size() < 2) return;
  const Eigen::Index bodies = Eigen::Index(t.body_names.size());
  MatX rows(Eigen::Index(t.samples.size()), 3 * bodies);
  for (std::size_t i = 0; i < t.samples.size(); ++i) {
    if (Eigen::Index(t.samples[i].body_center_of_mass.size()) != bodies)
      throw std::logic_error("trajectory sample without a centre of mass per body");
    for (Eigen::Index b = 0; b < bodies; ++b)
      rows.block<1, 3>(Eigen::Index(i), 3 * b) = t.samples[i].body_center_of_mass[b].transpose();
  }
  f.write_matrix("/samples/body_center_of_mass", rows);
  f.write_attribute("/samples/body_center_of_mass", "units", "m");
  f.write_attribute("/samples/body_center_of_mass", "bodies", format_name_list(t.body_names));
}

// Positions are the record; the displacement is what the XDMF sidecar shows
// (rest + displacement need not round to the stored positions bitwise, so
// both are kept).
void write_frames(H5File& f, const Trajectory& t) {
  f.create_group("/frames");
  std::vector<double> times;
  for (const TrajectoryFrame& frame : t.frames) times.push_back(frame.time);
  f.write_vector("/frames/time", times);
  f.write_attribute("/frames/time", "units", "s");
  const H5WriteOptions big = options_for_rows(t.rest_nodes.rows());
  for (std::size_t k = 0; k < t.frames.size(); ++k) {
    const std::string g = frame_group(k);
    const NodeArray x = as_rows(t.frames[k].positions);
    f.create_group(g);
    f.write_attribute(g, "time", t.frames[k].time);
    f.write_matrix(g + "/positions", x, big);
    f.write_attribute(g + "/positions", "units", "m");
    f.write_matrix(g + "/displacement", NodeArray(x - t.rest_nodes), big);
    f.write_attribute(g + "/displacement", "units", "m");
    f.write_matrix(g + "/velocity", as_rows(t.frames[k].velocities), big);
    f.write_attribute(g + "/velocity", "units", "m/s");
  }
}

void write_events(H5File& f, const std::vector<TrajectoryEvent>& events) {
  f.create_group("/events");
  std::vector<double> times;
  std::vector<std::string> kinds, details;
  for (const TrajectoryEvent& e : events) {
    times.push_back(e.time);
    kinds.push_back(e.kind);
    details.push_back(e.detail);
  }
  f.write_vector("/events/time", times);
  f.write_attribute("/events/time", "units", "s");
  f.write_attribute("/events", "kind", join_lines(kinds));
  f.write_attribute("/events", "detail", join_lines(details));
}

// One row per obstacle: its kind ("ground" or "box"), name and surface as
// escaped lines, and the box corners (a ground: its height in the z of both).
void write_obstacles(H5File& f, const std::vector<Obstacle>& obstacles) {
  if (obstacles.empty()) return;
  f.create_group("/obstacles");
  std::vector<std::string> kinds, names, surfaces;
  NodeArray lo(Eigen::Index(obstacles.size()), 3), hi(Eigen::Index(obstacles.size()), 3);
  for (std::size_t i = 0; i < obstacles.size(); ++i) {
    const Obstacle& o = obstacles[i];
    const bool ground = o.kind == Obstacle::Kind::kGround;
    kinds.push_back(ground ? "ground" : "box");
    names.push_back(o.name);
    surfaces.push_back(o.surface);
    const Vec3 a = ground ? Vec3(0, 0, o.ground_z) : o.lo, b = ground ? Vec3(0, 0, o.ground_z) : o.hi;
    lo.row(Eigen::Index(i)) = a.transpose();
    hi.row(Eigen::Index(i)) = b.transpose();
  }
  f.write_attribute("/obstacles", "kind", join_lines(kinds));
  f.write_attribute("/obstacles", "name", join_lines(names));
  f.write_attribute("/obstacles", "surface", join_lines(surfaces));
  f.write_matrix("/obstacles/lo", lo);
  f.write_attribute("/obstacles/lo", "units", "m");
  f.write_matrix("/obstacles/hi", hi);
  f.write_attribute("/obstacles/hi", "units", "m");
}

void write_sidecar(const std::string& path, const Trajectory& t) {
  XdmfHexMesh mesh;
  mesh.h5_file = file_name_of(path);
  mesh.nodes_dataset = "/mesh/nodes";
  mesh.connectivity_dataset = "/mesh/elements_vtk";
  mesh.n_nodes = std::size_t(t.rest_nodes.rows());
  mesh.n_elems = t.elements.size();
  const XdmfField material{"material_id", "/mesh/element_tag", 1, H5Dtype::kInt32};
  // An empty temporal collection is not a dataset ParaView opens; show the
  // rest mesh instead.
  if (t.frames.empty()) {
    write_hex_mesh_xdmf(xdmf_sidecar_path(path), mesh, {}, {material});
    return;
  }
  std::vector<XdmfTimeStep> steps;
  for (std::size_t k = 0; k < t.frames.size(); ++k) {
    const std::string g = frame_group(k);
    XdmfTimeStep step;
    step.time = t.frames[k].time;
    step.node_fields = {{"displacement", g + "/displacement", 3, H5Dtype::kFloat64},
                        {"velocity", g + "/velocity", 3, H5Dtype::kFloat64}};
    step.cell_fields = {material};
    steps.push_back(std::move(step));
  }
  write_hex_mesh_time_series_xdmf(xdmf_sidecar_path(path), mesh, steps);
}

// --- reading -------------------------------------------------------------

std::size_t expect_length(const H5File& f, const std::string& dataset, std::size_t size, std::size_t expected,
                          const std::string& reference) {
  if (size != expected)
    throw InputError(f.path() + ": dataset '" + dataset + "' has " + std::to_string(size) + " entries, expected " +
                     std::to_string(expected) + " (" + reference + ")");
  return size;
}

template <class T>
std::vector<T> read_column(const H5File& f, const std::string& name, std::size_t count) {
  const std::string path = "/samples/" + name;
  std::vector<T> v = f.read_vector<T>(path);
  expect_length(f, path, v.size(), count, "one per /samples/time");
  return v;
}

MatX read_rows3(const H5File& f, const std::string& path, Eigen::Index rows, const std::string& reference) {
  MatX m = f.read_matrix<double>(path, 3);
  if (m.rows() != rows)
    throw InputError(f.path() + ": dataset '" + path + "' has " + std::to_string(m.rows()) + " rows, expected " +
                     std::to_string(rows) + " (" + reference + ")");
  return m;
}

void read_samples(const H5File& f, Trajectory& t) {
  const std::vector<double> time = f.read_vector<double>("/samples/time");
  const std::size_t n = time.size();
  const auto phase = read_column<std::int32_t>(f, "phase", n);
  const auto kinetic = read_column<double>(f, "kinetic", n);
  const auto elastic = read_column<double>(f, "elastic", n);
  const auto gravity = read_column<double>(f, "gravity", n);
  read_column<double>(f, "total", n);  // derived; checked for shape only
  const MatX com = read_rows3(f, "/samples/center_of_mass", Eigen::Index(n), "one per /samples/time");
  const MatX vcom = read_rows3(f, "/samples/com_velocity", Eigen::Index(n), "one per /samples/time");
  const MatX rot = read_rows3(f, "/samples/rotation", Eigen::Index(n), "one per /samples/time");
  const auto contacts = read_column<std::int32_t>(f, "contacts", n);
  const auto active = read_column<std::int32_t>(f, "active_contacts", n);
  const auto newton = read_column<std::int32_t>(f, "newton_iterations", n);
  const auto penetration = read_column<double>(f, "max_penetration", n);
  const auto seconds = read_column<double>(f, "seconds", n);
  t.samples.resize(n);
  for (std::size_t i = 0; i < n; ++i) {
    TrajectorySample& s = t.samples[i];
    if (phase[i] < 0 || phase[i] > 2)
      throw InputError(f.path() + ": dataset '/samples/phase' entry " + std::to_string(i) + " is " +
                       std::to_string(phase[i]) + ", expected 0 (quasistatic), 1 (elastic) or 2 (rigid)");
    const Eigen::Index r = Eigen::Index(i);
    s.time = time[i];
    s.phase = static_cast<SimulationPhase>(phase[i]);
    s.kinetic = kinetic[i];
    s.elastic = elastic[i];
    s.gravity = gravity[i];
    s.center_of_mass = com.row(r).transpose();
    s.com_velocity = vcom.row(r).transpose();
    s.rotation = rot.row(r).transpose();
    s.contacts = contacts[i];
    s.active_contacts = active[i];
    s.newton_iterations = newton[i];
    s.max_penetration = penetration[i];
    s.seconds = seconds[i];
  }
}

void read_frames(const H5File& f, Trajectory& t) {
  const std::vector<double> time = f.read_vector<double>("/frames/time");
  const Eigen::Index n = t.rest_nodes.rows();
  const std::string per_node = "one per node of /mesh/nodes";
  t.frames.resize(time.size());
  for (std::size_t k = 0; k < time.size(); ++k) {
    const std::string g = frame_group(k);
    if (!f.is_group(g))
      throw InputError(f.path() + ": group '" + g + "' not found (/frames/time lists " + std::to_string(time.size()) +
                       " frames)");
    TrajectoryFrame& frame = t.frames[k];
    frame.time = time[k];
    frame.positions = as_vector(read_rows3(f, g + "/positions", n, per_node));
    frame.velocities = as_vector(read_rows3(f, g + "/velocity", n, per_node));
    // Only the sidecar reads the displacement, but a wrong one would show a
    // wrong motion in ParaView, so its shape is checked too.
    const std::vector<hsize_t> shape = f.dataset_shape(g + "/displacement");
    if (shape.size() != 2 || shape[0] != hsize_t(n) || shape[1] != 3)
      throw InputError(f.path() + ": dataset '" + g + "/displacement' must have shape (" + std::to_string(n) + ", 3)");
  }
}

// The `count` escaped lines of attribute `name` of `group` (join_lines);
// `per` says what each line belongs to, for the error.
std::vector<std::string> read_lines_attribute(const H5File& f, const std::string& group, const char* name,
                                              std::size_t count, const std::string& per) {
  std::vector<std::string> items;
  if (!split_lines(f.read_string_attribute(group, name), count, items))
    throw InputError(f.path() + ": attribute '" + name + "' of '" + group + "' does not hold " + std::to_string(count) +
                     " escaped lines (one per " + per + ")");
  return items;
}

void read_events(const H5File& f, Trajectory& t) {
  const std::vector<double> time = f.read_vector<double>("/events/time");
  const auto lines = [&](const char* name) {
    return read_lines_attribute(f, "/events", name, time.size(), "/events/time");
  };
  const std::vector<std::string> kinds = lines("kind"), details = lines("detail");
  t.events.resize(time.size());
  for (std::size_t i = 0; i < time.size(); ++i) t.events[i] = {time[i], kinds[i], details[i]};
}

void read_obstacles(const H5File& f, Trajectory& t) {
  const NodeArray lo = f.read_matrix<double>("/obstacles/lo", 3), hi = f.read_matrix<double>("/obstacles/hi", 3);
  const std::size_t n = std::size_t(lo.rows());
  if (std::size_t(hi.rows()) != n)
    throw InputError(f.path() + ": dataset '/obstacles/hi' has " + std::to_string(hi.rows()) + " rows, expected " +
                     std::to_string(n) + " (one per row of /obstacles/lo)");
  const auto lines = [&](const char* name) {
    return read_lines_attribute(f, "/obstacles", name, n, "row of /obstacles/lo");
  };
  const std::vector<std::string> kinds = lines("kind"), names = lines("name"), surfaces = lines("surface");
  t.obstacles.resize(n);
  for (std::size_t i = 0; i < n; ++i) {
    Obstacle& o = t.obstacles[i];
    if (kinds[i] != "ground" && kinds[i] != "box")
      throw InputError(f.path() + ": attribute 'kind' of '/obstacles', row " + std::to_string(i) + ": '" + kinds[i] +
                       "' is neither ground nor box");
    o.kind = kinds[i] == "ground" ? Obstacle::Kind::kGround : Obstacle::Kind::kBox;
    o.name = names[i];
    o.surface = surfaces[i];
    if (o.kind == Obstacle::Kind::kGround) {
      o.ground_z = lo(Eigen::Index(i), 2);
    } else {
      o.lo = lo.row(Eigen::Index(i)).transpose();
      o.hi = hi.row(Eigen::Index(i)).transpose();
    }
  }
}

}  // namespace

const char* phase_name(SimulationPhase phase) {
  switch (phase) {
    case SimulationPhase::kQuasistatic: return "quasistatic";
    case SimulationPhase::kElastic: return "elastic";
    case SimulationPhase::kRigid: return "rigid";
  }
  return "unknown";
}

std::string write_trajectory_artifact(const std::string& path, const Trajectory& t,
                                      const TrajectoryProvenance& provenance) {
  check_trajectory(t);
  ArtifactWriter writer(path, kSchema, kSchemaVersion, provenance.executable, provenance.config_text, provenance.inputs,
                        provenance.seed);
  H5File& f = writer.file();
  f.write_attribute("/", "scene", t.scene);
  f.write_attribute("/", "impact_model", t.impact_model);
  f.write_attribute("/", "time_step", t.time_step);
  f.write_attribute("/", "event_substeps", static_cast<std::int32_t>(t.event_substeps));
  f.write_attribute("/", "elastic_steps", t.elastic_steps);

  // write_hex_mesh reads only the nodes, elements and tags of a HexMesh.
  HexMesh mesh;
  mesh.nodes = t.rest_nodes;
  mesh.elements = t.elements;
  mesh.element_tag = t.element_tag;
  write_hex_mesh(f, "/mesh", mesh);
  f.write_attribute("/mesh", "material_names", format_name_list(t.material_names));

  write_samples(f, t.samples);
  write_body_centers(f, t);
  write_frames(f, t);
  write_events(f, t.events);
  write_obstacles(f, t.obstacles);

  f.create_group("/timings");
  f.write_attribute("/timings", "units", "s");
  write_attribute_fields(f, "/timings", t, kTimingFields);
  if (t.coarsening.level > 0) {
    const TrajectoryCoarsening& c = t.coarsening;
    f.create_group("/coarsening");
    write_attribute_fields(f, "/coarsening", c, kCoarseningFields);
    write_attribute_fields(f, "/coarsening", c, kCoarseningCheckFields);
  }
  if (!t.comparison.reference.empty()) {
    const TrajectoryComparison& c = t.comparison;
    f.create_group("/comparison");
    f.write_attribute("/comparison", "error_definition",
                      std::string("per frame: mean distance of this run's displacements, interpolated trilinearly to "
                                  "the fine nodes, to the fine run's, over the longest side of the rest box (thesis "
                                  "2.5.2)"));
    write_attribute_fields(f, "/comparison", c, kComparisonFields);
  }
  writer.commit();

  write_sidecar(path, t);
  return xdmf_sidecar_path(path);
}

Trajectory read_trajectory_artifact(const std::string& path) {
  const ArtifactReader in(path, kSchema, kSchemaVersion);
  const H5File& f = in.file();
  Trajectory t;
  t.scene = f.read_string_attribute("/", "scene");
  t.impact_model = f.read_string_attribute("/", "impact_model");
  t.time_step = f.read_attribute<double>("/", "time_step");
  if (f.has_attribute("/", "elastic_steps")) {  // written since event substeps exist
    t.event_substeps = f.read_attribute<std::int32_t>("/", "event_substeps");
    t.elastic_steps = f.read_attribute<std::int64_t>("/", "elastic_steps");
  }

  StoredHexMesh mesh = read_hex_mesh(f, "/mesh");
  if (mesh.element_tag.size() != mesh.elements.size())
    throw InputError(path + ": dataset '/mesh/element_tag' has " + std::to_string(mesh.element_tag.size()) +
                     " entries, expected " + std::to_string(mesh.elements.size()) + " (one per element)");
  t.rest_nodes = std::move(mesh.nodes);
  t.elements = std::move(mesh.elements);
  t.element_tag = std::move(mesh.element_tag);
  t.material_names = parse_name_list(f.read_string_attribute("/mesh", "material_names"));

  read_samples(f, t);
  if (f.exists("/samples/body_center_of_mass")) {
    t.body_names = parse_name_list(f.read_string_attribute("/samples/body_center_of_mass", "bodies"));
    const Eigen::Index bodies = Eigen::Index(t.body_names.size());
    const MatX rows = f.read_matrix<double>("/samples/body_center_of_mass", 3 * bodies);
    if (rows.rows() != Eigen::Index(t.samples.size()))
      throw InputError(path + ": dataset '/samples/body_center_of_mass' has " + std::to_string(rows.rows()) +
                       " rows, expected " + std::to_string(t.samples.size()) + " (one per /samples/time)");
    for (std::size_t i = 0; i < t.samples.size(); ++i)
      for (Eigen::Index b = 0; b < bodies; ++b)
        t.samples[i].body_center_of_mass.push_back(rows.block<1, 3>(Eigen::Index(i), 3 * b).transpose());
  }
  read_frames(f, t);
  read_events(f, t);
  if (f.exists("/obstacles")) read_obstacles(f, t);  // recorded since 2026-12-05

  read_attribute_fields(f, "/timings", t, kTimingFields);
  if (f.exists("/coarsening")) {
    TrajectoryCoarsening& c = t.coarsening;
    read_attribute_fields(f, "/coarsening", c, kCoarseningFields);
    // Written since the check's counts are recorded.
    if (f.has_attribute("/coarsening", "check_tolerance"))
      read_attribute_fields(f, "/coarsening", c, kCoarseningCheckFields);
  }
  if (f.exists("/comparison")) {
    TrajectoryComparison& c = t.comparison;
    read_attribute_fields(f, "/comparison", c, kComparisonFields);
  }
  return t;
}

}  // namespace msfab
