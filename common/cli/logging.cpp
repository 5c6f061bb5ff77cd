#include "cli/logging.hpp"

#include <spdlog/pattern_formatter.h>
#include <spdlog/sinks/stdout_sinks.h>
#include <spdlog/spdlog.h>

#include <atomic>
#include <chrono>
#include <cstdio>
#include <memory>

#include "cli/progress.hpp"
#include "core/errors.hpp"

namespace msfab {
namespace {

using Clock = std::chrono::steady_clock;

std::atomic<Clock::rep> g_start_ticks{Clock::now().time_since_epoch().count()};

// "%*" in the pattern: "[  12.3s] ".
class ElapsedFlag final : public spdlog::custom_flag_formatter {
 public:
  void format(const spdlog::details::log_msg&, const std::tm&, spdlog::memory_buf_t& dest) override {
    if (progress_bar_on_screen()) {
      static const char clear_line[] = "\r\033[K";
      dest.append(clear_line, clear_line + sizeof clear_line - 1);
    }
    char buf[32];
    int n = std::snprintf(buf, sizeof buf, "[%6.1fs] ", elapsed_seconds());
    dest.append(buf, buf + n);
  }
  std::unique_ptr<custom_flag_formatter> clone() const override { return std::make_unique<ElapsedFlag>(); }
};

// "%&" in the pattern: nothing for info, "warning: " etc. otherwise, so the
// common case stays uncluttered and problems stand out.
class LevelTagFlag final : public spdlog::custom_flag_formatter {
 public:
  void format(const spdlog::details::log_msg& msg, const std::tm&, spdlog::memory_buf_t& dest) override {
    const char* tag = "";
    switch (msg.level) {
      case spdlog::level::trace: tag = "trace: "; break;
      case spdlog::level::debug: tag = "debug: "; break;
      case spdlog::level::warn: tag = "warning: "; break;
      case spdlog::level::err: tag = "error: "; break;
      case spdlog::level::critical: tag = "critical: "; break;
      default: break;
    }
    dest.append(tag, tag + std::char_traits<char>::length(tag));
  }
  std::unique_ptr<custom_flag_formatter> clone() const override { return std::make_unique<LevelTagFlag>(); }
};

spdlog::level::level_enum to_spdlog(LogLevel level) {
  switch (level) {
    case LogLevel::trace: return spdlog::level::trace;
    case LogLevel::debug: return spdlog::level::debug;
    case LogLevel::info: return spdlog::level::info;
    case LogLevel::warn: return spdlog::level::warn;
    case LogLevel::error: return spdlog::level::err;
  }
  return spdlog::level::info;
}

}  // namespace

LogLevel parse_log_level(const std::string& name) {
  if (name == "trace") return LogLevel::trace;
  if (name == "debug") return LogLevel::debug;
  if (name == "info") return LogLevel::info;
  if (name == "warn") return LogLevel::warn;
  if (name == "error") return LogLevel::error;
  throw InputError("--log-level '" + name + "': expected one of trace, debug, info, warn, error");
}

void init_logging(const std::string& stage_name, LogLevel level) {
  g_start_ticks.store(Clock::now().time_since_epoch().count());
  auto sink = std::make_shared<spdlog::sinks::stderr_sink_mt>();
  auto formatter = std::make_unique<spdlog::pattern_formatter>();
  formatter->add_flag<ElapsedFlag>('*').add_flag<LevelTagFlag>('&').set_pattern("%*%&%v");
  sink->set_formatter(std::move(formatter));
  auto logger = std::make_shared<spdlog::logger>(stage_name, std::move(sink));
  logger->set_level(to_spdlog(level));
  logger->flush_on(spdlog::level::trace);  // batch logs must be complete if the job is killed
  spdlog::set_default_logger(std::move(logger));
}

double elapsed_seconds() {
  const Clock::duration since = Clock::now().time_since_epoch() - Clock::duration(g_start_ticks.load());
  return std::chrono::duration<double>(since).count();
}

}  // namespace msfab
