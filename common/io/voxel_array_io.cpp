#include "io/voxel_array_io.hpp"

#include <algorithm>
#include <cstring>
#include <limits>

#include "core/errors.hpp"
#include "io/input_file.hpp"
#include "io/path_names.hpp"

namespace msfab {
namespace {

struct ElementType {
  int bytes = 0;
  bool is_signed = false;
  bool big_endian = false;
};

// NumPy's type strings: byte order ('<', '>', '|', '='), kind ('u', 'i',
// 'b') and size in bytes, e.g. "<u2", "|u1", "|b1".
bool parse_descr(const std::string& descr, ElementType& type) {
  if (descr.size() != 3) return false;
  const char order = descr[0], kind = descr[1], size = descr[2];
  if (order != '<' && order != '>' && order != '|' && order != '=') return false;
  if (kind != 'u' && kind != 'i' && kind != 'b') return false;
  if (size != '1' && size != '2' && size != '4' && size != '8') return false;
  if (kind == 'b' && size != '1') return false;
  type.bytes = size - '0';
  type.is_signed = kind == 'i';
  type.big_endian = order == '>';
  return true;
}

bool raw_dtype_type(const std::string& name, ElementType& type) {
  const std::vector<std::string> names = raw_voxel_dtypes();
  const auto it = std::find(names.begin(), names.end(), name);
  if (it == names.end()) return false;
  type.is_signed = name[0] == 'i';
  type.bytes = std::stoi(name.substr(type.is_signed ? 3 : 4)) / 8;
  type.big_endian = false;
  return true;
}

// Value `index` of the array at `data`, as a signed 64-bit integer (uint64
// values above 2^63 - 1 come back negative and are refused as ids).
long long element(const char* data, std::size_t index, const ElementType& type) {
  unsigned char b[8];
  std::memcpy(b, data + index * type.bytes, type.bytes);
  if (type.big_endian) std::reverse(b, b + type.bytes);
  std::uint64_t u = 0;
  for (int k = type.bytes - 1; k >= 0; --k) u = (u << 8) | b[k];
  if (type.is_signed && type.bytes < 8 && (u >> (8 * type.bytes - 1)) & 1) u |= ~std::uint64_t(0) << (8 * type.bytes);
  return static_cast<long long>(u);
}

std::string shape_text(const std::vector<long long>& shape) {
  std::string s = "(";
  for (std::size_t a = 0; a < shape.size(); ++a) s += (a ? ", " : "") + std::to_string(shape[a]);
  return s + (shape.size() == 1 ? ",)" : ")");
}

// The value text of `key` in the header dictionary, e.g. "'<u1'", "False",
// "(4, 5, 6)".
std::string dictionary_value(const std::string& header, const std::string& key, const std::string& source) {
  const std::size_t at = header.find("'" + key + "'");
  if (at == std::string::npos) throw InputError(source + ": the .npy header has no '" + key + "'");
  std::size_t p = header.find(':', at);
  if (p == std::string::npos) throw InputError(source + ": malformed .npy header near '" + key + "'");
  p = header.find_first_not_of(' ', p + 1);
  if (p == std::string::npos) throw InputError(source + ": malformed .npy header near '" + key + "'");
  const char open = header[p];
  if (open == '(' || open == '\'') {
    const std::size_t end = header.find(open == '(' ? ')' : '\'', p + 1);
    if (end == std::string::npos) throw InputError(source + ": malformed .npy header near '" + key + "'");
    return header.substr(p, end + 1 - p);
  }
  const std::size_t end = header.find_first_of(",} ", p);
  return header.substr(p, end == std::string::npos ? std::string::npos : end - p);
}

std::vector<long long> parse_shape(const std::string& text, const std::string& source) {
  std::vector<long long> shape;
  std::size_t p = 1;  // after '('
  while (p < text.size()) {
    p = text.find_first_not_of(" ,", p);
    if (p == std::string::npos || text[p] == ')') break;
    std::size_t used = 0;
    try {
      shape.push_back(std::stoll(text.substr(p), &used));
    } catch (const std::exception&) {
      throw InputError(source + ": the .npy shape " + text + " is not a tuple of integers");
    }
    p += used;
  }
  return shape;
}

std::vector<int> ids_from(const char* data, const ElementType& type, int nx, int ny, int nz, bool x_fastest,
                          const std::string& source) {
  const std::size_t n = std::size_t(nx) * ny * nz;
  std::vector<int> ids(n);
  for (std::size_t m = 0; m < n; ++m) {
    const long long id = element(data, m, type);
    if (id < 0 || id > std::numeric_limits<int>::max())
      throw InputError(source + ": value " + std::to_string(id) + " at position " + std::to_string(m) +
                       " is not a material id (0 = void, 1, 2, ...)");
    std::size_t target = m;
    if (!x_fastest) {  // C order of a[i, j, k]: k fastest
      const std::size_t k = m % nz, j = (m / nz) % ny, i = m / (std::size_t(nz) * ny);
      target = i + std::size_t(nx) * (j + std::size_t(ny) * k);
    }
    ids[target] = static_cast<int>(id);
  }
  return ids;
}

std::string grid_text(int nx, int ny, int nz) {
  return std::to_string(nx) + " x " + std::to_string(ny) + " x " + std::to_string(nz);
}

}  // namespace

std::vector<std::string> raw_voxel_dtypes() {
  return {"uint8", "int8", "uint16", "int16", "uint32", "int32", "uint64", "int64"};
}

std::vector<int> parse_npy_voxel_ids(const std::string& bytes, const std::string& source, int nx, int ny, int nz) {
  // Format: magic "\x93NUMPY", major and minor version bytes, the header
  // length (uint16 in version 1, uint32 in 2 and 3), the header (a Python
  // dict literal), then the data.
  if (bytes.size() < 10 || bytes.compare(0, 6, "\x93NUMPY") != 0)
    throw InputError(source + ": not a .npy file (no \\x93NUMPY magic)");
  const int major = static_cast<unsigned char>(bytes[6]);
  if (major < 1 || major > 3)
    throw InputError(source + ": .npy format version " + std::to_string(major) + " is not supported");
  std::size_t header_length = 0, header_start = 0;
  if (major == 1) {
    header_length = static_cast<unsigned char>(bytes[8]) | (std::size_t(static_cast<unsigned char>(bytes[9])) << 8);
    header_start = 10;
  } else {
    if (bytes.size() < 12) throw InputError(source + ": truncated .npy header");
    for (int b = 3; b >= 0; --b) header_length = (header_length << 8) | static_cast<unsigned char>(bytes[8 + b]);
    header_start = 12;
  }
  if (header_start + header_length > bytes.size()) throw InputError(source + ": truncated .npy header");
  const std::string header = bytes.substr(header_start, header_length);

  const std::string descr_text = dictionary_value(header, "descr", source);
  const std::string descr = descr_text.size() >= 2 ? descr_text.substr(1, descr_text.size() - 2) : descr_text;
  ElementType type;
  if (!parse_descr(descr, type))
    throw InputError(source + ": dtype '" + descr +
                     "' is not supported (integer or bool ids: u1, i1, b1, u2, i2, u4, i4, u8, i8)");
  const std::string order = dictionary_value(header, "fortran_order", source);
  if (order != "True" && order != "False") throw InputError(source + ": malformed fortran_order '" + order + "'");
  const std::vector<long long> shape = parse_shape(dictionary_value(header, "shape", source), source);

  const bool flat_grid = nz == 1 && shape.size() == 2;
  if (!((shape.size() == 3 && shape[0] == nx && shape[1] == ny && shape[2] == nz) ||
        (flat_grid && shape[0] == nx && shape[1] == ny)))
    throw InputError(source + ": array of shape " + shape_text(shape) + " for a grid of " + grid_text(nx, ny, nz) +
                     " voxels (expected shape (" + std::to_string(nx) + ", " + std::to_string(ny) + ", " +
                     std::to_string(nz) + "), a[i, j, k] = voxel (i, j, k))");
  const std::size_t data_start = header_start + header_length;
  const std::uint64_t expected = std::uint64_t(nx) * ny * nz * type.bytes;
  if (bytes.size() - data_start != expected)
    throw InputError(source + ": " + std::to_string(bytes.size() - data_start) + " bytes of data for shape " +
                     shape_text(shape) + " of '" + descr + "' (" + std::to_string(expected) + " expected; truncated?)");
  // Fortran order stores a[i, j, k] with i fastest: the grid's own order.
  return ids_from(bytes.data() + data_start, type, nx, ny, nz, order == "True", source);
}

std::vector<int> read_voxel_ids(const std::string& path, int nx, int ny, int nz, const std::string& raw_dtype) {
  const bool npy = ends_with(path, ".npy");
  if (npy) return parse_npy_voxel_ids(read_text_file(path, kMaxVoxelArrayBytes), path, nx, ny, nz);
  ElementType type;
  if (!raw_dtype_type(raw_dtype, type)) {
    std::string names;
    for (const std::string& n : raw_voxel_dtypes()) names += (names.empty() ? "" : ", ") + n;
    throw InputError(path + ": a raw voxel file needs its dtype (one of " + names + ")" +
                     (raw_dtype.empty() ? "" : ", got '" + raw_dtype + "'"));
  }
  const std::string bytes = read_text_file(path, kMaxVoxelArrayBytes);
  const std::uint64_t expected = std::uint64_t(nx) * ny * nz * type.bytes;
  if (bytes.size() != expected)
    throw InputError(path + ": " + std::to_string(bytes.size()) + " bytes for a grid of " + grid_text(nx, ny, nz) +
                     " voxels of " + raw_dtype + " (" + std::to_string(expected) + " expected)");
  return ids_from(bytes.data(), type, nx, ny, nz, true, path);
}

}  // namespace msfab
