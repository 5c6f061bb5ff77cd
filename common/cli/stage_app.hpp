#pragma once
// Command-line conventions shared by every stage executable (DESIGN §6).
//
//   int main(int argc, char** argv) {
//     msfab::StageApp app("msfab-simulate", "static and dynamic FEM on a scene");
//     app.add_common_options();
//     app.flag("--resume", resume, "continue from the last checkpoint");
//     return app.run(argc, argv, [&](msfab::StageContext& ctx) {
//       double E = ctx.config.require_positive("E", "Young's modulus");
//       ctx.finish_config();   // unknown keys refused; --print-config stops here
//       ...
//     });
//   }
//
// run() parses the command line, sets up logging and threads, loads the
// config (+ --set overrides), calls the stage body and maps the outcome to
// an exit code: 0 ok, 2 bad usage or input (CLI11 errors, InputError),
// 3 NumericalError, 1 anything else. Errors go to stderr as
// "<stage>: error: <message>".
//
// CLI11 stays behind this interface (stage_app.cpp): its header costs 6 s
// of CPU per file that includes it, and every stage's main would.
#include <cstdint>
#include <functional>
#include <memory>
#include <optional>
#include <string>
#include <vector>

#include "io/config.hpp"

namespace CLI {
class App;
class Option;
}  // namespace CLI

namespace msfab {

struct StageOptions {
  std::string config_path;             // --config; empty = built-in defaults
  std::vector<std::string> overrides;  // --set key=value, in order given
  std::string out;                     // --out; empty when not given
  int threads = 0;                     // --threads; 0 = OpenMP default
  std::uint64_t seed = 0;              // --seed
  std::string log_level = "info";      // --log-level
  bool quiet = false;                  // --quiet
  std::string memory_limit;            // --memory-limit; empty = available memory
  bool print_config = false;           // --print-config
};

// A `grid.size`-style list of cell counts from the config, for memory
// estimates made before the scene is read: the counts, their product and
// "nx x ny x nz". Empty when the key is absent (the scene reader names it).
struct ConfigGridSize {
  std::vector<int> counts;
  double cells = 0;
  std::string text;
};
ConfigGridSize config_grid_size(const Config& config, const std::string& key = "grid.size");

struct StageContext {
  std::string stage_name;
  Config config;  // loaded, overrides applied
  StageOptions options;
  std::string command_line;  // shell-quoted argv, for provenance

  // The --out path; InputError when it was not given (under --print-config
  // a stand-in, since nothing will be written).
  const std::string& require_out() const;
  // Called once the stage has read its config, before any work: refuses
  // unknown keys (Config::check_no_unknown_keys); with --print-config,
  // prints the effective config (Config::effective_text) to stdout and ends
  // the run with exit code 0.
  void finish_config() const;
  // InputError ("<out>: output folder does not exist") unless the folder
  // --out writes into exists; stages call it after validating their config,
  // before any long work.
  void check_out_folder() const;
  // Refuses (InputError, exit 2) a run whose estimated peak memory exceeds
  // the limit (cli/memory_budget.hpp): "<what> needs about 31.2 GiB, more
  // than the 22.1 GiB available; <remedy>, or set --memory-limit". Stages
  // call it with their dominant arrays, before any long work. Logs the
  // estimate at debug level either way.
  void check_memory(double estimated_bytes, const std::string& what, const std::string& remedy) const;
};

// A stage-specific option, for chaining its settings:
//   app.option("--scene", scene_path, "voxel scene").type_name("FILE").required();
class StageOption {
 public:
  explicit StageOption(CLI::Option* option) : option_(option) {}

  StageOption& required();
  // The value's name in --help. Values of FILE, PATH, DIR and TEXT options
  // (TEXT: any string option not renamed) are checked against --out, which
  // must not overwrite them.
  StageOption& type_name(const std::string& name);
  StageOption& one_of(const std::vector<std::string>& choices);
  StageOption& non_negative();
  StageOption& in_range(double min, double max);
  // A list option that takes exactly `count` values.
  StageOption& values(int count);
  // After parsing: whether the option was on the command line.
  bool given() const;

 private:
  CLI::Option* option_;
};

class StageApp {
 public:
  StageApp(std::string name, std::string description);
  ~StageApp();
  StageApp(const StageApp&) = delete;
  StageApp& operator=(const StageApp&) = delete;

  const std::string& name() const { return name_; }

  // Stage-specific options and flags (a name such as "--scene", "-s,--scene"
  // or a positional "artifact"), written into `value` when parsed.
  StageOption option(const std::string& name, std::string& value, const std::string& help);
  StageOption option(const std::string& name, int& value, const std::string& help);
  StageOption option(const std::string& name, double& value, const std::string& help);
  StageOption option(const std::string& name, std::vector<double>& values, const std::string& help);
  StageOption option(const std::string& name, std::vector<std::string>& values, const std::string& help);
  StageOption flag(const std::string& name, bool& value, const std::string& help);

  // --config, --set, --out, --threads, --seed, --log-level, --quiet,
  // --memory-limit, --print-config, --version (--help is always there).
  void add_common_options();
  // --version alone, for tools that take none of the common options.
  void add_version_option();
  // YAML used when --config is not given; its display name in messages is
  // "<built-in defaults of NAME>". Without it the config starts empty.
  void set_default_config(std::string yaml_text);

  // For stages run on several MPI ranks (parallel/mpi_session.hpp): ranks
  // other than 0 draw no progress and log only warnings and errors, so a
  // job speaks with one voice.
  void set_rank(int rank) { rank_ = rank; }

  int run(int argc, const char* const* argv, const std::function<void(StageContext&)>& body);

 private:
  Config load_config() const;

  std::string name_;
  std::unique_ptr<CLI::App> cli_;
  StageOptions options_;
  std::optional<std::string> default_config_;
  int rank_ = 0;
};

// argv joined with shell quoting where needed, e.g. "msfab-map --set 'a=b c'".
std::string quoted_command_line(int argc, const char* const* argv);

}  // namespace msfab
