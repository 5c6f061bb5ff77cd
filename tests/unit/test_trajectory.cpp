// The msfab.trajectory artifact: exact round trip, XDMF sidecar, plots,
// atomic failure and schema checks.
#include <gtest/gtest.h>
#include <unistd.h>

#include <atomic>
#include <cmath>
#include <cstdint>
#include <cstdlib>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <iterator>
#include <limits>
#include <string>
#include <vector>

#include "core/errors.hpp"
#include "dynamics/trajectory.hpp"
#include "io/artifact.hpp"
#include "io/hdf5_file.hpp"
#include "io/xdmf.hpp"

namespace msfab {
namespace {

namespace fs = std::filesystem;

class TrajectoryArtifact : public ::testing::Test {
 protected:
  void SetUp() override {
    static std::atomic<int> counter{0};
    dir_ = fs::temp_directory_path() /
           ("msfab_trajectory_" + std::to_string(::getpid()) + "_" + std::to_string(counter++));
    fs::create_directories(dir_);
  }
  void TearDown() override {
    std::error_code ignored;
    fs::remove_all(dir_, ignored);
  }
  std::string file(const std::string& name) const { return (dir_ / name).string(); }

  fs::path dir_;
};

std::uint64_t bits(double v) {
  std::uint64_t b;
  std::memcpy(&b, &v, sizeof b);
  return b;
}

std::string read_text(const std::string& path) {
  std::ifstream in(path, std::ios::binary);
  return std::string(std::istreambuf_iterator<char>(in), std::istreambuf_iterator<char>());
}

std::size_t trajectory_count_of(const std::string& text, const std::string& what) {
  std::size_t n = 0;
  for (auto at = text.find(what); at != std::string::npos; at = text.find(what, at + 1)) ++n;
  return n;
}

// Two hexahedra side by side along x (3 x 2 x 2 nodes), toolkit numbering
// node = 4x + 2y + z within each element; 5 samples through all three
// phases, 3 frames and 2 events. The numbers are deliberately awkward
// (irrational, tiny, negative zero, NaN) so a lossy path would show.
Trajectory synthetic_trajectory() {
  Trajectory t;
  t.scene = "drop-test";
  t.impact_model = "dmv";
  t.time_step = 1.0 / 3000.0;
  t.rest_nodes.resize(12, 3);
  for (int i = 0; i < 3; ++i)
    for (int j = 0; j < 2; ++j)
      for (int k = 0; k < 2; ++k) t.rest_nodes.row(4 * i + 2 * j + k) << 0.01 * i / 3.0, 0.01 * j, 0.1 + 0.01 * k;
  for (int e = 0; e < 2; ++e) {
    std::array<int, 8> el;
    for (int c = 0; c < 8; ++c) el[c] = 4 * (e + (c >> 2 & 1)) + 2 * (c >> 1 & 1) + (c & 1);
    t.elements.push_back(el);
  }
  t.element_tag = {0, 1};
  t.material_names = {"stiff", "soft"};

  const SimulationPhase phases[5] = {SimulationPhase::kQuasistatic, SimulationPhase::kElastic,
                                     SimulationPhase::kElastic, SimulationPhase::kRigid, SimulationPhase::kRigid};
  for (int i = 0; i < 5; ++i) {
    TrajectorySample s;
    s.time = i * t.time_step;
    s.phase = phases[i];
    s.kinetic = 0.5 * std::sqrt(2.0 + i);
    s.elastic = i == 2 ? std::numeric_limits<double>::denorm_min() : 1e-300 * i;
    s.gravity = -9.81 * std::sin(0.3 * i);
    s.center_of_mass = Vec3(0.005, 0.005, 0.105 - 1e-3 * i * i / 7.0);
    s.com_velocity = Vec3(-0.0, 1e-17 * i, -std::cbrt(3.0 + i));
    s.rotation = Vec3(std::atan(0.1 * i), 0, -1.0 / (7 + i));
    s.contacts = 4 - i;
    s.active_contacts = i % 3;
    s.newton_iterations = 2 * i + 1;
    s.max_penetration = 1e-6 / (1 + i);
    s.seconds = 0.001 * std::exp(-double(i));
    t.samples.push_back(s);
  }
  for (int k = 0; k < 3; ++k) {
    TrajectoryFrame f;
    f.time = 2 * k * t.time_step;
    f.positions.resize(36);
    f.velocities.resize(36);
    for (int d = 0; d < 36; ++d) {
      // Frame 2 is squashed almost onto the origin, where rest + (x - rest)
      // no longer rounds back to x.
      const double rest = t.rest_nodes(d / 3, d % 3);
      f.positions[d] = k == 2 ? 1e-9 * rest + 1e-19 * d : rest + 1e-4 * std::sin(d + k);
      f.velocities[d] = std::cos(0.7 * d * (k + 1)) / 3.0;
    }
    t.frames.push_back(f);
  }
  t.events = {{t.time_step, "contact", "4 nodes, max penetration 1e-6 m"},
              {3 * t.time_step, "rigid", "line one\nline two, with a \\ backslash"}};
  Obstacle ground;
  ground.name = "floor";
  ground.ground_z = -1.0 / 3.0;
  ground.surface = "table";
  Obstacle wall;
  wall.kind = Obstacle::Kind::kBox;
  wall.name = "wall, tall";
  wall.lo = Vec3(0.02, -0.05, 0);
  wall.hi = Vec3(0.02 + 1.0 / 7.0, 0.05, std::sqrt(2e-4));
  t.obstacles = {ground, wall};
  t.seconds_quasistatic = 0.125 / 3;
  t.seconds_elastic = std::sqrt(0.5);
  t.seconds_rigid = 1e-5 / 7;
  t.seconds_total = t.seconds_quasistatic + t.seconds_elastic + t.seconds_rigid;
  return t;
}

#define EXPECT_SAME_DOUBLE(a, b) EXPECT_EQ(bits(a), bits(b)) << #a << " = " << (a) << " vs " << (b)

void expect_same_vec3(const Vec3& a, const Vec3& b) {
  for (int c = 0; c < 3; ++c) EXPECT_SAME_DOUBLE(a[c], b[c]);
}

void expect_identical(const Trajectory& a, const Trajectory& b) {
  EXPECT_EQ(a.scene, b.scene);
  EXPECT_EQ(a.impact_model, b.impact_model);
  EXPECT_SAME_DOUBLE(a.time_step, b.time_step);
  ASSERT_EQ(a.rest_nodes.rows(), b.rest_nodes.rows());
  for (Eigen::Index i = 0; i < a.rest_nodes.size(); ++i)
    EXPECT_SAME_DOUBLE(a.rest_nodes.data()[i], b.rest_nodes.data()[i]);
  EXPECT_EQ(a.elements, b.elements);
  EXPECT_EQ(a.element_tag, b.element_tag);
  EXPECT_EQ(a.material_names, b.material_names);
  ASSERT_EQ(a.samples.size(), b.samples.size());
  for (std::size_t i = 0; i < a.samples.size(); ++i) {
    const TrajectorySample &x = a.samples[i], &y = b.samples[i];
    EXPECT_SAME_DOUBLE(x.time, y.time);
    EXPECT_EQ(x.phase, y.phase);
    EXPECT_SAME_DOUBLE(x.kinetic, y.kinetic);
    EXPECT_SAME_DOUBLE(x.elastic, y.elastic);
    EXPECT_SAME_DOUBLE(x.gravity, y.gravity);
    expect_same_vec3(x.center_of_mass, y.center_of_mass);
    expect_same_vec3(x.com_velocity, y.com_velocity);
    expect_same_vec3(x.rotation, y.rotation);
    EXPECT_EQ(x.contacts, y.contacts);
    EXPECT_EQ(x.active_contacts, y.active_contacts);
    EXPECT_EQ(x.newton_iterations, y.newton_iterations);
    EXPECT_SAME_DOUBLE(x.max_penetration, y.max_penetration);
    EXPECT_SAME_DOUBLE(x.seconds, y.seconds);
  }
  ASSERT_EQ(a.frames.size(), b.frames.size());
  for (std::size_t k = 0; k < a.frames.size(); ++k) {
    EXPECT_SAME_DOUBLE(a.frames[k].time, b.frames[k].time);
    ASSERT_EQ(a.frames[k].positions.size(), b.frames[k].positions.size());
    ASSERT_EQ(a.frames[k].velocities.size(), b.frames[k].velocities.size());
    for (Eigen::Index d = 0; d < a.frames[k].positions.size(); ++d) {
      EXPECT_SAME_DOUBLE(a.frames[k].positions[d], b.frames[k].positions[d]);
      EXPECT_SAME_DOUBLE(a.frames[k].velocities[d], b.frames[k].velocities[d]);
    }
  }
  ASSERT_EQ(a.events.size(), b.events.size());
  for (std::size_t i = 0; i < a.events.size(); ++i) {
    EXPECT_SAME_DOUBLE(a.events[i].time, b.events[i].time);
    EXPECT_EQ(a.events[i].kind, b.events[i].kind);
    EXPECT_EQ(a.events[i].detail, b.events[i].detail);
  }
  ASSERT_EQ(a.obstacles.size(), b.obstacles.size());
  for (std::size_t i = 0; i < a.obstacles.size(); ++i) {
    const Obstacle &x = a.obstacles[i], &y = b.obstacles[i];
    EXPECT_EQ(x.kind, y.kind);
    EXPECT_EQ(x.name, y.name);
    EXPECT_EQ(x.surface, y.surface);
    EXPECT_SAME_DOUBLE(x.ground_z, y.ground_z);
    expect_same_vec3(x.lo, y.lo);
    expect_same_vec3(x.hi, y.hi);
  }
  EXPECT_SAME_DOUBLE(a.seconds_quasistatic, b.seconds_quasistatic);
  EXPECT_SAME_DOUBLE(a.seconds_elastic, b.seconds_elastic);
  EXPECT_SAME_DOUBLE(a.seconds_rigid, b.seconds_rigid);
  EXPECT_SAME_DOUBLE(a.seconds_total, b.seconds_total);
  EXPECT_EQ(a.coarsening.level, b.coarsening.level);
  EXPECT_EQ(a.coarsening.material, b.coarsening.material);
  EXPECT_EQ(a.coarsening.database, b.coarsening.database);
  EXPECT_EQ(a.coarsening.element, b.coarsening.element);
  EXPECT_EQ(a.coarsening.fallback, b.coarsening.fallback);
  EXPECT_EQ(a.coarsening.fallback_blocks, b.coarsening.fallback_blocks);
  EXPECT_SAME_DOUBLE(a.coarsening.check_tolerance, b.coarsening.check_tolerance);
  EXPECT_EQ(a.coarsening.checked_blocks, b.coarsening.checked_blocks);
  EXPECT_EQ(a.coarsening.replaced_blocks, b.coarsening.replaced_blocks);
  EXPECT_EQ(a.coarsening.window, b.coarsening.window);
  EXPECT_EQ(a.coarsening.unresolved_windows, b.coarsening.unresolved_windows);
  EXPECT_EQ(a.coarsening.fine_elements, b.coarsening.fine_elements);
  EXPECT_SAME_DOUBLE(a.coarsening.seconds, b.coarsening.seconds);
  EXPECT_EQ(a.comparison.reference, b.comparison.reference);
  EXPECT_SAME_DOUBLE(a.comparison.error_at_release, b.comparison.error_at_release);
  EXPECT_SAME_DOUBLE(a.comparison.error_max, b.comparison.error_max);
  EXPECT_SAME_DOUBLE(a.comparison.error_mean, b.comparison.error_mean);
  EXPECT_SAME_DOUBLE(a.comparison.error_final, b.comparison.error_final);
  EXPECT_SAME_DOUBLE(a.comparison.max_center_of_mass_distance, b.comparison.max_center_of_mass_distance);
  EXPECT_SAME_DOUBLE(a.comparison.fine_seconds_per_step, b.comparison.fine_seconds_per_step);
  EXPECT_SAME_DOUBLE(a.comparison.seconds_per_step, b.comparison.seconds_per_step);
}

template <class F>
std::string trajectory_input_error_message(F&& action) {
  try {
    action();
  } catch (const InputError& e) {
    return e.what();
  }
  ADD_FAILURE() << "no InputError";
  return {};
}

TEST_F(TrajectoryArtifact, RoundTripIsBitwiseExact) {
  const Trajectory t = synthetic_trajectory();
  // The stored positions must not be rebuilt from the displacement: in
  // frame 2 that loses bits, which this test would then catch.
  bool lossy = false;
  for (Eigen::Index d = 0; d < 36; ++d) {
    const double rest = t.rest_nodes(d / 3, d % 3), x = t.frames[2].positions[d];
    lossy = lossy || rest + (x - rest) != x;
  }
  ASSERT_TRUE(lossy) << "frame 2 should exercise positions that displacement cannot reproduce";

  const std::string config_file = file("dynamics.yaml");
  std::ofstream(config_file) << "scene: drop-test\n";
  TrajectoryProvenance provenance;
  provenance.config_text = "scene: drop-test\n";
  provenance.inputs = {config_file};
  provenance.seed = 42;
  const std::string path = file("run.h5");
  const std::string xmf = write_trajectory_artifact(path, t, provenance);
  EXPECT_EQ(xmf, file("run.xmf"));
  for (const auto& entry : fs::directory_iterator(dir_)) EXPECT_NE(entry.path().extension(), ".tmp") << entry.path();

  expect_identical(t, read_trajectory_artifact(path));

  const ArtifactReader in(path, "msfab.trajectory", 1);
  EXPECT_EQ(in.config(), provenance.config_text);
  EXPECT_EQ(in.seed(), 42u);
  ASSERT_EQ(in.inputs().size(), 1u);
  EXPECT_EQ(in.inputs()[0].path, config_file);
  EXPECT_EQ(in.producer().rfind("msfab-dynamics ", 0), 0u) << in.producer();
  // The displacement the sidecar shows is positions - rest.
  const MatX u = in.file().read_matrix<double>("/frames/000001/displacement", 3);
  for (Eigen::Index d = 0; d < 36; ++d)
    EXPECT_EQ(u(d / 3, d % 3), t.frames[1].positions[d] - t.rest_nodes(d / 3, d % 3));
  EXPECT_EQ(in.file().read_string_attribute("/samples/total", "units"), "J");
  const std::vector<double> total = in.file().read_vector<double>("/samples/total");
  EXPECT_EQ(total[1], t.samples[1].total());
  const MatX conn_vtk = in.file().read_matrix<double>("/mesh/elements_vtk", 8);
  EXPECT_EQ(conn_vtk(1, 1), t.elements[1][kToolkitNodeAtVtkCorner[1]]);
}

TEST_F(TrajectoryArtifact, CoarseningAndComparisonRoundTrip) {
  Trajectory t = synthetic_trajectory();
  t.coarsening = {1, "ddfem", "db/palette3.coarse_db.h5", "enhanced", "galerkin", 3, 0.1, 40, 12, 2, 1, 12800, 0.0123};
  t.comparison = {"fine.h5", 1.5e-3, 2.25e-2, 1.0e-2, 2.0e-2, 1.7e-3, 3.5, 0.18};
  const std::string path = file("coarse.h5");
  write_trajectory_artifact(path, t, {});
  expect_identical(t, read_trajectory_artifact(path));
  const ArtifactReader in(path, "msfab.trajectory", 1);
  EXPECT_NE(in.file().read_string_attribute("/comparison", "error_definition").find("2.5.2"), std::string::npos);
  // A fine run without a reference stores neither group.
  const std::string fine = file("fine.h5");
  write_trajectory_artifact(fine, synthetic_trajectory(), {});
  const ArtifactReader plain(fine, "msfab.trajectory", 1);
  EXPECT_FALSE(plain.file().exists("/coarsening"));
  EXPECT_FALSE(plain.file().exists("/comparison"));
}

TEST_F(TrajectoryArtifact, EmptyTrajectoryRoundTrips) {
  Trajectory t = synthetic_trajectory();
  t.samples.clear();
  t.frames.clear();
  t.events.clear();
  t.material_names.clear();
  t.obstacles.clear();
  const std::string path = file("empty.h5");
  const std::string xmf = write_trajectory_artifact(path, t, {});
  expect_identical(t, read_trajectory_artifact(path));
  // Without frames the sidecar shows the rest mesh.
  const std::string text = read_text(xmf);
  EXPECT_EQ(trajectory_count_of(text, "<Grid "), 1u);
  EXPECT_NE(text.find("empty.h5:/mesh/nodes"), std::string::npos);
  // One event with empty texts must not read back as none.
  t.events = {{0.5, "", ""}};
  const std::string one = file("one_event.h5");
  write_trajectory_artifact(one, t, {});
  expect_identical(t, read_trajectory_artifact(one));
}

TEST_F(TrajectoryArtifact, SidecarNamesEveryFrame) {
  const Trajectory t = synthetic_trajectory();
  const std::string xmf = write_trajectory_artifact(file("run.h5"), t, {});
  ASSERT_TRUE(fs::exists(xmf));
  const std::string text = read_text(xmf);
  EXPECT_EQ(trajectory_count_of(text, "<Time Value="), 3u);
  EXPECT_NE(text.find("CollectionType=\"Temporal\""), std::string::npos);
  for (const char* frame : {"000000", "000001", "000002"}) {
    EXPECT_NE(text.find(std::string("run.h5:/frames/") + frame + "/displacement"), std::string::npos) << frame;
    EXPECT_NE(text.find(std::string("run.h5:/frames/") + frame + "/velocity"), std::string::npos) << frame;
  }
  EXPECT_EQ(trajectory_count_of(text, "run.h5:/mesh/elements_vtk"), 3u);
  // Frame times are written so that they read back exactly.
  std::vector<double> times;
  const std::string tag = "<Time Value=\"";
  for (auto at = text.find(tag); at != std::string::npos; at = text.find(tag, at + 1))
    times.push_back(std::strtod(text.c_str() + at + tag.size(), nullptr));
  ASSERT_EQ(times.size(), 3u);
  for (std::size_t k = 0; k < 3; ++k) EXPECT_SAME_DOUBLE(times[k], t.frames[k].time);
}

TEST_F(TrajectoryArtifact, MissingFolderIsInputErrorAndLeavesNothing) {
  const fs::path folder = dir_ / "missing";
  const std::string path = (folder / "run.h5").string();
  const std::string message =
      trajectory_input_error_message([&] { write_trajectory_artifact(path, synthetic_trajectory(), {}); });
  EXPECT_NE(message.find(folder.string()), std::string::npos) << message;
  EXPECT_FALSE(fs::exists(folder));
  EXPECT_TRUE(fs::is_empty(dir_));
}

TEST_F(TrajectoryArtifact, WrongSchemaIsInputError) {
  const std::string path = file("result.h5");
  {
    ArtifactWriter out(path, "msfab.result", 1, "msfab-simulate", "", {}, 0);
    out.file().write_attribute("/", "scene", "drop-test");
    out.commit();
  }
  const std::string message = trajectory_input_error_message([&] { read_trajectory_artifact(path); });
  EXPECT_NE(message.find(path), std::string::npos) << message;
  EXPECT_NE(message.find("msfab.trajectory"), std::string::npos) << message;
  EXPECT_NE(message.find("msfab.result"), std::string::npos) << message;
}

TEST_F(TrajectoryArtifact, DamagedFileNamesFileAndDataset) {
  const std::string path = file("run.h5");
  write_trajectory_artifact(path, synthetic_trajectory(), {});
  {
    H5File f = H5File::open(path, H5File::Mode::kReadWrite);
    ASSERT_GE(H5Ldelete(f.id(), "/frames/000001/velocity", H5P_DEFAULT), 0);
  }
  std::string message = trajectory_input_error_message([&] { read_trajectory_artifact(path); });
  EXPECT_NE(message.find(path), std::string::npos) << message;
  EXPECT_NE(message.find("/frames/000001/velocity"), std::string::npos) << message;

  write_trajectory_artifact(path, synthetic_trajectory(), {});
  {
    H5File f = H5File::open(path, H5File::Mode::kReadWrite);
    ASSERT_GE(H5Ldelete(f.id(), "/samples/kinetic", H5P_DEFAULT), 0);
    f.write_vector("/samples/kinetic", std::vector<double>{1, 2, 3, 4});
  }
  message = trajectory_input_error_message([&] { read_trajectory_artifact(path); });
  EXPECT_NE(message.find(path), std::string::npos) << message;
  EXPECT_NE(message.find("/samples/kinetic"), std::string::npos) << message;
  EXPECT_NE(message.find("expected 5"), std::string::npos) << message;

  write_trajectory_artifact(path, synthetic_trajectory(), {});
  {
    H5File f = H5File::open(path, H5File::Mode::kReadWrite);
    f.write_attribute("/events", "kind", "contact");  // two events, one line
  }
  message = trajectory_input_error_message([&] { read_trajectory_artifact(path); });
  EXPECT_NE(message.find("'kind'"), std::string::npos) << message;
  EXPECT_NE(message.find("/events"), std::string::npos) << message;

  write_trajectory_artifact(path, synthetic_trajectory(), {});
  {
    H5File f = H5File::open(path, H5File::Mode::kReadWrite);
    f.write_attribute("/obstacles", "kind", "ground\ncone");
  }
  message = trajectory_input_error_message([&] { read_trajectory_artifact(path); });
  EXPECT_NE(message.find(path), std::string::npos) << message;
  EXPECT_NE(message.find("'cone' is neither ground nor box"), std::string::npos) << message;
}

}  // namespace
}  // namespace msfab
