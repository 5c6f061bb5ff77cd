#include "io/vdb_grid_io.hpp"

#include <algorithm>
#include <cmath>
#include <limits>
#include <sstream>

#include "core/errors.hpp"
#include "io/input_file.hpp"

#ifdef MSFAB_WITH_OPENVDB
#include <openvdb/io/File.h>
#include <openvdb/openvdb.h>
#include <openvdb/tools/Interpolation.h>
#include <sys/resource.h>

#include <cstdint>
#include <filesystem>
#include <fstream>
#include <mutex>
#include <new>
#endif

namespace msfab {

#ifdef MSFAB_WITH_OPENVDB

namespace {

// A kB figure of a /proc file ("MemAvailable:", "VmData:"), or -1.
long long proc_kilobytes(const char* file, const std::string& key) {
  std::ifstream in(file);
  std::string word;
  while (in >> word)
    if (word == key) {
      long long kb = -1;
      in >> kb;
      return kb;
    }
  return -1;
}

// While a file is read, the heap may grow by at most 256 MiB plus a
// thousand times the file's size, and by at most half the memory available
// when the read starts (RLIMIT_DATA, restored afterwards). A truncated or
// corrupt .vdb can make OpenVDB take garbage for a buffer's size; without
// the bound that allocation succeeds on an overcommitting system and the
// process is killed once the buffer is filled (24 GB of a half-written
// 3 kB file was seen), with it the allocation throws std::bad_alloc, which
// is reported as an unreadable file (exit 2). No grid expands its file a
// thousand-fold: blocks of one value are stored as tiles, not voxels.
class HeapBudget {
 public:
  explicit HeapBudget(std::uintmax_t file_bytes) {
    const long long available = proc_kilobytes("/proc/meminfo", "MemAvailable:");
    const long long used = proc_kilobytes("/proc/self/status", "VmData:");
    if (available <= 0 || used < 0 || getrlimit(RLIMIT_DATA, &saved_) != 0) return;
    const double growth = std::min(0.5 * 1024.0 * double(available), 256.0 * 1024 * 1024 + 1000.0 * double(file_bytes));
    const rlim_t budget = static_cast<rlim_t>(1024.0 * double(used) + growth);
    if (saved_.rlim_cur != RLIM_INFINITY && saved_.rlim_cur <= budget) return;
    rlimit bounded = saved_;
    bounded.rlim_cur = saved_.rlim_max == RLIM_INFINITY ? budget : std::min<rlim_t>(budget, saved_.rlim_max);
    active_ = setrlimit(RLIMIT_DATA, &bounded) == 0;
  }
  ~HeapBudget() {
    if (active_) setrlimit(RLIMIT_DATA, &saved_);
  }
  HeapBudget(const HeapBudget&) = delete;
  HeapBudget& operator=(const HeapBudget&) = delete;

 private:
  rlimit saved_{};
  bool active_ = false;
};

// The grid `name` of the file, or its only grid when `name` is empty.
openvdb::GridBase::Ptr read_named_grid(const std::string& path, const std::string& name) {
  static std::once_flag registered;
  std::call_once(registered, [] { openvdb::initialize(); });
  require_regular_file(path);
  const HeapBudget budget(std::filesystem::file_size(path));
  try {
    openvdb::io::File file(path);
    file.open(/*delayLoad=*/false);
    std::vector<std::string> names;
    for (auto it = file.beginName(); it != file.endName(); ++it) names.push_back(it.gridName());
    std::string list;
    for (const std::string& n : names) list += (list.empty() ? "" : ", ") + ("'" + n + "'");
    if (names.empty()) throw InputError(path + ": the file holds no grid");
    std::string chosen = name;
    if (chosen.empty()) {
      if (names.size() > 1)
        throw InputError(path + ": the file holds " + std::to_string(names.size()) + " grids (" + list +
                         "); name one with `grid`");
      chosen = names.front();
    } else if (std::find(names.begin(), names.end(), chosen) == names.end()) {
      throw InputError(path + ": no grid named '" + chosen + "'; the file holds " + list);
    }
    openvdb::GridBase::Ptr grid = file.readGrid(chosen);
    file.close();
    return grid;
  } catch (const openvdb::Exception& e) {
    throw InputError(path + ": not a readable OpenVDB file: " + e.what());
  } catch (const std::bad_alloc&) {
    throw InputError(path +
                     ": not a readable OpenVDB file: reading it would take more memory than such a file can hold "
                     "(truncated or corrupt?)");
  }
}

std::string number_text(double x) {
  std::ostringstream o;
  o.precision(9);
  o << x;
  return o.str();
}

std::string coord_text(const openvdb::Coord& c) {
  std::ostringstream o;
  o << "(" << c.x() << ", " << c.y() << ", " << c.z() << ")";
  return o.str();
}

template <class GridT>
VdbVoxelIds ids_from(const GridT& grid, const std::string& path, int nx, int ny, int nz,
                     const std::array<long long, 3>& origin) {
  VdbVoxelIds out;
  out.ids.resize(std::size_t(nx) * ny * nz);
  auto accessor = grid.getConstAccessor();
  long long active_inside = 0;
  std::size_t v = 0;
  for (int k = 0; k < nz; ++k)
    for (int j = 0; j < ny; ++j)
      for (int i = 0; i < nx; ++i, ++v) {
        const openvdb::Coord c(int(origin[0] + i), int(origin[1] + j), int(origin[2] + k));
        typename GridT::ValueType value;
        const bool active = accessor.probeValue(c, value);
        active_inside += active;
        const double id = static_cast<double>(value);
        if (!(id >= 0 && id <= double(std::numeric_limits<int>::max()) && id == std::floor(id)))
          throw InputError(path + ": grid '" + grid.getName() + "' holds " + number_text(id) + " at index " +
                           coord_text(c) + (active ? "" : " (the grid's background)") +
                           ", which is not a material id (a whole number 0 .. 2^31 - 1, 0 = void)");
        out.ids[v] = static_cast<int>(id);
      }
  out.active_outside = static_cast<long long>(grid.activeVoxelCount()) - active_inside;
  return out;
}

// The checks on a scene box in index space that OpenVDB's 32-bit
// coordinates need.
void check_index_box(const std::string& path, int nx, int ny, int nz, const std::array<long long, 3>& origin) {
  const long long n[3] = {nx, ny, nz};
  for (int a = 0; a < 3; ++a)
    if (origin[a] < std::numeric_limits<int>::min() || origin[a] + n[a] - 1 > std::numeric_limits<int>::max())
      throw InputError(path + ": the index box from origin " + std::to_string(origin[a]) +
                       " leaves OpenVDB's 32-bit coordinates");
}

struct VolumeView {
  virtual ~VolumeView() = default;
  virtual double sample(const Vec3& p) const = 0;
  virtual std::array<Vec3, 2> inside_box(bool level_set, double threshold) const = 0;
};

template <class GridT>
class TypedVolume final : public VolumeView {
 public:
  explicit TypedVolume(typename GridT::ConstPtr grid) : grid_(std::move(grid)), accessor_(grid_->getConstAccessor()) {}

  double sample(const Vec3& p) const override {
    const openvdb::Vec3d index = grid_->transform().worldToIndex(openvdb::Vec3d(p.x(), p.y(), p.z()));
    if constexpr (std::is_same_v<typename GridT::ValueType, bool>) {
      return openvdb::tools::PointSampler::sample(accessor_, index) ? 1.0 : 0.0;
    } else {
      return static_cast<double>(openvdb::tools::BoxSampler::sample(accessor_, index));
    }
  }

  std::array<Vec3, 2> inside_box(bool level_set, double threshold) const override {
    openvdb::CoordBBox inside;  // empty
    for (auto it = grid_->cbeginValueAll(); it; ++it) {
      const double value = static_cast<double>(*it);
      if (level_set ? value < threshold : value > threshold) {
        openvdb::CoordBBox b;
        it.getBoundingBox(b);
        inside.expand(b);
      }
    }
    Vec3 lo = Vec3::Constant(std::numeric_limits<double>::infinity()), hi = -lo;
    if (inside.empty()) return {lo, hi};
    // Voxel centres sit on integer index coordinates: a voxel spans +-1/2.
    const openvdb::Vec3d a = inside.min().asVec3d() - openvdb::Vec3d(0.5),
                         b = inside.max().asVec3d() + openvdb::Vec3d(0.5);
    for (int corner = 0; corner < 8; ++corner) {
      const openvdb::Vec3d q((corner & 1) ? b.x() : a.x(), (corner & 2) ? b.y() : a.y(), (corner & 4) ? b.z() : a.z());
      const openvdb::Vec3d w = grid_->transform().indexToWorld(q);
      const Vec3 world(w.x(), w.y(), w.z());
      lo = lo.cwiseMin(world), hi = hi.cwiseMax(world);
    }
    return {lo, hi};
  }

 private:
  typename GridT::ConstPtr grid_;
  // Caches the path to the last visited leaf, hence mutable (and the class
  // not thread-safe).
  mutable typename GridT::ConstAccessor accessor_;
};

}  // namespace

bool vdb_input_available() { return true; }

VdbVoxelIds read_vdb_voxel_ids(const std::string& path, const std::string& grid_name, int nx, int ny, int nz,
                               const std::array<long long, 3>& origin) {
  check_index_box(path, nx, ny, nz, origin);
  const openvdb::GridBase::Ptr base = read_named_grid(path, grid_name);
  if (auto g = openvdb::gridConstPtrCast<openvdb::BoolGrid>(base)) return ids_from(*g, path, nx, ny, nz, origin);
  if (auto g = openvdb::gridConstPtrCast<openvdb::Int32Grid>(base)) return ids_from(*g, path, nx, ny, nz, origin);
  if (auto g = openvdb::gridConstPtrCast<openvdb::Int64Grid>(base)) return ids_from(*g, path, nx, ny, nz, origin);
  if (auto g = openvdb::gridConstPtrCast<openvdb::FloatGrid>(base)) return ids_from(*g, path, nx, ny, nz, origin);
  if (auto g = openvdb::gridConstPtrCast<openvdb::DoubleGrid>(base)) return ids_from(*g, path, nx, ny, nz, origin);
  throw InputError(path + ": grid '" + base->getName() + "' holds values of type " + base->valueType() +
                   "; material ids need bool, int32, int64, float or double values");
}

struct VdbVolume::Impl {
  std::string name, value_type;
  bool level_set = false;
  double voxel_size = 0;
  std::unique_ptr<VolumeView> view;
};

VdbVolume VdbVolume::read(const std::string& path, const std::string& grid_name) {
  const openvdb::GridBase::Ptr base = read_named_grid(path, grid_name);
  auto impl = std::make_unique<Impl>();
  impl->name = base->getName();
  impl->value_type = base->valueType();
  impl->level_set = base->getGridClass() == openvdb::GRID_LEVEL_SET;
  impl->voxel_size = base->voxelSize().x();
  if (auto g = openvdb::gridConstPtrCast<openvdb::FloatGrid>(base))
    impl->view = std::make_unique<TypedVolume<openvdb::FloatGrid>>(g);
  else if (auto g = openvdb::gridConstPtrCast<openvdb::DoubleGrid>(base))
    impl->view = std::make_unique<TypedVolume<openvdb::DoubleGrid>>(g);
  else if (auto g = openvdb::gridConstPtrCast<openvdb::BoolGrid>(base))
    impl->view = std::make_unique<TypedVolume<openvdb::BoolGrid>>(g);
  else
    throw InputError(path + ": grid '" + impl->name + "' holds values of type " + impl->value_type +
                     "; a shape needs a float, double or bool grid (a level set or a density)");
  if (!base->hasUniformVoxels())
    throw InputError(path + ": grid '" + impl->name + "' has voxels of unequal edges; resample it to cubic voxels");
  return VdbVolume(std::move(impl));
}

bool VdbVolume::is_level_set() const { return impl_->level_set; }
double VdbVolume::default_threshold() const { return impl_->level_set ? 0.0 : 0.5; }
double VdbVolume::sample(const Vec3& p) const { return impl_->view->sample(p); }
bool VdbVolume::inside(const Vec3& p, double threshold) const {
  const double v = sample(p);
  return impl_->level_set ? v < threshold : v > threshold;
}
std::array<Vec3, 2> VdbVolume::inside_box(double threshold) const {
  return impl_->view->inside_box(impl_->level_set, threshold);
}
std::string VdbVolume::describe() const {
  std::ostringstream o;
  o << "grid '" << impl_->name << "' (" << impl_->value_type << ", " << (impl_->level_set ? "level set" : "density")
    << ", voxel " << impl_->voxel_size << ")";
  return o.str();
}

#else  // no OpenVDB in this build

namespace {
[[noreturn]] void no_openvdb(const std::string& path) {
  throw InputError(path +
                   ": this build of msfab reads no .vdb files; install libopenvdb-dev and "
                   "libboost-iostreams-dev (make -f Makefile.pipeline deps) and build again");
}
}  // namespace

struct VdbVolume::Impl {};

bool vdb_input_available() { return false; }
VdbVoxelIds read_vdb_voxel_ids(const std::string& path, const std::string&, int, int, int,
                               const std::array<long long, 3>&) {
  no_openvdb(path);
}
VdbVolume VdbVolume::read(const std::string& path, const std::string&) { no_openvdb(path); }
bool VdbVolume::is_level_set() const { return false; }
double VdbVolume::default_threshold() const { return 0.5; }
double VdbVolume::sample(const Vec3&) const { return 0; }
bool VdbVolume::inside(const Vec3&, double) const { return false; }
std::array<Vec3, 2> VdbVolume::inside_box(double) const { return {Vec3::Zero(), Vec3::Zero()}; }
std::string VdbVolume::describe() const { return ""; }

#endif

VdbVolume::VdbVolume(std::unique_ptr<Impl> impl) : impl_(std::move(impl)) {}
VdbVolume::VdbVolume(VdbVolume&&) noexcept = default;
VdbVolume& VdbVolume::operator=(VdbVolume&&) noexcept = default;
VdbVolume::~VdbVolume() = default;

}  // namespace msfab
