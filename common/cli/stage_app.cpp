#include "cli/stage_app.hpp"

#include <omp.h>
#include <spdlog/spdlog.h>

#include <CLI/CLI.hpp>
#include <algorithm>
#include <charconv>
#include <cstdint>
#include <filesystem>
#include <iostream>
#include <limits>

#include "cli/allocator_tuning.hpp"
#include "cli/logging.hpp"
#include "cli/memory_budget.hpp"
#include "cli/progress.hpp"
#include "core/errors.hpp"
#include "core/version.hpp"
#include "io/atomic_file.hpp"
#include "io/input_file.hpp"

namespace msfab {
namespace {

// Prints "<stage>: error: <first line>" followed by any further lines as
// they are (residual histories, lists of keys).
void print_error(const std::string& stage, const std::string& message) {
  std::cerr << stage << ": error: " << message << "\n";
  std::cerr.flush();
}

// Checks the text before CLI11 converts it: CLI11 would wrap "-1" around
// to 2^64-1 for an unsigned option, and its range messages are unreadable.
// --threads above this is a typo, not a request: far more than any node's
// cores, and each OpenMP thread reserves a stack.
constexpr std::uint64_t kMaxThreads = 65536;

// A decimal integer in [positive ? 1 : 0, max]. Checked on the text, before
// CLI11 converts it: its conversion of a number past the type's range
// clamps or wraps instead of failing (a --seed of 2^64 became 2^64 - 1).
CLI::Validator integer_validator(bool positive, std::uint64_t max) {
  return CLI::Validator(
      [positive, max](std::string& text) -> std::string {
        const std::string kind = positive ? "positive" : "non-negative";
        std::uint64_t value = 0;
        const char* end = text.data() + text.size();
        const auto [stop, error] = std::from_chars(text.data(), end, value);
        if (text.empty() || stop != end || (error != std::errc() && error != std::errc::result_out_of_range))
          return "expected a " + kind + " integer, found '" + text + "'";
        if (error == std::errc::result_out_of_range || value > max)
          return "'" + text + "' is larger than " + std::to_string(max) + ", the largest value allowed";
        if (positive && value == 0) return "expected a " + kind + " integer, found '" + text + "'";
        return {};
      },
      "");
}

// Refuses, before any work, an --out the run could not write or that would
// destroy one of its inputs: an --out naming the same file as another
// option's value (the config, an input artifact, --structures: by device and
// inode when both exist, else by path), an existing folder, or a path in a
// folder that is missing or not writable. The folder is checked by creating
// and removing an exclusive temporary there, exactly as the writer will.
void check_output_path(const CLI::App& cli, const std::string& out) {
  for (const CLI::Option* option : cli.get_options()) {
    if (option->check_name("--out") || option->check_name("--set") || option->check_name("--log-level")) continue;
    if (option->get_items_expected_max() == 0) continue;  // a flag
    const std::string type = option->get_type_name();
    const std::string base = type.substr(0, type.find(':'));
    if (base != "TEXT" && base != "FILE" && base != "PATH" && base != "DIR") continue;  // numbers
    for (const std::string& value : option->results())
      if (!value.empty() && same_file(value, out))
        throw InputError(option->get_name() + " '" + value + "' and --out '" + out +
                         "' name the same file; the run would overwrite its own input");
  }
  try {
    AtomicFile probe(out);
    probe.discard();
  } catch (const InputError& e) {
    throw InputError(std::string("--out ") + e.what());
  }
}

}  // namespace

namespace {

// Thrown by finish_config() under --print-config; run() ends with exit 0.
struct ConfigPrinted {};

}  // namespace

const std::string& StageContext::require_out() const {
  static const std::string kNothingWritten = "(nothing is written under --print-config)";
  if (options.out.empty() && options.print_config) return kNothingWritten;
  if (options.out.empty()) throw InputError("missing --out PATH (where to write the result)");
  return options.out;
}

void StageContext::finish_config() const {
  config.check_no_unknown_keys();
  if (!options.print_config) return;
  std::cout << config.effective_text() << std::flush;
  throw ConfigPrinted{};
}

ConfigGridSize config_grid_size(const Config& config, const std::string& key) {
  ConfigGridSize size;
  if (!config.has(key)) return size;
  size.counts = config.get<std::vector<int>>(key);
  size.cells = 1;
  for (int n : size.counts)
    size.cells *= std::max(n, 1), size.text += (size.text.empty() ? "" : " x ") + std::to_string(n);
  return size;
}

void StageContext::check_memory(double estimated_bytes, const std::string& what, const std::string& remedy) const {
  const bool given = !options.memory_limit.empty();
  const double limit =
      given ? double(parse_memory_size(options.memory_limit, "--memory-limit")) : double(available_memory_bytes());
  spdlog::debug("memory: {} needs about {} (limit {}, {})", what, format_bytes(estimated_bytes), format_bytes(limit),
                given ? "--memory-limit" : "available now");
  if (limit <= 0 || estimated_bytes <= limit) return;
  throw InputError(what + " needs about " + format_bytes(estimated_bytes) + ", more than the " + format_bytes(limit) +
                   (given ? " of --memory-limit" : " available") + "; " + remedy +
                   (given ? "" : ", or set --memory-limit if the estimate is too cautious"));
}

void StageContext::check_out_folder() const {
  if (options.print_config) return;
  const std::string& out = require_out();
  if (!std::filesystem::is_directory(std::filesystem::absolute(out).parent_path()))
    throw InputError(out + ": output folder does not exist");
}

StageOption& StageOption::required() {
  option_->required();
  return *this;
}

StageOption& StageOption::type_name(const std::string& name) {
  option_->type_name(name);
  return *this;
}

StageOption& StageOption::one_of(const std::vector<std::string>& choices) {
  option_->check(CLI::IsMember(choices));
  return *this;
}

StageOption& StageOption::non_negative() {
  option_->check(CLI::NonNegativeNumber);
  return *this;
}

StageOption& StageOption::in_range(double min, double max) {
  option_->check(CLI::Range(min, max));
  return *this;
}

StageOption& StageOption::values(int count) {
  option_->expected(count);
  return *this;
}

bool StageOption::given() const { return option_->count() > 0; }

StageApp::StageApp(std::string name, std::string description)
    : name_(std::move(name)), cli_(std::make_unique<CLI::App>(description, name_)) {
  keep_freed_memory_for_reuse();
  cli_->footer(
      "Exit codes: 0 done; 1 internal error; 2 bad usage or bad input; 3 numerical failure.\n"
      "Config keys can be overridden with --set key.path=value (value in YAML syntax).");
}

StageApp::~StageApp() = default;

StageOption StageApp::option(const std::string& name, std::string& value, const std::string& help) {
  return StageOption(cli_->add_option(name, value, help));
}

StageOption StageApp::option(const std::string& name, int& value, const std::string& help) {
  return StageOption(cli_->add_option(name, value, help));
}

StageOption StageApp::option(const std::string& name, double& value, const std::string& help) {
  return StageOption(cli_->add_option(name, value, help));
}

StageOption StageApp::option(const std::string& name, std::vector<double>& values, const std::string& help) {
  return StageOption(cli_->add_option(name, values, help));
}

StageOption StageApp::option(const std::string& name, std::vector<std::string>& values, const std::string& help) {
  return StageOption(cli_->add_option(name, values, help));
}

StageOption StageApp::flag(const std::string& name, bool& value, const std::string& help) {
  return StageOption(cli_->add_flag(name, value, help));
}

void StageApp::add_common_options() {
  cli_->add_option("-c,--config", options_.config_path, "YAML config file (default: built-in defaults)")
      ->type_name("FILE");
  cli_->add_option("--set", options_.overrides,
                   "override a config value, e.g. --set grid.size=[8,8,8] (value in YAML syntax; repeatable)")
      ->allow_extra_args(false)
      ->type_name("KEY=VALUE");
  cli_->add_option("-o,--out", options_.out, "output path")->type_name("PATH");
  cli_->add_option("-j,--threads", options_.threads, "worker threads (default: OMP_NUM_THREADS or all cores)")
      ->type_name("N")
      ->check(integer_validator(true, kMaxThreads));
  cli_->add_option("--seed", options_.seed, "global random seed (default: 0)")
      ->type_name("N")
      ->check(integer_validator(false, std::numeric_limits<std::uint64_t>::max()));
  cli_->add_option("--log-level", options_.log_level, "how much to log (default: info)")
      ->type_name("LEVEL")
      ->check(CLI::IsMember({"trace", "debug", "info", "warn", "error"}));
  cli_->add_flag("-q,--quiet", options_.quiet, "only warnings and errors; no progress display");
  cli_->add_option("--memory-limit", options_.memory_limit,
                   "memory a run may use, e.g. 64G (default: what the system has available); a run estimated "
                   "above it is refused before it starts")
      ->type_name("SIZE")
      ->check(CLI::Validator(
          [](std::string& text) -> std::string {
            try {
              parse_memory_size(text, "--memory-limit");
            } catch (const InputError& e) {
              return e.what();
            }
            return {};
          },
          ""));
  cli_->add_flag("--print-config", options_.print_config,
                 "print the effective config (the file, --set overrides and the defaults this stage reads) as YAML "
                 "and exit without running");
  add_version_option();
}

void StageApp::add_version_option() {
  std::string text = name_ + " " + version() + " (revision " + git_revision() + ")";
  if (*stage_identity() != '\0')
    text += "\nstage identity " + std::string(stage_identity()) + "\n  (SHA-256 of the " +
            std::to_string(stage_identity_source_count()) +
            " source files it is built from; the pipeline reruns this stage's artifacts when it changes)";
  cli_->set_version_flag("--version", text);
}

void StageApp::set_default_config(std::string yaml_text) { default_config_ = std::move(yaml_text); }

Config StageApp::load_config() const {
  Config config = !options_.config_path.empty() ? Config::load_file(options_.config_path)
                  : default_config_ ? Config::from_string(*default_config_, "<built-in defaults of " + name_ + ">")
                                    : Config::from_string("{}", "<no config file>");
  config.apply_overrides(options_.overrides);
  return config;
}

int StageApp::run(int argc, const char* const* argv, const std::function<void(StageContext&)>& body) {
  try {
    cli_->parse(argc, argv);
  } catch (const CLI::ParseError& e) {
    if (e.get_exit_code() == static_cast<int>(CLI::ExitCodes::Success)) {
      cli_->exit(e);  // --help / --version print to stdout
      return kExitOk;
    }
    print_error(name_, std::string(e.what()) + "\nRun with --help for more information.");
    return kExitBadInput;
  }

  try {
    LogLevel level = parse_log_level(options_.log_level);
    if ((options_.quiet || rank_ != 0) && level < LogLevel::warn) level = LogLevel::warn;
    init_logging(name_, level);
    Progress::set_quiet(options_.quiet || rank_ != 0);
    if (options_.threads > 0) omp_set_num_threads(options_.threads);

    StageContext ctx{name_, load_config(), options_, quoted_command_line(argc, argv)};
    if (!options_.out.empty()) check_output_path(*cli_, options_.out);
    spdlog::debug("{} {} (revision {}), {} threads, seed {}", name_, version(), git_revision(), omp_get_max_threads(),
                  options_.seed);
    spdlog::debug("command line: {}", ctx.command_line);
    body(ctx);
    return kExitOk;
  } catch (const ConfigPrinted&) {
    return kExitOk;
  } catch (const InputError& e) {
    print_error(name_, e.what());
    return kExitBadInput;
  } catch (const NumericalError& e) {
    print_error(name_, e.what());
    return kExitNumerical;
  } catch (const std::exception& e) {
    print_error(name_, std::string("internal error: ") + e.what());
    return kExitInternal;
  } catch (...) {
    print_error(name_, "internal error: unknown exception");
    return kExitInternal;
  }
}

std::string quoted_command_line(int argc, const char* const* argv) {
  std::string out;
  for (int i = 0; i < argc; ++i) {
    std::string arg = argv[i] ? argv[i] : "";
    const bool plain = !arg.empty() && arg.find_first_not_of(
                                           "abcdefghijklmnopqrstuvwxyzABCDEFGHIJKLMNOPQRSTUVWXYZ"
                                           "0123456789_-+=/.,:@%") == std::string::npos;
    if (!out.empty()) out += ' ';
    if (plain) {
      out += arg;
    } else {
      out += '\'';
      for (char c : arg) out += c == '\'' ? std::string("'\\''") : std::string(1, c);
      out += '\'';
    }
  }
  return out;
}

}  // namespace msfab
