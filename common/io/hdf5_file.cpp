#include "io/hdf5_file.hpp"

#include <algorithm>
#include <cerrno>
#include <cmath>
#include <cstring>
#include <filesystem>
#include <stdexcept>
#include <utility>

#include "core/errors.hpp"
#include "io/atomic_file.hpp"
#include "io/input_file.hpp"

namespace msfab {
namespace {

// HDF5 prints its error stack to stderr by default. We report errors as
// exceptions instead. In a thread-safe HDF5 build the setting is per thread.
void silence_hdf5_errors() {
  thread_local bool silenced = false;
  if (!silenced) {
    H5Eset_auto2(H5E_DEFAULT, nullptr, nullptr);
    silenced = true;
  }
}

herr_t keep_innermost_description(unsigned /*n*/, const H5E_error2_t* error, void* client) {
  auto* text = static_cast<std::string*>(client);
  if (text->empty() && error->desc != nullptr) *text = error->desc;
  return 0;
}

// The most specific message on HDF5's error stack, e.g.
// "truncated file: eof = 1024, sblock->base_addr = 0, stored_eof = 2048".
std::string hdf5_error_detail() {
  std::string text;
  H5Ewalk2(H5E_DEFAULT, H5E_WALK_UPWARD, keep_innermost_description, &text);
  H5Eclear2(H5E_DEFAULT);
  return text.empty() ? std::string("unknown HDF5 error") : text;
}

hid_t file_type_of(H5Dtype dtype) {
  switch (dtype) {
    case H5Dtype::kFloat64: return H5T_IEEE_F64LE;
    case H5Dtype::kInt32: return H5T_STD_I32LE;
    case H5Dtype::kInt64: return H5T_STD_I64LE;
    case H5Dtype::kUInt8: return H5T_STD_U8LE;
    case H5Dtype::kUInt64: return H5T_STD_U64LE;
  }
  throw std::logic_error("unknown H5Dtype");
}

hid_t memory_type_of(H5Dtype dtype) {
  switch (dtype) {
    case H5Dtype::kFloat64: return H5T_NATIVE_DOUBLE;
    case H5Dtype::kInt32: return H5T_NATIVE_INT32;
    case H5Dtype::kInt64: return H5T_NATIVE_INT64;
    case H5Dtype::kUInt8: return H5T_NATIVE_UINT8;
    case H5Dtype::kUInt64: return H5T_NATIVE_UINT64;
  }
  throw std::logic_error("unknown H5Dtype");
}

std::size_t size_of(H5Dtype dtype) { return dtype == H5Dtype::kUInt8 ? 1 : dtype == H5Dtype::kInt32 ? 4 : 8; }

// Describes a stored type the way numpy names dtypes.
std::string describe_type(hid_t type) {
  const H5T_class_t type_class = H5Tget_class(type);
  const std::size_t bits = 8 * H5Tget_size(type);
  switch (type_class) {
    case H5T_FLOAT: return "float" + std::to_string(bits);
    case H5T_INTEGER: return (H5Tget_sign(type) == H5T_SGN_NONE ? "uint" : "int") + std::to_string(bits);
    case H5T_STRING: return "string";
    case H5T_COMPOUND: return "compound";
    default: return "an unsupported type";
  }
}

// True when every value of the stored type fits the requested one exactly.
bool converts_losslessly(hid_t stored, H5Dtype wanted) {
  const H5T_class_t stored_class = H5Tget_class(stored);
  const std::size_t stored_size = H5Tget_size(stored);
  const bool stored_signed = H5Tget_sign(stored) != H5T_SGN_NONE;
  if (wanted == H5Dtype::kFloat64) {
    return stored_class == H5T_FLOAT || (stored_class == H5T_INTEGER && stored_size <= 4);
  }
  if (stored_class != H5T_INTEGER) return false;
  const bool wanted_signed = wanted == H5Dtype::kInt32 || wanted == H5Dtype::kInt64;
  const std::size_t wanted_size = size_of(wanted);
  if (stored_signed == wanted_signed) return stored_size <= wanted_size;
  return !stored_signed && wanted_signed && stored_size < wanted_size;
}

std::vector<std::string> split_path(const std::string& path) {
  std::vector<std::string> parts;
  std::size_t start = 0;
  while (start <= path.size()) {
    const std::size_t slash = path.find('/', start);
    const std::size_t end = slash == std::string::npos ? path.size() : slash;
    if (end > start) parts.push_back(path.substr(start, end - start));
    if (slash == std::string::npos) break;
    start = slash + 1;
  }
  return parts;
}

H5Id link_creation_with_parents() {
  H5Id lcpl(H5Pcreate(H5P_LINK_CREATE), H5Pclose);
  H5Pset_create_intermediate_group(lcpl.get(), 1);
  return lcpl;
}

// Chunks of about target_bytes: trailing dimensions are kept whole and the
// leading ones are cut, so a chunk is a contiguous block of rows.
std::vector<hsize_t> chunk_shape(const std::vector<hsize_t>& shape, std::size_t element_size,
                                 std::size_t target_bytes) {
  std::vector<hsize_t> chunk = shape;
  for (std::size_t d = 0; d < chunk.size(); ++d) {
    hsize_t inner_bytes = element_size;
    for (std::size_t k = d + 1; k < chunk.size(); ++k) inner_bytes *= chunk[k];
    if (inner_bytes * chunk[d] <= target_bytes) break;
    chunk[d] = std::max<hsize_t>(1, target_bytes / inner_bytes);
    if (chunk[d] > 1) break;
  }
  return chunk;
}

bool gzip_available() {
  static const bool available = H5Zfilter_avail(H5Z_FILTER_DEFLATE) > 0;
  return available;
}

}  // namespace

const char* dtype_name(H5Dtype dtype) {
  switch (dtype) {
    case H5Dtype::kFloat64: return "float64";
    case H5Dtype::kInt32: return "int32";
    case H5Dtype::kInt64: return "int64";
    case H5Dtype::kUInt8: return "uint8";
    case H5Dtype::kUInt64: return "uint64";
  }
  return "unknown";
}

// ---------------------------------------------------------------------------
// H5Id

H5Id& H5Id::operator=(H5Id&& other) noexcept {
  if (this != &other) {
    reset();
    id_ = other.id_;
    closer_ = other.closer_;
    other.id_ = -1;
  }
  return *this;
}

void H5Id::reset() noexcept {
  if (id_ >= 0 && closer_ != nullptr) closer_(id_);
  id_ = -1;
}

herr_t H5Id::close() {
  herr_t status = 0;
  if (id_ >= 0 && closer_ != nullptr) status = closer_(id_);
  id_ = -1;
  return status;
}

// ---------------------------------------------------------------------------
// Opening and closing

H5File H5File::create(const std::string& path) {
  silence_hdf5_errors();
  H5Id access(H5Pcreate(H5P_FILE_ACCESS), H5Pclose);
  // Closing the file closes it for real even if an object id leaked, so a
  // following rename never races with buffered writes.
  H5Pset_fclose_degree(access.get(), H5F_CLOSE_STRONG);
  // The 1.8 file format checksums its metadata, so a damaged file is far
  // more often refused with an error instead of being read as garbage; every
  // HDF5 reader since 2008 (h5py, ParaView) opens it.
  H5Pset_libver_bounds(access.get(), H5F_LIBVER_V18, H5F_LIBVER_V18);
  H5Id file(H5Fcreate(path.c_str(), H5F_ACC_TRUNC, H5P_DEFAULT, access.get()), H5Fclose);
  if (!file.valid()) {
    throw std::runtime_error(path + ": cannot create HDF5 file (" + hdf5_error_detail() + ")");
  }
  return H5File(path, std::move(file));
}

H5File H5File::create_in(const AtomicFile& tmp) {
  // HDF5 opens files by name. Through /proc/self/fd it reopens the inode the
  // temporary's descriptor holds, so a file or symlink swapped in under the
  // temporary's name meanwhile is never opened, let alone truncated; where
  // /proc is missing the name is used and the check below catches a swap.
  const std::string by_descriptor = "/proc/self/fd/" + std::to_string(tmp.fd());
  std::error_code ec;
  const bool proc = std::filesystem::exists(by_descriptor, ec);
  H5File created = create(proc ? by_descriptor : tmp.tmp_path());
  created.path_ = tmp.tmp_path();
  void* handle = nullptr;
  if (H5Fget_vfd_handle(created.id(), H5P_DEFAULT, &handle) < 0 || handle == nullptr) {
    throw std::runtime_error(tmp.tmp_path() + ": cannot reach the file HDF5 opened (" + hdf5_error_detail() + ")");
  }
  tmp.check_is_this_file(*static_cast<int*>(handle));
  return created;
}

H5File H5File::open(const std::string& path, Mode mode) {
  silence_hdf5_errors();
  require_regular_file(path);  // a FIFO or a device would block or read forever
  if (H5Fis_hdf5(path.c_str()) <= 0) {
    H5Eclear2(H5E_DEFAULT);
    throw InputError(path + ": not a valid HDF5 file (truncated or corrupt: no HDF5 signature)");
  }
  H5Id access(H5Pcreate(H5P_FILE_ACCESS), H5Pclose);
  H5Pset_fclose_degree(access.get(), H5F_CLOSE_STRONG);
  const unsigned flags = mode == Mode::kRead ? H5F_ACC_RDONLY : H5F_ACC_RDWR;
  H5Id file(H5Fopen(path.c_str(), flags, access.get()), H5Fclose);
  if (!file.valid()) {
    const std::string detail = hdf5_error_detail();
    if (detail.find("unable to lock") != std::string::npos) {
      throw InputError(path + ": cannot open, the file is in use by another process (" + detail + ")");
    }
    throw InputError(path + ": not a valid HDF5 file (truncated or corrupt: " + detail + ")");
  }
  return H5File(path, std::move(file));
}

void H5File::require_open() const {
  if (!file_.valid()) throw std::logic_error(path_ + ": HDF5 file used after close()");
  silence_hdf5_errors();
}

void H5File::flush() {
  require_open();
  if (H5Fflush(file_.get(), H5F_SCOPE_GLOBAL) < 0) {
    throw std::runtime_error(path_ + ": flushing the HDF5 file failed (" + hdf5_error_detail() + ")");
  }
}

void H5File::close() {
  if (!file_.valid()) return;
  silence_hdf5_errors();
  if (file_.close() < 0) {
    throw std::runtime_error(path_ + ": closing the HDF5 file failed (" + hdf5_error_detail() + ")");
  }
}

// ---------------------------------------------------------------------------
// Structure

bool H5File::exists(const std::string& path) const {
  require_open();
  // H5Lexists fails, rather than answering false, when a parent is missing,
  // so walk the path one link at a time.
  std::string prefix;
  for (const std::string& part : split_path(path)) {
    prefix += "/" + part;
    if (H5Lexists(file_.get(), prefix.c_str(), H5P_DEFAULT) <= 0) {
      H5Eclear2(H5E_DEFAULT);
      return false;
    }
  }
  return true;
}

bool H5File::is_group(const std::string& path) const {
  if (!exists(path)) return false;
  H5Id object(H5Oopen(file_.get(), path.c_str(), H5P_DEFAULT), H5Oclose);
  return object.valid() && H5Iget_type(object.get()) == H5I_GROUP;
}

bool H5File::is_dataset(const std::string& path) const {
  if (!exists(path)) return false;
  H5Id object(H5Oopen(file_.get(), path.c_str(), H5P_DEFAULT), H5Oclose);
  return object.valid() && H5Iget_type(object.get()) == H5I_DATASET;
}

void H5File::create_group(const std::string& path) {
  require_open();
  if (exists(path)) {
    if (is_group(path)) return;
    throw std::runtime_error(path_ + ": cannot create group '" + path + "', a dataset has that name");
  }
  H5Id lcpl = link_creation_with_parents();
  H5Id group(H5Gcreate2(file_.get(), path.c_str(), lcpl.get(), H5P_DEFAULT, H5P_DEFAULT), H5Gclose);
  if (!group.valid()) {
    throw std::runtime_error(path_ + ": cannot create group '" + path + "' (" + hdf5_error_detail() + ")");
  }
}

namespace {
herr_t collect_child_name(hid_t, const char* name, const H5L_info_t*, void* client) {
  static_cast<std::vector<std::string>*>(client)->emplace_back(name);
  return 0;
}
}  // namespace

std::vector<std::string> H5File::children(const std::string& group) const {
  require_open();
  if (!is_group(group)) throw InputError(path_ + ": group '" + group + "' not found");
  H5Id handle(H5Gopen2(file_.get(), group.c_str(), H5P_DEFAULT), H5Gclose);
  std::vector<std::string> names;
  if (H5Literate(handle.get(), H5_INDEX_NAME, H5_ITER_INC, nullptr, collect_child_name, &names) < 0) {
    throw InputError(path_ + ": cannot list group '" + group + "' (" + hdf5_error_detail() + ")");
  }
  return names;
}

// ---------------------------------------------------------------------------
// Datasets

std::size_t H5File::element_count(const std::vector<hsize_t>& shape) {
  std::size_t count = 1;
  for (hsize_t extent : shape) count *= std::size_t(extent);
  return count;
}

void H5File::check_element_count(const std::string& path, std::size_t count, const std::vector<hsize_t>& shape) const {
  if (count != element_count(shape)) {
    throw std::runtime_error(path_ + ": dataset '" + path + "' given " + std::to_string(count) +
                             " values but its shape holds " + std::to_string(element_count(shape)));
  }
}

namespace {
std::string shape_text(const std::vector<hsize_t>& shape) {
  std::string text = "(";
  for (std::size_t d = 0; d < shape.size(); ++d) {
    text += (d ? ", " : "") + std::to_string(shape[d]);
  }
  return text + ")";
}
}  // namespace

void H5File::check_rank(const std::string& path, const std::vector<hsize_t>& shape, std::size_t rank) const {
  if (shape.size() != rank) {
    throw InputError(path_ + ": dataset '" + path + "' has shape " + shape_text(shape) + ", expected rank " +
                     std::to_string(rank));
  }
}

void H5File::check_cols(const std::string& path, const std::vector<hsize_t>& shape, Eigen::Index expected_cols) const {
  if (shape[1] != hsize_t(expected_cols)) {
    throw InputError(path_ + ": dataset '" + path + "' has shape " + shape_text(shape) + ", expected " +
                     std::to_string(expected_cols) + " columns");
  }
}

void H5File::write_raw(const std::string& path, H5Dtype dtype, const void* data, const std::vector<hsize_t>& shape,
                       const H5WriteOptions& options) {
  require_open();
  if (exists(path)) throw std::runtime_error(path_ + ": '" + path + "' already exists");
  H5Id space(shape.empty() ? H5Screate(H5S_SCALAR) : H5Screate_simple(int(shape.size()), shape.data(), nullptr),
             H5Sclose);
  if (!space.valid()) {
    throw std::runtime_error(path_ + ": bad shape " + shape_text(shape) + " for '" + path + "'");
  }
  const std::size_t count = element_count(shape);
  H5Id create(H5Pcreate(H5P_DATASET_CREATE), H5Pclose);
  if (options.gzip_level > 0 && !shape.empty() && count > 0) {
    if (!gzip_available()) throw std::runtime_error("this HDF5 library has no gzip filter");
    const std::vector<hsize_t> chunk = chunk_shape(shape, size_of(dtype), options.chunk_bytes);
    H5Pset_chunk(create.get(), int(chunk.size()), chunk.data());
    H5Pset_shuffle(create.get());
    H5Pset_deflate(create.get(), unsigned(std::min(options.gzip_level, 9)));
  }
  H5Id lcpl = link_creation_with_parents();
  H5Id dataset(
      H5Dcreate2(file_.get(), path.c_str(), file_type_of(dtype), space.get(), lcpl.get(), create.get(), H5P_DEFAULT),
      H5Dclose);
  if (!dataset.valid()) {
    throw std::runtime_error(path_ + ": cannot create dataset '" + path + "' (" + hdf5_error_detail() + ")");
  }
  if (count > 0 && H5Dwrite(dataset.get(), memory_type_of(dtype), H5S_ALL, H5S_ALL, H5P_DEFAULT, data) < 0) {
    throw std::runtime_error(path_ + ": writing dataset '" + path + "' failed (" + hdf5_error_detail() + ")");
  }
  if (dataset.close() < 0) {
    throw std::runtime_error(path_ + ": closing dataset '" + path + "' failed (" + hdf5_error_detail() + ")");
  }
}

std::vector<hsize_t> H5File::dataset_shape(const std::string& path) const {
  require_open();
  if (!is_dataset(path)) throw InputError(path_ + ": dataset '" + path + "' not found");
  H5Id dataset(H5Dopen2(file_.get(), path.c_str(), H5P_DEFAULT), H5Dclose);
  H5Id space(H5Dget_space(dataset.get()), H5Sclose);
  const int rank = H5Sget_simple_extent_ndims(space.get());
  if (rank < 0) {
    throw InputError(path_ + ": dataset '" + path + "' has an unreadable shape (" + hdf5_error_detail() + ")");
  }
  std::vector<hsize_t> shape(std::size_t(rank), 0);
  if (rank > 0) H5Sget_simple_extent_dims(space.get(), shape.data(), nullptr);
  return shape;
}

void H5File::read_raw(const std::string& path, H5Dtype dtype, void* data, std::size_t count) const {
  require_open();
  if (!is_dataset(path)) throw InputError(path_ + ": dataset '" + path + "' not found");
  H5Id dataset(H5Dopen2(file_.get(), path.c_str(), H5P_DEFAULT), H5Dclose);
  H5Id stored_type(H5Dget_type(dataset.get()), H5Tclose);
  if (!converts_losslessly(stored_type.get(), dtype)) {
    throw InputError(path_ + ": dataset '" + path + "' holds " + describe_type(stored_type.get()) +
                     ", cannot read it as " + dtype_name(dtype));
  }
  H5Id space(H5Dget_space(dataset.get()), H5Sclose);
  const hssize_t stored_count = H5Sget_simple_extent_npoints(space.get());
  if (stored_count < 0 || std::size_t(stored_count) != count) {
    throw InputError(path_ + ": dataset '" + path + "' holds " + std::to_string(stored_count) + " values, expected " +
                     std::to_string(count));
  }
  if (count > 0 && H5Dread(dataset.get(), memory_type_of(dtype), H5S_ALL, H5S_ALL, H5P_DEFAULT, data) < 0) {
    throw InputError(path_ + ": reading dataset '" + path + "' failed (file corrupt? " + hdf5_error_detail() + ")");
  }
}

void H5File::check_finite(const std::string& object, const std::string& attribute, H5Dtype dtype, const void* data,
                          std::size_t count, Finite finite) const {
  if (dtype != H5Dtype::kFloat64) return;
  const double* values = static_cast<const double*>(data);
  for (std::size_t i = 0; i < count; ++i) {
    const double v = values[i];
    if (std::isfinite(v) || (finite == Finite::nan_means_missing && std::isnan(v))) continue;
    const std::string where =
        attribute.empty() ? "dataset '" + object + "'" : "attribute '" + attribute + "' on '" + object + "'";
    throw InputError(path_ + ": " + where + " holds " + (std::isnan(v) ? "NaN" : "an infinite value") +
                     (count > 1 ? " at index " + std::to_string(i) : std::string()) +
                     "; the file is damaged or was not written by msfab");
  }
}

// ---------------------------------------------------------------------------
// Datasets written and read piece by piece

void H5File::create_chunked_raw(const std::string& path, H5Dtype dtype, const std::vector<hsize_t>& shape,
                                const std::vector<hsize_t>& chunk, int gzip_level) {
  require_open();
  if (exists(path)) throw std::runtime_error(path_ + ": '" + path + "' already exists");
  if (shape.empty() || chunk.size() != shape.size())
    throw std::logic_error(path_ + ": chunked dataset '" + path + "' needs a chunk shape of rank " +
                           std::to_string(shape.size()) + " >= 1");
  for (hsize_t c : chunk)
    if (c == 0) throw std::logic_error(path_ + ": chunked dataset '" + path + "': chunk extents must be >= 1");
  H5Id space(H5Screate_simple(int(shape.size()), shape.data(), nullptr), H5Sclose);
  if (!space.valid()) throw std::runtime_error(path_ + ": bad shape " + shape_text(shape) + " for '" + path + "'");
  H5Id create(H5Pcreate(H5P_DATASET_CREATE), H5Pclose);
  H5Pset_chunk(create.get(), int(chunk.size()), chunk.data());
  if (gzip_level > 0) {
    if (!gzip_available()) throw std::runtime_error("this HDF5 library has no gzip filter");
    H5Pset_shuffle(create.get());
    H5Pset_deflate(create.get(), unsigned(std::min(gzip_level, 9)));
  }
  H5Id lcpl = link_creation_with_parents();
  H5Id dataset(
      H5Dcreate2(file_.get(), path.c_str(), file_type_of(dtype), space.get(), lcpl.get(), create.get(), H5P_DEFAULT),
      H5Dclose);
  if (!dataset.valid())
    throw std::runtime_error(path_ + ": cannot create dataset '" + path + "' (" + hdf5_error_detail() + ")");
  if (dataset.close() < 0)
    throw std::runtime_error(path_ + ": closing dataset '" + path + "' failed (" + hdf5_error_detail() + ")");
}

namespace {
// Selects offset/count in the dataset's file space (std::out_of_range naming
// the dataset when the block does not fit). Returns the file space and a
// matching memory space.
std::pair<H5Id, H5Id> select_slab(const std::string& file, const std::string& path, hid_t dataset,
                                  const std::vector<hsize_t>& offset, const std::vector<hsize_t>& count) {
  H5Id space(H5Dget_space(dataset), H5Sclose);
  const int rank = H5Sget_simple_extent_ndims(space.get());
  std::vector<hsize_t> shape(std::size_t(std::max(rank, 0)), 0);
  if (rank > 0) H5Sget_simple_extent_dims(space.get(), shape.data(), nullptr);
  bool fits = offset.size() == shape.size() && count.size() == shape.size() && rank > 0;
  for (std::size_t d = 0; fits && d < shape.size(); ++d) fits = offset[d] + count[d] <= shape[d];
  if (!fits)
    throw std::out_of_range(file + ": dataset '" + path + "' of shape " + shape_text(shape) +
                            " has no block at offset " + shape_text(offset) + " of " + shape_text(count));
  H5Sselect_hyperslab(space.get(), H5S_SELECT_SET, offset.data(), nullptr, count.data(), nullptr);
  H5Id memory(H5Screate_simple(int(count.size()), count.data(), nullptr), H5Sclose);
  return {std::move(space), std::move(memory)};
}
}  // namespace

void H5File::write_slab_raw(const std::string& path, H5Dtype dtype, const void* data,
                            const std::vector<hsize_t>& offset, const std::vector<hsize_t>& count) {
  require_open();
  if (!is_dataset(path)) throw std::runtime_error(path_ + ": dataset '" + path + "' not found");
  H5Id dataset(H5Dopen2(file_.get(), path.c_str(), H5P_DEFAULT), H5Dclose);
  auto [space, memory] = select_slab(path_, path, dataset.get(), offset, count);
  if (element_count(count) > 0 &&
      H5Dwrite(dataset.get(), memory_type_of(dtype), memory.get(), space.get(), H5P_DEFAULT, data) < 0)
    throw std::runtime_error(path_ + ": writing a block of dataset '" + path + "' failed (" + hdf5_error_detail() +
                             ")");
}

void H5File::read_slab_raw(const std::string& path, H5Dtype dtype, void* data, const std::vector<hsize_t>& offset,
                           const std::vector<hsize_t>& count) const {
  require_open();
  if (!is_dataset(path)) throw InputError(path_ + ": dataset '" + path + "' not found");
  H5Id dataset(H5Dopen2(file_.get(), path.c_str(), H5P_DEFAULT), H5Dclose);
  H5Id stored_type(H5Dget_type(dataset.get()), H5Tclose);
  if (!converts_losslessly(stored_type.get(), dtype))
    throw InputError(path_ + ": dataset '" + path + "' holds " + describe_type(stored_type.get()) +
                     ", cannot read it as " + dtype_name(dtype));
  auto [space, memory] = select_slab(path_, path, dataset.get(), offset, count);
  if (element_count(count) > 0 &&
      H5Dread(dataset.get(), memory_type_of(dtype), memory.get(), space.get(), H5P_DEFAULT, data) < 0)
    throw InputError(path_ + ": reading a block of dataset '" + path + "' failed (file corrupt? " +
                     hdf5_error_detail() + ")");
}

// ---------------------------------------------------------------------------
// Attributes

namespace {
std::string on_object(const std::string& name, const std::string& object) {
  return "attribute '" + name + "' on '" + object + "'";
}
}  // namespace

H5Id H5File::open_object_for_reading(const std::string& object) const {
  require_open();
  if (!exists(object)) throw InputError(path_ + ": object '" + object + "' not found");
  H5Id handle(H5Oopen(file_.get(), object.c_str(), H5P_DEFAULT), H5Oclose);
  if (!handle.valid()) {
    throw InputError(path_ + ": cannot open '" + object + "' (" + hdf5_error_detail() + ")");
  }
  return handle;
}

H5Id H5File::open_attribute_for_reading(const std::string& object, const std::string& name) const {
  H5Id target = open_object_for_reading(object);
  if (H5Aexists(target.get(), name.c_str()) <= 0) {
    H5Eclear2(H5E_DEFAULT);
    throw InputError(path_ + ": " + on_object(name, object) + " not found");
  }
  H5Id attribute(H5Aopen(target.get(), name.c_str(), H5P_DEFAULT), H5Aclose);
  if (!attribute.valid()) {
    throw InputError(path_ + ": cannot open " + on_object(name, object) + " (" + hdf5_error_detail() + ")");
  }
  return attribute;
}

bool H5File::has_attribute(const std::string& object, const std::string& name) const {
  require_open();
  if (!exists(object)) return false;
  H5Id target(H5Oopen(file_.get(), object.c_str(), H5P_DEFAULT), H5Oclose);
  const htri_t found = target.valid() ? H5Aexists(target.get(), name.c_str()) : -1;
  H5Eclear2(H5E_DEFAULT);
  return found > 0;
}

namespace {
// Opens the object and removes an attribute of that name so it can be
// re-created with a new type or size.
H5Id open_for_attribute_write(hid_t file, const std::string& file_path, const std::string& object,
                              const std::string& name) {
  H5Id target(H5Oopen(file, object.c_str(), H5P_DEFAULT), H5Oclose);
  if (!target.valid()) {
    throw std::runtime_error(file_path + ": cannot write " + on_object(name, object) + ", the object does not exist");
  }
  if (H5Aexists(target.get(), name.c_str()) > 0 && H5Adelete(target.get(), name.c_str()) < 0) {
    throw std::runtime_error(file_path + ": cannot replace " + on_object(name, object) + " (" + hdf5_error_detail() +
                             ")");
  }
  return target;
}
}  // namespace

void H5File::write_attribute(const std::string& object, const std::string& name, const std::string& value) {
  require_open();
  H5Id target = open_for_attribute_write(file_.get(), path_, object, name);
  // Variable-length UTF-8: the text lives in the global heap, so long
  // values (a whole config file) do not hit the 64 KiB object-header limit,
  // and h5py reads it back as str.
  H5Id type(H5Tcopy(H5T_C_S1), H5Tclose);
  H5Tset_size(type.get(), H5T_VARIABLE);
  H5Tset_cset(type.get(), H5T_CSET_UTF8);
  H5Id space(H5Screate(H5S_SCALAR), H5Sclose);
  H5Id attribute(H5Acreate2(target.get(), name.c_str(), type.get(), space.get(), H5P_DEFAULT, H5P_DEFAULT), H5Aclose);
  const char* text = value.c_str();
  if (!attribute.valid() || H5Awrite(attribute.get(), type.get(), &text) < 0) {
    throw std::runtime_error(path_ + ": writing " + on_object(name, object) + " failed (" + hdf5_error_detail() + ")");
  }
}

void H5File::write_attribute_raw(const std::string& object, const std::string& name, H5Dtype dtype, const void* data,
                                 std::size_t count, bool scalar) {
  require_open();
  H5Id target = open_for_attribute_write(file_.get(), path_, object, name);
  const hsize_t extent = count;
  H5Id space(scalar ? H5Screate(H5S_SCALAR) : H5Screate_simple(1, &extent, nullptr), H5Sclose);
  H5Id attribute(H5Acreate2(target.get(), name.c_str(), file_type_of(dtype), space.get(), H5P_DEFAULT, H5P_DEFAULT),
                 H5Aclose);
  if (!attribute.valid() || (count > 0 && H5Awrite(attribute.get(), memory_type_of(dtype), data) < 0)) {
    throw std::runtime_error(path_ + ": writing " + on_object(name, object) + " failed (" + hdf5_error_detail() + ")");
  }
}

std::size_t H5File::attribute_size(const std::string& object, const std::string& name) const {
  H5Id attribute = open_attribute_for_reading(object, name);
  H5Id space(H5Aget_space(attribute.get()), H5Sclose);
  const hssize_t count = H5Sget_simple_extent_npoints(space.get());
  if (count < 0) {
    throw InputError(path_ + ": " + on_object(name, object) + " has an unreadable shape");
  }
  return std::size_t(count);
}

void H5File::read_attribute_raw(const std::string& object, const std::string& name, H5Dtype dtype, void* data,
                                std::size_t count, bool scalar) const {
  H5Id attribute = open_attribute_for_reading(object, name);
  H5Id stored_type(H5Aget_type(attribute.get()), H5Tclose);
  if (!converts_losslessly(stored_type.get(), dtype)) {
    throw InputError(path_ + ": " + on_object(name, object) + " holds " + describe_type(stored_type.get()) +
                     ", expected " + dtype_name(dtype));
  }
  H5Id space(H5Aget_space(attribute.get()), H5Sclose);
  const hssize_t stored_count = H5Sget_simple_extent_npoints(space.get());
  if (stored_count < 0 || std::size_t(stored_count) != count) {
    throw InputError(path_ + ": " + on_object(name, object) + " holds " + std::to_string(stored_count) +
                     " values, expected " + (scalar ? std::string("a single value") : std::to_string(count)));
  }
  if (count > 0 && H5Aread(attribute.get(), memory_type_of(dtype), data) < 0) {
    throw InputError(path_ + ": reading " + on_object(name, object) + " failed (" + hdf5_error_detail() + ")");
  }
}

std::string H5File::read_string_attribute(const std::string& object, const std::string& name) const {
  H5Id attribute = open_attribute_for_reading(object, name);
  H5Id stored_type(H5Aget_type(attribute.get()), H5Tclose);
  if (H5Tget_class(stored_type.get()) != H5T_STRING) {
    throw InputError(path_ + ": " + on_object(name, object) + " holds " + describe_type(stored_type.get()) +
                     ", expected a string");
  }
  H5Id space(H5Aget_space(attribute.get()), H5Sclose);
  if (H5Sget_simple_extent_npoints(space.get()) != 1) {
    throw InputError(path_ + ": " + on_object(name, object) + " is an array, expected one string");
  }
  const auto fail = [&] {
    return InputError(path_ + ": reading " + on_object(name, object) + " failed (" + hdf5_error_detail() + ")");
  };
  if (H5Tis_variable_str(stored_type.get()) > 0) {
    H5Id memory_type(H5Tcopy(H5T_C_S1), H5Tclose);
    H5Tset_size(memory_type.get(), H5T_VARIABLE);
    H5Tset_cset(memory_type.get(), H5Tget_cset(stored_type.get()));
    char* text = nullptr;
    if (H5Aread(attribute.get(), memory_type.get(), &text) < 0) throw fail();
    std::string value = text != nullptr ? std::string(text) : std::string();
    H5free_memory(text);
    return value;
  }
  // Fixed-length strings, as other tools may write them.
  const std::size_t size = H5Tget_size(stored_type.get());
  std::string buffer(size, '\0');
  if (H5Aread(attribute.get(), stored_type.get(), buffer.data()) < 0) throw fail();
  const std::size_t nul = buffer.find('\0');
  if (nul != std::string::npos) buffer.resize(nul);
  if (H5Tget_strpad(stored_type.get()) == H5T_STR_SPACEPAD) {
    buffer.erase(buffer.find_last_not_of(' ') + 1);
  }
  return buffer;
}

}  // namespace msfab
