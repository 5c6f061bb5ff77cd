#pragma once
// Process-wide logging for stage executables (DESIGN §6).
//
// After init_logging() the default spdlog logger writes plain lines to
// stderr, each prefixed with the time since the stage started:
//   [  12.3s] assembled 1.2M dofs
//   [  12.4s] warning: mesh has 3 disconnected pieces
// so logs stay readable in batch-job output files. Stages log with the usual
// spdlog::info(...), spdlog::warn(...), ... calls.
#include <string>

namespace msfab {

enum class LogLevel { trace, debug, info, warn, error };

// "trace" | "debug" | "info" | "warn" | "error"; anything else -> InputError.
LogLevel parse_log_level(const std::string& name);

// Installs the stderr logger named `stage_name` at `level` and restarts the
// elapsed-time clock. Safe to call again (tests, repeated runs).
void init_logging(const std::string& stage_name, LogLevel level);

// Seconds since the last init_logging() (or since first use).
double elapsed_seconds();

}  // namespace msfab
