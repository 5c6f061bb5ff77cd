#include <gtest/gtest.h>
#include <omp.h>
#include <spdlog/spdlog.h>
#include <unistd.h>

#include <filesystem>
#include <fstream>
#include <regex>
#include <stdexcept>
#include <string>
#include <vector>

#include "cli/logging.hpp"
#include "cli/progress.hpp"
#include "cli/stage_app.hpp"
#include "core/errors.hpp"

namespace msfab {
namespace {

bool contains(const std::string& text, const std::string& part) { return text.find(part) != std::string::npos; }

// Runs a fresh StageApp on `args` (argv[0] is added) and records what the
// stage body saw and what went to stderr.
struct StageRun {
  int exit_code = -1;
  bool body_ran = false;
  std::string stderr_text;
  std::string stdout_text;
  StageOptions options;
  std::string command_line;
};

StageRun run_stage(std::vector<std::string> args, const std::function<void(StageContext&)>& body,
                   const char* default_config = nullptr, int rank = 0) {
  args.insert(args.begin(), "msfab-test");
  std::vector<const char*> argv;
  for (const auto& a : args) argv.push_back(a.c_str());

  StageRun result;
  StageApp app("msfab-test", "a stage used by the unit tests");
  app.add_common_options();
  if (default_config) app.set_default_config(default_config);
  app.set_rank(rank);
  testing::internal::CaptureStderr();
  testing::internal::CaptureStdout();
  result.exit_code = app.run(static_cast<int>(argv.size()), argv.data(), [&](StageContext& ctx) {
    result.body_ran = true;
    result.options = ctx.options;
    result.command_line = ctx.command_line;
    body(ctx);
  });
  result.stdout_text = testing::internal::GetCapturedStdout();
  result.stderr_text = testing::internal::GetCapturedStderr();
  return result;
}

const auto kNothing = [](StageContext&) {};

TEST(StageApp, SuccessReturnsZeroAndPassesOptions) {
  double E = 0;
  std::vector<int> size;
  StageRun r = run_stage(
      {"--set", "E=5", "--set", "grid.size=[8,8,8]", "--seed", "42", "--out", "result.h5", "--quiet"},
      [&](StageContext& ctx) {
        E = ctx.config.get<double>("E");
        size = ctx.config.get<std::vector<int>>("grid.size");
        ctx.config.check_no_unknown_keys();
        EXPECT_EQ(ctx.require_out(), "result.h5");
      },
      "E: 1\ngrid: {size: [2, 2, 2]}\n");
  EXPECT_EQ(r.exit_code, 0) << r.stderr_text;
  EXPECT_TRUE(r.body_ran);
  EXPECT_DOUBLE_EQ(E, 5.0);
  EXPECT_EQ(size, (std::vector<int>{8, 8, 8}));
  EXPECT_EQ(r.options.seed, 42u);
  EXPECT_EQ(r.options.overrides.size(), 2u);
  EXPECT_TRUE(r.options.quiet);
  EXPECT_EQ(r.command_line, "msfab-test --set E=5 --set 'grid.size=[8,8,8]' --seed 42 --out result.h5 --quiet");
  EXPECT_EQ(r.stderr_text, "");  // --quiet: nothing at info level
}

TEST(StageApp, InputErrorReturnsTwoWithOneLineMessage) {
  StageRun r = run_stage({}, [](StageContext&) { throw InputError("scene.yaml: E = -1: must be positive"); });
  EXPECT_EQ(r.exit_code, 2);
  EXPECT_EQ(r.stderr_text, "msfab-test: error: scene.yaml: E = -1: must be positive\n");
}

TEST(StageApp, NumericalErrorReturnsThree) {
  StageRun r = run_stage({}, [](StageContext&) { throw NumericalError("Newton did not converge\n  |r| = 1e-3"); });
  EXPECT_EQ(r.exit_code, 3);
  EXPECT_EQ(r.stderr_text, "msfab-test: error: Newton did not converge\n  |r| = 1e-3\n");
}

TEST(StageApp, OtherExceptionsAreInternalErrors) {
  StageRun r = run_stage({}, [](StageContext&) { throw std::runtime_error("index out of bounds"); });
  EXPECT_EQ(r.exit_code, 1);
  EXPECT_EQ(r.stderr_text, "msfab-test: error: internal error: index out of bounds\n");
}

TEST(StageApp, UnknownFlagReturnsTwoWithoutRunningTheStage) {
  StageRun r = run_stage({"--bogus"}, kNothing);
  EXPECT_EQ(r.exit_code, 2);
  EXPECT_FALSE(r.body_ran);
  EXPECT_TRUE(contains(r.stderr_text, "msfab-test: error: ")) << r.stderr_text;
  EXPECT_TRUE(contains(r.stderr_text, "--bogus")) << r.stderr_text;
}

TEST(StageApp, BadOptionValuesReturnTwo) {
  EXPECT_EQ(run_stage({"--threads", "0"}, kNothing).exit_code, 2);
  EXPECT_EQ(run_stage({"--threads", "many"}, kNothing).exit_code, 2);
  EXPECT_EQ(run_stage({"--seed", "-1"}, kNothing).exit_code, 2);
  // Past the type's range: refused, not clamped (2^64 became 2^64 - 1).
  StageRun big = run_stage({"--seed", "18446744073709551616"}, kNothing);
  EXPECT_EQ(big.exit_code, 2);
  EXPECT_TRUE(contains(big.stderr_text, "larger than 18446744073709551615")) << big.stderr_text;
  EXPECT_EQ(run_stage({"--threads", "4294967297"}, kNothing).exit_code, 2);
  StageRun largest = run_stage({"--seed", "18446744073709551615"}, kNothing);
  EXPECT_EQ(largest.exit_code, 0) << largest.stderr_text;
  EXPECT_EQ(largest.options.seed, 18446744073709551615u);
  EXPECT_EQ(run_stage({"--log-level", "loud"}, kNothing).exit_code, 2);
  StageRun r = run_stage({"--set", "grid.size"}, kNothing);
  EXPECT_EQ(r.exit_code, 2);
  EXPECT_TRUE(contains(r.stderr_text, "--set 'grid.size': expected key=value")) << r.stderr_text;
}

TEST(StageApp, HelpAndVersionReturnZero) {
  StageRun help = run_stage({"--help"}, kNothing);
  EXPECT_EQ(help.exit_code, 0);
  EXPECT_FALSE(help.body_ran);
  EXPECT_TRUE(contains(help.stdout_text, "--config")) << help.stdout_text;
  EXPECT_TRUE(contains(help.stdout_text, "Exit codes")) << help.stdout_text;
  StageRun version = run_stage({"--version"}, kNothing);
  EXPECT_EQ(version.exit_code, 0);
  EXPECT_TRUE(contains(version.stdout_text, "msfab-test")) << version.stdout_text;
}

TEST(StageApp, ConfigFileIsLoadedAndMissingFileIsBadInput) {
  const auto dir = std::filesystem::temp_directory_path() / ("msfab_stage_app_test_" + std::to_string(::getpid()));
  std::filesystem::create_directories(dir);
  const std::string path = (dir / "stage.yaml").string();
  std::ofstream(path) << "iterations: 7\nmaterails: []\n";

  int iterations = 0;
  StageRun r = run_stage({"--config", path}, [&](StageContext& ctx) {
    iterations = ctx.config.get<int>("iterations");
    ctx.config.get_or("materials", std::vector<double>{});
    ctx.config.check_no_unknown_keys();
  });
  EXPECT_EQ(iterations, 7);
  EXPECT_EQ(r.exit_code, 2);  // the misspelled key stops the stage
  EXPECT_TRUE(contains(r.stderr_text, "unknown key 'materails' in " + path)) << r.stderr_text;

  StageRun missing = run_stage({"--config", (dir / "nope.yaml").string()}, kNothing);
  EXPECT_EQ(missing.exit_code, 2);
  EXPECT_FALSE(missing.body_ran);
  EXPECT_TRUE(contains(missing.stderr_text, "nope.yaml: no such file")) << missing.stderr_text;

  StageRun no_out = run_stage({}, [](StageContext& ctx) { ctx.require_out(); });
  EXPECT_EQ(no_out.exit_code, 2);
  EXPECT_TRUE(contains(no_out.stderr_text, "--out")) << no_out.stderr_text;
  std::filesystem::remove_all(dir);
}

TEST(StageApp, ThreadsOptionSetsOpenMpThreads) {
  const int before = omp_get_max_threads();
  int seen = 0;
  StageRun r = run_stage({"--threads", "3"}, [&](StageContext&) { seen = omp_get_max_threads(); });
  omp_set_num_threads(before);
  EXPECT_EQ(r.exit_code, 0);
  EXPECT_EQ(seen, 3);
}

TEST(StageAppLogging, LinesCarryElapsedTimeAndLevelTag) {
  init_logging("msfab-test", LogLevel::info);
  testing::internal::CaptureStderr();
  spdlog::info("assembled {} dofs", 24);
  spdlog::warn("mesh has {} pieces", 3);
  spdlog::debug("hidden at info level");
  const std::string text = testing::internal::GetCapturedStderr();
  EXPECT_TRUE(std::regex_search(text, std::regex(R"(^\[ +\d+\.\ds\] assembled 24 dofs\n)"))) << text;
  EXPECT_TRUE(std::regex_search(text, std::regex(R"(\n\[ +\d+\.\ds\] warning: mesh has 3 pieces\n$)"))) << text;
  EXPECT_FALSE(contains(text, "hidden"));
  EXPECT_THROW(parse_log_level("verbose"), InputError);
  EXPECT_EQ(parse_log_level("debug"), LogLevel::debug);
}

TEST(StageAppProgress, CountsTicksFromManyThreadsAndReportsCompletion) {
  init_logging("msfab-test", LogLevel::info);
  Progress::set_quiet(false);
  testing::internal::CaptureStderr();
  {
    Progress progress("cells", 20000);
#pragma omp parallel for num_threads(4)
    for (int i = 0; i < 20000; ++i) progress.tick();
    EXPECT_EQ(progress.count(), 20000u);
    progress.done();
    progress.done();  // a second call adds nothing
  }
  const std::string text = testing::internal::GetCapturedStderr();
  // stderr is captured (not a terminal): plain lines, one final summary.
  const auto first = text.find("cells: 20000 done in");
  EXPECT_NE(first, std::string::npos) << text;
  EXPECT_EQ(text.find("cells: 20000 done in", first + 1), std::string::npos) << text;
}

// A job on several MPI ranks speaks through rank 0: the others keep their
// warnings and errors but draw no progress and log no info lines.
TEST(StageApp, OnlyRankZeroLogsInfoAndProgress) {
  const auto body = [](StageContext&) {
    spdlog::info("info line");
    spdlog::warn("warning line");
    Progress progress("items", 4);
    for (int i = 0; i < 4; ++i) progress.tick();
    progress.done();
  };
  const StageRun root = run_stage({}, body, nullptr, 0);
  const StageRun other = run_stage({}, body, nullptr, 1);
  Progress::set_quiet(false);
  ASSERT_EQ(root.exit_code, 0);
  ASSERT_EQ(other.exit_code, 0);
  EXPECT_TRUE(contains(root.stderr_text, "info line")) << root.stderr_text;
  EXPECT_TRUE(contains(root.stderr_text, "items: 4 done in")) << root.stderr_text;
  EXPECT_TRUE(contains(other.stderr_text, "warning line")) << other.stderr_text;
  EXPECT_FALSE(contains(other.stderr_text, "info line")) << other.stderr_text;
  EXPECT_FALSE(contains(other.stderr_text, "items:")) << other.stderr_text;
}

TEST(StageAppProgress, QuietProgressPrintsNothing) {
  init_logging("msfab-test", LogLevel::info);
  Progress::set_quiet(true);
  testing::internal::CaptureStderr();
  {
    Progress progress("cells", 10);
    for (int i = 0; i < 10; ++i) progress.tick();
    progress.done();
    EXPECT_EQ(progress.count(), 10u);
  }
  Progress::set_quiet(false);
  EXPECT_EQ(testing::internal::GetCapturedStderr(), "");
}

}  // namespace
}  // namespace msfab
