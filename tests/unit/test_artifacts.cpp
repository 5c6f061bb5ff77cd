// HDF5 wrapper, artifact provenance/atomicity, SHA-256 and XDMF sidecars.
#include <gtest/gtest.h>
#include <unistd.h>

#include <Eigen/Geometry>
#include <atomic>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <regex>
#include <sstream>
#include <stdexcept>
#include <string>
#include <vector>

#include "core/errors.hpp"
#include "core/version.hpp"
#include "io/artifact.hpp"
#include "io/atomic_file.hpp"
#include "io/checkpoint_file.hpp"
#include "io/commit_group.hpp"
#include "io/hdf5_file.hpp"
#include "io/path_names.hpp"
#include "io/sha256.hpp"
#include "io/xdmf.hpp"

namespace msfab {
namespace {

namespace fs = std::filesystem;

// A fresh folder per test, removed afterwards.
class ScratchDir : public ::testing::Test {
 protected:
  void SetUp() override {
    static std::atomic<int> counter{0};
    dir_ =
        fs::temp_directory_path() / ("msfab_artifacts_" + std::to_string(::getpid()) + "_" + std::to_string(counter++));
    fs::create_directories(dir_);
  }
  void TearDown() override {
    std::error_code ignored;
    fs::remove_all(dir_, ignored);
  }
  std::string file(const std::string& name) const { return (dir_ / name).string(); }
  // Names of the temporaries ("*.tmp") left in the folder.
  std::vector<std::string> temporaries() const {
    std::vector<std::string> names;
    for (const auto& entry : fs::directory_iterator(dir_))
      if (entry.path().extension() == ".tmp") names.push_back(entry.path().filename().string());
    return names;
  }

  fs::path dir_;
};

std::string read_bytes(const std::string& path) {
  std::ifstream in(path, std::ios::binary);
  std::ostringstream text;
  text << in.rdbuf();
  return text.str();
}

void write_bytes(const std::string& path, const std::string& bytes) {
  std::ofstream out(path, std::ios::binary);
  out << bytes;
}

template <class F>
std::string input_error_message(F&& action) {
  try {
    action();
  } catch (const InputError& e) {
    return e.what();
  }
  ADD_FAILURE() << "expected an InputError";
  return "";
}

// ---------------------------------------------------------------------------
// H5File

using ArtifactH5File = ScratchDir;

TEST_F(ArtifactH5File, RoundTripsEveryDtypeAndRank) {
  const std::string path = file("types.h5");
  std::vector<double> cube(2 * 3 * 4);
  for (std::size_t i = 0; i < cube.size(); ++i) cube[i] = 0.5 * double(i) - 3.25;
  const std::vector<std::int32_t> ints = {-7, 0, 2147483647, -2147483647 - 1, 5, 6};
  const std::vector<std::int64_t> longs = {std::int64_t(1) << 53, -1, 42};
  std::vector<std::uint8_t> bytes(2 * 2 * 2 * 3);
  for (std::size_t i = 0; i < bytes.size(); ++i) bytes[i] = std::uint8_t(250 + i);  // wraps
  const std::vector<std::uint64_t> seeds = {~std::uint64_t(0), 0};
  const double scalar = 6.02214076e23;
  {
    H5File out = H5File::create(path);
    out.write_dataset("/scalar", &scalar, {});
    out.write_dataset("/f64/rank3", cube, {2, 3, 4});
    out.write_dataset("/i32/rank2", ints, {3, 2});
    out.write_vector("/i64/rank1", longs);
    out.write_dataset("/u8/rank4", bytes, {2, 2, 2, 3});
    out.write_vector("/u64", seeds);
    out.write_dataset("/empty", std::vector<double>{}, {0, 3});
    out.close();
  }
  const H5File in = H5File::open(path);
  const NdArray<double> s = in.read_dataset<double>("/scalar");
  EXPECT_TRUE(s.shape.empty());
  ASSERT_EQ(s.values.size(), 1u);
  EXPECT_EQ(s.values[0], scalar);

  const NdArray<double> c = in.read_dataset<double>("/f64/rank3");
  EXPECT_EQ(c.shape, (std::vector<hsize_t>{2, 3, 4}));
  EXPECT_EQ(c.values, cube);

  const NdArray<std::int32_t> i = in.read_dataset<std::int32_t>("/i32/rank2");
  EXPECT_EQ(i.shape, (std::vector<hsize_t>{3, 2}));
  EXPECT_EQ(i.values, ints);

  EXPECT_EQ(in.read_vector<std::int64_t>("/i64/rank1"), longs);

  const NdArray<std::uint8_t> b = in.read_dataset<std::uint8_t>("/u8/rank4");
  EXPECT_EQ(b.shape, (std::vector<hsize_t>{2, 2, 2, 3}));
  EXPECT_EQ(b.values, bytes);

  EXPECT_EQ(in.read_vector<std::uint64_t>("/u64"), seeds);
  EXPECT_EQ(in.dataset_shape("/empty"), (std::vector<hsize_t>{0, 3}));
  EXPECT_EQ(in.read_matrix<double>("/empty", 3).rows(), 0);
}

TEST_F(ArtifactH5File, EigenMatricesAreRowMajorOnDisk) {
  const std::string path = file("matrix.h5");
  Eigen::MatrixXd m(2, 3);
  m << 1, 2, 3, 4, 5, 6;
  Eigen::MatrixXi conn(1, 2);
  conn << 7, 9;
  Eigen::VectorXd v(3);
  v << 0.1, 0.2, 0.3;
  {
    H5File out = H5File::create(path);
    out.write_matrix("/m", m);
    out.write_matrix("/m_transposed", m.transpose());
    out.write_matrix("/conn", conn);
    out.write_vector("/v", v);
  }
  const H5File in = H5File::open(path);
  const NdArray<double> raw = in.read_dataset<double>("/m");
  EXPECT_EQ(raw.shape, (std::vector<hsize_t>{2, 3}));
  EXPECT_EQ(raw.values, (std::vector<double>{1, 2, 3, 4, 5, 6}));
  EXPECT_EQ(in.read_matrix<double>("/m"), m);
  EXPECT_EQ(in.read_dataset<double>("/m_transposed").values, (std::vector<double>{1, 4, 2, 5, 3, 6}));
  EXPECT_EQ(in.read_matrix<std::int32_t>("/conn", 2), conn);
  EXPECT_EQ(in.read_vector<double>("/v"), (std::vector<double>{0.1, 0.2, 0.3}));

  const std::string wrong_cols = input_error_message([&] { in.read_matrix<double>("/m", 4); });
  EXPECT_NE(wrong_cols.find("(2, 3)"), std::string::npos) << wrong_cols;
  EXPECT_NE(wrong_cols.find("4 columns"), std::string::npos) << wrong_cols;
  const std::string wrong_rank = input_error_message([&] { in.read_vector<double>("/m"); });
  EXPECT_NE(wrong_rank.find("rank 1"), std::string::npos) << wrong_rank;
}

TEST_F(ArtifactH5File, GzipRoundTripIsChunkedAndSmaller) {
  const std::size_t rows = 40000;
  std::vector<double> smooth(rows * 3);
  for (std::size_t k = 0; k < smooth.size(); ++k) smooth[k] = std::floor(double(k) / 1000.0);
  const std::string plain = file("plain.h5");
  const std::string packed = file("packed.h5");
  {
    H5File out = H5File::create(plain);
    out.write_dataset("/u", smooth, {rows, 3});
  }
  {
    H5File out = H5File::create(packed);
    H5WriteOptions options;
    options.gzip_level = 6;
    options.chunk_bytes = 64 * 1024;
    out.write_dataset("/u", smooth, {rows, 3}, options);
  }
  const H5File in = H5File::open(packed);
  EXPECT_EQ(in.read_dataset<double>("/u").values, smooth);

  H5Id dataset(H5Dopen2(in.id(), "/u", H5P_DEFAULT), H5Dclose);
  H5Id create(H5Dget_create_plist(dataset.get()), H5Pclose);
  ASSERT_EQ(H5Pget_layout(create.get()), H5D_CHUNKED);
  hsize_t chunk[2] = {0, 0};
  ASSERT_EQ(H5Pget_chunk(create.get(), 2, chunk), 2);
  EXPECT_EQ(chunk[1], 3u);                      // rows stay whole
  EXPECT_EQ(chunk[0], 64u * 1024 / 24);         // ~64 KiB per chunk
  EXPECT_GE(H5Pget_nfilters(create.get()), 2);  // shuffle + deflate
  EXPECT_LT(fs::file_size(packed) * 10, fs::file_size(plain));
}

TEST_F(ArtifactH5File, AttributesOnRootGroupsAndDatasets) {
  const std::string path = file("attrs.h5");
  const std::string long_text(100000, 'x');  // beyond the 64 KiB header limit
  {
    H5File out = H5File::create(path);
    out.write_vector("/mesh/nodes", std::vector<double>{0.0, 1.0});
    out.write_attribute("/mesh/nodes", "units", "m");
    out.write_attribute("/mesh", "spacing", std::vector<double>{0.5, 0.25, 0.125});
    out.write_attribute("/", "count", std::int32_t(12));
    out.write_attribute("/", "big", std::int64_t(1) << 40);
    out.write_attribute("/", "young", 2.1e11);
    out.write_attribute("/", "notes", long_text);
    out.write_attribute("/", "young", std::string("replaced by text"));
    // A fixed-length string, as other tools write them.
    H5Id type(H5Tcopy(H5T_C_S1), H5Tclose);
    H5Tset_size(type.get(), 8);
    H5Tset_strpad(type.get(), H5T_STR_NULLPAD);
    H5Id space(H5Screate(H5S_SCALAR), H5Sclose);
    H5Id attr(H5Acreate2(out.id(), "fixed", type.get(), space.get(), H5P_DEFAULT, H5P_DEFAULT), H5Aclose);
    const char fixed[8] = {'P', 'a', '\0', '\0', '\0', '\0', '\0', '\0'};
    H5Awrite(attr.get(), type.get(), fixed);
  }
  const H5File in = H5File::open(path);
  EXPECT_TRUE(in.is_group("/mesh"));
  EXPECT_TRUE(in.is_dataset("/mesh/nodes"));
  EXPECT_FALSE(in.is_group("/mesh/nodes"));
  EXPECT_FALSE(in.exists("/mesh/elements/connectivity"));
  EXPECT_EQ(in.children("/"), (std::vector<std::string>{"mesh"}));
  EXPECT_EQ(in.read_string_attribute("/mesh/nodes", "units"), "m");
  EXPECT_EQ(in.read_attribute_vector<double>("/mesh", "spacing"), (std::vector<double>{0.5, 0.25, 0.125}));
  EXPECT_EQ(in.read_attribute<std::int32_t>("/", "count"), 12);
  EXPECT_EQ(in.read_attribute<double>("/", "count"), 12.0);  // lossless widening
  EXPECT_EQ(in.read_attribute<std::int64_t>("/", "big"), std::int64_t(1) << 40);
  EXPECT_EQ(in.read_string_attribute("/", "young"), "replaced by text");
  EXPECT_EQ(in.read_string_attribute("/", "notes"), long_text);
  EXPECT_EQ(in.read_string_attribute("/", "fixed"), "Pa");
  EXPECT_TRUE(in.has_attribute("/mesh/nodes", "units"));
  EXPECT_FALSE(in.has_attribute("/mesh/nodes", "density"));
  EXPECT_FALSE(in.has_attribute("/nowhere", "units"));

  const std::string narrowing = input_error_message([&] { in.read_attribute<std::int32_t>("/", "big"); });
  EXPECT_NE(narrowing.find("int64"), std::string::npos) << narrowing;
  const std::string missing = input_error_message([&] { in.read_string_attribute("/mesh", "units"); });
  EXPECT_NE(missing.find(path), std::string::npos) << missing;
  EXPECT_NE(missing.find("'units'"), std::string::npos) << missing;
  const std::string not_text = input_error_message([&] { in.read_string_attribute("/", "count"); });
  EXPECT_NE(not_text.find("expected a string"), std::string::npos) << not_text;
}

TEST_F(ArtifactH5File, ReadErrorsNameFileAndDataset) {
  const std::string path = file("result.h5");
  {
    H5File out = H5File::create(path);
    out.write_vector("/stress", std::vector<double>{1.5, 2.5});
    EXPECT_THROW(out.write_vector("/stress", std::vector<double>{1.0}), std::runtime_error);
    EXPECT_THROW(out.write_dataset("/bad", std::vector<double>{1.0, 2.0}, {3}), std::runtime_error);
  }
  const H5File in = H5File::open(path);
  const std::string missing = input_error_message([&] { in.read_vector<double>("/displacement"); });
  EXPECT_EQ(missing, path + ": dataset '/displacement' not found");
  const std::string lossy = input_error_message([&] { in.read_vector<std::int32_t>("/stress"); });
  EXPECT_NE(lossy.find(path), std::string::npos) << lossy;
  EXPECT_NE(lossy.find("float64"), std::string::npos) << lossy;
  EXPECT_NE(lossy.find("int32"), std::string::npos) << lossy;
  const std::string absent = input_error_message([&] { H5File::open(file("absent.h5")); });
  EXPECT_EQ(absent, file("absent.h5") + ": no such file");
}

TEST_F(ArtifactH5File, NonFiniteValuesAreRefusedWhereTheyAreRead) {
  const std::string path = file("damaged.h5");
  {
    H5File out = H5File::create(path);
    out.write_vector("/fine", std::vector<double>{1.0, 2.0});
    out.write_vector("/reference", std::vector<double>{1.0, std::nan(""), 3.0});
    out.write_matrix("/field", Eigen::MatrixXd::Constant(2, 2, HUGE_VAL));
    out.write_vector("/missing", std::vector<double>{std::nan(""), 2.0});
    out.write_attribute("/", "scale", -HUGE_VAL);
    out.write_vector("/counts", std::vector<std::int32_t>{1, 2});
  }
  const H5File in = H5File::open(path);
  EXPECT_EQ(in.read_vector<double>("/fine").size(), 2u);
  EXPECT_EQ(input_error_message([&] { in.read_vector<double>("/reference"); }),
            path + ": dataset '/reference' holds NaN at index 1; the file is damaged or was not written by msfab");
  EXPECT_NE(input_error_message([&] { in.read_matrix<double>("/field"); }).find("'/field' holds an infinite value"),
            std::string::npos);
  EXPECT_NE(input_error_message([&] { in.read_dataset<double>("/reference"); }).find("index 1"), std::string::npos);
  EXPECT_NE(input_error_message([&] { in.read_slab<double>("/reference", {1}, {2}); }).find("index 0"),
            std::string::npos);
  EXPECT_NE(input_error_message([&] { in.read_attribute<double>("/", "scale"); }).find("attribute 'scale' on '/'"),
            std::string::npos);
  // NaN as "not computed" where a reader says so; infinity never.
  EXPECT_TRUE(std::isnan(in.read_vector<double>("/missing", Finite::nan_means_missing)[0]));
  EXPECT_THROW(in.read_matrix<double>("/field", -1, Finite::nan_means_missing), InputError);
  EXPECT_EQ(in.read_vector<std::int32_t>("/counts")[1], 2);
}

// ---------------------------------------------------------------------------
// ArtifactWriter / ArtifactReader

using ArtifactWriterTest = ScratchDir;
using ArtifactReaderTest = ScratchDir;

void write_small_artifact(const std::string& path, const std::string& schema, int version,
                          const std::vector<std::string>& inputs = {}) {
  ArtifactWriter out(path, schema, version, "msfab-test", "solver:\n  tol: 1e-8\n", inputs, 7);
  Eigen::MatrixXd u = Eigen::MatrixXd::Constant(2000, 3, 0.25);
  out.file().write_matrix("/displacement", u);
  out.file().write_attribute("/displacement", "units", "m");
  out.commit();
}

TEST_F(ArtifactWriterTest, RecordsProvenanceAsRootAttributes) {
  const std::string input = file("mesh.h5");
  write_bytes(input, "pretend mesh content");
  const std::string path = file("result.h5");
  const std::string config = "material: pla\nload: 10 N\n";
  {
    ArtifactWriter out(path, "msfab.result", 3, "msfab-simulate", config, {input}, 123456789012345ull);
    out.file().write_vector("/x", std::vector<double>{1.0});
    EXPECT_TRUE(fs::exists(out.tmp_path()));
    EXPECT_TRUE(std::regex_match(out.tmp_path(), std::regex(R"(.*/result\.h5\.[0-9a-f]{16}\.tmp)"))) << out.tmp_path();
    EXPECT_FALSE(fs::exists(path));
    out.commit();
    EXPECT_TRUE(out.committed());
  }
  EXPECT_TRUE(temporaries().empty());
  const ArtifactReader in(path, "msfab.result", 3);
  EXPECT_EQ(in.schema(), "msfab.result");
  EXPECT_EQ(in.schema_version(), 3);
  EXPECT_EQ(in.config(), config);
  EXPECT_EQ(in.seed(), 123456789012345ull);
  EXPECT_EQ(in.producer(), std::string("msfab-simulate ") + version() + " (git " + git_revision() + ")");
  EXPECT_TRUE(std::regex_match(in.created(), std::regex(R"(\d{4}-\d\d-\d\dT\d\d:\d\d:\d\dZ)"))) << in.created();
  const std::vector<ArtifactInput> inputs = in.inputs();
  ASSERT_EQ(inputs.size(), 1u);
  EXPECT_EQ(inputs[0].path, input);
  EXPECT_EQ(inputs[0].sha256, sha256_hex("pretend mesh content"));
  EXPECT_NE(in.file().read_string_attribute("/", "inputs").find(sha256_file_hex(input)), std::string::npos);
  EXPECT_EQ(in.file().read_vector<double>("/x"), std::vector<double>{1.0});
}

TEST_F(ArtifactWriterTest, ThrowBeforeCommitKeepsOldFileAndRemovesTmp) {
  const std::string path = file("result.h5");
  write_small_artifact(path, "msfab.result", 1);
  const std::string before = read_bytes(path);
  ASSERT_GT(before.size(), 1000u);
  try {
    ArtifactWriter out(path, "msfab.result", 1, "msfab-test", "new config", {}, 8);
    out.file().write_matrix("/displacement", Eigen::MatrixXd::Ones(4000, 3));
    out.file().flush();
    ASSERT_TRUE(fs::exists(out.tmp_path()));
    throw std::runtime_error("solver blew up");
  } catch (const std::runtime_error& e) {
    EXPECT_STREQ(e.what(), "solver blew up");
  }
  EXPECT_EQ(read_bytes(path), before);
  EXPECT_TRUE(temporaries().empty());
  EXPECT_EQ(ArtifactReader(path, "msfab.result", 1).config(), "solver:\n  tol: 1e-8\n");
}

TEST_F(ArtifactWriterTest, MissingInputOrFolderIsInputErrorAndCreatesNothing) {
  const std::string path = file("result.h5");
  const std::string missing_input = file("missing_mesh.h5");
  const std::string message =
      input_error_message([&] { ArtifactWriter out(path, "msfab.result", 1, "msfab-test", "", {missing_input}, 0); });
  EXPECT_EQ(message, missing_input + ": no such file");
  EXPECT_TRUE(temporaries().empty());
  const std::string nested = file("no/such/dir/result.h5");
  const std::string folder =
      input_error_message([&] { ArtifactWriter out(nested, "msfab.result", 1, "msfab-test", "", {}, 0); });
  EXPECT_NE(folder.find("does not exist"), std::string::npos) << folder;
}

// Temporaries cannot be hijacked: a symlink planted under the old fixed
// name "<path>.tmp" (or any name) is never followed, a symlink at the final
// path is replaced rather than written through, and two writers of the same
// output each get their own temporary.
TEST_F(ArtifactWriterTest, PlantedSymlinkAtTheTemporaryNameIsNotFollowed) {
  const std::string victim = file("victim.txt");
  write_bytes(victim, "must survive");
  const std::string path = file("result.h5");
  fs::create_symlink(victim, path + ".tmp");
  fs::create_symlink(victim, file("result.xmf.tmp"));
  write_small_artifact(path, "msfab.result", 1);
  write_hex_mesh_xdmf(file("result.xmf"), XdmfHexMesh{"result.h5", "/n", "/c", 1, 1}, {}, {});
  EXPECT_EQ(read_bytes(victim), "must survive");
  EXPECT_TRUE(fs::is_regular_file(fs::symlink_status(path)));
  EXPECT_TRUE(fs::is_regular_file(fs::symlink_status(file("result.xmf"))));
  EXPECT_EQ(ArtifactReader(path, "msfab.result", 1).seed(), 7u);
}

TEST_F(ArtifactWriterTest, SymlinkAtTheOutputIsReplacedNotWrittenThrough) {
  const std::string victim = file("victim.txt");
  write_bytes(victim, "must survive");
  const std::string path = file("result.h5");
  fs::create_symlink(victim, path);
  write_small_artifact(path, "msfab.result", 1);
  EXPECT_EQ(read_bytes(victim), "must survive");
  EXPECT_TRUE(fs::is_regular_file(fs::symlink_status(path)));
}

TEST_F(ArtifactWriterTest, TwoWritersOfOneOutputHaveTheirOwnTemporaries) {
  const std::string path = file("result.h5");
  ArtifactWriter first(path, "msfab.result", 1, "msfab-test", "first", {}, 1);
  ArtifactWriter second(path, "msfab.result", 1, "msfab-test", "second", {}, 2);
  EXPECT_NE(first.tmp_path(), second.tmp_path());
  first.file().write_vector("/x", std::vector<double>{1.0});
  second.file().write_vector("/x", std::vector<double>{2.0});
  first.commit();
  EXPECT_EQ(ArtifactReader(path, "msfab.result", 1).config(), "first");
  second.commit();
  const ArtifactReader in(path, "msfab.result", 1);
  EXPECT_EQ(in.config(), "second");
  EXPECT_EQ(in.file().read_vector<double>("/x"), std::vector<double>{2.0});
  EXPECT_TRUE(temporaries().empty());
}

TEST_F(ArtifactWriterTest, OutputThatIsAnInputOrAFolderIsInputErrorAndTouchesNothing) {
  const std::string input = file("mesh.h5");
  write_bytes(input, "the only copy");
  const std::string same =
      input_error_message([&] { ArtifactWriter out(input, "msfab.result", 1, "msfab-test", "", {input}, 0); });
  EXPECT_NE(same.find("also an input"), std::string::npos) << same;
  const std::string link = file("link.h5");
  fs::create_symlink(input, link);
  input_error_message([&] { ArtifactWriter out(link, "msfab.result", 1, "msfab-test", "", {input}, 0); });
  EXPECT_EQ(read_bytes(input), "the only copy");
  fs::create_directory(file("folder.h5"));
  const std::string folder =
      input_error_message([&] { ArtifactWriter out(file("folder.h5"), "msfab.result", 1, "msfab-test", "", {}, 0); });
  EXPECT_NE(folder.find("is a folder"), std::string::npos) << folder;
  EXPECT_TRUE(temporaries().empty());
}

TEST_F(ArtifactWriterTest, AtomicFileWritesPatchesAndCommitsWhole) {
  const std::string path = file("table.csv");
  write_bytes(path, "old");
  {
    AtomicFile out(path);
    out.write("xx,b\n");
    out.write_at(0, "a", 1);
    out.write_at(1, ",", 1);
    EXPECT_EQ(read_bytes(path), "old");
  }  // destroyed without commit: nothing changes
  EXPECT_EQ(read_bytes(path), "old");
  EXPECT_TRUE(temporaries().empty());
  AtomicFile out(path);
  out.write("xx,b\n");
  out.write_at(0, "a", 1);
  out.commit();
  EXPECT_EQ(read_bytes(path), "ax,b\n");
  EXPECT_TRUE(temporaries().empty());
}

TEST_F(ArtifactWriterTest, ReadOnlyFolderIsInputError) {
  // Root writes into folders without write permission; sysfs refuses new
  // files to everyone (EACCES, or EROFS where it is mounted read-only).
  const bool root = ::geteuid() == 0;
  if (root && !fs::is_directory("/sys")) GTEST_SKIP() << "root writes into read-only folders and there is no /sys";
  const std::string folder = root ? std::string("/sys") : file("locked");
  if (!root) {
    fs::create_directory(folder);
    fs::permissions(folder, fs::perms::owner_read | fs::perms::owner_exec);
  }
  const std::string message = input_error_message([&] { AtomicFile out(folder + "/x.h5"); });
  EXPECT_NE(message.find("not writable"), std::string::npos) << message;
  if (!root) fs::permissions(folder, fs::perms::owner_all);
}

TEST_F(ArtifactReaderTest, SchemaMismatchNamesFileExpectedAndFound) {
  const std::string path = file("db.h5");
  write_small_artifact(path, "msfab.coarse_db", 1);
  const std::string message = input_error_message([&] { ArtifactReader in(path, "msfab.result", 1); });
  EXPECT_NE(message.find(path), std::string::npos) << message;
  EXPECT_NE(message.find("expected schema 'msfab.result' version 1"), std::string::npos) << message;
  EXPECT_NE(message.find("found schema 'msfab.coarse_db' version 1"), std::string::npos) << message;
}

TEST_F(ArtifactReaderTest, VersionMismatchNamesFileExpectedAndFound) {
  const std::string path = file("result_v4.h5");
  write_small_artifact(path, "msfab.result", 4);
  const std::string message = input_error_message([&] { ArtifactReader in(path, "msfab.result", 1, 3); });
  EXPECT_NE(message.find(path), std::string::npos) << message;
  EXPECT_NE(message.find("version 1 to 3"), std::string::npos) << message;
  EXPECT_NE(message.find("found schema 'msfab.result' version 4"), std::string::npos) << message;
  EXPECT_EQ(ArtifactReader(path, "msfab.result", 2, 4).schema_version(), 4);
}

TEST_F(ArtifactReaderTest, TruncatedFileIsInputError) {
  const std::string path = file("truncated.h5");
  write_small_artifact(path, "msfab.result", 1);
  fs::resize_file(path, fs::file_size(path) / 2);
  const std::string message = input_error_message([&] { ArtifactReader in(path, "msfab.result", 1); });
  EXPECT_NE(message.find(path), std::string::npos) << message;
  EXPECT_NE(message.find("truncated or corrupt"), std::string::npos) << message;
}

TEST_F(ArtifactReaderTest, NonHdf5AndForeignFilesAreInputErrors) {
  const std::string text = file("notes.h5");
  write_bytes(text, "this is a yaml file, not hdf5\n");
  const std::string garbage = input_error_message([&] { ArtifactReader in(text, "msfab.result", 1); });
  EXPECT_NE(garbage.find(text), std::string::npos) << garbage;
  EXPECT_NE(garbage.find("not a valid HDF5 file"), std::string::npos) << garbage;

  const std::string missing = input_error_message([&] { ArtifactReader in(file("nothing.h5"), "msfab.result", 1); });
  EXPECT_EQ(missing, file("nothing.h5") + ": no such file");

  const std::string foreign = file("foreign.h5");
  H5File::create(foreign).write_vector("/data", std::vector<double>{1.0});
  const std::string unmarked = input_error_message([&] { ArtifactReader in(foreign, "msfab.result", 1); });
  EXPECT_NE(unmarked.find("not an msfab artifact"), std::string::npos) << unmarked;
}

// Side outputs are named after the --out path's stem: the first listed
// suffix that matches is dropped, a name that is only the suffix is kept.
// A checkpoint is read back only by the run that wrote it: another schema
// or another run text is refused, naming the file; a rewrite leaves no
// temporary behind.
TEST_F(ScratchDir, CheckpointIsReadOnlyByTheRunThatWroteIt) {
  const std::string path = checkpoint_path(file("run.h5"));
  EXPECT_EQ(path, file("run.h5.checkpoint.h5"));
  for (int round = 1; round <= 2; ++round)
    write_checkpoint_file(path, "msfab.test.checkpoint", "config: 1\n# seed 7\n",
                          [&](H5File& f) { f.write_vector("/done", std::vector<double>(round, 1.5)); });
  EXPECT_TRUE(temporaries().empty());
  const H5File f = open_checkpoint_file(path, "msfab.test.checkpoint", "test", "config: 1\n# seed 7\n");
  EXPECT_EQ(f.read_vector<double>("/done"), std::vector<double>(2, 1.5));
  try {
    open_checkpoint_file(path, "msfab.other.checkpoint", "other-stage", "config: 1\n# seed 7\n");
    ADD_FAILURE() << "another schema was accepted";
  } catch (const InputError& e) {
    EXPECT_EQ(std::string(e.what()), path + ": not a other-stage checkpoint");
  }
  try {
    open_checkpoint_file(path, "msfab.test.checkpoint", "test", "config: 1\n# seed 8\n");
    ADD_FAILURE() << "another run's text was accepted";
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find(path + ": checkpoint was written with a different configuration or seed"),
              std::string::npos)
        << e.what();
  }
}

TEST(PathNames, SuffixesAreDroppedInOrderAndOnlyWhenSomethingIsLeft) {
  EXPECT_TRUE(ends_with("a/part.vdb", ".vdb"));
  EXPECT_FALSE(ends_with("a/part.vdb.bak", ".vdb"));
  EXPECT_FALSE(ends_with("vdb", ".vdb"));
  EXPECT_EQ(without_suffix("out/x.mapped.h5", {".mapped.h5", ".h5"}), "out/x");
  EXPECT_EQ(without_suffix("out/x.h5", {".mapped.h5", ".h5"}), "out/x");
  EXPECT_EQ(without_suffix("out/x.gamut.h5", {".h5", ".gamut.h5"}), "out/x.gamut");
  EXPECT_EQ(without_suffix("out/x.txt", {".h5"}), "out/x.txt");
  EXPECT_EQ(without_suffix(".h5", {".h5"}), ".h5");
}

TEST(ArtifactInputs, FormatAndParseRoundTrip) {
  const std::vector<ArtifactInput> inputs = {{"a/mesh file.h5", std::string(64, 'a')}, {"db.h5", std::string(64, 'b')}};
  const std::string text = format_inputs(inputs);
  EXPECT_EQ(text, std::string(64, 'a') + "  a/mesh file.h5\n" + std::string(64, 'b') + "  db.h5\n");
  const std::vector<ArtifactInput> back = parse_inputs(text);
  ASSERT_EQ(back.size(), 2u);
  EXPECT_EQ(back[0].path, "a/mesh file.h5");
  EXPECT_EQ(back[1].sha256, std::string(64, 'b'));
}

// ---------------------------------------------------------------------------
// SHA-256

TEST(Sha256, FipsTestVectors) {
  EXPECT_EQ(sha256_hex("abc"), "ba7816bf8f01cfea414140de5dae2223b00361a396177a9cb410ff61f20015ad");
  EXPECT_EQ(sha256_hex(""), "e3b0c44298fc1c149afbf4c8996fb92427ae41e4649b934ca495991b7852b855");
  EXPECT_EQ(sha256_hex("abcdbcdecdefdefgefghfghighijhijkijkljklmklmnlmnomnopnopq"),
            "248d6a61d20638b8e5c026930c3e6039a33ce45964ff2167f6ecedd419db06c1");
}

TEST(Sha256, PiecewiseUpdatesMatchOneShot) {
  std::string message;
  for (int i = 0; i < 200; ++i) message.push_back(char('a' + (i * 7) % 26));
  for (std::size_t length : {55u, 56u, 63u, 64u, 65u, 119u, 120u, 128u, 200u}) {
    const std::string part = message.substr(0, length);
    const std::string whole = sha256_hex(part);
    for (std::size_t split = 0; split <= length; split += 13) {
      Sha256 hasher;
      hasher.update(part.substr(0, split));
      hasher.update(part.substr(split));
      EXPECT_EQ(hasher.hex(), whole) << "length " << length << " split " << split;
    }
  }
  EXPECT_NE(sha256_hex(message.substr(0, 55)), sha256_hex(message.substr(0, 56)));
  Sha256 finished;
  finished.update("abc");
  EXPECT_EQ(finished.hex(), sha256_hex("abc"));
  EXPECT_THROW(finished.update("d"), std::logic_error);
  EXPECT_THROW(finished.digest(), std::logic_error);
}

using Sha256File = ScratchDir;

TEST_F(Sha256File, StreamsFilesMillionAVector) {
  const std::string path = file("a.bin");
  write_bytes(path, std::string(1000000, 'a'));  // FIPS 180-2 long message
  EXPECT_EQ(sha256_file_hex(path), "cdc76e5c9914fb9281a1c7e284d73e67f1809a48a497200e046d39ccc7112cd0");
  const std::string message = input_error_message([&] { sha256_file_hex(file("none.bin")); });
  EXPECT_EQ(message, file("none.bin") + ": no such file");
}

// ---------------------------------------------------------------------------
// XDMF

// Checks that every start tag is closed in order; returns the problem or "".
std::string check_tag_balance(const std::string& xml) {
  std::vector<std::string> open;
  std::size_t at = 0;
  while ((at = xml.find('<', at)) != std::string::npos) {
    const std::size_t end = xml.find('>', at);
    if (end == std::string::npos) return "unterminated tag";
    const std::string tag = xml.substr(at + 1, end - at - 1);
    at = end + 1;
    if (tag.empty() || tag[0] == '?' || tag[0] == '!') continue;
    if (tag.back() == '/') continue;
    const std::string name = tag.substr(tag[0] == '/' ? 1 : 0, tag.find_first_of(" /", 1) - (tag[0] == '/' ? 1 : 0));
    if (tag[0] == '/') {
      if (open.empty() || open.back() != name) return "unexpected </" + name + ">";
      open.pop_back();
    } else {
      open.push_back(name);
    }
  }
  return open.empty() ? "" : "unclosed <" + open.back() + ">";
}

std::size_t count_of(const std::string& text, const std::string& needle) {
  std::size_t n = 0;
  for (std::size_t at = text.find(needle); at != std::string::npos; at = text.find(needle, at + 1)) ++n;
  return n;
}

Eigen::Vector3i toolkit_corner(int node) { return {(node >> 2) & 1, (node >> 1) & 1, node & 1}; }

TEST(Xdmf, VtkOrderMapsUnitCubeCorners) {
  const std::array<Eigen::Vector3i, 8> vtk_corners = {
      Eigen::Vector3i(0, 0, 0), Eigen::Vector3i(1, 0, 0), Eigen::Vector3i(1, 1, 0), Eigen::Vector3i(0, 1, 0),
      Eigen::Vector3i(0, 0, 1), Eigen::Vector3i(1, 0, 1), Eigen::Vector3i(1, 1, 1), Eigen::Vector3i(0, 1, 1)};
  for (int v = 0; v < 8; ++v) {
    EXPECT_EQ(toolkit_corner(kToolkitNodeAtVtkCorner[v]), vtk_corners[v]) << "VTK corner " << v;
  }
  // Thesis Table 2.1 (1-based) lists node 2 at (-1,-1,+1) and node 5 at (+1,-1,-1).
  EXPECT_EQ(toolkit_corner(1), Eigen::Vector3i(0, 0, 1));
  EXPECT_EQ(toolkit_corner(4), Eigen::Vector3i(1, 0, 0));

  Eigen::MatrixXi toolkit(2, 8);
  for (int e = 0; e < 2; ++e) {
    for (int k = 0; k < 8; ++k) toolkit(e, k) = 100 * e + k;
  }
  const Eigen::MatrixXi vtk = hex_connectivity_to_vtk_order(toolkit);
  EXPECT_EQ(vtk.row(0), (Eigen::RowVectorXi(8) << 0, 4, 6, 2, 1, 5, 7, 3).finished());
  EXPECT_EQ(vtk(1, 2), 106);
  // VTK's bottom face is counter-clockwise seen from +z, so its normal
  // (p1 - p0) x (p3 - p0) points up, toward the top face.
  const Eigen::Vector3d p0 = vtk_corners[0].cast<double>(), p1 = vtk_corners[1].cast<double>(),
                        p3 = vtk_corners[3].cast<double>();
  EXPECT_GT((p1 - p0).cross(p3 - p0).z(), 0.0);
  EXPECT_THROW(hex_connectivity_to_vtk_order(Eigen::MatrixXi(1, 4)), std::invalid_argument);
}

using XdmfFiles = ScratchDir;

XdmfHexMesh two_hex_mesh() {
  XdmfHexMesh mesh;
  mesh.h5_file = "result.h5";
  mesh.nodes_dataset = "/mesh/nodes";
  mesh.connectivity_dataset = "/mesh/connectivity";
  mesh.n_nodes = 12;
  mesh.n_elems = 2;
  return mesh;
}

TEST_F(XdmfFiles, StaticMeshPointsAtMatchingDatasets) {
  // Two unit cubes side by side along x: 3 x 2 x 2 nodes.
  Eigen::MatrixXd nodes(12, 3);
  for (int n = 0; n < 12; ++n) nodes.row(n) << n / 4, (n / 2) % 2, n % 2;
  Eigen::MatrixXi toolkit(2, 8);
  for (int e = 0; e < 2; ++e) {
    for (int k = 0; k < 8; ++k) toolkit(e, k) = 4 * e + k;
  }
  {
    H5File out = H5File::create(file("result.h5"));
    out.write_matrix("/mesh/nodes", nodes);
    out.write_matrix("/mesh/connectivity", hex_connectivity_to_vtk_order(toolkit));
    out.write_matrix("/displacement", Eigen::MatrixXd::Zero(12, 3));
    out.write_vector("/density", std::vector<double>{1.0, 0.5});
  }
  const std::string xmf = file("result.xmf");
  write_hex_mesh_xdmf(xmf, two_hex_mesh(), {{"displacement", "/displacement", 3}}, {{"density", "/density", 1}});
  EXPECT_TRUE(temporaries().empty());
  const std::string xml = read_bytes(xmf);
  EXPECT_EQ(check_tag_balance(xml), "");
  EXPECT_NE(xml.find("TopologyType=\"Hexahedron\" NumberOfElements=\"2\""), std::string::npos);
  EXPECT_NE(xml.find("GeometryType=\"XYZ\""), std::string::npos);
  EXPECT_NE(xml.find("Name=\"displacement\" AttributeType=\"Vector\" Center=\"Node\""), std::string::npos);
  EXPECT_NE(xml.find("Name=\"density\" AttributeType=\"Scalar\" Center=\"Cell\""), std::string::npos);

  // Every DataItem names a dataset of exactly the stated dimensions.
  const H5File h5 = H5File::open(file("result.h5"));
  const std::regex item(R"re(<DataItem Dimensions="([0-9 ]+)"[^>]*>result\.h5:([^<]+)</DataItem>)re");
  std::size_t items = 0;
  for (std::sregex_iterator it(xml.begin(), xml.end(), item), end; it != end; ++it, ++items) {
    std::istringstream dims((*it)[1].str());
    std::vector<hsize_t> stated;
    for (hsize_t d; dims >> d;) stated.push_back(d);
    EXPECT_EQ(h5.dataset_shape((*it)[2].str()), stated) << (*it)[0].str();
  }
  EXPECT_EQ(items, 4u);
  // The bottom face of the first hex in VTK order is counter-clockwise.
  const Eigen::MatrixXi conn = h5.read_matrix<std::int32_t>("/mesh/connectivity", 8);
  const Eigen::Vector3d a = nodes.row(conn(0, 1)) - nodes.row(conn(0, 0));
  const Eigen::Vector3d b = nodes.row(conn(0, 3)) - nodes.row(conn(0, 0));
  const Eigen::Vector3d up = nodes.row(conn(0, 4)) - nodes.row(conn(0, 0));
  EXPECT_GT(a.cross(b).dot(up), 0.0);
}

TEST_F(XdmfFiles, TimeSeriesIsTemporalCollection) {
  std::vector<XdmfTimeStep> steps;
  for (int i = 0; i < 3; ++i) {
    XdmfTimeStep step;
    step.time = 0.5 * i;
    step.node_fields.push_back({"u", "/frames/" + std::to_string(i) + "/u", 3});
    steps.push_back(step);
  }
  const std::string xmf = file("motion.xmf");
  write_hex_mesh_time_series_xdmf(xmf, two_hex_mesh(), steps);
  const std::string xml = read_bytes(xmf);
  EXPECT_EQ(check_tag_balance(xml), "");
  EXPECT_NE(xml.find("GridType=\"Collection\" CollectionType=\"Temporal\""), std::string::npos);
  EXPECT_EQ(count_of(xml, "GridType=\"Uniform\""), 3u);
  EXPECT_EQ(count_of(xml, "result.h5:/mesh/nodes"), 3u);
  EXPECT_NE(xml.find("<Time Value=\"0.5\"/>"), std::string::npos);
  EXPECT_NE(xml.find("result.h5:/frames/2/u"), std::string::npos);
  EXPECT_LT(xml.find("<Time Value=\"0\"/>"), xml.find("<Time Value=\"1\"/>"));
}

TEST_F(XdmfFiles, UnsupportedComponentsThrowAndWriteNothing) {
  const std::string xmf = file("bad.xmf");
  EXPECT_THROW(write_hex_mesh_xdmf(xmf, two_hex_mesh(), {{"weird", "/w", 2}}, {}), std::invalid_argument);
  EXPECT_FALSE(fs::exists(xmf));
  EXPECT_TRUE(temporaries().empty());
}

// ---------------------------------------------------------------------------
// Commit groups

using CommitGroupTest = ScratchDir;

// A member with one dataset holding `value`.
ArtifactWriter& add_member(CommitGroup& group, const std::string& path, double value,
                           std::vector<ArtifactInput> inputs = {}) {
  ArtifactWriter& w = group.add(path, "msfab.test", 1, "msfab-test", "", std::move(inputs), 1);
  w.file().write_vector("/value", std::vector<double>{value});
  return w;
}

double value_of(const std::string& path) {
  return ArtifactReader(path, "msfab.test", 1).file().read_vector<double>("/value")[0];
}

TEST_F(CommitGroupTest, MembersAppearTogetherAndALaterOneRecordsAnEarliersHash) {
  CommitGroup group;
  ArtifactWriter& set = add_member(group, file("a.h5"), 1.0);
  const ArtifactInput set_input = group.as_input(set);
  add_member(group, file("b.h5"), 2.0, {set_input});
  EXPECT_FALSE(fs::exists(file("a.h5")));
  group.commit();
  EXPECT_EQ(value_of(file("a.h5")), 1.0);
  EXPECT_EQ(value_of(file("b.h5")), 2.0);
  const std::vector<ArtifactInput> inputs = ArtifactReader(file("b.h5"), "msfab.test", 1).inputs();
  ASSERT_EQ(inputs.size(), 1u);
  EXPECT_EQ(inputs[0].path, file("a.h5"));
  EXPECT_EQ(inputs[0].sha256, sha256_file_hex(file("a.h5")));
  EXPECT_TRUE(temporaries().empty());
  EXPECT_FALSE(fs::exists(pending_journal_path(file("a.h5"))));
}

TEST_F(CommitGroupTest, AGroupNotCommittedLeavesTheOldFilesAndNoTemporaries) {
  {
    CommitGroup old_group;
    add_member(old_group, file("a.h5"), 1.0);
    add_member(old_group, file("b.h5"), 2.0);
    old_group.commit();
  }
  {
    CommitGroup group;
    add_member(group, file("a.h5"), 10.0);
    add_member(group, file("b.h5"), 20.0);
  }  // an exception before commit()
  EXPECT_EQ(value_of(file("a.h5")), 1.0);
  EXPECT_EQ(value_of(file("b.h5")), 2.0);
  EXPECT_TRUE(temporaries().empty());
}

// Killed between the renames: one member new, one old on disk. Opening
// either one as an artifact first finishes the group, so no reader sees
// the mixture; the journals are gone afterwards.
TEST_F(CommitGroupTest, AnInterruptedCommitIsFinishedByTheNextReaderOfAnyMember) {
  for (const char* opened_first : {"a.h5", "b.h5"}) {
    {
      CommitGroup old_group;
      add_member(old_group, file("a.h5"), 1.0);
      add_member(old_group, file("b.h5"), 2.0);
      old_group.commit();
    }
    for (std::size_t renames : {std::size_t(0), std::size_t(1)}) {
      {
        CommitGroup group;
        add_member(group, file("a.h5"), 10.0 + double(renames));
        add_member(group, file("b.h5"), 20.0 + double(renames));
        group.commit_interrupted_after(renames);
      }
      EXPECT_TRUE(fs::exists(pending_journal_path(file("a.h5"))));
      EXPECT_EQ(temporaries().size(), 2 - renames);
      EXPECT_EQ(H5File::open(file("a.h5")).read_vector<double>("/value")[0], renames == 1 ? 10.0 + 1 : 1.0)
          << "the raw file is mixed before a reader finishes the group";
      const std::string other = std::string(opened_first) == "a.h5" ? "b.h5" : "a.h5";
      const double first = value_of(file(opened_first));
      EXPECT_EQ(first, (std::string(opened_first) == "a.h5" ? 10.0 : 20.0) + double(renames));
      EXPECT_EQ(value_of(file(other)), (other == "a.h5" ? 10.0 : 20.0) + double(renames));
      EXPECT_TRUE(temporaries().empty());
      EXPECT_FALSE(fs::exists(pending_journal_path(file("a.h5"))));
      EXPECT_FALSE(fs::exists(pending_journal_path(file("b.h5"))));
    }
  }
}

// A stale journal must not roll its temporaries over a newer commit.
TEST_F(CommitGroupTest, ACommitOverAnInterruptedGroupFinishesItFirst) {
  {
    CommitGroup group;
    add_member(group, file("a.h5"), 1.0);
    add_member(group, file("b.h5"), 2.0);
    group.commit_interrupted_after(0);
  }
  ArtifactWriter single(file("a.h5"), "msfab.test", 1, "msfab-test", "", std::vector<std::string>{}, 1);
  single.file().write_vector("/value", std::vector<double>{5.0});
  single.commit();
  EXPECT_EQ(value_of(file("a.h5")), 5.0);
  EXPECT_EQ(value_of(file("b.h5")), 2.0);
  EXPECT_TRUE(temporaries().empty());
}

TEST_F(CommitGroupTest, AForeignJournalIsRefusedAndNothingIsRenamed) {
  write_bytes(file("victim"), "keep");
  write_bytes(file("a.h5"), "old");
  write_bytes(pending_journal_path(file("a.h5")),
              "msfab commit group 1\n" + file("victim") + "\t" + file("a.h5") + "\n");
  const std::string message = input_error_message([&] { complete_interrupted_commit(file("a.h5")); });
  EXPECT_NE(message.find(pending_journal_path(file("a.h5")) + ": not a commit journal"), std::string::npos) << message;
  EXPECT_EQ(read_bytes(file("victim")), "keep");
  EXPECT_EQ(read_bytes(file("a.h5")), "old");
  write_bytes(pending_journal_path(file("a.h5")), "something else\n");
  EXPECT_THROW(ArtifactReader(file("a.h5"), "msfab.test", 1), InputError);
}

TEST_F(CommitGroupTest, OneOutputNamedTwiceIsAnInputError) {
  CommitGroup group;
  add_member(group, file("a.h5"), 1.0);
  EXPECT_THROW(add_member(group, file("a.h5"), 2.0), InputError);
}

}  // namespace
}  // namespace msfab
