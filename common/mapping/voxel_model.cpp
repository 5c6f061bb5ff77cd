#include "mapping/voxel_model.hpp"

#include <spdlog/spdlog.h>

#include <algorithm>
#include <cstdio>
#include <cstring>
#include <exception>
#include <filesystem>
#include <memory>
#include <stdexcept>

#include "cli/progress.hpp"
#include "core/errors.hpp"
#include "io/atomic_file.hpp"

namespace msfab {
namespace fs = std::filesystem;

// ---------------------------------------------------------------------------
// The model

VoxelModel::VoxelModel(const MappedDesign& mapped, const MicrostructureSet& set) : m_(mapped), set_(set) {
  if (m_.vx != set.nx || m_.vy != set.ny || m_.vz != set.nz)
    throw InputError("the mapping's cells hold " + std::to_string(m_.vx) + " x " + std::to_string(m_.vy) + " x " +
                     std::to_string(m_.vz) + " voxels, the structures " + std::to_string(set.nx) + " x " +
                     std::to_string(set.ny) + " x " + std::to_string(set.nz));
  if (std::int64_t(m_.structure.size()) != m_.cells() || std::int64_t(m_.shift.size()) != m_.cells() ||
      std::int64_t(m_.roles.size()) != m_.cells())
    throw std::invalid_argument("VoxelModel: per-cell arrays of the wrong size");
  for (std::size_t c = 0; c < m_.structure.size(); ++c)
    if (m_.roles[c] == CellRole::design && (m_.structure[c] < 0 || std::size_t(m_.structure[c]) >= set.items.size()))
      throw InputError("cell " + std::to_string(c) + " maps to structure " + std::to_string(m_.structure[c]) +
                       ", the set holds " + std::to_string(set.items.size()));
}

Vec3 VoxelModel::voxel_size() const {
  const double hx = m_.cell_size / cell_voxels_x(), hy = m_.cell_size / cell_voxels_y();
  return {hx, hy, m_.dimension == 3 ? m_.cell_size / cell_voxels_z() : hx};
}

void VoxelModel::layer(std::int64_t z, std::vector<int>& ids) const {
  const std::int64_t NX = nx(), NY = ny();
  ids.resize(std::size_t(NX * NY));
  const int vx = m_.vx, vy = m_.vy, vz = m_.vz, t = m_.tiling;
  const std::int64_t k = z / cell_voxels_z();
  const int lz = int(z % vz);
#pragma omp parallel for schedule(static)
  for (std::int64_t Y = 0; Y < NY; ++Y) {
    const std::int64_t j = Y / cell_voxels_y();
    const int ly = int(Y % vy);
    int* row = &ids[std::size_t(Y * NX)];
    for (std::int64_t i = 0; i < m_.nx; ++i) {
      const std::size_t cell = std::size_t(i + m_.nx * (j + m_.ny * k));
      int* out = row + i * std::int64_t(vx) * t;
      if (m_.roles[cell] != CellRole::design) {
        std::fill(out, out + std::int64_t(vx) * t, m_.roles[cell] == CellRole::solid ? 1 : 0);
        continue;
      }
      const std::vector<int>& s = set_.items[std::size_t(m_.structure[cell])].ids;
      const bool shift = m_.shift[cell] != 0;
      const int sx = shift ? vx / 2 : 0, y = shift ? (ly + vy / 2) % vy : ly, zz = shift ? (lz + vz / 2) % vz : lz;
      const int* src = &s[std::size_t(vx) * (y + std::size_t(vy) * zz)];
      for (int copy = 0; copy < t; ++copy, out += vx)
        for (int x = 0; x < vx; ++x) out[x] = src[(x + sx) % vx];
    }
  }
}

// ---------------------------------------------------------------------------
// Voxel artifact

void write_voxels_artifact(const std::string& path, const VoxelModel& model, const std::string& executable,
                           const std::string& config_text, const std::vector<std::string>& inputs, std::uint64_t seed) {
  const MappedDesign& m = model.mapping();
  const int bits = bits_per_voxel(model.max_id());
  const std::size_t layer_voxels = std::size_t(model.nx() * model.ny());
  const std::size_t row_bytes = (layer_voxels * bits + 7) / 8;
  ArtifactWriter out(path, kVoxelsSchema, kVoxelsSchemaVersion, executable, config_text, inputs, seed);
  H5File& f = out.file();
  f.write_attribute("/", "size", std::vector<std::int64_t>{model.nx(), model.ny(), model.nz()});
  const Vec3 h = model.voxel_size();
  f.write_attribute("/", "voxel_size", std::vector<double>{h.x(), h.y(), h.z()});
  f.write_attribute("/", "dimension", static_cast<std::int32_t>(m.dimension));
  f.write_attribute("/", "grid", std::vector<std::int32_t>{m.nx, m.ny, m.nz});
  f.write_attribute("/", "cell_voxels",
                    std::vector<std::int32_t>{model.cell_voxels_x(), model.cell_voxels_y(), model.cell_voxels_z()});
  f.write_attribute("/", "tiling", static_cast<std::int32_t>(m.tiling));

  // Chunks of about 1 MiB: whole layers (up to one layer of cells) when a
  // layer is small, parts of a layer when it is large.
  constexpr std::size_t kChunk = std::size_t(1) << 20;
  const std::size_t chunk_cols = std::min(row_bytes, kChunk);
  const int cz = model.cell_voxels_z();  // voxel layers per layer of cells
  const std::size_t chunk_rows = std::clamp<std::size_t>(kChunk / chunk_cols, 1, std::size_t(cz));
  f.create_chunked_dataset<std::uint8_t>("/voxels", {hsize_t(model.nz()), hsize_t(row_bytes)},
                                         {hsize_t(chunk_rows), hsize_t(chunk_cols)}, 4);
  f.write_attribute("/voxels", "bits_per_voxel", static_cast<std::int32_t>(bits));
  f.write_attribute("/voxels", "order",
                    "row z: layer z, ids x fastest (X + nx Y), bits_per_voxel bits each, least significant first, "
                    "padded to whole bytes");
  f.write_attribute("/voxels", "ids", model.max_id() == 1 ? "0 void, 1 stiff" : "0 void, 1 stiff, 2 soft");

  std::vector<std::uint8_t> slab(std::size_t(cz) * row_bytes);
  std::vector<int> ids;
  Progress progress("voxel file", std::uint64_t(m.nz));
  for (int k = 0; k < m.nz; ++k) {
    for (int lz = 0; lz < cz; ++lz) {
      model.layer(std::int64_t(k) * cz + lz, ids);
      const std::vector<std::uint8_t> packed = pack_voxels(ids, bits);
      std::copy(packed.begin(), packed.end(), slab.begin() + std::ptrdiff_t(lz * row_bytes));
    }
    f.write_slab("/voxels", slab.data(), {hsize_t(k) * hsize_t(cz), 0}, {hsize_t(cz), hsize_t(row_bytes)});
    progress.tick();
  }
  progress.done();
  out.commit();
}

VoxelsReader::VoxelsReader(const std::string& path) : in_(path, kVoxelsSchema, kVoxelsSchemaVersion) {
  const H5File& f = in_.file();
  const auto size = f.read_attribute_vector<std::int64_t>("/", "size");
  if (size.size() != 3 || size[0] < 1 || size[1] < 1 || size[2] < 1)
    throw InputError(path + ": attribute size must hold 3 positive sizes");
  nx_ = size[0], ny_ = size[1], nz_ = size[2];
  bits_ = f.read_attribute<std::int32_t>("/voxels", "bits_per_voxel");
  if (bits_ < 1 || bits_ > 8) throw InputError(path + ": /voxels bits_per_voxel must be 1..8");
  row_bytes_ = (std::size_t(nx_ * ny_) * bits_ + 7) / 8;
  const auto shape = f.dataset_shape("/voxels");
  if (shape.size() != 2 || shape[0] != hsize_t(nz_) || shape[1] != row_bytes_)
    throw InputError(path + ": /voxels must have shape (" + std::to_string(nz_) + ", " + std::to_string(row_bytes_) +
                     ")");
}

std::vector<int> VoxelsReader::layer(std::int64_t z) const {
  if (z < 0 || z >= nz_) throw std::out_of_range("VoxelsReader::layer: no layer " + std::to_string(z));
  const std::vector<std::uint8_t> row = in_.file().read_slab<std::uint8_t>("/voxels", {hsize_t(z), 0}, {1, row_bytes_});
  return unpack_voxels(row.data(), std::size_t(nx_ * ny_), bits_);
}

// ---------------------------------------------------------------------------
// STL surfaces

namespace {

// A binary STL written through an AtomicFile (io/atomic_file.hpp): header,
// a triangle count patched at the end, 50 bytes per triangle; committed over
// <path> by finish().
class StlFile {
 public:
  explicit StlFile(std::string path) : out_(std::move(path)) {
    char header[80] = {};
    std::snprintf(header, sizeof header, "msfab-map voxel surface");
    out_.write(header, 80);
    const std::uint32_t zero = 0;
    out_.write(&zero, 4);
  }
  StlFile(const StlFile&) = delete;
  StlFile& operator=(const StlFile&) = delete;

  // The unit square of the face of voxel p on `axis` (side 1: the upper
  // one), counter-clockwise seen from outside, as two triangles.
  void quad(int axis, int side, const std::int64_t p[3], const Vec3& h) {
    const int b = (axis + 1) % 3, c = (axis + 2) % 3;
    static const int kCorners[2][4][2] = {{{0, 0}, {0, 1}, {1, 1}, {1, 0}}, {{0, 0}, {1, 0}, {1, 1}, {0, 1}}};
    float v[4][3];
    for (int q = 0; q < 4; ++q) {
      double x[3];
      x[axis] = double(p[axis] + side);
      x[b] = double(p[b] + kCorners[side][q][0]);
      x[c] = double(p[c] + kCorners[side][q][1]);
      for (int d = 0; d < 3; ++d) v[q][d] = float(x[d] * h[d]);
    }
    float n[3] = {0, 0, 0};
    n[axis] = side == 1 ? 1.0f : -1.0f;
    triangle(n, v[0], v[1], v[2]);
    triangle(n, v[0], v[2], v[3]);
  }

  std::int64_t triangles() const { return count_; }
  const std::string& path() const { return out_.path(); }

  void finish() {
    flush();
    if (count_ > std::int64_t(UINT32_MAX))
      throw std::runtime_error(out_.path() + ": more triangles than STL can count");
    const std::uint32_t count = std::uint32_t(count_);
    out_.write_at(80, &count, 4);
    out_.commit();
  }

 private:
  void triangle(const float n[3], const float a[3], const float b[3], const float c[3]) {
    char record[50] = {};
    std::memcpy(record, n, 12);
    std::memcpy(record + 12, a, 12);
    std::memcpy(record + 24, b, 12);
    std::memcpy(record + 36, c, 12);
    buffer_.insert(buffer_.end(), record, record + 50);
    ++count_;
    if (buffer_.size() >= (std::size_t(1) << 20)) flush();
  }
  void flush() {
    out_.write(buffer_.data(), buffer_.size());
    buffer_.clear();
  }

  AtomicFile out_;
  std::vector<char> buffer_;
  std::int64_t count_ = 0;
};

}  // namespace

StlExport write_material_stls(const std::string& stem, const VoxelModel& model) {
  const int materials = model.max_id();
  std::vector<std::unique_ptr<StlFile>> files;
  for (int id = 1; id <= materials; ++id)
    files.push_back(std::make_unique<StlFile>(stem + ".material" + std::to_string(id) + ".stl"));
  const std::int64_t NX = model.nx(), NY = model.ny(), NZ = model.nz();
  const Vec3 h = model.voxel_size();
  // Three layers at a time; the outside of the model is void.
  std::vector<int> below(std::size_t(NX * NY), 0), here, above;
  model.layer(0, here);
  Progress progress("stl surfaces", std::uint64_t(NZ));
  for (std::int64_t Z = 0; Z < NZ; ++Z) {
    if (Z + 1 < NZ)
      model.layer(Z + 1, above);
    else
      above.assign(std::size_t(NX * NY), 0);
    for (std::int64_t Y = 0; Y < NY; ++Y)
      for (std::int64_t X = 0; X < NX; ++X) {
        const std::size_t v = std::size_t(X + NX * Y);
        const int id = here[v];
        if (id <= 0) continue;
        const int across[6] = {X > 0 ? here[v - 1] : 0,
                               X + 1 < NX ? here[v + 1] : 0,
                               Y > 0 ? here[v - NX] : 0,
                               Y + 1 < NY ? here[v + NX] : 0,
                               below[v],
                               above[v]};
        const std::int64_t p[3] = {X, Y, Z};
        for (int f = 0; f < 6; ++f)
          if (across[f] != id) files[std::size_t(id - 1)]->quad(f / 2, f % 2, p, h);
      }
    below.swap(here);
    here.swap(above);
    progress.tick();
  }
  progress.done();
  StlExport result;
  for (auto& file : files) {
    file->finish();
    result.paths.push_back(file->path());
    result.triangles.push_back(file->triangles());
  }
  return result;
}

// ---------------------------------------------------------------------------
// PNG slices

Rgb slice_color(int id) {
  switch (id) {
    case 0: return {255, 255, 255};
    case 1: return {40, 40, 40};
    case 2: return {230, 120, 30};
    default: return {0, 110, 220};
  }
}

std::int64_t write_png_slices(const std::string& folder, const VoxelModel& model) {
  std::error_code ec;
  fs::create_directories(folder, ec);
  if (ec) throw std::runtime_error(folder + ": cannot create the folder (" + ec.message() + ")");
  const std::int64_t NX = model.nx(), NY = model.ny(), NZ = model.nz();
  const int digits = std::max(5, int(std::to_string(NZ - 1).size()));
  // Layers are independent and PNG compression dominates: one layer per
  // thread at a time (each holds its own layer and image).
  Progress progress("png slices", std::uint64_t(NZ));
  std::exception_ptr failure;
#pragma omp parallel
  {
    std::vector<int> ids;
#pragma omp for schedule(dynamic, 1)
    for (std::int64_t Z = 0; Z < NZ; ++Z) {
      try {
        model.layer(Z, ids);
        PngImage image(static_cast<int>(NX), static_cast<int>(NY));
        for (std::int64_t Y = 0; Y < NY; ++Y)
          for (std::int64_t X = 0; X < NX; ++X)
            image.set(int(X), int(NY - 1 - Y), slice_color(ids[std::size_t(X + NX * Y)]));
        std::string number = std::to_string(Z);
        number.insert(0, std::size_t(std::max(0, digits - int(number.size()))), '0');
        image.write_png((fs::path(folder) / ("z" + number + ".png")).string());
        progress.tick();
      } catch (...) {
#pragma omp critical(msfab_png_slices)
        if (!failure) failure = std::current_exception();
      }
    }
  }
  if (failure) std::rethrow_exception(failure);
  progress.done();
  return NZ;
}

}  // namespace msfab
