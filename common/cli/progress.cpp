#include "cli/progress.hpp"

#include <spdlog/spdlog.h>
#include <unistd.h>

#include <algorithm>
#include <cstdio>

namespace msfab {
namespace {

std::atomic<bool> g_quiet{false};
std::atomic<int> g_bars_on_screen{0};

constexpr std::chrono::milliseconds kRedrawInterval{100};
constexpr std::chrono::seconds kPlainLineInterval{30};
constexpr int kBarWidth = 28;

std::string format_duration(double seconds) {
  if (!(seconds >= 0) || seconds > 1e7) return "?";
  auto s = static_cast<long long>(seconds + 0.5);
  char buf[32];
  if (s >= 3600)
    std::snprintf(buf, sizeof buf, "%lld:%02lld:%02lld", s / 3600, (s / 60) % 60, s % 60);
  else
    std::snprintf(buf, sizeof buf, "%lld:%02lld", s / 60, s % 60);
  return buf;
}

std::string format_rate(double per_second) {
  char buf[32];
  if (per_second >= 100)
    std::snprintf(buf, sizeof buf, "%.0f/s", per_second);
  else
    std::snprintf(buf, sizeof buf, "%.3g/s", per_second);
  return buf;
}

}  // namespace

void Progress::set_quiet(bool quiet) { g_quiet.store(quiet); }

bool progress_bar_on_screen() { return g_bars_on_screen.load(std::memory_order_relaxed) > 0; }

Progress::Progress(std::string label, std::uint64_t total)
    : label_(std::move(label)),
      total_(total),
      enabled_(!g_quiet.load() && spdlog::default_logger_raw()->should_log(spdlog::level::info)),
      terminal_(isatty(fileno(stderr)) != 0),
      start_(Clock::now()),
      last_line_(start_) {
  next_check_.store((start_ + kRedrawInterval).time_since_epoch().count(), std::memory_order_relaxed);
}

Progress::~Progress() {
  std::lock_guard<std::mutex> lock(report_mutex_);
  // Unfinished (an exception is unwinding): end the bar's line so the error
  // message that follows starts on a line of its own.
  if (!finished_ && bar_drawn_) {
    std::fputc('\n', stderr);
    g_bars_on_screen.fetch_sub(1);
  }
}

void Progress::tick(std::uint64_t n) {
  count_.fetch_add(n, std::memory_order_relaxed);
  maybe_report();
}

void Progress::set(std::uint64_t count) {
  count_.store(count, std::memory_order_relaxed);
  maybe_report();
}

void Progress::maybe_report() {
  if (!enabled_) return;
  const auto now = Clock::now().time_since_epoch().count();
  if (now < next_check_.load(std::memory_order_relaxed)) return;
  // One thread reports; the others carry on with their work.
  std::unique_lock<std::mutex> lock(report_mutex_, std::try_to_lock);
  if (!lock.owns_lock() || finished_) return;
  next_check_.store((Clock::now() + kRedrawInterval).time_since_epoch().count(), std::memory_order_relaxed);
  report(count(), false);
}

void Progress::done() {
  std::lock_guard<std::mutex> lock(report_mutex_);
  if (finished_) return;
  if (enabled_) report(count(), true);
  finished_ = true;
}

void Progress::report(std::uint64_t count, bool final) {
  const double seconds = std::chrono::duration<double>(Clock::now() - start_).count();
  if (terminal_)
    draw_bar(count, seconds, final);
  else
    write_line(count, seconds, final);
}

void Progress::draw_bar(std::uint64_t count, double seconds, bool final) {
  const double rate = seconds > 0 ? count / seconds : 0.0;
  std::string line = "\r\033[K" + label_ + " ";
  if (total_ > 0) {
    const double fraction = std::min(1.0, static_cast<double>(count) / total_);
    const int filled = static_cast<int>(fraction * kBarWidth);
    line += "[" + std::string(filled, '#') + std::string(kBarWidth - filled, '.') + "] ";
    char buf[96];
    std::snprintf(buf, sizeof buf, "%3d%% %llu/%llu ", static_cast<int>(fraction * 100),
                  static_cast<unsigned long long>(count), static_cast<unsigned long long>(total_));
    line += buf;
  } else {
    line += std::to_string(count) + " ";
  }
  line += format_rate(rate);
  if (final) {
    line += "  in " + format_duration(seconds) + "\n";
  } else if (total_ > 0 && count > 0) {
    line += "  ETA " + format_duration((total_ - std::min(count, total_)) / rate);
  } else {
    line += "  " + format_duration(seconds);
  }
  std::fputs(line.c_str(), stderr);
  std::fflush(stderr);
  if (!bar_drawn_ && !final) g_bars_on_screen.fetch_add(1);
  if (bar_drawn_ && final) g_bars_on_screen.fetch_sub(1);
  bar_drawn_ = true;
}

void Progress::write_line(std::uint64_t count, double seconds, bool final) {
  const auto now = Clock::now();
  const double rate = seconds > 0 ? count / seconds : 0.0;
  if (final) {
    spdlog::info("{}: {} done in {:.1f}s ({})", label_, count, seconds, format_rate(rate));
    return;
  }
  const std::uint64_t decile = total_ > 0 ? std::min<std::uint64_t>(10, count * 10 / total_) : 0;
  const bool new_decile = decile > last_decile_ && decile < 10;  // 100% is done()'s line
  if (!new_decile && now - last_line_ < kPlainLineInterval) return;
  last_decile_ = std::max(last_decile_, decile);
  last_line_ = now;
  if (total_ > 0) {
    const std::string eta = count > 0 ? format_duration((total_ - std::min(count, total_)) / rate) : "?";
    spdlog::info("{}: {}/{} ({}%), {}, ETA {}", label_, count, total_, count * 100 / total_, format_rate(rate), eta);
  } else {
    spdlog::info("{}: {} so far, {}", label_, count, format_rate(rate));
  }
}

}  // namespace msfab
