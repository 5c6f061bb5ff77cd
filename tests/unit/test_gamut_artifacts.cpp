// The sampler's artifacts: bit-packed voxels, the microstructures and gamut
// files read back exactly, bad files rejected; and the PNG writer's output
// decodes to the pixels drawn.
#include <gtest/gtest.h>
#include <zlib.h>

#include <filesystem>
#include <fstream>
#include <random>

#include "core/errors.hpp"
#include "gamut/gamut_artifact.hpp"
#include "gamut/microstructure_set.hpp"
#include "io/hdf5_file.hpp"
#include "io/png_image.hpp"

namespace msfab {
namespace {
namespace fs = std::filesystem;

fs::path scratch(const std::string& name) {
  const fs::path dir = fs::temp_directory_path() / ("msfab_gamut_artifacts_" + std::to_string(::getpid()));
  fs::create_directories(dir);
  return dir / name;
}

TEST(GamutArtifacts, VoxelPackingRoundTrips) {
  std::mt19937 rng(3);
  for (int max_id : {1, 2, 3, 7}) {
    const int bits = bits_per_voxel(max_id);
    EXPECT_EQ(bits, max_id == 1 ? 1 : max_id <= 3 ? 2 : 3);
    std::vector<int> ids(1000);
    for (int& v : ids) v = static_cast<int>(rng() % (max_id + 1));
    const std::vector<std::uint8_t> packed = pack_voxels(ids, bits);
    EXPECT_EQ(packed.size(), (1000 * bits + 7) / 8);
    EXPECT_EQ(unpack_voxels(packed.data(), ids.size(), bits), ids);
  }
}

MicrostructureSet sample_set() {
  MicrostructureSet s;
  s.space = "cubic2d";
  s.property_names = {"E", "nu", "G", "rho"};
  s.E_stiff = 1e6;
  s.nx = s.ny = 5, s.nz = 1;
  s.stiff = {1e6, 0.3};
  s.soft = {1e4, 0.45};
  s.soft_is_void = false;
  for (int i = 0; i < 3; ++i) {
    Microstructure m;
    m.ids.assign(25, 1);
    m.ids[i] = 2, m.ids[7 + i] = 0;
    m.properties = VecX::LinSpaced(4, 1.0 + i, 4.0 + i);
    m.unit = VecX::Constant(4, 0.1 * i);
    m.C = Mat6::Identity() * (i + 1);
    m.C(0, 1) = m.C(1, 0) = 0.25;
    m.cycle = i;
    m.step = static_cast<SampleStep>(i);
    m.parent = i - 1;
    s.items.push_back(m);
  }
  return s;
}

TEST(GamutArtifacts, MicrostructuresReadBackExactly) {
  const MicrostructureSet s = sample_set();
  const std::string path = scratch("set.h5").string();
  write_microstructures_artifact(path, s, "msfab-test", "a: 1\n", {}, 5);
  const MicrostructureSet r = read_microstructures_artifact(path);
  EXPECT_EQ(r.space, s.space);
  EXPECT_EQ(r.property_names, s.property_names);
  EXPECT_EQ(r.nx, 5);
  EXPECT_EQ(r.nz, 1);
  EXPECT_FALSE(r.soft_is_void);
  EXPECT_EQ(r.soft.E, 1e4);
  ASSERT_EQ(r.items.size(), 3u);
  for (int i = 0; i < 3; ++i) {
    EXPECT_EQ(r.items[i].ids, s.items[i].ids);
    EXPECT_EQ(r.items[i].properties, s.items[i].properties);
    EXPECT_EQ(r.items[i].unit, s.items[i].unit);
    EXPECT_EQ(r.items[i].C, s.items[i].C);
    EXPECT_EQ(r.items[i].cycle, i);
    EXPECT_EQ(r.items[i].step, s.items[i].step);
    EXPECT_EQ(r.items[i].parent, i - 1);
  }
  // A gamut file is not a microstructures file.
  Gamut g;
  g.space = "cubic2d";
  g.property_names = {"E", "nu"};
  g.level_set = GamutLevelSet::from_points({VecX::Constant(2, 0.5), VecX::Constant(2, 0.6)});
  const std::string gpath = scratch("g.h5").string();
  write_gamut_artifact(gpath, g, "msfab-test", "", {}, 1);
  EXPECT_THROW(read_microstructures_artifact(gpath), InputError);
}

TEST(GamutArtifacts, GamutLevelSetReadsBackWithTheSameQueries) {
  std::vector<VecX> points;
  std::mt19937 rng(11);
  std::uniform_real_distribution<double> u(0.3, 0.7);
  for (int i = 0; i < 200; ++i) points.push_back(Eigen::Vector3d(u(rng), u(rng), u(rng)));
  Gamut g;
  g.space = "custom";
  g.property_names = {"a", "b", "c"};
  g.E_stiff = 2e9;
  g.level_set = GamutLevelSet::from_points(points);
  g.history = {{0, 10, 10, 0, 0.01, 1.5}, {1, 20, 8, 2, 0.02, 2.5}};
  g.bound_stiff = MatX::Random(3, 3);
  g.bound_soft = MatX::Zero(3, 3);
  const std::string path = scratch("gamut.h5").string();
  write_gamut_artifact(path, g, "msfab-test", "", {}, 1);
  const Gamut r = read_gamut_artifact(path);
  EXPECT_EQ(r.bound_stiff, g.bound_stiff);  // the Voigt bound's base materials
  EXPECT_EQ(r.bound_soft, g.bound_soft);
  EXPECT_EQ(r.property_names, g.property_names);
  EXPECT_EQ(r.E_stiff, 2e9);
  EXPECT_EQ(r.level_set.values(), g.level_set.values());
  EXPECT_EQ(r.level_set.padding(), g.level_set.padding());
  EXPECT_DOUBLE_EQ(g.level_set.padding(), 1.5 * g.level_set.spacing());  // the default radius
  for (const VecX& p : {VecX(Eigen::Vector3d(0.5, 0.5, 0.5)), VecX(Eigen::Vector3d(0.1, 0.9, 0.33))}) {
    EXPECT_EQ(r.level_set.value(p), g.level_set.value(p));
    EXPECT_EQ(r.level_set.gradient(p), g.level_set.gradient(p));
  }
  ASSERT_EQ(r.history.size(), 2u);
  EXPECT_EQ(r.history[1].continuous_added, 2);
  EXPECT_EQ(r.history[1].coverage, 0.02);
  // Coverage: the points fill a box of side 0.4 (volume 0.064) blurred by
  // the implicit function's radius: a little more, never less than half.
  const double c = coverage(g.level_set);
  EXPECT_GT(c, 0.032);
  EXPECT_LT(c, 0.25);
  EXPECT_THROW(GamutLevelSet::from_values(3, 4, 0.0, 0.25, std::vector<double>(63, 0.0)), InputError);
}

TEST(PngImage, WritesAValidPngWithThePixelsDrawn) {
  PngImage img(7, 3, {255, 255, 255});
  img.set(2, 1, {10, 20, 30});
  img.set(100, 100, {1, 1, 1});  // ignored
  const std::string path = scratch("x.png").string();
  img.write_png(path);
  std::ifstream f(path, std::ios::binary);
  const std::vector<unsigned char> bytes((std::istreambuf_iterator<char>(f)), std::istreambuf_iterator<char>());
  ASSERT_GT(bytes.size(), 8u + 25 + 12);
  EXPECT_EQ(std::string(bytes.begin() + 1, bytes.begin() + 4), "PNG");
  auto u32 = [&](std::size_t at) {
    return std::uint32_t(bytes[at]) << 24 | std::uint32_t(bytes[at + 1]) << 16 | std::uint32_t(bytes[at + 2]) << 8 |
           bytes[at + 3];
  };
  EXPECT_EQ(std::string(bytes.begin() + 12, bytes.begin() + 16), "IHDR");
  EXPECT_EQ(u32(16), 7u);
  EXPECT_EQ(u32(20), 3u);
  EXPECT_EQ(u32(29), crc32(0, bytes.data() + 12, 17));  // the chunk's CRC covers type and data
  const std::size_t idat = 8 + 25;
  EXPECT_EQ(std::string(bytes.begin() + idat + 4, bytes.begin() + idat + 8), "IDAT");
  const std::uint32_t n = u32(idat);
  std::vector<unsigned char> raw(3 * (3 * 7 + 1));
  uLongf raw_size = raw.size();
  ASSERT_EQ(uncompress(raw.data(), &raw_size, bytes.data() + idat + 8, n), Z_OK);
  ASSERT_EQ(raw_size, raw.size());
  const std::size_t pixel = 1 * (3 * 7 + 1) + 1 + 3 * 2;
  EXPECT_EQ(raw[pixel], 10);
  EXPECT_EQ(raw[pixel + 2], 30);
  EXPECT_EQ(raw[0], 0);  // filter byte
  EXPECT_EQ(raw[1], 255);
}

}  // namespace
}  // namespace msfab
