#include "dynamics/scene_parameters.hpp"

#include <yaml-cpp/yaml.h>

#include <algorithm>
#include <cctype>
#include <cmath>
#include <cstdio>
#include <map>
#include <stdexcept>

#include "core/errors.hpp"
#include "fem/hex8.hpp"

namespace msfab {

// ---- morph ------------------------------------------------------------------

GeometryMorph::GeometryMorph(std::array<std::vector<double>, 3> reference, std::array<std::vector<double>, 3> current)
    : reference_(std::move(reference)), current_(std::move(current)) {}

bool GeometryMorph::is_identity() const {
  for (int a = 0; a < 3; ++a)
    if (reference_[a] != current_[a]) return false;
  return true;
}

double GeometryMorph::map(int axis, double x) const {
  const std::vector<double>& b = reference_[axis];
  const std::vector<double>& c = current_[axis];
  if (b.empty()) return x;
  // Outside the faces the map translates with the nearest face, so regions
  // just beyond the body (a flat clamp on a face) move with it.
  if (x <= b.front()) return x + (c.front() - b.front());
  if (x >= b.back()) return x + (c.back() - b.back());
  const std::size_t k = static_cast<std::size_t>(std::upper_bound(b.begin(), b.end(), x) - b.begin()) - 1;
  const double s = (x - b[k]) / (b[k + 1] - b[k]);
  return c[k] + s * (c[k + 1] - c[k]);
}

Vec3 GeometryMorph::map(const Vec3& x) const { return Vec3(map(0, x.x()), map(1, x.y()), map(2, x.z())); }

void GeometryMorph::apply(HexMesh& mesh) const {
  if (is_identity()) return;
  for (int i = 0; i < mesh.num_nodes(); ++i) mesh.nodes.row(i) = map(Vec3(mesh.nodes.row(i).transpose())).transpose();
  // Elements between the same pair of faces on every axis have one shape;
  // share its geometry, keyed by edge lengths rounded far below any face gap.
  std::map<std::array<long long, 3>, int> shape_index;
  std::vector<hex8::ElementGeometry> geometries;
  const hex8::QuadratureRule rule = hex8::gauss_rule(2);
  for (int e = 0; e < mesh.num_elements(); ++e) {
    const hex8::NodeMatrix X = mesh.element_rest_positions(e);
    const Vec3 edge = (X.row(7) - X.row(0)).transpose();  // corner 7 is (1,1,1), corner 0 is (0,0,0)
    std::array<long long, 3> key;
    for (int a = 0; a < 3; ++a) key[a] = std::llround(edge(a) * 1e12);
    auto [it, added] = shape_index.emplace(key, static_cast<int>(geometries.size()));
    if (added) {
      hex8::NodeMatrix box;
      for (int c = 0; c < 8; ++c) box.row(c) = edge.cwiseProduct(Vec3(c >> 2 & 1, c >> 1 & 1, c & 1)).transpose();
      geometries.push_back(hex8::element_geometry(box, rule));
    }
    mesh.element_geometry[e] = it->second;
  }
  mesh.geometries = std::move(geometries);
}

// ---- substitution -----------------------------------------------------------

namespace {

bool is_name(const std::string& s) {
  if (s.empty() || !(std::isalpha(static_cast<unsigned char>(s[0])) || s[0] == '_')) return false;
  return std::all_of(s.begin(), s.end(),
                     [](char c) { return std::isalnum(static_cast<unsigned char>(c)) || c == '_'; });
}

ParameterValues read_values(const Config& c, const std::string& key) {
  ParameterValues out;
  const Config section = c.child(key);
  for (const std::string& name : section.keys()) {
    if (!is_name(name)) section.fail(name, "a parameter name must be a letter or '_' followed by letters, digits, '_'");
    out[name] = section.require_finite(name, "parameter value");
  }
  return out;
}

bool plain_number(const YAML::Node& node, double& value) {
  if (!node.IsScalar() || node.Tag() == "!") return false;  // quoted: a string even if it reads as a number
  const std::string& s = node.Scalar();
  if (s.empty()) return false;
  char* end = nullptr;
  value = std::strtod(s.c_str(), &end);
  return end == s.c_str() + s.size() && std::isfinite(value);
}

std::string number_text(double x) {
  char buf[40];
  std::snprintf(buf, sizeof buf, "%.17g", x);
  return buf;
}

// Every scalar of the document with its override-style key path.
void collect_scalars(const YAML::Node& node, const std::string& path,
                     std::vector<std::pair<std::string, YAML::Node>>& out) {
  if (node.IsScalar()) {
    out.emplace_back(path, node);
  } else if (node.IsSequence()) {
    for (std::size_t i = 0; i < node.size(); ++i) collect_scalars(node[i], path + "[" + std::to_string(i) + "]", out);
  } else if (node.IsMap()) {
    for (auto it = node.begin(); it != node.end(); ++it)
      collect_scalars(it->second, path.empty() ? it->first.Scalar() : path + "." + it->first.Scalar(), out);
  }
}

bool starts_with(const std::string& s, const std::string& prefix) { return s.compare(0, prefix.size(), prefix) == 0; }

// The axis of a box corner coordinate "<prefix>[i].min[a]" style path, when
// `path` is one under one of `prefixes` (-1 otherwise).
int box_axis(const std::string& path, const std::vector<std::string>& box_keys) {
  for (const std::string& key : box_keys) {
    for (const char* corner : {".min[", ".max["}) {
      const std::string tail = corner;
      const auto at = path.rfind(tail);
      if (at == std::string::npos || at + tail.size() + 2 != path.size() || path.back() != ']') continue;
      const std::string owner = path.substr(0, at);
      const bool match = key.back() == ']' ? (starts_with(owner, key.substr(0, key.size() - 2) + "[") &&
                                              owner.find('.', key.size() - 2) == std::string::npos)
                                           : owner == key;
      const char a = path[at + tail.size()];
      if (match && a >= '0' && a <= '2') return a - '0';
    }
  }
  return -1;
}

struct Scalar {
  std::string path;
  std::string text;
  bool numeric = false, expression = false;
  double number = 0;
};

class Substitution {
 public:
  Substitution(const Config& config, ParameterValues current, ParameterValues reference)
      : config_(config), current_(std::move(current)), reference_(std::move(reference)) {}

  double at(const Scalar& s, const ParameterValues& values) const {
    if (s.numeric) return s.number;
    try {
      return evaluate_parameter_expression(s.text, values);
    } catch (const std::invalid_argument& e) {
      throw InputError(config_.source() + ": " + s.path + " = \"" + s.text + "\": " + e.what() +
                       (&values == &reference_ && reference_ != current_ ? " (at the reference parameters)" : ""));
    }
  }
  const ParameterValues& current() const { return current_; }
  const ParameterValues& reference() const { return reference_; }
  const Config& config() const { return config_; }

 private:
  const Config& config_;
  ParameterValues current_, reference_;
};

GeometryMorph build_morph(const Substitution& sub, const std::vector<Scalar>& faces, const std::vector<int>& axes) {
  const char* axis_name = "xyz";
  std::array<std::vector<double>, 3> ref, cur;
  for (int a = 0; a < 3; ++a) {
    struct Face {
      double ref, cur;
      const Scalar* source;
    };
    std::vector<Face> list;
    for (std::size_t i = 0; i < faces.size(); ++i)
      if (axes[i] == a) list.push_back({sub.at(faces[i], sub.reference()), sub.at(faces[i], sub.current()), &faces[i]});
    if (list.empty()) continue;
    std::stable_sort(list.begin(), list.end(), [](const Face& x, const Face& y) { return x.ref < y.ref; });
    const double extent = std::max(1e-300, list.back().ref - list.front().ref);
    const double tol = 1e-9 * extent;
    const Face* group = &list.front();
    ref[a].push_back(group->ref);
    cur[a].push_back(group->cur);
    for (const Face& f : list) {
      if (f.ref - group->ref <= tol) {
        if (std::abs(f.cur - group->cur) > tol)
          throw InputError(sub.config().source() + ": " + f.source->path + " and " + group->source->path +
                           ": these box faces coincide at the reference parameters (" + axis_name[a] + " = " +
                           number_text(f.ref) + ") but not at the current ones (" + number_text(group->cur) + " vs " +
                           number_text(f.cur) +
                           "); the voxel mesh is built at the reference values and moved, so "
                           "faces that meet there must stay together");
        continue;
      }
      if (!(f.cur - cur[a].back() > tol))
        throw InputError(sub.config().source() + ": " + f.source->path + " = \"" + f.source->text +
                         "\": at the current parameters the box faces along " + axis_name[a] +
                         " change order or meet (" + number_text(cur[a].back()) + " then " + number_text(f.cur) +
                         "); the voxel mesh is built at the reference values and moved, so their order must stay");
      group = &f;
      ref[a].push_back(f.ref);
      cur[a].push_back(f.cur);
    }
  }
  return GeometryMorph(ref, cur);
}

}  // namespace

GeometryMorph apply_scene_parameters(const Config& config) {
  const bool has_reference = config.has("reference_parameters");
  if (!config.has("parameters")) {
    if (has_reference) config.fail("reference_parameters", "needs a `parameters` section to refer to");
    return {};
  }
  const ParameterValues current = read_values(config, "parameters");
  ParameterValues reference = current;
  if (has_reference)
    for (const auto& [name, value] : read_values(config, "reference_parameters")) {
      if (!current.count(name))
        config.child("reference_parameters").fail(name, "is not one of the scene's `parameters`");
      reference[name] = value;
    }
  const Substitution sub(config, current, reference);

  // The document as it stands (--set overrides applied), quotes kept.
  const YAML::Node document = YAML::Load(config.resolved_text());
  std::vector<std::pair<std::string, YAML::Node>> nodes;
  collect_scalars(document, "", nodes);
  std::vector<Scalar> scalars;
  for (const auto& [path, node] : nodes) {
    if (starts_with(path, "parameters.") || starts_with(path, "reference_parameters.")) continue;
    Scalar s;
    s.path = path;
    s.text = node.Scalar();
    s.numeric = plain_number(node, s.number);
    s.expression = !s.numeric && looks_like_expression(s.text, current);
    if (s.numeric || s.expression) scalars.push_back(s);
  }

  const std::vector<std::string> geometry_keys{"geometry.boxes[]"};
  const std::vector<std::string> region_keys{"clamp", "press.region", "pluck.region"};
  std::vector<Scalar> faces;
  std::vector<int> face_axes;
  for (const Scalar& s : scalars) {
    const int a = box_axis(s.path, geometry_keys);
    if (a >= 0) faces.push_back(s), face_axes.push_back(a);
  }
  const GeometryMorph morph = build_morph(sub, faces, face_axes);

  Config writable = config;  // shares the document
  for (const Scalar& s : scalars) {
    double value;
    if (box_axis(s.path, geometry_keys) >= 0) {
      value = sub.at(s, sub.reference());
    } else if (const int a = box_axis(s.path, region_keys); a >= 0) {
      value = morph.map(a, sub.at(s, sub.reference()));
    } else {
      value = sub.at(s, sub.current());
    }
    if (s.expression || value != s.number) writable.apply_override(s.path + "=" + number_text(value));
  }
  return morph;
}

}  // namespace msfab
