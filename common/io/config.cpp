#include "io/config.hpp"

#include <algorithm>
#include <cctype>
#include <cerrno>
#include <charconv>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <functional>
#include <limits>
#include <map>
#include <set>
#include <sstream>

#include "core/errors.hpp"
#include "io/input_file.hpp"

namespace msfab {

struct Config::Document {
  YAML::Node root;
  std::string source;
  bool from_file = false;                         // source is a path, not a display name
  std::set<std::string> asked;                    // key paths some accessor asked for
  std::set<std::string> accepted;                 // key paths whose whole subtree was read
  std::map<std::string, std::string> overridden;  // key path -> "--set" text
  // Defaults get_or() returned for absent keys, by full key path.
  std::map<std::string, YAML::Node> defaults;

  // The --set assignment that wrote `full_path` or one of its ancestors.
  const std::string* override_of(const std::string& full_path) const {
    for (const auto& [path, assignment] : overridden) {
      const bool covers =
          full_path == path || (full_path.size() > path.size() && full_path.compare(0, path.size(), path) == 0 &&
                                (full_path[path.size()] == '.' || full_path[path.size()] == '['));
      if (covers) return &assignment;
    }
    return nullptr;
  }
};

namespace {

std::string join(const std::string& prefix, const std::string& key) {
  if (key.empty()) return prefix;  // "" names the node itself
  return prefix.empty() ? key : prefix + "." + key;
}

std::vector<std::string> split_dots(const std::string& key) {
  std::vector<std::string> parts;
  std::string::size_type start = 0;
  while (true) {
    auto dot = key.find('.', start);
    parts.push_back(key.substr(start, dot - start));
    if (dot == std::string::npos) break;
    start = dot + 1;
  }
  return parts;
}

// "materials[3].nu" -> "materials[].nu": the known keys of one list element
// are the keys read from any element.
std::string without_indices(const std::string& path) {
  std::string out;
  bool in_index = false;
  for (char c : path) {
    if (c == '[') {
      in_index = true;
      out += "[]";
    } else if (c == ']') {
      in_index = false;
    } else if (!in_index) {
      out += c;
    }
  }
  return out;
}

// "materials[0].E" -> ("materials[0]", "E"); "E" -> ("", "E").
std::pair<std::string, std::string> parent_and_name(const std::string& path) {
  auto dot = path.rfind('.');
  if (dot == std::string::npos) return {"", path};
  return {path.substr(0, dot), path.substr(dot + 1)};
}

std::string flow_text(const YAML::Node& node) {
  YAML::Emitter out;
  out << YAML::Flow << node;
  return out.c_str();
}

bool is_quoted(const YAML::Node& node) { return node.IsScalar() && node.Tag() == "!"; }

// How a value looks in "found ..." messages.
std::string describe(const YAML::Node& node) {
  if (node.IsNull()) return "nothing";
  if (node.IsSequence()) return "a list " + flow_text(node);
  if (node.IsMap()) return "a mapping";
  if (is_quoted(node)) return "the quoted string \"" + node.Scalar() + "\"";
  return "'" + node.Scalar() + "'";
}

std::string value_text(const YAML::Node& node) {
  if (node.IsScalar()) return node.Scalar();
  if (node.IsNull()) return "(nothing)";
  return flow_text(node);
}

// Levenshtein distance, for "did you mean" hints on misspelled keys.
std::size_t edit_distance(const std::string& a, const std::string& b) {
  std::vector<std::size_t> row(b.size() + 1);
  for (std::size_t j = 0; j <= b.size(); ++j) row[j] = j;
  for (std::size_t i = 1; i <= a.size(); ++i) {
    std::size_t diagonal = row[0];
    row[0] = i;
    for (std::size_t j = 1; j <= b.size(); ++j) {
      std::size_t above = row[j];
      row[j] = std::min({row[j] + 1, row[j - 1] + 1, diagonal + (a[i - 1] != b[j - 1] ? 1u : 0u)});
      diagonal = above;
    }
  }
  return row[b.size()];
}

std::string format_number(double x) {
  char buf[64];
  std::snprintf(buf, sizeof buf, "%.12g", x);
  return buf;
}
std::string format_number(int x) { return std::to_string(x); }
std::string format_number(std::int64_t x) { return std::to_string(x); }

// ---- scalar parsing: stricter than yaml-cpp's own conversions -------------

bool parse_double(const std::string& text, double& out) {
  static const std::map<std::string, double> special = {{".inf", std::numeric_limits<double>::infinity()},
                                                        {"+.inf", std::numeric_limits<double>::infinity()},
                                                        {"-.inf", -std::numeric_limits<double>::infinity()},
                                                        {".nan", std::numeric_limits<double>::quiet_NaN()}};
  std::string lower = text;
  std::transform(lower.begin(), lower.end(), lower.begin(), [](unsigned char c) { return std::tolower(c); });
  if (auto it = special.find(lower); it != special.end()) {
    out = it->second;
    return true;
  }
  if (text.empty() || text.find_first_not_of("0123456789+-.eE") != std::string::npos) return false;
  errno = 0;
  char* end = nullptr;
  out = std::strtod(text.c_str(), &end);
  return end == text.c_str() + text.size() && !(errno == ERANGE && std::isinf(out));
}

bool parse_int64(const std::string& text, std::int64_t& out) {
  if (text.empty() || text.find_first_not_of("0123456789+-") != std::string::npos) return false;
  errno = 0;
  char* end = nullptr;
  long long v = std::strtoll(text.c_str(), &end, 10);
  if (end != text.c_str() + text.size() || errno == ERANGE) return false;
  out = static_cast<std::int64_t>(v);
  return true;
}

bool parse_uint64(const std::string& text, std::uint64_t& out) {
  if (text.empty() || text.find_first_not_of("0123456789+") != std::string::npos) return false;
  errno = 0;
  char* end = nullptr;
  unsigned long long v = std::strtoull(text.c_str(), &end, 10);
  if (end != text.c_str() + text.size() || errno == ERANGE) return false;
  out = static_cast<std::uint64_t>(v);
  return true;
}

bool parse_bool(const std::string& text, bool& out) {
  std::string lower = text;
  std::transform(lower.begin(), lower.end(), lower.begin(), [](unsigned char c) { return std::tolower(c); });
  if (lower == "true" || lower == "yes" || lower == "on") {
    out = true;
    return true;
  }
  if (lower == "false" || lower == "no" || lower == "off") {
    out = false;
    return true;
  }
  return false;
}

// Reads one value of type T from a node; `where` prefixes every message.
template <class T>
struct Reader;

[[noreturn]] void type_error(const std::string& where, const std::string& path, const YAML::Node& node,
                             const char* expected) {
  throw InputError(where + ": " + path + ": expected " + expected + ", found " + describe(node));
}

template <>
struct Reader<double> {
  static constexpr const char* name = "a number";
  static double read(const std::string& where, const std::string& path, const YAML::Node& node) {
    double v = 0;
    if (!node.IsScalar() || is_quoted(node) || !parse_double(node.Scalar(), v)) type_error(where, path, node, name);
    // Refused here, for every number of every stage, rather than key by key:
    // a NaN passes every range test written as `v < lo || v > hi`, and a
    // modulus of 1e308 overflows the first product it enters.
    if (!std::isfinite(v)) throw InputError(where + ": " + path + " = " + node.Scalar() + ": expected a finite number");
    if (std::abs(v) > kLargestConfigNumber)
      throw InputError(where + ": " + path + " = " + node.Scalar() + ": beyond ±" +
                       format_number(kLargestConfigNumber) +
                       "; no quantity read from a config needs such a value, and its products overflow");
    return v;
  }
};

// An unquoted scalar that `parse` accepts (a quoted "3" is a string, not a
// number), or a type error expecting `Name`.
template <class T, bool (*parse)(const std::string&, T&), const char* Name>
struct UnquotedScalarReader {
  static constexpr const char* name = Name;
  static T read(const std::string& where, const std::string& path, const YAML::Node& node) {
    T v{};
    if (!node.IsScalar() || is_quoted(node) || !parse(node.Scalar(), v)) type_error(where, path, node, name);
    return v;
  }
};
constexpr char kAnInteger[] = "an integer", kANonNegativeInteger[] = "a non-negative integer",
               kTrueOrFalse[] = "true or false";
template <>
struct Reader<std::int64_t> : UnquotedScalarReader<std::int64_t, parse_int64, kAnInteger> {};
template <>
struct Reader<std::uint64_t> : UnquotedScalarReader<std::uint64_t, parse_uint64, kANonNegativeInteger> {};
template <>
struct Reader<bool> : UnquotedScalarReader<bool, parse_bool, kTrueOrFalse> {};

template <>
struct Reader<int> {
  static constexpr const char* name = "an integer";
  static int read(const std::string& where, const std::string& path, const YAML::Node& node) {
    std::int64_t v = Reader<std::int64_t>::read(where, path, node);
    if (v < std::numeric_limits<int>::min() || v > std::numeric_limits<int>::max())
      throw InputError(where + ": " + path + " = " + node.Scalar() + ": integer out of range");
    return static_cast<int>(v);
  }
};

template <>
struct Reader<std::string> {
  static constexpr const char* name = "a string";
  static std::string read(const std::string& where, const std::string& path, const YAML::Node& node) {
    if (!node.IsScalar()) type_error(where, path, node, name);
    return node.Scalar();
  }
};

template <class E>
struct ListReader {
  static std::vector<E> read(const std::string& where, const std::string& path, const YAML::Node& node,
                             const char* name) {
    if (!node.IsSequence()) type_error(where, path, node, name);
    std::vector<E> out;
    out.reserve(node.size());
    for (std::size_t i = 0; i < node.size(); ++i)
      out.push_back(Reader<E>::read(where, path + "[" + std::to_string(i) + "]", node[i]));
    return out;
  }
};

template <>
struct Reader<std::vector<double>> {
  static constexpr const char* name = "a list of numbers";
  static std::vector<double> read(const std::string& where, const std::string& path, const YAML::Node& node) {
    return ListReader<double>::read(where, path, node, name);
  }
};

template <>
struct Reader<std::vector<int>> {
  static constexpr const char* name = "a list of integers";
  static std::vector<int> read(const std::string& where, const std::string& path, const YAML::Node& node) {
    return ListReader<int>::read(where, path, node, name);
  }
};

template <>
struct Reader<std::vector<std::string>> {
  static constexpr const char* name = "a list of strings";
  static std::vector<std::string> read(const std::string& where, const std::string& path, const YAML::Node& node) {
    return ListReader<std::string>::read(where, path, node, name);
  }
};

// yaml-cpp shares the node of an anchor between all its aliases, so a few
// hundred bytes of nested anchors ("a billion laughs") stand for a tree of
// billions of nodes, and every walk over the tree (this check, the unknown-
// key check, resolved_text()) would take forever. The document is therefore
// walked once, as expanded, against a budget: each node costs 1 plus the
// length of its text. A document without aliases costs at most about twice
// its size, so the budget of 4 x its size + 1,000,000 only ever stops
// alias expansion, and every later walk is bounded by it too. Nesting is
// bounded as well (an anchor may hold an alias of itself).
struct ExpansionBudget {
  std::string source;
  std::uint64_t limit = 0, left = 0;
  int depth = 0;
  static constexpr int kMaxDepth = 256;

  ExpansionBudget(std::string source_name, std::size_t text_size)
      : source(std::move(source_name)), limit(4 * std::uint64_t(text_size) + 1000000), left(limit) {}

  void spend(const YAML::Node& node) {
    const std::uint64_t cost = 1 + (node.IsScalar() ? node.Scalar().size() : 0);
    if (cost > left)
      throw InputError(source + ": YAML aliases expand the document to more than " + std::to_string(limit) +
                       " nodes and characters; refusing it (nested anchors and aliases, an 'alias bomb'?)");
    left -= cost;
  }
};

// yaml-cpp keeps the first of two equal keys and drops the other without a
// word; a strict config refuses them, and keys that are not plain scalars.
void check_keys_are_unique(const YAML::Node& node, const std::string& path, ExpansionBudget& budget) {
  const std::string& source = budget.source;
  budget.spend(node);
  if (!node.IsMap() && !node.IsSequence()) return;
  if (++budget.depth > ExpansionBudget::kMaxDepth)
    throw InputError(source + ": " + (path.empty() ? std::string("the document") : "'" + path + "'") +
                     " is nested more than " + std::to_string(ExpansionBudget::kMaxDepth) + " levels deep");
  if (node.IsMap()) {
    std::set<std::string> seen;
    for (auto it = node.begin(); it != node.end(); ++it) {
      // A copy: the iterator's -> hands out a proxy that dies with the
      // statement, so a reference to its member would dangle.
      const YAML::Node key = it->first;
      if (!key.IsScalar())
        throw InputError(source + ": line " + std::to_string(key.Mark().line + 1) + ": key under " +
                         (path.empty() ? std::string("top level") : "'" + path + "'") + " is not a plain name");
      if (!seen.insert(key.Scalar()).second)
        throw InputError(source + ": line " + std::to_string(key.Mark().line + 1) + ": duplicate key '" +
                         join(path, key.Scalar()) + "'");
      budget.spend(key);
      check_keys_are_unique(it->second, join(path, key.Scalar()), budget);
    }
  } else {
    std::size_t i = 0;
    for (auto it = node.begin(); it != node.end(); ++it, ++i) {
      if (it->IsMap() || it->IsSequence())
        check_keys_are_unique(*it, path + "[" + std::to_string(i) + "]", budget);
      else
        budget.spend(*it);
    }
  }
  --budget.depth;
}

std::string trim(const std::string& s) {
  auto first = s.find_first_not_of(" \t");
  if (first == std::string::npos) return "";
  auto last = s.find_last_not_of(" \t");
  return s.substr(first, last - first + 1);
}

// One step of an override path: a mapping key or a list index.
struct PathStep {
  std::string key;  // empty for an index step
  std::size_t index = 0;
};

std::vector<PathStep> parse_override_path(const std::string& path, const std::string& assignment) {
  auto bad = [&](const std::string& why) -> InputError { return InputError("--set '" + assignment + "': " + why); };
  std::vector<PathStep> steps;
  for (const std::string& segment : split_dots(path)) {
    auto bracket = segment.find('[');
    std::string name = segment.substr(0, bracket);
    if (name.empty()) throw bad("empty key name in '" + path + "'");
    if (name.find_first_of("]{}:,#&*!|>'\"%@` ") != std::string::npos)
      throw bad("invalid character in key name '" + name + "'");
    steps.push_back({name, 0});
    while (bracket != std::string::npos) {
      auto close = segment.find(']', bracket);
      if (close == std::string::npos) throw bad("missing ']' in '" + segment + "'");
      std::string digits = segment.substr(bracket + 1, close - bracket - 1);
      std::uint64_t index = 0;
      if (!parse_uint64(digits, index) || digits.find('+') != std::string::npos)
        throw bad("list index '" + digits + "' is not a non-negative integer");
      steps.push_back({"", static_cast<std::size_t>(index)});
      bracket = close + 1 < segment.size() ? close + 1 : std::string::npos;
      if (bracket != std::string::npos && segment[bracket] != '[')
        throw bad("unexpected text after ']' in '" + segment + "'");
    }
  }
  return steps;
}

// Why a path cannot be written (set_at_steps).
struct PathError {
  std::string why;
};

// Writes `value` at `steps` below `root`, creating mappings that do not
// exist, and returns the path walked ("a.b[2].c"). Throws PathError where a
// step meets a value that is not a mapping, or a list index out of range.
std::string set_at_steps(const YAML::Node& root, const std::vector<PathStep>& steps, const YAML::Node& value) {
  // reset() rebinds the handle; operator= would overwrite the node in place.
  YAML::Node cur;
  cur.reset(root);
  std::string walked;
  for (std::size_t s = 0; s < steps.size(); ++s) {
    const PathStep& step = steps[s];
    const bool last = s + 1 == steps.size();
    if (step.key.empty()) {
      if (!cur.IsSequence()) throw PathError{"'" + walked + "' is not a list"};
      if (step.index >= cur.size())
        throw PathError{"index " + std::to_string(step.index) + " is out of range for '" + walked + "' (" +
                        std::to_string(cur.size()) + " elements)"};
      walked += "[" + std::to_string(step.index) + "]";
      if (last) {
        cur[step.index] = value;
      } else {
        YAML::Node next = cur[step.index];
        cur.reset(next);
      }
    } else {
      if (cur.IsDefined() && !cur.IsMap() && !cur.IsNull())  // new keys start undefined
        throw PathError{"'" + walked + "' is " + describe(cur) + ", not a mapping"};
      walked = join(walked, step.key);
      if (last) {
        cur[step.key] = value;
      } else {
        YAML::Node next = cur[step.key];
        cur.reset(next);
      }
    }
  }
  return walked;
}

}  // namespace

// ---- construction ---------------------------------------------------------

Config::Config(std::shared_ptr<Document> doc, YAML::Node node, std::string path)
    : doc_(std::move(doc)), node_(node), path_(std::move(path)) {}

Config::Config() : Config(from_string("{}", "<empty config>")) {}

Config Config::from_string(const std::string& yaml_text, const std::string& display_name) {
  auto doc = std::make_shared<Document>();
  doc->source = display_name;
  try {
    doc->root = YAML::Load(yaml_text);
  } catch (const YAML::ParserException& e) {
    throw InputError(display_name + ": line " + std::to_string(e.mark.line + 1) + ", column " +
                     std::to_string(e.mark.column + 1) + ": YAML syntax error: " + e.msg);
  } catch (const YAML::Exception& e) {
    throw InputError(display_name + ": cannot read YAML: " + e.what());
  }
  if (doc->root.IsNull()) doc->root = YAML::Node(YAML::NodeType::Map);  // empty file
  if (!doc->root.IsMap())
    throw InputError(display_name + ": expected a mapping of keys to values at top level, found " +
                     describe(doc->root));
  ExpansionBudget budget(display_name, yaml_text.size());
  check_keys_are_unique(doc->root, "", budget);
  return Config(doc, doc->root, "");
}

Config Config::load_file(const std::string& path) {
  Config config = from_string(read_text_file(path, kMaxConfigBytes), path);
  config.doc_->from_file = true;
  return config;
}

// ---- overrides --------------------------------------------------------------

void Config::apply_override(const std::string& assignment) {
  auto bad = [&](const std::string& why) -> InputError { return InputError("--set '" + assignment + "': " + why); };
  auto eq = assignment.find('=');
  if (eq == std::string::npos) throw bad("expected key=value");
  std::string path = trim(assignment.substr(0, eq));
  std::string value_text = trim(assignment.substr(eq + 1));
  if (path.empty()) throw bad("missing key before '='");
  if (value_text.empty()) throw bad("missing value after '=' (write key=\"\" for an empty string)");
  std::vector<PathStep> steps = parse_override_path(path, assignment);

  YAML::Node value;
  try {
    value = YAML::Load(value_text);
  } catch (const YAML::Exception& e) {
    throw bad("cannot parse value '" + value_text + "': " + e.msg);
  }
  ExpansionBudget budget("--set '" + assignment + "'", value_text.size());
  check_keys_are_unique(value, path, budget);

  std::string walked;
  try {
    walked = set_at_steps(doc_->root, steps, value);
  } catch (const PathError& e) {
    throw bad(e.why);
  }
  doc_->overridden[walked] = assignment;
}

void Config::apply_overrides(const std::vector<std::string>& assignments) {
  for (const auto& a : assignments) apply_override(a);
}

// ---- lookups ------------------------------------------------------------------

const std::string& Config::source() const { return doc_->source; }

std::string Config::key_path(const std::string& key) const { return join(path_, key); }

std::string Config::where(const std::string& full_path) const {
  const std::string* assignment = doc_->override_of(full_path);
  return assignment ? doc_->source + " (with --set " + *assignment + ")" : doc_->source;
}

std::optional<YAML::Node> Config::lookup(const std::string& key, bool consume) const {
  YAML::Node cur;
  cur.reset(node_);
  std::string path = path_;
  if (key.empty()) return cur;  // the node itself (fail("", ...) on a list item)
  auto parts = split_dots(key);
  for (std::size_t i = 0; i < parts.size(); ++i) {
    if (parts[i].empty()) throw std::logic_error("Config: empty segment in key '" + key + "'");
    if (!cur.IsMap()) throw InputError(where(path) + ": " + path + ": expected a mapping, found " + describe(cur));
    path = join(path, parts[i]);
    doc_->asked.insert(path);
    const YAML::Node& map = cur;
    YAML::Node next = map[parts[i]];
    if (!next.IsDefined()) return std::nullopt;
    cur.reset(next);
  }
  if (consume) doc_->accepted.insert(path);
  return cur;
}

void Config::fail_at(const std::string& full_path, const YAML::Node& value, const std::string& problem) const {
  throw InputError(where(full_path) + ": " + full_path + " = " + value_text(value) + ": " + problem);
}

void Config::fail(const std::string& key, const std::string& problem) const {
  auto value = lookup(key, false);
  if (!value) throw InputError(where(key_path(key)) + ": " + key_path(key) + ": " + problem);
  fail_at(key_path(key), *value, problem);
}

template <class T>
T Config::get(const std::string& key) const {
  auto value = lookup(key, true);
  const std::string path = key_path(key);
  if (!value)
    throw InputError(where(path) + ": missing required key '" + path + "' (expected " + Reader<T>::name + ")");
  if (value->IsNull())
    throw InputError(where(path) + ": " + path + ": no value given (expected " + Reader<T>::name + ")");
  return Reader<T>::read(where(path), path, *value);
}

namespace {

// A default as YAML; doubles in their shortest form that reads back to the
// same bits (1e-09, not 1.0000000000000001e-09).
std::string shortest_text(double v) {
  char buffer[64];
  const auto end = std::to_chars(buffer, buffer + sizeof buffer, v).ptr;
  return std::string(buffer, end);
}
template <class T>
YAML::Node default_node(const T& value) {
  return YAML::Node(value);
}
template <>
YAML::Node default_node<double>(const double& value) {
  return YAML::Node(shortest_text(value));
}
template <>
YAML::Node default_node<std::vector<double>>(const std::vector<double>& values) {
  YAML::Node list(YAML::NodeType::Sequence);
  for (double v : values) list.push_back(YAML::Node(shortest_text(v)));
  return list;
}

}  // namespace

template <class T>
T Config::get_or(const std::string& key, const T& fallback) const {
  auto value = lookup(key, true);
  const std::string path = key_path(key);
  if (!value || value->IsNull()) {
    doc_->defaults.try_emplace(path, default_node(fallback));
    return fallback;
  }
  return Reader<T>::read(where(path), path, *value);
}

bool Config::has(const std::string& key) const {
  auto value = lookup(key, false);
  return value && !value->IsNull();
}

std::string Config::get_path(const std::string& key) const {
  const std::string value = get<std::string>(key);
  if (value.empty()) fail(key, "expected a file path, found an empty string");
  const std::filesystem::path file(value);
  if (file.is_absolute() || !doc_->from_file || doc_->override_of(key_path(key))) return value;
  return (std::filesystem::path(doc_->source).parent_path() / file).lexically_normal().string();
}

Config Config::child(const std::string& key) const {
  auto value = lookup(key, false);
  const std::string path = key_path(key);
  if (!value) throw InputError(where(path) + ": missing required section '" + path + "'");
  if (!value->IsMap())
    throw InputError(where(path) + ": " + path + ": expected a mapping of keys to values, found " + describe(*value));
  return Config(doc_, *value, path);
}

std::vector<Config> Config::children(const std::string& key) const {
  auto value = lookup(key, false);
  const std::string path = key_path(key);
  if (!value) throw InputError(where(path) + ": missing required list '" + path + "'");
  if (!value->IsSequence())
    throw InputError(where(path) + ": " + path + ": expected a list of mappings, found " + describe(*value));
  std::vector<Config> out;
  for (std::size_t i = 0; i < value->size(); ++i) {
    const std::string item_path = path + "[" + std::to_string(i) + "]";
    YAML::Node item = (*value)[i];
    if (!item.IsMap())
      throw InputError(where(item_path) + ": " + item_path + ": expected a mapping of keys to values, found " +
                       describe(item));
    out.push_back(Config(doc_, item, item_path));
  }
  return out;
}

std::vector<std::string> Config::keys() const {
  std::vector<std::string> out;
  for (auto it = node_.begin(); it != node_.end(); ++it) out.push_back(it->first.Scalar());
  return out;
}

YAML::Node Config::raw(const std::string& key) const {
  auto value = lookup(key, true);
  if (!value) throw InputError(where(key_path(key)) + ": missing required key '" + key_path(key) + "'");
  return YAML::Clone(*value);
}

// ---- validation ---------------------------------------------------------------

template <class T>
T Config::require_positive(const std::string& key, const std::string& what) const {
  T v = get<T>(key);
  if (!(v > 0)) fail(key, (what.empty() ? std::string("value") : what) + " must be positive");
  return v;  // finite: Reader<double> refuses anything else
}

template <class T>
T Config::require_range(const std::string& key, T lo, T hi, Bounds bounds, const std::string& what) const {
  T v = get<T>(key);
  const bool open_lo = bounds == Bounds::Open || bounds == Bounds::OpenClosed;
  const bool open_hi = bounds == Bounds::Open || bounds == Bounds::ClosedOpen;
  const bool above_lo = open_lo ? v > lo : v >= lo;
  const bool below_hi = open_hi ? v < hi : v <= hi;
  if (!(above_lo && below_hi)) {
    const std::string interval =
        std::string(open_lo ? "(" : "[") + format_number(lo) + ", " + format_number(hi) + (open_hi ? ")" : "]");
    fail(key, (what.empty() ? std::string("value") : what) + " must be in " + interval);
  }
  return v;
}

double Config::require_finite(const std::string& key, const std::string&) const {
  return get<double>(key);  // Reader<double> refuses non-finite values, naming the key
}

std::string Config::one_of(const std::string& key, const std::vector<std::string>& choices) const {
  std::string v = get<std::string>(key);
  if (std::find(choices.begin(), choices.end(), v) == choices.end()) {
    std::string list;
    for (const auto& c : choices) list += (list.empty() ? "" : ", ") + c;
    fail(key, "must be one of: " + list);
  }
  return v;
}

// ---- strictness -----------------------------------------------------------------

namespace {

struct UnknownKeyCheck {
  const Config::Document& doc;
  std::function<std::string(const std::string&)> where;

  void walk(const YAML::Node& node, const std::string& path) const {
    if (node.IsMap()) {
      for (auto it = node.begin(); it != node.end(); ++it) {
        const std::string key = it->first.Scalar();
        const std::string key_path = join(path, key);
        if (!doc.asked.count(key_path)) report(key, path);
        if (!doc.accepted.count(key_path)) walk(it->second, key_path);
      }
    } else if (node.IsSequence()) {
      for (std::size_t i = 0; i < node.size(); ++i) walk(node[i], path + "[" + std::to_string(i) + "]");
    }
  }

  [[noreturn]] void report(const std::string& key, const std::string& parent) const {
    const std::string level = without_indices(parent);
    std::set<std::string> known;
    for (const auto& asked : doc.asked) {
      auto [asked_parent, name] = parent_and_name(asked);
      if (without_indices(asked_parent) == level) known.insert(name);
    }
    std::string message = "unknown key '" + key + "' in " + where(join(parent, key)) + " (" +
                          (parent.empty() ? std::string("at top level") : "under '" + parent + "'") + ")";
    std::string best;
    std::size_t best_distance = std::max<std::size_t>(2, key.size() / 3) + 1;
    for (const auto& k : known) {
      std::size_t d = edit_distance(key, k);
      if (d < best_distance) {
        best_distance = d;
        best = k;
      }
    }
    if (known.empty()) {
      message += "; no keys are read here";
    } else {
      std::string list;
      for (const auto& k : known) list += (list.empty() ? "" : ", ") + k;
      message += "; known keys: " + list;
    }
    if (!best.empty()) message += " (did you mean '" + best + "'?)";
    throw InputError(message);
  }
};

}  // namespace

void Config::check_no_unknown_keys() const {
  UnknownKeyCheck check{*doc_, [this](const std::string& p) { return where(p); }};
  check.walk(node_, path_);
}

namespace {

// Like yaml-cpp's own emitter, but keeps quoted scalars quoted: "007" must
// read back as a string, not as the number 7.
void emit(YAML::Emitter& out, const YAML::Node& node) {
  switch (node.Type()) {
    case YAML::NodeType::Scalar:
      if (is_quoted(node))
        out << YAML::DoubleQuoted << node.Scalar();
      else
        out << node.Scalar();
      break;
    case YAML::NodeType::Sequence:
      if (node.Style() == YAML::EmitterStyle::Flow) out << YAML::Flow;
      out << YAML::BeginSeq;
      for (const auto& item : node) emit(out, item);
      out << YAML::EndSeq;
      break;
    case YAML::NodeType::Map:
      if (node.Style() == YAML::EmitterStyle::Flow) out << YAML::Flow;
      out << YAML::BeginMap;
      for (auto it = node.begin(); it != node.end(); ++it) {
        out << YAML::Key << it->first.Scalar() << YAML::Value;
        emit(out, it->second);
      }
      out << YAML::EndMap;
      break;
    default: out << YAML::Null;
  }
}

}  // namespace

std::string Config::resolved_text() const {
  YAML::Emitter out;
  emit(out, node_);
  return std::string(out.c_str()) + "\n";
}

std::string Config::effective_text() const {
  YAML::Node effective = YAML::Clone(doc_->root);
  std::string listing;
  for (const auto& [path, value] : doc_->defaults) {
    try {
      set_at_steps(effective, parse_override_path(path, path), value);
    } catch (const PathError&) {
      continue;  // under a list item that is not there, or a value that is not a mapping
    }
    YAML::Emitter v;
    v << YAML::Flow << value;
    listing += "#   " + path + " = " + v.c_str() + "\n";
  }
  YAML::Emitter out;
  emit(out, effective);
  return "# effective config: " + doc_->source + " with --set overrides applied" +
         (listing.empty() ? std::string("\n") : "; defaults filled in:\n" + listing) + out.c_str() + "\n";
}

// ---- explicit instantiations -------------------------------------------------------

#define MSFAB_CONFIG_VALUE_TYPE(T)                     \
  template T Config::get<T>(const std::string&) const; \
  template T Config::get_or<T>(const std::string&, const T&) const;
MSFAB_CONFIG_VALUE_TYPE(double)
MSFAB_CONFIG_VALUE_TYPE(int)
MSFAB_CONFIG_VALUE_TYPE(std::int64_t)
MSFAB_CONFIG_VALUE_TYPE(std::uint64_t)
MSFAB_CONFIG_VALUE_TYPE(bool)
MSFAB_CONFIG_VALUE_TYPE(std::string)
MSFAB_CONFIG_VALUE_TYPE(std::vector<double>)
MSFAB_CONFIG_VALUE_TYPE(std::vector<int>)
MSFAB_CONFIG_VALUE_TYPE(std::vector<std::string>)
#undef MSFAB_CONFIG_VALUE_TYPE

template double Config::require_positive<double>(const std::string&, const std::string&) const;
template int Config::require_positive<int>(const std::string&, const std::string&) const;
template std::int64_t Config::require_positive<std::int64_t>(const std::string&, const std::string&) const;
template double Config::require_range<double>(const std::string&, double, double, Bounds, const std::string&) const;
template int Config::require_range<int>(const std::string&, int, int, Bounds, const std::string&) const;
template std::int64_t Config::require_range<std::int64_t>(const std::string&, std::int64_t, std::int64_t, Bounds,
                                                          const std::string&) const;

}  // namespace msfab
