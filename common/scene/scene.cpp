#include "scene/scene.hpp"

#include <spdlog/spdlog.h>

#include <Eigen/Eigenvalues>
#include <Eigen/Geometry>
#include <algorithm>
#include <array>
#include <cmath>
#include <limits>
#include <map>
#include <numeric>
#include <sstream>

#include "core/errors.hpp"
#include "fem/surface_voxelizer.hpp"
#include "fem/voxel_shapes.hpp"
#include "io/linear_solver_config.hpp"
#include "io/material_config.hpp"
#include "io/path_names.hpp"
#include "io/surface_mesh_io.hpp"
#include "io/vdb_grid_io.hpp"
#include "io/voxel_array_io.hpp"
#include "material/linear_anisotropic.hpp"
#include "material/linear_isotropic.hpp"
#include "material/neo_hookean.hpp"

namespace msfab {
namespace {

constexpr double kPi = 3.14159265358979323846;

Vec3 read_vec3(const Config& c, const std::string& key) {
  const auto v = c.get<std::vector<double>>(key);
  if (v.size() != 3) c.fail(key, "expected 3 numbers [x, y, z], found " + std::to_string(v.size()));
  for (double x : v)
    if (!std::isfinite(x)) c.fail(key, "values must be finite");
  return Vec3(v[0], v[1], v[2]);
}

int read_axis(const Config& c, const std::string& key) {
  const std::string a = c.one_of(key, {"x", "y", "z"});
  return a == "x" ? 0 : a == "y" ? 1 : 2;
}

MaterialPtr make_material(const Config& c, PaletteEntry& p) {
  p.model = c.one_of("model", {"neo-hookean", "linear", "linear-anisotropic"});
  p.density = read_density(c, 1000.0);
  if (p.model == "linear-anisotropic") {
    const auto v = c.get<std::vector<double>>("C");
    if (v.size() != 36) c.fail("C", "expected the 6x6 Voigt stiffness as 36 numbers (row by row)");
    Mat6 C;
    for (int i = 0; i < 36; ++i) C(i / 6, i % 6) = v[i];
    try {
      return std::make_shared<LinearAnisotropic>(C);
    } catch (const InputError& e) {
      c.fail("C", e.what());
    }
  }
  const ElasticConstants elastic = read_elastic_constants(c);
  p.E = elastic.E;
  p.nu = elastic.nu;
  if (p.model == "neo-hookean") return std::make_shared<NeoHookean>(p.E, p.nu);
  return std::make_shared<LinearIsotropic>(p.E, p.nu);
}

Region read_region(const Config& parent, const VoxelGrid& grid) {
  const Config c = parent.child("region");
  Region r;
  const bool face = c.has("face"), box = c.has("box");
  if (face == box) parent.fail("region", "give exactly one of 'face' (xmin..zmax) or 'box' {min, max}");
  if (face) {
    const std::string f = c.one_of("face", {"xmin", "xmax", "ymin", "ymax", "zmin", "zmax"});
    r.kind = Region::Kind::Face;
    r.axis = f[0] - 'x';
    r.upper = f.substr(1) == "max";
  } else {
    const Config b = c.child("box");
    r.kind = Region::Kind::Box;
    r.lo = read_vec3(b, "min");
    r.hi = read_vec3(b, "max");
    if ((r.lo.array() > r.hi.array()).any()) b.fail("max", "box max must be >= min in every coordinate");
  }
  (void)grid;
  return r;
}

// `voxels: {file: F.npy}`, `{file: F.raw, dtype: uint8}` or
// `{file: F.vdb, grid: ids, origin: [i, j, k]}`: every voxel's id from the
// file (docs/scenes.md, "Your own object"). Returns the file's path.
std::string paint_voxel_file(const Config& c, VoxelGrid& grid, const std::vector<MaterialPtr>& material_by_id) {
  const std::string path = c.get_path("file");
  std::vector<int> ids;
  if (ends_with(path, ".vdb")) {
    if (c.has("dtype")) c.fail("dtype", "a .vdb file says its own value type; drop it");
    std::array<long long, 3> origin{0, 0, 0};
    if (c.has("origin")) {
      const auto o = c.get<std::vector<int>>("origin");
      if (o.size() != 3) c.fail("origin", "expected the index coordinate [i, j, k] of the grid's voxel (0, 0, 0)");
      origin = {o[0], o[1], o[2]};
    }
    VdbVoxelIds read = read_vdb_voxel_ids(path, c.get_or<std::string>("grid", ""), grid.nx, grid.ny, grid.nz, origin);
    if (read.active_outside > 0)
      spdlog::warn(
          "{}: {} active voxels lie outside the grid's {} x {} x {} voxels from index ({}, {}, {}) and are "
          "cut off",
          path, read.active_outside, grid.nx, grid.ny, grid.nz, origin[0], origin[1], origin[2]);
    ids = std::move(read.ids);
  } else {
    for (const char* key : {"grid", "origin"})
      if (c.has(key)) c.fail(key, "is for .vdb files only");
    ids = read_voxel_ids(path, grid.nx, grid.ny, grid.nz, c.get_or<std::string>("dtype", ""));
  }
  std::map<int, long long> unknown;
  for (int id : ids)
    if (id >= static_cast<int>(material_by_id.size()) || (id > 0 && !material_by_id[id])) ++unknown[id];
  if (!unknown.empty())
    c.fail("file", path + " uses material id " + std::to_string(unknown.begin()->first) + " (" +
                       std::to_string(unknown.begin()->second) + " voxels), which is not in the palette (0 = void)");
  grid.ids = ids;
  return path;
}

// Where a part's file sits in the scene: a file point p lies at
// scale * p + offset (metres).
struct Placement {
  double scale = 1.0;
  Vec3 offset = Vec3::Zero();
};
Placement read_placement(const Config& c) {
  Placement p;
  p.scale = c.get_or<double>("scale", 1.0);
  if (!(p.scale > 0) || !std::isfinite(p.scale)) c.fail("scale", "must be a positive finite number");
  if (c.has("offset")) p.offset = read_vec3(c, "offset");
  return p;
}

// The layout's VDB shape `c` (a `vdb` item's mapping), its threshold, and
// the box of its inside in scene coordinates.
struct PlacedVolume {
  VdbVolume volume;
  Placement placement;
  double threshold;
  std::array<Vec3, 2> box;
};
PlacedVolume placed_volume(const Config& c) {
  const std::string path = c.get_path("file");
  VdbVolume volume = VdbVolume::read(path, c.get_or<std::string>("grid", ""));
  const Placement placement = read_placement(c);
  const double threshold = c.get_or<double>("threshold", volume.default_threshold());
  if (!std::isfinite(threshold)) c.fail("threshold", "must be a finite number");
  std::array<Vec3, 2> box = volume.inside_box(threshold);
  if (!(box[0].array() <= box[1].array()).all()) {
    std::ostringstream o;
    o << path << ": " << volume.describe() << " has no stored value " << (volume.is_level_set() ? "below" : "above")
      << " the threshold " << threshold << ", so nothing is inside";
    c.fail("file", o.str());
  }
  for (Vec3& corner : box) corner = placement.scale * corner + placement.offset;
  return {std::move(volume), placement, threshold, box};
}

// The layout's surface mesh `c` (a `mesh` item's mapping) in scene
// coordinates, vertices merged; InputError naming the file if it is not closed.
TriangleSurface placed_surface(const Config& c) {
  const std::string path = c.get_path("file");
  TriangleSurface surface = merge_equal_vertices(read_surface_mesh(path));
  const SurfaceClosure closure = check_closure(surface);
  if (!closure.closed()) {
    const Vec3 a = surface.vertices[closure.example_edge[0]], b = surface.vertices[closure.example_edge[1]];
    std::ostringstream o;
    o << path << ": the surface does not enclose a volume: " << closure.unmatched_edges
      << " triangle edges have no partner running the other way (a hole, a crack between parts that do not share "
         "vertices, or triangles of opposite orientation), e.g. the edge from ("
      << a.transpose() << ") to (" << b.transpose() << ")";
    c.fail("file", o.str());
  }
  const Placement placement = read_placement(c);
  for (Vec3& p : surface.vertices) p = placement.scale * p + placement.offset;
  return surface;
}

// `grid: {voxel_size: h, size_from_parts: true, margin: m}`: the grid that
// covers the bounding box of the layout's surface meshes and VDB shapes
// plus m voxels on every side, its origin at the box's lower corner minus
// the margin.
VoxelGrid grid_around_parts(const Config& config) {
  const Config g = config.child("grid");
  for (const char* key : {"size", "origin"})
    if (g.has(key)) g.fail(key, "comes from the parts with size_from_parts; drop it");
  const double h = g.require_positive("voxel_size", "voxel size");
  const int margin = g.get_or<int>("margin", 0);
  if (margin < 0) g.fail("margin", "must be >= 0 voxels");
  Vec3 lo = Vec3::Constant(std::numeric_limits<double>::infinity()), hi = -lo;
  for (const Config& item : config.children("layout")) {
    std::array<Vec3, 2> box{lo, hi};
    if (item.has("mesh")) box = bounding_box(placed_surface(item.child("mesh")));
    if (item.has("vdb")) box = placed_volume(item.child("vdb")).box;
    lo = lo.cwiseMin(box[0]), hi = hi.cwiseMax(box[1]);
  }
  if (!(lo.array() <= hi.array()).all())
    g.fail("size_from_parts", "needs at least one `mesh` or `vdb` item in the layout");
  std::array<int, 3> n{};
  for (int a = 0; a < 3; ++a) {
    // A part whose extent is a whole number of voxels up to round-off takes exactly that many.
    const double voxels = (hi[a] - lo[a]) / h;
    n[a] = std::max(1, static_cast<int>(std::ceil(voxels - 1e-9 * std::max(1.0, voxels)))) + 2 * margin;
  }
  if (double(n[0]) * n[1] * n[2] > 2e9) g.fail("voxel_size", "gives the parts more than 2e9 voxels");
  VoxelGrid grid(n[0], n[1], n[2], h);
  grid.origin = lo - Vec3::Constant(margin * h);
  spdlog::info("grid from the parts: {} x {} x {} voxels from ({:.6g}, {:.6g}, {:.6g})", n[0], n[1], n[2],
               grid.origin.x(), grid.origin.y(), grid.origin.z());
  return grid;
}

// `mesh: {file: F.stl, scale: s, offset: [x, y, z]}, id: n`: the voxels whose
// centre lies inside the closed surface take id n; a file vertex p lies at
// s p + offset in the scene (metres). Returns the file's path.
std::string paint_mesh_file(const Config& item, VoxelGrid& grid, int id) {
  const Config c = item.child("mesh");
  const std::string path = c.get_path("file");
  const TriangleSurface surface = placed_surface(c);
  const auto [lo, hi] = bounding_box(surface);
  const Vec3 grid_hi = grid.origin + grid.extent();
  const long long painted = paint_surface(grid, surface, id);
  std::ostringstream box;
  box << "its bounding box after scale and offset is [" << lo.transpose() << "] - [" << hi.transpose()
      << "], the grid's [" << grid.origin.transpose() << "] - [" << grid_hi.transpose() << "]";
  if (painted == 0)
    c.fail("file", path + " contains no voxel centre: " + box.str() + " (check scale, offset and grid)");
  if ((lo.array() < grid.origin.array()).any() || (hi.array() > grid_hi.array()).any())
    spdlog::warn("{}: the surface reaches beyond the grid and is cut off there; {}", path, box.str());
  spdlog::debug("{}: {} triangles, {} voxels painted with id {}", path, surface.triangles.size(), painted, id);
  return path;
}

// `vdb: {file: F.vdb, grid: name, scale: s, offset: [x, y, z], threshold: t},
// id: n`: the voxels whose centre lies inside the level set or density take
// id n. Returns the file's path.
std::string paint_vdb_file(const Config& item, VoxelGrid& grid, int id) {
  const Config c = item.child("vdb");
  const std::string path = c.get_path("file");
  const PlacedVolume part = placed_volume(c);
  long long painted = 0;
  for (int k = 0; k < grid.nz; ++k)
    for (int j = 0; j < grid.ny; ++j)
      for (int i = 0; i < grid.nx; ++i) {
        const Vec3 in_file = (grid.voxel_center(i, j, k) - part.placement.offset) / part.placement.scale;
        if (part.volume.inside(in_file, part.threshold)) grid.at(i, j, k) = id, ++painted;
      }
  const Vec3 grid_hi = grid.origin + grid.extent();
  std::ostringstream box;
  box << "the box of its inside after scale and offset is [" << part.box[0].transpose() << "] - ["
      << part.box[1].transpose() << "], the grid's [" << grid.origin.transpose() << "] - [" << grid_hi.transpose()
      << "]";
  if (painted == 0)
    c.fail("file", path + ": " + part.volume.describe() + " contains no voxel centre: " + box.str() +
                       " (check scale, offset, threshold and grid)");
  if ((part.box[0].array() < grid.origin.array()).any() || (part.box[1].array() > grid_hi.array()).any())
    spdlog::warn("{}: the shape reaches beyond the grid and is cut off there; {}", path, box.str());
  spdlog::debug("{}: {}, {} voxels painted with id {}", path, part.volume.describe(), painted, id);
  return path;
}

// A boundary or load entry with its config path and region read.
template <class Entry>
Entry entry_on_region(const Config& entry, const VoxelGrid& grid) {
  Entry e;
  e.where = entry.path();
  e.region = read_region(entry, grid);
  return e;
}

// One entry of `boundary`: a region fixed in some components, moved by a
// displacement, or turned about an axis.
BoundaryCondition read_boundary_condition(const Config& b, const VoxelGrid& grid) {
  auto bc = entry_on_region<BoundaryCondition>(b, grid);
  const bool has_disp = b.has("displacement"), has_rot = b.has("rotation");
  if (has_disp) bc.displacement = read_vec3(b, "displacement");
  if (has_rot) {
    const Config r = b.child("rotation");
    bc.has_rotation = true;
    bc.rotation_axis = read_vec3(r, "axis");
    if (bc.rotation_axis.norm() == 0) r.fail("axis", "rotation axis must be non-zero");
    bc.rotation_axis.normalize();
    bc.rotation_center = read_vec3(r, "center");
    bc.rotation_angle = r.require_finite("angle_deg") * kPi / 180.0;
  }
  if (b.has("fix")) {
    for (const std::string& comp : b.get<std::vector<std::string>>("fix")) {
      if (comp != "x" && comp != "y" && comp != "z") b.fail("fix", "components are x, y, z; found '" + comp + "'");
      bc.fix[comp[0] - 'x'] = true;
    }
  } else if (has_disp || has_rot) {
    bc.fix[0] = bc.fix[1] = bc.fix[2] = true;
  } else {
    b.fail("", "a boundary condition needs 'fix', 'displacement' or 'rotation'");
  }
  return bc;
}

// One entry of `loads`: a total force on a region, or a traction on a face.
Load read_load(const Config& l, const VoxelGrid& grid) {
  auto load = entry_on_region<Load>(l, grid);
  const bool f = l.has("force"), t = l.has("traction");
  if (f == t) l.fail("", "a load needs exactly one of 'force' (total, N) or 'traction' (Pa)");
  load.is_traction = t;
  load.value = read_vec3(l, t ? "traction" : "force");
  if (t && load.region.kind != Region::Kind::Face) l.fail("traction", "a traction needs a face region");
  return load;
}

}  // namespace

std::vector<PaletteEntry> read_materials(const Config& config, std::vector<MaterialPtr>* material_by_id) {
  std::vector<PaletteEntry> palette;
  material_by_id->assign(1, nullptr);
  for (const Config& m : config.children("materials")) {
    PaletteEntry p;
    p.id = m.get<int>("id");
    if (p.id <= 0 || p.id > 65535) m.fail("id", "material ids are 1..65535 (0 is void)");
    p.name = m.get_or<std::string>("name", "material" + std::to_string(p.id));
    p.material = make_material(m, p);
    if (p.id >= static_cast<int>(material_by_id->size())) material_by_id->resize(p.id + 1);
    if ((*material_by_id)[p.id]) m.fail("id", "material id " + std::to_string(p.id) + " is defined twice");
    (*material_by_id)[p.id] = p.material;
    palette.push_back(p);
  }
  if (palette.empty()) config.fail("materials", "the palette is empty");
  return palette;
}

std::vector<std::string> paint_layout(const Config& config, VoxelGrid& grid,
                                      const std::vector<MaterialPtr>& material_by_id) {
  std::vector<std::string> files;
  // The `ids` list of a pattern item: each a palette id or 0 (void).
  auto id_list_of = [&](const Config& c) {
    const std::vector<int> ids = c.get<std::vector<int>>("ids");
    for (int id : ids)
      if (id < 0 || id >= static_cast<int>(material_by_id.size()) || (id > 0 && !material_by_id[id]))
        c.fail("ids", "material id " + std::to_string(id) + " is not in the palette");
    return ids;
  };
  for (const Config& item : config.children("layout")) {
    auto id_of = [&](const std::string& key) {
      const int id = item.get<int>(key);
      if (id < 0 || id >= static_cast<int>(material_by_id.size()) || (id > 0 && !material_by_id[id]))
        item.fail(key, "material id " + std::to_string(id) + " is not in the palette (0 = void)");
      return id;
    };
    if (item.has("fill")) {
      std::fill(grid.ids.begin(), grid.ids.end(), id_of("fill"));
    } else if (item.has("box")) {
      const Config b = item.child("box");
      paint_box(grid, read_vec3(b, "min"), read_vec3(b, "max"), id_of("id"));
    } else if (item.has("layers")) {
      const Config l = item.child("layers");
      const auto t = l.get<std::vector<double>>("thickness");
      const std::vector<int> ids = id_list_of(l);
      if (t.size() != ids.size() || t.empty()) l.fail("ids", "need one id per thickness");
      for (double x : t)
        if (!(x > 0)) l.fail("thickness", "layer thicknesses must be positive");
      paint_layers(grid, read_axis(l, "axis"), t, ids);
    } else if (item.has("cylinder")) {
      const Config c = item.child("cylinder");
      const int axis = read_axis(c, "axis");
      paint_cylinder(grid, axis, read_vec3(c, "center"), c.require_positive("radius"), c.get_or<double>("from", -1e300),
                     c.get_or<double>("to", 1e300), id_of("id"));
    } else if (item.has("helical_fibers")) {
      const Config c = item.child("helical_fibers");
      paint_helical_fibers(grid, read_axis(c, "axis"), read_vec3(c, "center"), c.require_positive("helix_radius"),
                           c.require_positive("pitch"), c.require_positive("fiber_radius"),
                           c.require_positive<int>("count"), id_of("id"));
    } else if (item.has("checker")) {
      const Config c = item.child("checker");
      const std::vector<int> ids = id_list_of(c);
      if (ids.size() < 2) c.fail("ids", "a checkerboard needs at least two ids");
      paint_checker(grid, c.require_positive("cell", "checker cell size"), ids);
    } else if (item.has("random_field")) {
      const Config c = item.child("random_field");
      const std::vector<int> ids = id_list_of(c);
      if (ids.empty()) c.fail("ids", "a random field needs at least one id");
      paint_random_field(grid, ids, c.get<std::uint64_t>("seed"));
    } else if (item.has("voxels")) {
      files.push_back(paint_voxel_file(item.child("voxels"), grid, material_by_id));
    } else if (item.has("mesh")) {
      files.push_back(paint_mesh_file(item, grid, id_of("id")));
    } else if (item.has("vdb")) {
      files.push_back(paint_vdb_file(item, grid, id_of("id")));
    } else {
      item.fail("",
                "a layout item needs one of: fill, box, layers, cylinder, helical_fibers, checker, random_field, "
                "voxels, mesh, vdb");
    }
  }
  return files;
}

std::string Region::describe() const {
  std::ostringstream o;
  if (kind == Kind::Face) {
    o << "face " << char('x' + axis) << (upper ? "max" : "min");
  } else {
    o << "box [" << lo.transpose() << "] - [" << hi.transpose() << "]";
  }
  return o.str();
}

Scene read_scene(const Config& config) {
  Scene s;
  s.name = config.get_or<std::string>("name", "scene");
  {
    const Config g = config.child("grid");
    if (g.get_or<bool>("size_from_parts", false)) {
      s.grid = grid_around_parts(config);
    } else {
      const auto size = g.get<std::vector<int>>("size");
      if (size.size() != 3) g.fail("size", "expected [nx, ny, nz]");
      for (int n : size)
        if (n <= 0) g.fail("size", "grid dimensions must be positive");
      if (double(size[0]) * size[1] * size[2] > 2e9) g.fail("size", "grid has more than 2e9 voxels");
      s.grid = VoxelGrid(size[0], size[1], size[2], g.require_positive("voxel_size", "voxel size"));
      if (g.has("origin")) s.grid.origin = read_vec3(g, "origin");
    }
  }
  s.palette = read_materials(config, &s.material_by_id);
  s.nonlinear = false;
  for (const auto& p : s.palette) s.nonlinear |= p.model == "neo-hookean";

  s.geometry_files = paint_layout(config, s.grid, s.material_by_id);
  if (s.grid.count_solid() == 0) config.fail("layout", "the layout leaves every voxel void (empty grid)");

  if (config.has("boundary"))
    for (const Config& b : config.children("boundary")) s.boundary.push_back(read_boundary_condition(b, s.grid));
  if (config.has("loads"))
    for (const Config& l : config.children("loads")) s.loads.push_back(read_load(l, s.grid));
  if (config.has("gravity")) s.gravity = read_vec3(config, "gravity");

  if (config.has("solver")) {
    const Config c = config.child("solver");
    NewtonOptions& o = s.newton;
    o.relative_tolerance = c.get_or<double>("tolerance", o.relative_tolerance);
    if (!(o.relative_tolerance > 0 && o.relative_tolerance < 1)) c.fail("tolerance", "must be in (0, 1)");
    o.max_iterations = c.get_or<int>("max_iterations", o.max_iterations);
    if (o.max_iterations < 1) c.fail("max_iterations", "must be at least 1");
    o.load_steps = c.get_or<int>("load_steps", o.load_steps);
    if (o.load_steps < 1) c.fail("load_steps", "must be at least 1");
    o.max_step_halvings = c.get_or<int>("max_step_halvings", o.max_step_halvings);
    LinearSolverKeys keys;
    keys.legacy_tolerance = "pcg_tolerance";
    keys.legacy_max_iterations = "pcg_max_iterations";
    const LinearSolverChoice linear = read_linear_solver_choice(
        c, {"auto", "cholmod", "pcg", "pcg-mg"}, linear_solver_defaults(o.linear_solver, o.linear), keys);
    o.linear_solver = linear.kind;
    apply_linear_solver_limits(linear, o.linear);
    o.linear.pcg_preconditioner = c.get_or<std::string>("pcg_preconditioner", o.linear.pcg_preconditioner);
    o.auto_iterative_dofs = c.get_or<int>("auto_iterative_dofs", o.auto_iterative_dofs);
  }
  return s;
}

RegionNodes select_region(const Region& region, const VoxelGrid& grid, const VoxelMesh& vm) {
  RegionNodes out;
  const HexMesh& mesh = vm.mesh;
  const double tol = 1e-9 * grid.voxel_size;
  if (region.kind == Region::Kind::Box) {
    for (int n = 0; n < mesh.num_nodes(); ++n) {
      const Vec3 p = mesh.nodes.row(n).transpose();
      if ((p.array() >= region.lo.array() - tol).all() && (p.array() <= region.hi.array() + tol).all())
        out.nodes.push_back(n);
    }
    out.weight.assign(out.nodes.size(), out.nodes.empty() ? 0.0 : 1.0 / out.nodes.size());
    return out;
  }
  // Face: every solid voxel touching the plane contributes a quarter of its
  // face area to each of the face's four nodes.
  const int a = region.axis, u = (a + 1) % 3, v = (a + 2) % 3;
  const int dims[3] = {grid.nx, grid.ny, grid.nz};
  const int layer = region.upper ? dims[a] - 1 : 0;
  std::map<int, double> area;
  const double quarter = 0.25 * grid.voxel_size * grid.voxel_size;
  for (int iu = 0; iu < dims[u]; ++iu)
    for (int iv = 0; iv < dims[v]; ++iv) {
      int ijk[3];
      ijk[a] = layer;
      ijk[u] = iu;
      ijk[v] = iv;
      const int e = vm.voxel_element[grid.index(ijk[0], ijk[1], ijk[2])];
      if (e < 0) continue;
      for (int c = 0; c < 8; ++c) {
        const int bits[3] = {c >> 2 & 1, c >> 1 & 1, c & 1};
        if (bits[a] != (region.upper ? 1 : 0)) continue;
        area[mesh.elements[e][c]] += quarter;
      }
    }
  for (const auto& [n, w] : area) {
    out.nodes.push_back(n);
    out.weight.push_back(w);
  }
  return out;
}

namespace {

// Each connected part of the mesh must have its six rigid motions fixed by
// the Dirichlet DOFs, or the stiffness matrix is singular.
void check_rigid_motion_fixed(const HexMesh& mesh, const DirichletConditions& d) {
  const int n = mesh.num_nodes();
  std::vector<int> parent(n);
  std::iota(parent.begin(), parent.end(), 0);
  auto find = [&](int x) {
    while (parent[x] != x) x = parent[x] = parent[parent[x]];
    return x;
  };
  for (const auto& el : mesh.elements)
    for (int i = 1; i < 8; ++i) parent[find(el[i])] = find(el[0]);
  std::map<int, Eigen::Matrix<double, 6, 6>> gram;
  std::map<int, int> part_nodes;
  const Vec3 c = 0.5 * (mesh.bbox_min() + mesh.bbox_max());
  const double L = std::max(1e-300, (mesh.bbox_max() - mesh.bbox_min()).norm());
  for (int i = 0; i < n; ++i) {
    const int root = find(i);
    part_nodes[root]++;
    auto& G = gram[root];
    if (part_nodes[root] == 1) G.setZero();
    const Vec3 p = (mesh.nodes.row(i).transpose() - c) / L;
    for (int a = 0; a < 3; ++a) {
      if (!d.fixed[3 * i + a]) continue;
      // Row of the rigid-mode matrix for DOF (i, a): translations, then rotations e_k x p.
      Eigen::Matrix<double, 6, 1> r = Eigen::Matrix<double, 6, 1>::Zero();
      r[a] = 1;
      for (int k = 0; k < 3; ++k) r[3 + k] = Vec3::Unit(k).cross(p)[a];
      G += r * r.transpose();
    }
  }
  int part_index = 0;
  for (const auto& [root, G] : gram) {
    const double lmin = Eigen::SelfAdjointEigenSolver<Eigen::Matrix<double, 6, 6>>(G).eigenvalues().minCoeff();
    if (!(lmin > 1e-10)) {
      std::ostringstream msg;
      msg << "the boundary conditions leave rigid motion free";
      if (gram.size() > 1) msg << " for disconnected part " << part_index << " (" << part_nodes[root] << " nodes)";
      msg << ": the stiffness matrix would be singular; fix enough nodes (e.g. a whole face) on every part";
      throw InputError(msg.str());
    }
    ++part_index;
  }
}

}  // namespace

StaticConditions build_static_conditions(const Scene& scene, const VoxelMesh& vm) {
  const HexMesh& mesh = vm.mesh;
  StaticConditions sc;
  sc.dirichlet = DirichletConditions::none(mesh.num_dofs());
  sc.force = VecX::Zero(mesh.num_dofs());
  for (const auto& bc : scene.boundary) {
    const RegionNodes sel = select_region(bc.region, scene.grid, vm);
    if (sel.nodes.empty())
      throw InputError(bc.where + ": region (" + bc.region.describe() + ") selects no solid node; it lies in void");
    const Mat3 R = Eigen::AngleAxisd(bc.rotation_angle, bc.rotation_axis).toRotationMatrix();
    for (int node : sel.nodes) {
      const Vec3 X = mesh.nodes.row(node).transpose();
      Vec3 u = bc.displacement;
      if (bc.has_rotation) u += R * (X - bc.rotation_center) + bc.rotation_center - X;
      for (int a = 0; a < 3; ++a)
        if (bc.fix[a]) {
          sc.dirichlet.fixed[3 * node + a] = 1;
          sc.dirichlet.displacement[3 * node + a] = u[a];
        }
    }
  }
  if (sc.dirichlet.count_fixed() == 0)
    throw InputError(
        "the scene has no boundary condition: without fixed nodes the stiffness matrix is singular "
        "(add a 'boundary' entry with 'fix' or 'displacement')");
  check_rigid_motion_fixed(mesh, sc.dirichlet);

  for (const auto& load : scene.loads) {
    const RegionNodes sel = select_region(load.region, scene.grid, vm);
    if (sel.nodes.empty())
      throw InputError(load.where + ": load region (" + load.region.describe() +
                       ") selects no solid node; a load on void has nothing to act on");
    double total = 0;
    for (double w : sel.weight) total += w;
    for (size_t k = 0; k < sel.nodes.size(); ++k) {
      const double share = load.is_traction ? sel.weight[k] : sel.weight[k] / total;
      sc.force.segment<3>(3 * sel.nodes[k]) += share * load.value;
    }
  }
  if (scene.gravity.norm() > 0) {
    const double vol = std::pow(scene.grid.voxel_size, 3);
    std::vector<double> density(scene.material_by_id.size(), 0.0);
    for (const auto& p : scene.palette) density[p.id] = p.density;
    for (int e = 0; e < mesh.num_elements(); ++e) {
      const double m = density[mesh.element_tag[e]] * vol;
      for (int node : mesh.elements[e]) sc.force.segment<3>(3 * node) += 0.125 * m * scene.gravity;
    }
  }
  return sc;
}

}  // namespace msfab
