#pragma once
// Strict YAML configuration (DESIGN §6).
//
// A Config is a view of one mapping inside a YAML document: the document's
// source (a file path or a display name), and the key path of the mapping
// inside it ("" at top level, "boundary", "materials[1]"). Every accessor
// records the key it was asked for, so that after a stage has read what it
// understands, check_no_unknown_keys() can reject anything it never asked
// about; that is how a misspelled key is caught instead of silently ignored.
//
// Every error is an InputError whose message names the source, the full key
// path and what was wrong, e.g.
//   configs/scenes/bar.yaml: materials[1].nu = 0.5: Poisson's ratio must be in (-1, 0.5)
//
// Keys may be dotted ("solver.tolerance") to reach into nested mappings.
// Copies of a Config share the document and its read-tracking; a Config is
// not meant to be read from several threads at once.
#include <yaml-cpp/yaml.h>

#include <cstdint>
#include <memory>
#include <optional>
#include <string>
#include <vector>

namespace msfab {

// Every number read from a config is finite and at most this in magnitude
// (.inf, .nan and 1e308 are InputErrors naming the key).
inline constexpr double kLargestConfigNumber = 1e100;

// Which ends of an interval belong to it: Open = (lo, hi), Closed = [lo, hi].
enum class Bounds { Closed, Open, OpenClosed, ClosedOpen };

class Config {
 public:
  // An empty mapping named "<empty config>" (for members filled in later).
  Config();
  // Reads a YAML file. Missing file -> "<path>: no such file"; a syntax
  // error names the file, line and column; duplicate keys are rejected.
  static Config load_file(const std::string& path);
  // Parses YAML text (built-in defaults, tests). `display_name` stands in
  // for the file name in messages.
  static Config from_string(const std::string& yaml_text, const std::string& display_name);

  // Applies one "a.b[2].c=value" assignment. The value is parsed as YAML, so
  // "grid.size=[8,8,8]" sets a list; missing intermediate mappings are
  // created. A malformed assignment -> InputError naming it.
  void apply_override(const std::string& assignment);
  void apply_overrides(const std::vector<std::string>& assignments);

  // Required value: missing key, wrong type or malformed value -> InputError.
  // Supported T: double, int, std::int64_t, std::uint64_t, bool, std::string,
  // std::vector<double>, std::vector<int>, std::vector<std::string>.
  template <class T>
  T get(const std::string& key) const;
  // Optional value: `fallback` when the key is absent or null (recorded for
  // effective_text()); a present value of the wrong type is still an error.
  template <class T>
  T get_or(const std::string& key, const T& fallback) const;
  std::string get_or(const std::string& key, const char* fallback) const {
    return get_or<std::string>(key, std::string(fallback));
  }

  bool has(const std::string& key) const;

  // A file path (required). A relative path is taken relative to the folder
  // of the config file it was written in, so configs can refer to their
  // neighbours; values from --set or built-in defaults stay relative to the
  // working directory.
  std::string get_path(const std::string& key) const;

  // A nested mapping (required). Its keys are checked like top-level ones.
  Config child(const std::string& key) const;
  // A list of mappings, e.g. `materials: [{E: 1, nu: 0.3}, ...]` (required;
  // an empty list is allowed). Elements have paths "materials[0]", ...
  std::vector<Config> children(const std::string& key) const;
  // Keys of this mapping in file order; marks nothing as read (use it to
  // iterate user-named entries, then child(name) each).
  std::vector<std::string> keys() const;
  // The raw YAML under `key`, accepted wholesale: nothing inside it will be
  // reported as unknown. For sections handed to another parser.
  YAML::Node raw(const std::string& key) const;

  // Read-and-validate helpers (T = double or int / std::int64_t). `what`
  // names the quantity in the message ("Young's modulus"); empty = "value".
  template <class T = double>
  T require_positive(const std::string& key, const std::string& what = {}) const;
  template <class T = double>
  T require_range(const std::string& key, T lo, T hi, Bounds bounds = Bounds::Closed,
                  const std::string& what = {}) const;
  // get<double>: every number the reader returns is finite (and at most
  // kLargestConfigNumber); the name states the requirement at call sites.
  double require_finite(const std::string& key, const std::string& what = {}) const;
  std::string one_of(const std::string& key, const std::vector<std::string>& choices) const;
  // Throws InputError "<source>: <path> = <value>: <problem>" for checks the
  // helpers above do not cover. key "" names this node itself (a list item).
  [[noreturn]] void fail(const std::string& key, const std::string& problem) const;

  // Every key anywhere under this mapping that no accessor asked for ->
  // InputError "unknown key 'materails' in <source> (at top level); known
  // keys: E, materials, nu".
  void check_no_unknown_keys() const;

  // The effective configuration (overrides applied) as YAML text.
  std::string resolved_text() const;
  // The same with every default a get_or() has used so far written in at
  // its key, preceded by comment lines listing those defaults: what a run
  // would read (--print-config). Sections a stage never asked about stay
  // as given.
  std::string effective_text() const;

  const std::string& source() const;
  // Key path of this mapping inside the document ("" at top level).
  const std::string& path() const { return path_; }
  // Full key path of `key` under this mapping, as used in messages.
  std::string key_path(const std::string& key) const;

  struct Document;  // shared by all views of one document (config.cpp)

 private:
  Config(std::shared_ptr<Document> doc, YAML::Node node, std::string path);

  // The value under `key` (nullopt when absent), marking the key as asked
  // for; `consume` also accepts everything below it.
  std::optional<YAML::Node> lookup(const std::string& key, bool consume) const;
  std::string where(const std::string& full_path) const;
  [[noreturn]] void fail_at(const std::string& full_path, const YAML::Node& value, const std::string& problem) const;

  std::shared_ptr<Document> doc_;
  YAML::Node node_;
  std::string path_;
};

}  // namespace msfab
