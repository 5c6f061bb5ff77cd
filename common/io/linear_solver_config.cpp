#include "io/linear_solver_config.hpp"

#include <spdlog/spdlog.h>

#include <algorithm>

#include "core/errors.hpp"

namespace msfab {

std::vector<std::string> linear_solver_kinds() { return {"auto", "cholmod", "pcg", "pcg-mg", "matrix-free"}; }

namespace {

std::string joined(const std::vector<std::string>& names) {
  std::string out;
  for (const std::string& n : names) out += (out.empty() ? "" : ", ") + n;
  return out;
}

// The key a value is read from: the current name, or the earlier one (with
// a warning) when only that is given.
std::string present_key(const Config& config, const std::string& key, const std::string& legacy) {
  if (legacy.empty() || !config.has(legacy)) return key;
  if (config.has(key))
    config.fail(legacy, "is the earlier name of " + config.key_path(key) + "; give only one of them");
  spdlog::warn("{}: {} is an earlier name; write {}", config.source(), config.key_path(legacy), config.key_path(key));
  return legacy;
}

// Earlier kind names: homogenize's direct and multigrid solvers are the
// cholmod and matrix-free kinds of every other stage.
std::string current_kind_name(const std::string& kind) {
  if (kind == "direct") return "cholmod";
  if (kind == "multigrid") return "matrix-free";
  return kind;
}

bool is_offered(const std::string& kind, const std::vector<std::string>& offered) {
  return std::find(offered.begin(), offered.end(), kind) != offered.end();
}

}  // namespace

LinearSolverChoice read_linear_solver_choice(const Config& config, const std::vector<std::string>& offered,
                                             const LinearSolverChoice& defaults, const LinearSolverKeys& keys) {
  LinearSolverChoice c = defaults;
  const std::string kind_key = present_key(config, keys.kind, keys.legacy_kind);
  c.kind_key = config.key_path(kind_key);
  const std::string given = config.get_or<std::string>(kind_key, defaults.kind);
  c.kind = current_kind_name(given);
  if (c.kind != given)
    spdlog::warn("{}: {} = {} is an earlier name; write {}", config.source(), c.kind_key, given, c.kind);
  if (!is_offered(c.kind, offered))
    config.fail(kind_key, "linear solver '" + given + "' is unknown here; choose one of " + joined(offered));

  const std::string tolerance_key = present_key(config, keys.tolerance, keys.legacy_tolerance);
  c.tolerance_key = config.key_path(tolerance_key);
  c.tolerance = config.get_or<double>(tolerance_key, defaults.tolerance);
  if (!(c.tolerance > 0 && c.tolerance < 1)) config.fail(tolerance_key, "must be in (0, 1)");

  const std::string iterations_key = present_key(config, keys.max_iterations, keys.legacy_max_iterations);
  c.max_iterations_key = config.key_path(iterations_key);
  c.max_iterations = config.get_or<int>(iterations_key, defaults.max_iterations);
  if (c.max_iterations < 1) config.fail(iterations_key, "must be at least 1");
  return c;
}

void override_linear_solver_kind(LinearSolverChoice& choice, const std::string& kind,
                                 const std::vector<std::string>& offered, const std::string& option_name) {
  const std::string current = current_kind_name(kind);
  if (!is_offered(current, offered))
    throw InputError(option_name + " " + kind + ": linear solver '" + kind + "' is unknown here; choose one of " +
                     joined(offered));
  choice.kind = current;
  choice.kind_key = option_name;
}

}  // namespace msfab
