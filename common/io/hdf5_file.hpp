#pragma once
// A small RAII layer over the HDF5 1.10 C API: files, groups, n-dimensional
// datasets of a few fixed dtypes, and attributes.
//
// Layout: datasets are C order (row-major, last index fastest), as HDF5
// itself and h5py/numpy use. Eigen matrices are written as shape
// (rows, cols) with each row contiguous, so `h5dump` and numpy show the
// matrix as it looks in C++; read_matrix() converts back.
//
// Errors: failures while reading throw InputError naming the file, the
// object and what was wrong ("out.h5: dataset '/u' not found"); failures
// while writing throw std::runtime_error. HDF5's own error printing is off.
// Floating-point values read back must be finite unless the caller passes
// Finite::nan_means_missing (for the few datasets where NaN marks a value
// that was not computed): a NaN or infinity that a damaged or hand-edited
// file carries is refused where it is read, naming the file, the object and
// the index, instead of surfacing later as "error nan".
// The HDF5 library is used from one thread at a time.
#include <hdf5.h>

#include <Eigen/Core>
#include <cstddef>
#include <cstdint>
#include <string>
#include <type_traits>
#include <vector>

namespace msfab {

class AtomicFile;

// The element types a dataset or numeric attribute may have.
enum class H5Dtype { kFloat64, kInt32, kInt64, kUInt8, kUInt64 };

// The dtype of a supported element type; any other T fails to compile.
template <class T>
struct H5DtypeOf {
  static_assert(std::is_same_v<T, double> || std::is_same_v<T, std::int32_t> || std::is_same_v<T, std::int64_t> ||
                    std::is_same_v<T, std::uint8_t> || std::is_same_v<T, std::uint64_t>,
                "T is not a supported HDF5 element type");
  static constexpr H5Dtype value = std::is_same_v<T, double>         ? H5Dtype::kFloat64
                                   : std::is_same_v<T, std::int32_t> ? H5Dtype::kInt32
                                   : std::is_same_v<T, std::int64_t> ? H5Dtype::kInt64
                                   : std::is_same_v<T, std::uint8_t> ? H5Dtype::kUInt8
                                                                     : H5Dtype::kUInt64;
};

const char* dtype_name(H5Dtype dtype);  // "float64", "int32", ...

// What a reader accepts in floating-point data (see the header comment).
enum class Finite { required, nan_means_missing };

// Owns one HDF5 identifier and releases it with the matching close call.
class H5Id {
 public:
  using Closer = herr_t (*)(hid_t);
  H5Id() = default;
  H5Id(hid_t id, Closer closer) : id_(id), closer_(closer) {}
  H5Id(const H5Id&) = delete;
  H5Id& operator=(const H5Id&) = delete;
  H5Id(H5Id&& other) noexcept : id_(other.id_), closer_(other.closer_) { other.id_ = -1; }
  H5Id& operator=(H5Id&& other) noexcept;
  ~H5Id() { reset(); }

  hid_t get() const { return id_; }
  bool valid() const { return id_ >= 0; }
  void reset() noexcept;  // closes now; errors are ignored
  herr_t close();         // closes now and reports the result

 private:
  hid_t id_ = -1;
  Closer closer_ = nullptr;
};

struct H5WriteOptions {
  // 0 stores the data as-is; 1..9 applies byte shuffle + gzip at that level.
  // Compressed datasets are chunked along the leading dimension(s) so one
  // chunk holds about chunk_bytes, which keeps partial reads cheap.
  int gzip_level = 0;
  std::size_t chunk_bytes = std::size_t(1) << 20;
};

// An n-dimensional array in C order. A scalar dataset has shape {}.
template <class T>
struct NdArray {
  std::vector<hsize_t> shape;
  std::vector<T> values;
};

class H5File {
 public:
  enum class Mode { kRead, kReadWrite };

  // Creates (or truncates) a file. Throws std::runtime_error.
  static H5File create(const std::string& path);
  // Creates the file inside `tmp`'s temporary (io/atomic_file.hpp) and checks
  // that HDF5 opened that very file; close() it, then tmp.commit().
  static H5File create_in(const AtomicFile& tmp);
  // Opens an existing file. Throws InputError "<path>: no such file" or
  // "<path>: not a valid HDF5 file (truncated or corrupt): <detail>".
  static H5File open(const std::string& path, Mode mode = Mode::kRead);

  H5File(H5File&&) noexcept = default;
  H5File& operator=(H5File&&) noexcept = default;
  ~H5File() = default;  // closes quietly; call close() to see errors

  const std::string& path() const { return path_; }
  bool is_open() const { return file_.valid(); }
  hid_t id() const { return file_.get(); }  // for what this wrapper lacks
  void flush();
  void close();

  // --- structure -------------------------------------------------------
  // Creates a group and any missing parents; a no-op if it exists.
  void create_group(const std::string& path);
  bool exists(const std::string& path) const;
  bool is_group(const std::string& path) const;
  bool is_dataset(const std::string& path) const;
  // Names of the direct children of a group, in name order.
  std::vector<std::string> children(const std::string& group) const;

  // --- writing datasets (parents are created; an existing path throws) ---
  template <class T>
  void write_dataset(const std::string& path, const T* data, const std::vector<hsize_t>& shape,
                     const H5WriteOptions& options = {}) {
    write_raw(path, H5DtypeOf<T>::value, data, shape, options);
  }
  template <class T>
  void write_dataset(const std::string& path, const std::vector<T>& values, const std::vector<hsize_t>& shape,
                     const H5WriteOptions& options = {}) {
    check_element_count(path, values.size(), shape);
    write_raw(path, H5DtypeOf<T>::value, values.data(), shape, options);
  }
  // Rank-1 dataset of shape (n).
  template <class T>
  void write_vector(const std::string& path, const std::vector<T>& values, const H5WriteOptions& options = {}) {
    write_raw(path, H5DtypeOf<T>::value, values.data(), {hsize_t(values.size())}, options);
  }
  template <class Derived>
  void write_vector(const std::string& path, const Eigen::DenseBase<Derived>& values,
                    const H5WriteOptions& options = {}) {
    static_assert(Derived::IsVectorAtCompileTime, "write_vector needs an Eigen vector");
    using Scalar = typename Derived::Scalar;
    const Eigen::Matrix<Scalar, Eigen::Dynamic, 1> copy = values.derived();
    write_raw(path, H5DtypeOf<Scalar>::value, copy.data(), {hsize_t(copy.size())}, options);
  }
  // Rank-2 dataset of shape (rows, cols), row-major.
  template <class Derived>
  void write_matrix(const std::string& path, const Eigen::DenseBase<Derived>& matrix,
                    const H5WriteOptions& options = {}) {
    using Scalar = typename Derived::Scalar;
    using RowMajor = Eigen::Matrix<Scalar, Eigen::Dynamic, Eigen::Dynamic, Eigen::RowMajor>;
    const RowMajor copy = matrix.derived();
    write_raw(path, H5DtypeOf<Scalar>::value, copy.data(), {hsize_t(copy.rows()), hsize_t(copy.cols())}, options);
  }

  // --- datasets written piece by piece (larger than memory) -------------
  // create_chunked_dataset makes a dataset of `shape` stored in chunks of
  // `chunk` (same rank, every entry >= 1; gzip_level 0..9 adds shuffle +
  // gzip) and writes no data: elements never written read as 0. write_slab
  // then fills the block of `count` elements per dimension starting at
  // `offset` from `data` (C order, count[0] * count[1] * ... values), so a
  // writer needs only one block in memory at a time. read_slab reads such a
  // block back (any dataset; same lossless conversions as read_dataset). A
  // block outside the dataset's shape throws std::out_of_range.
  //
  //   f.create_chunked_dataset<std::uint8_t>("/voxels", {layers, bytes}, {8, bytes}, 4);
  //   for (layer...) f.write_slab("/voxels", row.data(), {layer, 0}, {1, bytes});
  template <class T>
  void create_chunked_dataset(const std::string& path, const std::vector<hsize_t>& shape,
                              const std::vector<hsize_t>& chunk, int gzip_level = 0) {
    create_chunked_raw(path, H5DtypeOf<T>::value, shape, chunk, gzip_level);
  }
  template <class T>
  void write_slab(const std::string& path, const T* data, const std::vector<hsize_t>& offset,
                  const std::vector<hsize_t>& count) {
    write_slab_raw(path, H5DtypeOf<T>::value, data, offset, count);
  }
  template <class T>
  std::vector<T> read_slab(const std::string& path, const std::vector<hsize_t>& offset,
                           const std::vector<hsize_t>& count, Finite finite = Finite::required) const {
    std::vector<T> values(element_count(count));
    read_slab_raw(path, H5DtypeOf<T>::value, values.data(), offset, count);
    check_finite(path, {}, H5DtypeOf<T>::value, values.data(), values.size(), finite);
    return values;
  }

  // --- reading datasets --------------------------------------------------
  // A dataset is read as T when that is lossless: integers into a wide
  // enough integer type, floats (and integers up to 32 bit) into double.
  std::vector<hsize_t> dataset_shape(const std::string& path) const;
  template <class T>
  NdArray<T> read_dataset(const std::string& path, Finite finite = Finite::required) const {
    NdArray<T> array;
    array.shape = dataset_shape(path);
    array.values.resize(element_count(array.shape));
    read_raw(path, H5DtypeOf<T>::value, array.values.data(), array.values.size());
    check_finite(path, {}, H5DtypeOf<T>::value, array.values.data(), array.values.size(), finite);
    return array;
  }
  // Requires rank 1.
  template <class T>
  std::vector<T> read_vector(const std::string& path, Finite finite = Finite::required) const {
    const std::vector<hsize_t> shape = dataset_shape(path);
    check_rank(path, shape, 1);
    std::vector<T> values(shape[0]);
    read_raw(path, H5DtypeOf<T>::value, values.data(), values.size());
    check_finite(path, {}, H5DtypeOf<T>::value, values.data(), values.size(), finite);
    return values;
  }
  // Requires rank 2 and, when expected_cols >= 0, that many columns.
  template <class T>
  Eigen::Matrix<T, Eigen::Dynamic, Eigen::Dynamic> read_matrix(const std::string& path, Eigen::Index expected_cols = -1,
                                                               Finite finite = Finite::required) const {
    const std::vector<hsize_t> shape = dataset_shape(path);
    check_rank(path, shape, 2);
    if (expected_cols >= 0) check_cols(path, shape, expected_cols);
    Eigen::Matrix<T, Eigen::Dynamic, Eigen::Dynamic, Eigen::RowMajor> row_major(static_cast<Eigen::Index>(shape[0]),
                                                                                static_cast<Eigen::Index>(shape[1]));
    read_raw(path, H5DtypeOf<T>::value, row_major.data(), std::size_t(row_major.size()));
    check_finite(path, {}, H5DtypeOf<T>::value, row_major.data(), std::size_t(row_major.size()), finite);
    return row_major;
  }

  // --- attributes on "/", a group or a dataset (overwritten if present) --
  void write_attribute(const std::string& object, const std::string& name, const std::string& value);
  void write_attribute(const std::string& object, const std::string& name, const char* value) {
    write_attribute(object, name, std::string(value));
  }
  template <class T>
  void write_attribute(const std::string& object, const std::string& name, T value) {
    write_attribute_raw(object, name, H5DtypeOf<T>::value, &value, 1, true);
  }
  template <class T>
  void write_attribute(const std::string& object, const std::string& name, const std::vector<T>& values) {
    write_attribute_raw(object, name, H5DtypeOf<T>::value, values.data(), values.size(), false);
  }

  bool has_attribute(const std::string& object, const std::string& name) const;
  std::string read_string_attribute(const std::string& object, const std::string& name) const;
  // Requires a single value.
  template <class T>
  T read_attribute(const std::string& object, const std::string& name, Finite finite = Finite::required) const {
    T value{};
    read_attribute_raw(object, name, H5DtypeOf<T>::value, &value, 1, true);
    check_finite(object, name, H5DtypeOf<T>::value, &value, 1, finite);
    return value;
  }
  template <class T>
  std::vector<T> read_attribute_vector(const std::string& object, const std::string& name,
                                       Finite finite = Finite::required) const {
    std::vector<T> values(attribute_size(object, name));
    read_attribute_raw(object, name, H5DtypeOf<T>::value, values.data(), values.size(), false);
    check_finite(object, name, H5DtypeOf<T>::value, values.data(), values.size(), finite);
    return values;
  }

 private:
  H5File(std::string path, H5Id file) : path_(std::move(path)), file_(std::move(file)) {}

  static std::size_t element_count(const std::vector<hsize_t>& shape);
  void check_element_count(const std::string& path, std::size_t count, const std::vector<hsize_t>& shape) const;
  void check_rank(const std::string& path, const std::vector<hsize_t>& shape, std::size_t rank) const;
  void check_cols(const std::string& path, const std::vector<hsize_t>& shape, Eigen::Index expected_cols) const;
  void write_raw(const std::string& path, H5Dtype dtype, const void* data, const std::vector<hsize_t>& shape,
                 const H5WriteOptions& options);
  void read_raw(const std::string& path, H5Dtype dtype, void* data, std::size_t count) const;
  // InputError naming the file, the dataset (or the attribute `attribute` on
  // `object`) and the first bad index unless every float64 value is finite
  // (NaN allowed with Finite::nan_means_missing). Other dtypes pass.
  void check_finite(const std::string& object, const std::string& attribute, H5Dtype dtype, const void* data,
                    std::size_t count, Finite finite) const;
  void create_chunked_raw(const std::string& path, H5Dtype dtype, const std::vector<hsize_t>& shape,
                          const std::vector<hsize_t>& chunk, int gzip_level);
  void write_slab_raw(const std::string& path, H5Dtype dtype, const void* data, const std::vector<hsize_t>& offset,
                      const std::vector<hsize_t>& count);
  void read_slab_raw(const std::string& path, H5Dtype dtype, void* data, const std::vector<hsize_t>& offset,
                     const std::vector<hsize_t>& count) const;
  void write_attribute_raw(const std::string& object, const std::string& name, H5Dtype dtype, const void* data,
                           std::size_t count, bool scalar);
  void read_attribute_raw(const std::string& object, const std::string& name, H5Dtype dtype, void* data,
                          std::size_t count, bool scalar) const;
  std::size_t attribute_size(const std::string& object, const std::string& name) const;
  H5Id open_object_for_reading(const std::string& object) const;
  H5Id open_attribute_for_reading(const std::string& object, const std::string& name) const;
  void require_open() const;

  std::string path_;
  H5Id file_;
};

}  // namespace msfab
