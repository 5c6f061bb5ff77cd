#include "io/surface_mesh_io.hpp"

#include <algorithm>
#include <cctype>
#include <cmath>
#include <cstring>
#include <sstream>

#include "core/errors.hpp"
#include "io/input_file.hpp"

namespace msfab {
namespace {

std::string lower(std::string s) {
  std::transform(s.begin(), s.end(), s.begin(), [](unsigned char c) { return char(std::tolower(c)); });
  return s;
}

void require_finite(const Vec3& p, const std::string& where) {
  if (!p.allFinite()) throw InputError(where + ": a vertex coordinate is not a finite number");
}

// A binary STL is an 80-byte header, a little-endian uint32 triangle count
// and 50 bytes per triangle. Files that begin with "solid" are usually ASCII,
// but some binary writers put "solid" in the header too, so the size decides.
bool is_binary_stl(const std::string& bytes) {
  if (bytes.size() < 84) return false;
  std::uint32_t n = 0;
  std::memcpy(&n, bytes.data() + 80, 4);
  return bytes.size() == 84 + 50 * std::uint64_t(n);
}

float read_float(const char* p) {
  float f;
  std::memcpy(&f, p, 4);
  return f;
}

TriangleSurface parse_binary_stl(const std::string& bytes, const std::string& source) {
  std::uint32_t n = 0;
  std::memcpy(&n, bytes.data() + 80, 4);
  TriangleSurface s;
  s.vertices.reserve(3 * std::size_t(n));
  s.triangles.reserve(n);
  for (std::uint32_t t = 0; t < n; ++t) {
    const char* record = bytes.data() + 84 + 50 * std::size_t(t) + 12;  // after the normal
    for (int c = 0; c < 3; ++c) {
      const Vec3 p(read_float(record + 12 * c), read_float(record + 12 * c + 4), read_float(record + 12 * c + 8));
      require_finite(p, source + ": triangle " + std::to_string(t));
      s.vertices.push_back(p);
    }
    const int v = static_cast<int>(3 * t);
    s.triangles.push_back({v, v + 1, v + 2});
  }
  return s;
}

double parse_number(const std::string& token, const std::string& where) {
  try {
    std::size_t used = 0;
    const double value = std::stod(token, &used);
    if (used == token.size() && std::isfinite(value)) return value;
  } catch (const std::exception&) {
  }
  throw InputError(where + ": '" + token + "' is not a finite number");
}

TriangleSurface parse_ascii_stl(const std::string& text, const std::string& source) {
  TriangleSurface s;
  std::istringstream in(text);
  std::string line;
  int in_facet = -1;  // vertices of the open facet, -1 outside a facet
  for (int line_no = 1; std::getline(in, line); ++line_no) {
    std::istringstream words(line);
    std::string keyword;
    if (!(words >> keyword)) continue;
    keyword = lower(keyword);
    const std::string where = source + ": line " + std::to_string(line_no);
    if (keyword == "facet") {
      if (in_facet >= 0) throw InputError(where + ": 'facet' inside an unfinished facet");
      in_facet = 0;
    } else if (keyword == "vertex") {
      if (in_facet < 0) throw InputError(where + ": 'vertex' outside a facet");
      if (in_facet == 3) throw InputError(where + ": a facet with more than three vertices");
      std::string x, y, z, extra;
      if (!(words >> x >> y >> z) || (words >> extra)) throw InputError(where + ": expected 'vertex x y z'");
      s.vertices.emplace_back(parse_number(x, where), parse_number(y, where), parse_number(z, where));
      ++in_facet;
    } else if (keyword == "endfacet") {
      if (in_facet != 3) throw InputError(where + ": a facet needs exactly three vertices");
      const int v = static_cast<int>(s.vertices.size()) - 3;
      s.triangles.push_back({v, v + 1, v + 2});
      in_facet = -1;
    } else if (keyword != "solid" && keyword != "endsolid" && keyword != "outer" && keyword != "endloop") {
      throw InputError(where + ": unexpected '" + keyword + "' in an ASCII STL file");
    }
  }
  if (in_facet >= 0) throw InputError(source + ": the file ends inside a facet (truncated?)");
  return s;
}

}  // namespace

TriangleSurface parse_stl(const std::string& bytes, const std::string& source) {
  TriangleSurface s;
  if (is_binary_stl(bytes)) {
    s = parse_binary_stl(bytes, source);
  } else {
    const std::size_t start = bytes.find_first_not_of(" \t\r\n");
    if (start == std::string::npos || lower(bytes.substr(start, 5)) != "solid")
      throw InputError(source + ": neither a binary STL (84 + 50 n bytes for n triangles; this file has " +
                       std::to_string(bytes.size()) + ") nor an ASCII one (starting with 'solid')");
    s = parse_ascii_stl(bytes, source);
  }
  if (s.triangles.empty()) throw InputError(source + ": the file holds no triangles");
  return s;
}

TriangleSurface parse_obj(const std::string& text, const std::string& source) {
  TriangleSurface s;
  std::istringstream in(text);
  std::string line;
  for (int line_no = 1; std::getline(in, line); ++line_no) {
    std::istringstream words(line);
    std::string keyword;
    if (!(words >> keyword) || keyword[0] == '#') continue;
    const std::string where = source + ": line " + std::to_string(line_no);
    if (keyword == "v") {
      std::string x, y, z;
      if (!(words >> x >> y >> z)) throw InputError(where + ": expected 'v x y z'");
      s.vertices.emplace_back(parse_number(x, where), parse_number(y, where), parse_number(z, where));
    } else if (keyword == "f") {
      std::vector<int> corners;
      std::string token;
      while (words >> token) {
        // "v", "v/vt", "v//vn" or "v/vt/vn"; negative indices count back
        // from the last vertex read so far.
        const std::string index_text = token.substr(0, token.find('/'));
        long long index = 0;
        try {
          std::size_t used = 0;
          index = std::stoll(index_text, &used);
          if (used != index_text.size()) throw std::invalid_argument(token);
        } catch (const std::exception&) {
          throw InputError(where + ": '" + token + "' is not a vertex index");
        }
        const long long count = static_cast<long long>(s.vertices.size());
        const long long zero_based = index > 0 ? index - 1 : count + index;
        if (index == 0 || zero_based < 0 || zero_based >= count)
          throw InputError(where + ": vertex index " + std::to_string(index) + " does not name one of the " +
                           std::to_string(count) + " vertices read so far");
        corners.push_back(static_cast<int>(zero_based));
      }
      if (corners.size() < 3) throw InputError(where + ": a face needs at least three vertices");
      for (std::size_t c = 1; c + 1 < corners.size(); ++c)
        s.triangles.push_back({corners[0], corners[c], corners[c + 1]});
    }
    // vt, vn, g, o, s, l, usemtl, mtllib, ...: not geometry of the volume.
  }
  if (s.triangles.empty()) throw InputError(source + ": the file holds no faces ('f' lines)");
  return s;
}

TriangleSurface read_surface_mesh(const std::string& path) {
  const std::size_t dot = path.find_last_of('.');
  const std::string extension = dot == std::string::npos ? "" : lower(path.substr(dot));
  if (extension != ".stl" && extension != ".obj")
    throw InputError(path + ": unknown surface mesh format '" + extension + "' (expected .stl or .obj)");
  const std::string bytes = read_text_file(path, kMaxSurfaceMeshBytes);
  return extension == ".stl" ? parse_stl(bytes, path) : parse_obj(bytes, path);
}

}  // namespace msfab
