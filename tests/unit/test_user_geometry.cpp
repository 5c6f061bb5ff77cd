// A user's own object: closed surfaces (STL, OBJ) voxelized by winding
// number, and voxel arrays (.npy, raw) read into a grid.
#include <gtest/gtest.h>

#include <cmath>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <random>

#include "core/errors.hpp"
#include "fem/surface_voxelizer.hpp"
#include "fem/voxel_shapes.hpp"
#include "io/config.hpp"
#include "io/surface_mesh_io.hpp"
#include "io/voxel_array_io.hpp"
#include "scene/scene.hpp"

using namespace msfab;

namespace {

// The 12 triangles of the box [lo, hi], outward normals.
TriangleSurface box_surface(const Vec3& lo, const Vec3& hi) {
  TriangleSurface s;
  for (int c = 0; c < 8; ++c)
    s.vertices.emplace_back(c & 1 ? hi.x() : lo.x(), c & 2 ? hi.y() : lo.y(), c & 4 ? hi.z() : lo.z());
  const int quads[6][4] = {{0, 2, 3, 1}, {4, 5, 7, 6}, {0, 1, 5, 4}, {2, 6, 7, 3}, {0, 4, 6, 2}, {1, 3, 7, 5}};
  for (const auto& q : quads) {
    s.triangles.push_back({q[0], q[1], q[2]});
    s.triangles.push_back({q[0], q[2], q[3]});
  }
  return s;
}

TriangleSurface reversed_orientation(TriangleSurface s) {
  for (auto& t : s.triangles) std::swap(t[1], t[2]);
  return s;
}

// The octahedron |x - c|_1 <= r, outward normals.
TriangleSurface octahedron(const Vec3& c, double r) {
  TriangleSurface s;
  s.vertices = {c + Vec3(r, 0, 0), c - Vec3(r, 0, 0), c + Vec3(0, r, 0),
                c - Vec3(0, r, 0), c + Vec3(0, 0, r), c - Vec3(0, 0, r)};
  for (int sx = 0; sx < 2; ++sx)
    for (int sy = 0; sy < 2; ++sy)
      for (int sz = 0; sz < 2; ++sz) {
        std::array<int, 3> t{sx, 2 + sy, 4 + sz};
        // Outward when (x, y, z) of the octant is right-handed.
        const int flips = (sx == 1) + (sy == 1) + (sz == 1);
        if (flips % 2 == 1) std::swap(t[1], t[2]);
        s.triangles.push_back(t);
      }
  return s;
}

// A subdivided icosahedron with every vertex pushed radially by a random
// amount: a closed, non-convex, irregularly triangulated surface.
TriangleSurface bumpy_sphere(const Vec3& centre, double radius, double bump, std::uint64_t seed) {
  const double g = (1 + std::sqrt(5.0)) / 2;
  TriangleSurface s;
  s.vertices = {{-1, g, 0},  {1, g, 0},  {-1, -g, 0}, {1, -g, 0}, {0, -1, g},  {0, 1, g},
                {0, -1, -g}, {0, 1, -g}, {g, 0, -1},  {g, 0, 1},  {-g, 0, -1}, {-g, 0, 1}};
  s.triangles = {{0, 11, 5},  {0, 5, 1},  {0, 1, 7},  {0, 7, 10}, {0, 10, 11}, {1, 5, 9}, {5, 11, 4},
                 {11, 10, 2}, {10, 7, 6}, {7, 1, 8},  {3, 9, 4},  {3, 4, 2},   {3, 2, 6}, {3, 6, 8},
                 {3, 8, 9},   {4, 9, 5},  {2, 4, 11}, {6, 2, 10}, {8, 6, 7},   {9, 8, 1}};
  for (int level = 0; level < 3; ++level) {
    std::map<std::pair<int, int>, int> middle;
    auto mid = [&](int a, int b) {
      const auto key = std::minmax(a, b);
      auto it = middle.find(key);
      if (it != middle.end()) return it->second;
      s.vertices.push_back(0.5 * (s.vertices[a] + s.vertices[b]));
      return middle[key] = static_cast<int>(s.vertices.size()) - 1;
    };
    std::vector<std::array<int, 3>> finer;
    for (const auto& t : s.triangles) {
      const int ab = mid(t[0], t[1]), bc = mid(t[1], t[2]), ca = mid(t[2], t[0]);
      finer.push_back({t[0], ab, ca});
      finer.push_back({t[1], bc, ab});
      finer.push_back({t[2], ca, bc});
      finer.push_back({ab, bc, ca});
    }
    s.triangles = finer;
  }
  std::mt19937_64 rng(seed);
  std::uniform_real_distribution<double> u(-bump, bump);
  for (Vec3& p : s.vertices) p = centre + (radius + u(rng)) * p.normalized();
  return s;
}

// Generalized winding number by solid angles (Van Oosterom-Strackee), an
// independent reference for points away from the surface.
double winding_number(const TriangleSurface& s, const Vec3& p) {
  long double total = 0;
  for (const auto& t : s.triangles) {
    const Vec3 a = s.vertices[t[0]] - p, b = s.vertices[t[1]] - p, c = s.vertices[t[2]] - p;
    const double la = a.norm(), lb = b.norm(), lc = c.norm();
    const double num = a.dot(b.cross(c));
    const double den = la * lb * lc + a.dot(b) * lc + b.dot(c) * la + c.dot(a) * lb;
    total += 2 * std::atan2(num, den);
  }
  return static_cast<double>(total / (4 * M_PI));
}

std::string write_temp(const std::string& name, const std::string& bytes) {
  const auto path = std::filesystem::temp_directory_path() / ("msfab_user_geometry_" + name);
  std::ofstream(path, std::ios::binary) << bytes;
  return path.string();
}

std::string ascii_stl(const TriangleSurface& s) {
  std::ostringstream o;
  o.precision(17);
  o << "solid part\n";
  for (const auto& t : s.triangles) {
    o << "  facet normal 0 0 0\n    outer loop\n";
    for (int c = 0; c < 3; ++c)
      o << "      vertex " << s.vertices[t[c]].x() << " " << s.vertices[t[c]].y() << " " << s.vertices[t[c]].z()
        << "\n";
    o << "    endloop\n  endfacet\n";
  }
  o << "endsolid part\n";
  return o.str();
}

std::string binary_stl(const TriangleSurface& s, const std::string& header = "binary part") {
  std::string out(80, ' ');
  std::memcpy(out.data(), header.data(), std::min<std::size_t>(header.size(), 80));
  const std::uint32_t n = static_cast<std::uint32_t>(s.triangles.size());
  out.append(reinterpret_cast<const char*>(&n), 4);
  for (const auto& t : s.triangles) {
    float record[12] = {0, 0, 0};
    for (int c = 0; c < 3; ++c)
      for (int a = 0; a < 3; ++a) record[3 + 3 * c + a] = static_cast<float>(s.vertices[t[c]][a]);
    out.append(reinterpret_cast<const char*>(record), sizeof record);
    out.append(2, '\0');
  }
  return out;
}

std::string npy_file_bytes(const std::string& descr, bool fortran, const std::string& shape, const std::string& data) {
  std::string header =
      "{'descr': '" + descr + "', 'fortran_order': " + (fortran ? "True" : "False") + ", 'shape': " + shape + ", }";
  while ((10 + header.size() + 1) % 64 != 0) header += ' ';
  header += '\n';
  std::string out = "\x93NUMPY";
  out += char(1);
  out += char(0);
  out += char(header.size() & 0xff);
  out += char(header.size() >> 8);
  return out + header + data;
}

}  // namespace

TEST(SurfaceVoxelizer, BoxSurfaceEqualsThePaintedBoxInEitherOrientation) {
  VoxelGrid expected(12, 10, 8, 0.5, 0);
  const Vec3 lo(1.0, 0.5, 1.5), hi(4.5, 3.0, 3.5);  // faces on voxel boundaries
  paint_box(expected, lo, hi, 1);
  for (const TriangleSurface& s : {box_surface(lo, hi), reversed_orientation(box_surface(lo, hi))}) {
    VoxelGrid g(12, 10, 8, 0.5, 0);
    EXPECT_EQ(paint_surface(g, s, 1), static_cast<long long>(expected.count_solid()));
    EXPECT_EQ(g.ids, expected.ids);
  }
}

TEST(SurfaceVoxelizer, ColumnsThroughVerticesAndEdgesCountEachSheetOnce) {
  // Every vertex lies on a voxel-centre column and at a voxel-centre height,
  // so columns pass exactly through vertices and along edges' projections.
  VoxelGrid g(11, 11, 11, 1.0, 0);
  const Vec3 c = g.voxel_center(5, 5, 5);
  const TriangleSurface s = octahedron(c, 3.0);
  ASSERT_TRUE(check_closure(s).closed());
  const std::vector<char> inside = voxels_inside(g, s);
  int checked = 0;
  for (int k = 0; k < 11; ++k)
    for (int j = 0; j < 11; ++j)
      for (int i = 0; i < 11; ++i) {
        const int l1 = std::abs(i - 5) + std::abs(j - 5) + std::abs(k - 5);
        if (l1 == 3) continue;  // the centre lies on the surface: either answer is right
        EXPECT_EQ(bool(inside[g.index(i, j, k)]), l1 < 3) << i << " " << j << " " << k;
        ++checked;
      }
  EXPECT_GT(checked, 1000);
}

TEST(SurfaceVoxelizer, MatchesSolidAngleWindingNumberOnAnIrregularSurface) {
  VoxelGrid g(24, 22, 20, 0.1, 0);
  g.origin = Vec3(-0.13, 0.07, -0.02);
  const TriangleSurface s = bumpy_sphere(Vec3(1.1, 1.2, 0.95), 0.85, 0.15, 7);
  ASSERT_TRUE(check_closure(s).closed());
  const std::vector<char> inside = voxels_inside(g, s);
  int in = 0, compared = 0;
  for (int k = 0; k < g.nz; ++k)
    for (int j = 0; j < g.ny; ++j)
      for (int i = 0; i < g.nx; ++i) {
        const Vec3 p = g.voxel_center(i, j, k);
        const double w = winding_number(s, p);
        if (std::abs(std::abs(w) - 0.5) < 0.45) continue;  // too close to the surface for the reference
        EXPECT_EQ(bool(inside[g.index(i, j, k)]), std::abs(w) > 0.5) << p.transpose() << " w " << w;
        in += inside[g.index(i, j, k)];
        ++compared;
      }
  EXPECT_GT(in, 500);
  EXPECT_GT(compared, 9000);
  // Inward-facing normals give winding -1 inside: the same voxels.
  EXPECT_EQ(voxels_inside(g, reversed_orientation(s)), inside);
}

TEST(SurfaceVoxelizer, AnInwardFacingInnerShellLeavesACavity) {
  VoxelGrid g(10, 4, 10, 1.0, 0);
  TriangleSurface s = box_surface(Vec3(0, 0, 0), Vec3(10, 4, 10));
  const TriangleSurface cavity = reversed_orientation(box_surface(Vec3(3, 1, 3), Vec3(7, 3, 7)));
  const int base = static_cast<int>(s.vertices.size());
  s.vertices.insert(s.vertices.end(), cavity.vertices.begin(), cavity.vertices.end());
  for (const auto& t : cavity.triangles) s.triangles.push_back({base + t[0], base + t[1], base + t[2]});
  ASSERT_TRUE(check_closure(s).closed());
  EXPECT_EQ(paint_surface(g, s, 2), 400 - 32);
  EXPECT_EQ(g.at(5, 2, 5), 0);
  EXPECT_EQ(g.at(1, 2, 5), 2);
}

TEST(SurfaceVoxelizer, ClosureCountsHolesAndFlippedTriangles) {
  TriangleSurface s = box_surface(Vec3(0, 0, 0), Vec3(1, 1, 1));
  EXPECT_TRUE(check_closure(s).closed());
  TriangleSurface hole = s;
  hole.triangles.pop_back();
  EXPECT_EQ(check_closure(hole).unmatched_edges, 3);
  TriangleSurface flip = s;
  std::swap(flip.triangles[0][1], flip.triangles[0][2]);
  EXPECT_EQ(check_closure(flip).unmatched_edges, 6);
}

TEST(SurfaceMeshIo, AsciiAndBinaryStlAndObjGiveTheSameSurface) {
  const TriangleSurface box = box_surface(Vec3(0.25, 0.5, 0.75), Vec3(1.5, 2.25, 1.0));
  const TriangleSurface a = merge_equal_vertices(parse_stl(ascii_stl(box), "a.stl"));
  // A binary file whose header starts with "solid" is still binary.
  const TriangleSurface b = merge_equal_vertices(parse_stl(binary_stl(box, "solid but binary"), "b.stl"));
  std::ostringstream obj;
  obj << "# a box\no part\n";
  for (const Vec3& v : box.vertices) obj << "v " << v.x() << " " << v.y() << " " << v.z() << "\nvn 0 0 1\n";
  // Quads as "v/vt/vn" with negative (relative) indices: two triangles each.
  const int quads[6][4] = {{0, 2, 3, 1}, {4, 5, 7, 6}, {0, 1, 5, 4}, {2, 6, 7, 3}, {0, 4, 6, 2}, {1, 3, 7, 5}};
  for (const auto& q : quads)
    obj << "f " << q[0] - 8 << "/1/1 " << q[1] - 8 << "//1 " << q[2] + 1 << " " << q[3] + 1 << "\n";
  const TriangleSurface o = merge_equal_vertices(parse_obj(obj.str(), "c.obj"));
  for (const TriangleSurface* s : {&a, &b, &o}) {
    EXPECT_EQ(s->vertices.size(), 8u);
    EXPECT_EQ(s->triangles.size(), 12u);
    EXPECT_TRUE(check_closure(*s).closed());
    VoxelGrid g(8, 12, 6, 0.25, 0), ref(8, 12, 6, 0.25, 0);
    paint_box(ref, Vec3(0.25, 0.5, 0.75), Vec3(1.5, 2.25, 1.0), 1);
    paint_surface(g, *s, 1);
    EXPECT_EQ(g.ids, ref.ids);
  }
}

TEST(SurfaceMeshIo, MalformedFilesNameTheFileAndLine) {
  auto message = [](auto f) {
    try {
      f();
    } catch (const InputError& e) {
      return std::string(e.what());
    }
    return std::string("no error");
  };
  EXPECT_NE(message([] {
              parse_stl("solid x\nfacet normal 0 0 1\nouter loop\nvertex 0 0\n", "p.stl");
            }).find("p.stl: line 4"),
            std::string::npos);
  EXPECT_NE(
      message([] { parse_stl("solid x\nfacet normal 0 0 1\nouter loop\nvertex 0 0 0\n", "p.stl"); }).find("truncated"),
      std::string::npos);
  EXPECT_NE(message([] { parse_stl("hello", "p.stl"); }).find("neither a binary STL"), std::string::npos);
  EXPECT_NE(message([] { parse_stl("solid empty\nendsolid\n", "p.stl"); }).find("no triangles"), std::string::npos);
  EXPECT_NE(message([] { parse_obj("v 0 0 0\nv 1 0 0\nf 1 2 3\n", "q.obj"); }).find("q.obj: line 3: vertex index 3"),
            std::string::npos);
  EXPECT_NE(message([] { parse_obj("v 0 0 nan\n", "q.obj"); }).find("not a finite number"), std::string::npos);
  EXPECT_NE(message([] { read_surface_mesh("part.ply"); }).find("unknown surface mesh format"), std::string::npos);
}

TEST(VoxelArrayIo, NpyInCAndFortranOrderAndEveryIntegerWidth) {
  // ids[i, j, k] = 1 + i + 2 j + 6 k for a 2 x 3 x 4 grid.
  const int nx = 2, ny = 3, nz = 4;
  std::vector<int> expected(nx * ny * nz);
  for (int k = 0; k < nz; ++k)
    for (int j = 0; j < ny; ++j)
      for (int i = 0; i < nx; ++i) expected[i + nx * (j + ny * k)] = 1 + i + 2 * j + 6 * k;
  std::string c_u1, f_u1, c_i4, c_u2_big;
  for (int i = 0; i < nx; ++i)
    for (int j = 0; j < ny; ++j)
      for (int k = 0; k < nz; ++k) {
        const int v = 1 + i + 2 * j + 6 * k;
        c_u1 += char(v);
        const std::int32_t w = v;
        c_i4.append(reinterpret_cast<const char*>(&w), 4);
        c_u2_big += char(0);
        c_u2_big += char(v);
      }
  for (int v : expected) f_u1 += char(v);
  EXPECT_EQ(parse_npy_voxel_ids(npy_file_bytes("|u1", false, "(2, 3, 4)", c_u1), "a.npy", nx, ny, nz), expected);
  EXPECT_EQ(parse_npy_voxel_ids(npy_file_bytes("|u1", true, "(2, 3, 4)", f_u1), "a.npy", nx, ny, nz), expected);
  EXPECT_EQ(parse_npy_voxel_ids(npy_file_bytes("<i4", false, "(2, 3, 4)", c_i4), "a.npy", nx, ny, nz), expected);
  EXPECT_EQ(parse_npy_voxel_ids(npy_file_bytes(">u2", false, "(2, 3, 4)", c_u2_big), "a.npy", nx, ny, nz), expected);
  // A 2D array for a grid one voxel thick.
  std::string flat;
  for (int i = 0; i < nx; ++i)
    for (int j = 0; j < ny; ++j) flat += char(1 + i + 2 * j);
  EXPECT_EQ(parse_npy_voxel_ids(npy_file_bytes("|u1", false, "(2, 3)", flat), "a.npy", nx, ny, 1),
            std::vector<int>(expected.begin(), expected.begin() + nx * ny));

  EXPECT_THROW(parse_npy_voxel_ids(npy_file_bytes("|u1", false, "(3, 2, 4)", c_u1), "a.npy", nx, ny, nz), InputError);
  EXPECT_THROW(
      parse_npy_voxel_ids(npy_file_bytes("<f8", false, "(2, 3, 4)", std::string(192, '\0')), "a.npy", nx, ny, nz),
      InputError);
  EXPECT_THROW(parse_npy_voxel_ids(npy_file_bytes("|u1", false, "(2, 3, 4)", c_u1.substr(1)), "a.npy", nx, ny, nz),
               InputError);
  EXPECT_THROW(parse_npy_voxel_ids("not numpy", "a.npy", nx, ny, nz), InputError);
  std::string negative = c_i4;
  negative[0] = char(0xff), negative[1] = char(0xff), negative[2] = char(0xff), negative[3] = char(0xff);
  try {
    parse_npy_voxel_ids(npy_file_bytes("<i4", false, "(2, 3, 4)", negative), "a.npy", nx, ny, nz);
    ADD_FAILURE() << "a negative id was accepted";
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find("value -1"), std::string::npos) << e.what();
  }
}

TEST(VoxelArrayIo, RawFilesNeedTheirDtypeAndExactSize) {
  std::string bytes;
  for (int v = 0; v < 24; ++v) {
    const std::uint16_t w = static_cast<std::uint16_t>(v % 3);
    bytes.append(reinterpret_cast<const char*>(&w), 2);
  }
  const std::string path = write_temp("ids.raw", bytes);
  const std::vector<int> ids = read_voxel_ids(path, 2, 3, 4, "uint16");
  for (int v = 0; v < 24; ++v) EXPECT_EQ(ids[v], v % 3);
  EXPECT_THROW(read_voxel_ids(path, 2, 3, 4), InputError);             // no dtype
  EXPECT_THROW(read_voxel_ids(path, 2, 3, 4, "float32"), InputError);  // not an id type
  EXPECT_THROW(read_voxel_ids(path, 2, 3, 4, "uint8"), InputError);    // 48 bytes, 24 expected
  std::filesystem::remove(path);
}

TEST(UserGeometry, SceneLayoutFromStlAndNpyEqualsTheBoxScene) {
  const Vec3 lo(0.001, 0.002, 0.0), hi(0.004, 0.006, 0.003);
  // The STL in millimetres, placed by scale and offset.
  TriangleSurface mm = box_surface(1e3 * (lo - Vec3(0.001, 0, 0)), 1e3 * (hi - Vec3(0.001, 0, 0)));
  const std::string stl = write_temp("box.stl", binary_stl(mm));
  const std::string common =
      "grid: {size: [6, 8, 4], voxel_size: 0.001}\n"
      "materials: [{id: 1, model: linear, E: 1.0e6, nu: 0.3}, {id: 2, model: linear, E: 1.0e7, nu: 0.3}]\n"
      "boundary: [{region: {face: zmin}, fix: [x, y, z]}]\n";
  const Scene boxes = read_scene(Config::from_string(
      common + "layout: [{fill: 1}, {box: {min: [0.001, 0.002, 0], max: [0.004, 0.006, 0.003]}, id: 2}]\n",
      "box.yaml"));
  const Scene from_stl = read_scene(Config::from_string(
      common + "layout: [{fill: 1}, {mesh: {file: " + stl + ", scale: 0.001, offset: [0.001, 0, 0]}, id: 2}]\n",
      "stl.yaml"));
  EXPECT_EQ(from_stl.grid.ids, boxes.grid.ids);

  std::string data;  // C order: k fastest
  for (int i = 0; i < 6; ++i)
    for (int j = 0; j < 8; ++j)
      for (int k = 0; k < 4; ++k) data += char(boxes.grid.at(i, j, k));
  const std::string array = write_temp("ids.npy", npy_file_bytes("|u1", false, "(6, 8, 4)", data));
  const Scene from_npy =
      read_scene(Config::from_string(common + "layout: [{voxels: {file: " + array + "}}]\n", "npy.yaml"));
  EXPECT_EQ(from_npy.grid.ids, boxes.grid.ids);

  // An id outside the palette, a surface with a hole and a surface outside
  // the grid are refused, naming the file.
  data[5] = char(3);
  const std::string bad_array = write_temp("bad.npy", npy_file_bytes("|u1", false, "(6, 8, 4)", data));
  EXPECT_THROW(read_scene(Config::from_string(common + "layout: [{voxels: {file: " + bad_array + "}}]\n", "npy.yaml")),
               InputError);
  TriangleSurface holed = mm;
  holed.triangles.pop_back();
  const std::string holed_stl = write_temp("holed.stl", binary_stl(holed));
  try {
    read_scene(Config::from_string(
        common + "layout: [{fill: 1}, {mesh: {file: " + holed_stl + ", scale: 0.001}, id: 2}]\n", "stl.yaml"));
    ADD_FAILURE() << "an open surface was accepted";
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find("does not enclose a volume: 3 triangle edges"), std::string::npos) << e.what();
  }
  EXPECT_THROW(read_scene(Config::from_string(common + "layout: [{fill: 1}, {mesh: {file: " + stl +
                                                  ", scale: 0.001, offset: [1, 0, 0]}, id: 2}]\n",
                                              "stl.yaml")),
               InputError);
  for (const std::string& p : {stl, array, bad_array, holed_stl}) std::filesystem::remove(p);
}
