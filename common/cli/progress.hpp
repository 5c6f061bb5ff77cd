#pragma once
// Progress reporting for long loops (DESIGN §6).
//
// On a terminal, stderr shows one updating line with a bar, rate and ETA,
// redrawn at most ~10 times per second. Otherwise (batch jobs, pipes) a
// plain log line is written each time another 10% is done, or every 30 s
// when progress is slower than that. Nothing is shown under --quiet or when
// the log level is above info.
//
//   Progress progress("assembling", n_cells);
//   #pragma omp parallel for
//   for (...) { ...; progress.tick(); }
//   progress.done();
//
// tick() is safe to call from several threads; it costs one atomic add and
// a clock read, so in very tight loops tick once per chunk of work.
#include <atomic>
#include <chrono>
#include <cstdint>
#include <mutex>
#include <string>

namespace msfab {

class Progress {
 public:
  // total = 0 means "unknown": counts and rate are shown, no bar or ETA.
  Progress(std::string label, std::uint64_t total);
  ~Progress();
  Progress(const Progress&) = delete;
  Progress& operator=(const Progress&) = delete;

  void tick(std::uint64_t n = 1);
  void set(std::uint64_t count);
  // Final report ("label: 1000 done in 12.3s"); later calls do nothing.
  void done();

  std::uint64_t count() const { return count_.load(std::memory_order_relaxed); }

  // Set once by the stage from --quiet; applies to every later Progress.
  static void set_quiet(bool quiet);

 private:
  using Clock = std::chrono::steady_clock;

  void maybe_report();
  void report(std::uint64_t count, bool final);
  void draw_bar(std::uint64_t count, double seconds, bool final);
  void write_line(std::uint64_t count, double seconds, bool final);

  std::string label_;
  std::uint64_t total_;
  bool enabled_;
  bool terminal_;
  Clock::time_point start_;
  std::atomic<std::uint64_t> count_{0};
  std::atomic<Clock::rep> next_check_{0};  // ticks before this time skip reporting
  std::mutex report_mutex_;
  // Guarded by report_mutex_:
  bool finished_ = false;
  bool bar_drawn_ = false;
  std::uint64_t last_decile_ = 0;
  Clock::time_point last_line_;
};

// True while a terminal progress bar occupies the current stderr line; the
// logger then clears that line first so log lines never run into the bar
// (the bar reappears below at its next redraw).
bool progress_bar_on_screen();

}  // namespace msfab
