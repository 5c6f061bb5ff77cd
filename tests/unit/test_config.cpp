#include <gtest/gtest.h>
#include <sys/stat.h>
#include <unistd.h>

#include <chrono>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <string>
#include <vector>

#include "core/errors.hpp"
#include "io/config.hpp"
#include "io/input_file.hpp"
#include "io/linear_solver_config.hpp"
#include "io/material_config.hpp"

namespace msfab {
namespace {

// Runs `fn`, expects an InputError, and returns its message.
template <class Fn>
std::string input_error_of(Fn&& fn) {
  try {
    fn();
  } catch (const InputError& e) {
    return e.what();
  }
  ADD_FAILURE() << "expected an InputError";
  return "";
}

::testing::AssertionResult AssertContains(const char* text_expr, const char* part_expr, const std::string& text,
                                          const std::string& part) {
  if (text.find(part) != std::string::npos) return ::testing::AssertionSuccess();
  return ::testing::AssertionFailure() << text_expr << " = \"" << text << "\"\n  does not contain " << part_expr
                                       << " = \"" << part << "\"";
}
#define EXPECT_CONTAINS(text, part) EXPECT_PRED_FORMAT2(AssertContains, text, part)

const char* kScene = R"(
name: bar
E: 2.5e9
count: 12
enabled: true
grid:
  size: [4, 8, 16]
  spacing: 0.5
boundary:
  type: clamped
  faces: [xmin, xmax]
materials:
  - {E: 1.0e6, nu: 0.3}
  - E: 2.0e6
    nu: 0.45
)";

TEST(Config, TypedReadsOfScalarsAndLists) {
  Config c = Config::from_string(kScene, "bar.yaml");
  EXPECT_EQ(c.get<std::string>("name"), "bar");
  EXPECT_DOUBLE_EQ(c.get<double>("E"), 2.5e9);
  EXPECT_EQ(c.get<int>("count"), 12);
  EXPECT_DOUBLE_EQ(c.get<double>("count"), 12.0);  // an integer is a number too
  EXPECT_TRUE(c.get<bool>("enabled"));
  EXPECT_EQ(c.get<std::vector<int>>("grid.size"), (std::vector<int>{4, 8, 16}));
  EXPECT_EQ(c.get<std::vector<double>>("grid.size"), (std::vector<double>{4.0, 8.0, 16.0}));
  EXPECT_DOUBLE_EQ(c.get<double>("grid.spacing"), 0.5);
}

TEST(Config, DefaultsApplyOnlyWhenKeyIsAbsent) {
  Config c = Config::from_string("tol: 1e-6\nempty:\n", "s.yaml");
  EXPECT_DOUBLE_EQ(c.get_or("tol", 1.0), 1e-6);
  EXPECT_DOUBLE_EQ(c.get_or("max_step", 0.25), 0.25);
  EXPECT_EQ(c.get_or("empty", 7), 7);  // "key:" with no value counts as not given
  EXPECT_EQ(c.get_or("solver", "cholmod"), "cholmod");
  EXPECT_FALSE(c.has("max_step"));
  EXPECT_FALSE(c.has("empty"));
  EXPECT_TRUE(c.has("tol"));
  // A default does not excuse a wrongly typed value.
  Config bad = Config::from_string("tol: small\n", "s.yaml");
  EXPECT_CONTAINS(input_error_of([&] { bad.get_or("tol", 1.0); }), ("s.yaml: tol: expected a number"));
}

TEST(Config, EffectiveTextWritesInTheDefaultsThatWereRead) {
  Config c = Config::from_string(kScene, "scene.yaml");
  EXPECT_EQ(c.get_or<double>("grid.spacing", 9.0), 0.5);        // present: not a default
  EXPECT_EQ(c.get_or<double>("solver.tolerance", 1e-9), 1e-9);  // a new section
  EXPECT_EQ(c.children("materials")[1].get_or<double>("density", 1200.0 / 7), 1200.0 / 7);
  EXPECT_EQ(c.get_or<std::string>("name", "unnamed"), "bar");
  const std::string text = c.effective_text();
  EXPECT_CONTAINS(text, "#   solver.tolerance = 1e-09\n");
  EXPECT_CONTAINS(text, "#   materials[1].density = 171.42857142857142\n");
  EXPECT_EQ(text.find("grid.spacing ="), std::string::npos);
  // The text reads back as a config holding the defaults, to the bit.
  Config back = Config::from_string(text, "effective");
  EXPECT_EQ(back.get<double>("solver.tolerance"), 1e-9);
  EXPECT_EQ(back.children("materials")[1].get<double>("density"), 1200.0 / 7);
  EXPECT_EQ(back.children("materials")[1].get<double>("nu"), 0.45);
  EXPECT_EQ(back.get<double>("grid.spacing"), 0.5);
  // Nothing was added to the document itself.
  EXPECT_FALSE(c.has("solver.tolerance"));
}

TEST(Config, NestedChildrenCarryTheirKeyPath) {
  Config c = Config::from_string(kScene, "bar.yaml");
  Config boundary = c.child("boundary");
  EXPECT_EQ(boundary.path(), "boundary");
  EXPECT_EQ(boundary.get<std::string>("type"), "clamped");
  EXPECT_EQ(boundary.get<std::vector<std::string>>("faces"), (std::vector<std::string>{"xmin", "xmax"}));
  EXPECT_CONTAINS(input_error_of([&] { boundary.get<double>("type"); }),
                  ("bar.yaml: boundary.type: expected a number, found 'clamped'"));
  EXPECT_CONTAINS(input_error_of([&] { c.child("name"); }), ("bar.yaml: name: expected a mapping"));
  EXPECT_CONTAINS(input_error_of([&] { c.child("solver"); }), ("missing required section 'solver'"));
}

TEST(Config, ListsOfMapsGiveIndexedChildren) {
  Config c = Config::from_string(kScene, "bar.yaml");
  std::vector<Config> materials = c.children("materials");
  ASSERT_EQ(materials.size(), 2u);
  EXPECT_DOUBLE_EQ(materials[0].get<double>("E"), 1.0e6);
  EXPECT_DOUBLE_EQ(materials[1].get<double>("nu"), 0.45);
  EXPECT_EQ(materials[1].path(), "materials[1]");
  EXPECT_CONTAINS(input_error_of([&] { materials[1].get<int>("nu"); }),
                  ("bar.yaml: materials[1].nu: expected an integer, found '0.45'"));
  EXPECT_CONTAINS(input_error_of([&] { c.children("grid"); }), ("grid: expected a list of mappings"));
}

TEST(Config, OverridesReplaceValuesListsAndCreateNewPaths) {
  Config c = Config::from_string(kScene, "bar.yaml");
  c.apply_overrides(
      {"E=7", "grid.size=[8,8,8]", "solver.newton.max_iterations=50", "materials[1].nu=0.25", "name=\"two words\""});
  EXPECT_DOUBLE_EQ(c.get<double>("E"), 7.0);
  EXPECT_EQ(c.get<std::vector<int>>("grid.size"), (std::vector<int>{8, 8, 8}));
  EXPECT_DOUBLE_EQ(c.get<double>("grid.spacing"), 0.5);  // sibling untouched
  EXPECT_EQ(c.child("solver").child("newton").get<int>("max_iterations"), 50);
  EXPECT_DOUBLE_EQ(c.children("materials")[1].get<double>("nu"), 0.25);
  EXPECT_DOUBLE_EQ(c.children("materials")[0].get<double>("nu"), 0.3);
  EXPECT_EQ(c.get<std::string>("name"), "two words");
  // The resolved text reflects the overrides and parses back to the same values.
  Config again = Config::from_string(c.resolved_text(), "resolved");
  EXPECT_EQ(again.get<std::vector<int>>("grid.size"), (std::vector<int>{8, 8, 8}));
  EXPECT_EQ(again.get<int>("solver.newton.max_iterations"), 50);
  EXPECT_EQ(again.get<std::string>("name"), "two words");
  // Quoted strings stay strings on the way through.
  Config quoted = Config::from_string("id: \"007\"\nn: 7\n", "q.yaml");
  Config back = Config::from_string(quoted.resolved_text(), "resolved");
  EXPECT_EQ(back.get<std::string>("id"), "007");
  EXPECT_THROW(back.get<int>("id"), InputError);
  EXPECT_EQ(back.get<int>("n"), 7);
}

TEST(Config, MalformedOverridesNameTheOverride) {
  Config c = Config::from_string(kScene, "bar.yaml");
  EXPECT_CONTAINS(input_error_of([&] { c.apply_override("E"); }), ("--set 'E': expected key=value"));
  EXPECT_CONTAINS(input_error_of([&] { c.apply_override("=3"); }), ("--set '=3'"));
  EXPECT_CONTAINS(input_error_of([&] { c.apply_override("grid..size=3"); }), ("--set 'grid..size=3'"));
  EXPECT_CONTAINS(input_error_of([&] { c.apply_override("grid.size=[1,2"); }), ("cannot parse value"));
  EXPECT_CONTAINS(input_error_of([&] { c.apply_override("E.x=1"); }), ("not a mapping"));
  EXPECT_CONTAINS(input_error_of([&] { c.apply_override("materials[5].nu=0.1"); }), ("out of range"));
  EXPECT_CONTAINS(input_error_of([&] { c.apply_override("E="); }), ("missing value"));
}

TEST(Config, ErrorsAfterOverrideMentionTheOverride) {
  Config c = Config::from_string(kScene, "bar.yaml");
  c.apply_override("E=-1");
  std::string message = input_error_of([&] { c.require_positive("E", "Young's modulus"); });
  EXPECT_CONTAINS(message, ("bar.yaml (with --set E=-1): E = -1: Young's modulus must be positive"));
}

TEST(Config, UnknownTopLevelKeyIsReportedWithKnownKeys) {
  Config c = Config::from_string("E: 1\nnu: 0.3\nmaterails: []\n", "scene.yaml");
  c.get<double>("E");
  c.get<double>("nu");
  c.get_or("materials", std::vector<double>{});
  std::string message = input_error_of([&] { c.check_no_unknown_keys(); });
  EXPECT_CONTAINS(message, ("unknown key 'materails' in scene.yaml (at top level)"));
  EXPECT_CONTAINS(message, ("did you mean 'materials'?"));
  EXPECT_CONTAINS(message, ("known keys: E, materials, nu"));
}

TEST(Config, UnknownNestedKeyIsReportedWithItsPath) {
  Config c = Config::from_string(kScene, "bar.yaml");
  c.get<std::string>("name");
  c.get<double>("E");
  c.get<int>("count");
  c.get<bool>("enabled");
  c.get<std::vector<int>>("grid.size");  // grid.spacing never read
  Config boundary = c.child("boundary");
  boundary.get<std::string>("type");
  boundary.get<std::vector<std::string>>("faces");
  for (const Config& m : c.children("materials")) {
    m.get<double>("E");
    m.get<double>("nu");
  }
  std::string message = input_error_of([&] { c.check_no_unknown_keys(); });
  EXPECT_CONTAINS(message, ("unknown key 'spacing' in bar.yaml (under 'grid')"));
  EXPECT_CONTAINS(message, ("known keys: size"));

  c.get<double>("grid.spacing");
  EXPECT_NO_THROW(c.check_no_unknown_keys());
}

TEST(Config, MisspelledKeyInsideListElementIsCaught) {
  Config c = Config::from_string("materials:\n  - {E: 1, nu: 0.3}\n  - {E: 2, nuu: 0.3}\n", "m.yaml");
  for (const Config& m : c.children("materials")) {
    m.get<double>("E");
    m.get_or("nu", 0.0);
  }
  std::string message = input_error_of([&] { c.check_no_unknown_keys(); });
  EXPECT_CONTAINS(message, ("unknown key 'nuu' in m.yaml (under 'materials[1]')"));
  EXPECT_CONTAINS(message, ("did you mean 'nu'?"));
}

TEST(Config, SectionOnlyEnteredStillHasItsKeysChecked) {
  Config c = Config::from_string("solver:\n  tol: 1e-8\n  tolerance: 1e-6\n", "s.yaml");
  EXPECT_DOUBLE_EQ(c.child("solver").get<double>("tolerance"), 1e-6);
  EXPECT_CONTAINS(input_error_of([&] { c.check_no_unknown_keys(); }), ("unknown key 'tol' in s.yaml (under 'solver')"));
  // raw() accepts a whole section for another parser.
  Config d = Config::from_string("solver:\n  tol: 1e-8\n  anything: [1, 2]\n", "s.yaml");
  EXPECT_EQ(d.raw("solver")["anything"].size(), 2u);
  EXPECT_NO_THROW(d.check_no_unknown_keys());
}

TEST(Config, WrongTypesAreReportedAsSuch) {
  Config c = Config::from_string("E: abc\nn: 2.5\nflag: maybe\nsize: 8\nlist: [1, x]\nquoted: \"3\"\n", "t.yaml");
  EXPECT_CONTAINS(input_error_of([&] { c.get<double>("E"); }), ("t.yaml: E: expected a number, found 'abc'"));
  EXPECT_CONTAINS(input_error_of([&] { c.get<int>("n"); }), ("t.yaml: n: expected an integer, found '2.5'"));
  EXPECT_CONTAINS(input_error_of([&] { c.get<bool>("flag"); }), ("flag: expected true or false"));
  EXPECT_CONTAINS(input_error_of([&] { c.get<std::vector<int>>("size"); }),
                  ("size: expected a list of integers, found '8'"));
  EXPECT_CONTAINS(input_error_of([&] { c.get<std::vector<double>>("list"); }),
                  ("list[1]: expected a number, found 'x'"));
  EXPECT_CONTAINS(input_error_of([&] { c.get<double>("quoted"); }), ("found the quoted string \"3\""));
  EXPECT_CONTAINS(input_error_of([&] { c.get<std::string>("list"); }), ("list: expected a string"));
  EXPECT_CONTAINS(input_error_of([&] { c.get<std::uint64_t>("n"); }), ("expected a non-negative integer"));
}

TEST(Config, MissingRequiredKeyNamesFileAndPath) {
  Config c = Config::from_string(kScene, "configs/scenes/bar.yaml");
  EXPECT_CONTAINS(input_error_of([&] { c.children("materials")[0].get<double>("density"); }),
                  ("configs/scenes/bar.yaml: missing required key 'materials[0].density' (expected a number)"));
  EXPECT_CONTAINS(input_error_of([&] { c.get<double>("grid.origin"); }), ("missing required key 'grid.origin'"));
}

TEST(Config, RangeChecksNameFileKeyValueAndRule) {
  Config c =
      Config::from_string("materials:\n  - {E: -3, nu: 0.3}\n  - {E: 1e6, nu: 0.5}\n", "configs/scenes/bar.yaml");
  auto materials = c.children("materials");
  EXPECT_CONTAINS(input_error_of([&] { materials[0].require_positive("E", "Young's modulus"); }),
                  ("configs/scenes/bar.yaml: materials[0].E = -3: Young's modulus must be positive"));
  EXPECT_DOUBLE_EQ(materials[0].require_range("nu", -1.0, 0.5, Bounds::Open, "Poisson's ratio"), 0.3);
  EXPECT_DOUBLE_EQ(materials[1].require_positive("E"), 1e6);
  EXPECT_CONTAINS(input_error_of([&] { materials[1].require_range("nu", -1.0, 0.5, Bounds::Open, "Poisson's ratio"); }),
                  ("configs/scenes/bar.yaml: materials[1].nu = 0.5: Poisson's ratio must be in (-1, 0.5)"));
  // Closed bounds include the end point.
  EXPECT_DOUBLE_EQ(materials[1].require_range("nu", 0.0, 0.5, Bounds::Closed), 0.5);
  EXPECT_CONTAINS(input_error_of([&] { materials[1].require_range("nu", 0.0, 0.5, Bounds::ClosedOpen); }),
                  ("must be in [0, 0.5)"));
}

TEST(Config, NonFiniteAndChoiceChecks) {
  Config c = Config::from_string("a: -1\nb: 0\nc: 2\nmode: static\nkind: modal\nn: 0\n", "f.yaml");
  EXPECT_CONTAINS(input_error_of([&] { c.require_positive("a"); }), ("must be positive"));
  EXPECT_CONTAINS(input_error_of([&] { c.require_positive("b"); }), ("must be positive"));
  EXPECT_CONTAINS(input_error_of([&] { c.require_range("a", 0.0, 1.0); }), ("must be in [0, 1]"));
  EXPECT_DOUBLE_EQ(c.require_finite("c"), 2.0);
  EXPECT_EQ(c.one_of("mode", {"static", "dynamic"}), "static");
  EXPECT_CONTAINS(input_error_of([&] {
                    c.one_of("kind", {"static", "dynamic"});
                  }),
                  ("f.yaml: kind = modal: must be one of: static, dynamic"));
  EXPECT_CONTAINS(input_error_of([&] { c.require_positive<int>("n", "cell count"); }),
                  ("n = 0: cell count must be positive"));
}

// Non-finite and overflowing numbers are refused by the reader itself, for
// every key, in scalars and lists, from files and from --set alike.
TEST(Config, NonFiniteAndHugeNumbersAreRefusedWhereverTheyAreRead) {
  Config c = Config::from_string("a: .nan\nb: .inf\nc: -.inf\nd: 1e308\ne: -2e100\nf: [1, .nan]\ng: 1e100\n", "f.yaml");
  EXPECT_CONTAINS(input_error_of([&] { c.get<double>("a"); }), ("f.yaml: a = .nan: expected a finite number"));
  EXPECT_CONTAINS(input_error_of([&] { c.require_positive("b", "damping"); }), ("b = .inf: expected a finite"));
  EXPECT_CONTAINS(input_error_of([&] { c.get_or<double>("c", 1.0); }), ("c = -.inf"));
  EXPECT_CONTAINS(input_error_of([&] { c.get<double>("d"); }), ("d = 1e308: beyond"));
  EXPECT_CONTAINS(input_error_of([&] { c.require_range("e", -1e300, 0.0); }), ("e = -2e100: beyond"));
  EXPECT_CONTAINS(input_error_of([&] { c.get<std::vector<double>>("f"); }), ("f[1] = .nan"));
  EXPECT_DOUBLE_EQ(c.get<double>("g"), kLargestConfigNumber);
  c.apply_override("g=1e200");
  EXPECT_CONTAINS(input_error_of([&] { c.get<double>("g"); }), ("g = 1e200: beyond"));
}

TEST(Config, MalformedYamlReportsLineAndColumn) {
  std::string message = input_error_of([] { Config::from_string("a: 1\nb: [1, 2\nc: 3\n", "broken.yaml"); });
  EXPECT_CONTAINS(message, ("broken.yaml: line "));
  EXPECT_CONTAINS(message, ("YAML syntax error"));
  // The unclosed flow list is detected on line 3 (yaml-cpp reports where it gave up).
  EXPECT_TRUE(message.find("line 2") != std::string::npos || message.find("line 3") != std::string::npos) << message;
  EXPECT_CONTAINS(input_error_of([] { Config::from_string("a: 1\n  b: 2\n", "indent.yaml"); }),
                  "indent.yaml: line 2, column 4: YAML syntax error");
  EXPECT_CONTAINS(input_error_of([] { Config::from_string("a: 1\na: 2\n", "dup.yaml"); }),
                  ("dup.yaml: line 2: duplicate key 'a'"));
  EXPECT_CONTAINS(input_error_of([] { Config::from_string("- 1\n- 2\n", "list.yaml"); }),
                  ("list.yaml: expected a mapping"));
}

TEST(Config, LoadsFilesAndReportsMissingOnes) {
  const auto dir = std::filesystem::temp_directory_path() / ("msfab_config_test_" + std::to_string(::getpid()));
  std::filesystem::create_directories(dir);
  const std::string path = (dir / "scene.yaml").string();
  {
    std::ofstream out(path);
    out << "E: 3\nbad: [\n";
  }
  std::string message = input_error_of([&] { Config::load_file(path); });
  EXPECT_CONTAINS(message, (path + ": line 3"));
  {
    std::ofstream out(path);
    out << "E: 3\n";
  }
  Config c = Config::load_file(path);
  EXPECT_EQ(c.source(), path);
  EXPECT_EQ(c.get<int>("E"), 3);
  EXPECT_CONTAINS(input_error_of([&] { Config::load_file((dir / "nope.yaml").string()); }),
                  ((dir / "nope.yaml").string() + ": no such file"));
  Config empty = Config::from_string("", "empty.yaml");  // an empty file is an empty mapping
  EXPECT_TRUE(empty.keys().empty());
  EXPECT_NO_THROW(empty.check_no_unknown_keys());
  std::filesystem::remove_all(dir);
}

TEST(Config, RelativePathsAreTakenFromTheConfigFilesFolder) {
  const auto dir = std::filesystem::temp_directory_path() / ("msfab_config_paths_" + std::to_string(::getpid()));
  std::filesystem::create_directories(dir / "scenes");
  const std::string path = (dir / "scenes" / "bar.yaml").string();
  std::ofstream(path) << "db: ../data/db.h5\nabsolute: /data/x.h5\nout: r.h5\nempty: \"\"\n";
  Config c = Config::load_file(path);
  c.apply_override("out=here.h5");
  EXPECT_EQ(c.get_path("db"), (dir / "data" / "db.h5").string());
  EXPECT_EQ(c.get_path("absolute"), "/data/x.h5");
  EXPECT_EQ(c.get_path("out"), "here.h5");  // typed on the command line: relative to the working directory
  EXPECT_CONTAINS(input_error_of([&] { c.get_path("empty"); }), "empty = : expected a file path");
  EXPECT_EQ(Config::from_string("db: a/b.h5\n", "<defaults>").get_path("db"), "a/b.h5");
  EXPECT_EQ(Config().source(), "<empty config>");
  std::filesystem::remove_all(dir);
}

}  // namespace
}  // namespace msfab

namespace msfab {
namespace {
TEST(Config, FailOnTheNodeItselfNamesItsPath) {
  const Config c = Config::from_string("layout:\n  - {sphere: 1}\n", "cfg");
  const std::vector<Config> items = c.children("layout");
  try {
    items.at(0).fail("", "a layout item needs one of: fill, box");
    FAIL() << "no exception";
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find("layout[0]"), std::string::npos) << e.what();
    EXPECT_NE(std::string(e.what()).find("needs one of"), std::string::npos) << e.what();
  }
}
}  // namespace
}  // namespace msfab

namespace msfab {
namespace {

// "A billion laughs": nine levels of nine aliases stand for 9^9 scalars in a
// few hundred bytes. yaml-cpp shares the anchored nodes, so parsing is cheap;
// any walk of the expanded tree is not, and must be refused, not run.
std::string alias_bomb(int levels) {
  std::string text = "l0: &l0 [lol, lol, lol, lol, lol, lol, lol, lol, lol]\n";
  for (int i = 1; i < levels; ++i) {
    const std::string prev = "*l" + std::to_string(i - 1);
    text += "l" + std::to_string(i) + ": &l" + std::to_string(i) + " [";
    for (int k = 0; k < 9; ++k) text += (k ? ", " : "") + prev;
    text += "]\n";
  }
  return text;
}

TEST(Config, AliasBombIsRefusedQuicklyNamingTheFile) {
  const auto start = std::chrono::steady_clock::now();
  const std::string message = input_error_of([] { Config::from_string(alias_bomb(9), "bomb.yaml"); });
  EXPECT_CONTAINS(message, "bomb.yaml: YAML aliases expand the document");
  EXPECT_LT(std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count(), 5.0);
  EXPECT_CONTAINS(input_error_of([] { Config().apply_override("x=" + alias_bomb(9)); }), "--set 'x=");
  // An anchor that holds an alias of itself is refused, not walked forever.
  EXPECT_THROW(Config::from_string("a: &a [*a]\n", "loop.yaml"), InputError);
}

TEST(Config, ModerateAliasesStillWork) {
  Config c = Config::from_string("base: &m {E: 1.0e6, nu: 0.3}\nmaterials: [*m, *m, *m]\n", "ok.yaml");
  ASSERT_EQ(c.children("materials").size(), 3u);
  EXPECT_DOUBLE_EQ(c.children("materials")[2].get<double>("E"), 1.0e6);
  // 9^4 expanded scalars is far below the budget.
  EXPECT_NO_THROW(Config::from_string(alias_bomb(4), "small.yaml"));
}

TEST(Config, DevicesFifosFoldersAndHugeFilesAreRefusedNamingTheFile) {
  const auto dir = std::filesystem::temp_directory_path() / ("msfab_config_special_" + std::to_string(::getpid()));
  std::filesystem::create_directories(dir);
  EXPECT_CONTAINS(input_error_of([] { Config::load_file("/dev/zero"); }), "/dev/zero: is a character device");
  const std::string fifo = (dir / "pipe.yaml").string();
  ASSERT_EQ(::mkfifo(fifo.c_str(), 0600), 0);
  EXPECT_CONTAINS(input_error_of([&] { Config::load_file(fifo); }), fifo + ": is a FIFO");
  EXPECT_CONTAINS(input_error_of([&] { Config::load_file(dir.string()); }), dir.string() + ": is a folder");
  const std::string huge = (dir / "huge.yaml").string();
  std::ofstream(huge) << "a: 1\n";
  std::filesystem::resize_file(huge, kMaxConfigBytes + 1);  // sparse
  EXPECT_CONTAINS(input_error_of([&] { Config::load_file(huge); }), huge + ": is 16777217 bytes, more than the 16 MiB");
  std::filesystem::remove_all(dir);
}

TEST(InputFile, SameFileByInodeOrByPath) {
  const auto dir = std::filesystem::temp_directory_path() / ("msfab_same_file_" + std::to_string(::getpid()));
  std::filesystem::create_directories(dir / "sub");
  const std::string a = (dir / "a.h5").string();
  std::ofstream(a) << "x";
  std::filesystem::create_hard_link(a, dir / "hard.h5");
  std::filesystem::create_symlink(a, dir / "soft.h5");
  EXPECT_TRUE(same_file(a, (dir / "hard.h5").string()));
  EXPECT_TRUE(same_file(a, (dir / "soft.h5").string()));
  EXPECT_TRUE(same_file(a, (dir / "sub" / ".." / "a.h5").string()));
  EXPECT_TRUE(same_file((dir / "new.h5").string(), (dir / "sub" / ".." / "new.h5").string()));
  EXPECT_FALSE(same_file(a, (dir / "new.h5").string()));
  std::ofstream((dir / "b.h5").string()) << "x";
  EXPECT_FALSE(same_file(a, (dir / "b.h5").string()));
  std::filesystem::remove_all(dir);
}

TEST(LinearSolverConfig, ReadsTheThreeKeysWithTheStagesDefaults) {
  const Config c = Config::from_string("solver: {linear_solver: pcg, linear_tolerance: 1.0e-10}\n", "s.yaml");
  LinearSolverChoice defaults;
  defaults.max_iterations = 77;
  const LinearSolverChoice got = read_linear_solver_choice(c.child("solver"), {"auto", "cholmod", "pcg"}, defaults);
  EXPECT_EQ(got.kind, "pcg");
  EXPECT_EQ(got.tolerance, 1e-10);
  EXPECT_EQ(got.max_iterations, 77);
  EXPECT_EQ(got.max_iterations_key, "solver.linear_max_iterations");
  EXPECT_EQ(got.kind_key, "solver.linear_solver");
  c.check_no_unknown_keys();
}

TEST(LinearSolverConfig, EarlierNamesReadAsTheCurrentOnes) {
  LinearSolverKeys keys;
  keys.legacy_kind = "solver";
  keys.legacy_tolerance = "multigrid_tolerance";
  const Config old = Config::from_string("solver: multigrid\nmultigrid_tolerance: 1.0e-4\n", "h.yaml");
  const LinearSolverChoice got = read_linear_solver_choice(old, {"auto", "cholmod", "matrix-free"}, {}, keys);
  EXPECT_EQ(got.kind, "matrix-free");
  EXPECT_EQ(got.tolerance, 1e-4);
  EXPECT_EQ(got.tolerance_key, "multigrid_tolerance");
  old.check_no_unknown_keys();
  const Config direct = Config::from_string("linear_solver: direct\n", "h.yaml");
  EXPECT_EQ(read_linear_solver_choice(direct, {"auto", "cholmod"}, {}, keys).kind, "cholmod");
  const Config both = Config::from_string("solver: multigrid\nlinear_solver: cholmod\n", "h.yaml");
  EXPECT_CONTAINS(input_error_of([&] {
                    read_linear_solver_choice(both, {"auto", "cholmod"}, {}, keys);
                  }),
                  ("h.yaml: solver = multigrid: is the earlier name of linear_solver; give only one of them"));
}

TEST(LinearSolverConfig, RefusesWhatTheStageDoesNotOffer) {
  const std::vector<std::string> offered = {"auto", "cholmod", "matrix-free"};
  const auto error_for = [&](const std::string& yaml) {
    const Config c = Config::from_string(yaml, "h.yaml");
    return input_error_of([&] { read_linear_solver_choice(c, offered, {}); });
  };
  EXPECT_CONTAINS(error_for("linear_solver: pcg\n"),
                  ("h.yaml: linear_solver = pcg: linear solver 'pcg' is unknown here; choose one of auto, cholmod, "
                   "matrix-free"));
  EXPECT_CONTAINS(error_for("linear_tolerance: 1\n"), ("linear_tolerance = 1: must be in (0, 1)"));
  EXPECT_CONTAINS(error_for("linear_tolerance: 0\n"), ("linear_tolerance = 0: must be in (0, 1)"));
  EXPECT_CONTAINS(error_for("linear_max_iterations: 0\n"), ("linear_max_iterations = 0: must be at least 1"));
  LinearSolverChoice choice;
  EXPECT_CONTAINS(input_error_of([&] { override_linear_solver_kind(choice, "pcg", offered, "--solver"); }),
                  ("--solver pcg: linear solver 'pcg' is unknown here"));
  override_linear_solver_kind(choice, "multigrid", offered, "--solver");
  EXPECT_EQ(choice.kind, "matrix-free");
  EXPECT_EQ(choice.kind_key, "--solver");
}

TEST(MaterialConfig, OneReaderForElasticConstantsAndDensity) {
  const Config c = Config::from_string(
      "materials:\n  - {E: 2.0e6, nu: 0.7, density: 1200}\n  - {E: 0, nu: 0.3}\n  - {nu: 0.2}\n", "m.yaml");
  const auto m = c.children("materials");
  EXPECT_CONTAINS(input_error_of([&] { read_elastic_constants(m[0]); }),
                  ("m.yaml: materials[0].nu = 0.7: Poisson's ratio must be in (-1, 0.5)"));
  const ElasticConstants in_plane = read_elastic_constants(m[0], PoissonRange::InPlane);
  EXPECT_EQ(in_plane.E, 2e6);
  EXPECT_EQ(in_plane.nu, 0.7);
  EXPECT_EQ(read_density(m[0]), 1200);
  EXPECT_CONTAINS(input_error_of([&] { read_elastic_constants(m[1]); }),
                  ("materials[1].E = 0: Young's modulus must be positive"));
  EXPECT_CONTAINS(input_error_of([&] { read_density(m[1]); }), ("missing required key 'materials[1].density'"));
  EXPECT_EQ(read_density(m[1], 1000.0), 1000);
  const ElasticConstants fallback = read_elastic_constants(m[2], PoissonRange::Solid, ElasticConstants{1.0, 0.3});
  EXPECT_EQ(fallback.E, 1.0);
  EXPECT_EQ(fallback.nu, 0.2);
}

}  // namespace
}  // namespace msfab
