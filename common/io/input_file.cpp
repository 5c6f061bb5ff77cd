#include "io/input_file.hpp"

#include <fcntl.h>
#include <sys/stat.h>
#include <unistd.h>

#include <cerrno>
#include <cstring>
#include <filesystem>

#include "core/errors.hpp"

namespace msfab {
namespace {

const char* kind_of(mode_t mode) {
  if (S_ISDIR(mode)) return "a folder";
  if (S_ISFIFO(mode)) return "a FIFO (named pipe)";
  if (S_ISCHR(mode)) return "a character device";
  if (S_ISBLK(mode)) return "a block device";
  if (S_ISSOCK(mode)) return "a socket";
  return "not a regular file";
}

std::string mib(std::uint64_t bytes) {
  const double value = double(bytes) / double(1 << 20);
  char text[32];
  std::snprintf(text, sizeof text, value < 10 ? "%.1f MiB" : "%.0f MiB", value);
  return text;
}

// Opens `path` for reading without blocking (O_NONBLOCK keeps the open of a
// FIFO from waiting for a writer), then checks what it opened, so a file
// swapped for a FIFO between a check and the open cannot slip through.
// Returns the descriptor, in blocking mode again, and the size.
int open_regular(const std::string& path, std::uint64_t max_bytes, std::uint64_t& size) {
  const int fd = ::open(path.c_str(), O_RDONLY | O_NONBLOCK | O_CLOEXEC | O_NOCTTY);
  if (fd < 0) {
    const int err = errno;
    if (err == ENOENT) throw InputError(path + ": no such file");
    throw InputError(path + ": cannot open for reading (" + std::strerror(err) + ")");
  }
  struct stat st {};
  if (::fstat(fd, &st) != 0) {
    const int err = errno;
    ::close(fd);
    throw InputError(path + ": cannot read its status (" + std::strerror(err) + ")");
  }
  if (!S_ISREG(st.st_mode)) {
    ::close(fd);
    throw InputError(path + ": is " + kind_of(st.st_mode) + ", expected a regular file");
  }
  size = std::uint64_t(st.st_size);
  if (max_bytes > 0 && size > max_bytes) {
    ::close(fd);
    throw InputError(path + ": is " + std::to_string(size) + " bytes, more than the " + mib(max_bytes) +
                     " an input file of this kind may have");
  }
  const int flags = ::fcntl(fd, F_GETFL);
  if (flags >= 0) (void)::fcntl(fd, F_SETFL, flags & ~O_NONBLOCK);
  return fd;
}

}  // namespace

void require_regular_file(const std::string& path, std::uint64_t max_bytes) {
  std::uint64_t size = 0;
  ::close(open_regular(path, max_bytes, size));
}

std::string read_text_file(const std::string& path, std::uint64_t max_bytes) {
  std::uint64_t size = 0;
  const int fd = open_regular(path, max_bytes, size);
  std::string text;
  text.reserve(std::size_t(size));
  char block[1 << 16];
  for (;;) {
    const ssize_t n = ::read(fd, block, sizeof block);
    if (n < 0) {
      if (errno == EINTR) continue;
      const int err = errno;
      ::close(fd);
      throw InputError(path + ": read error (" + std::strerror(err) + ")");
    }
    if (n == 0) break;
    text.append(block, std::size_t(n));
    if (max_bytes > 0 && text.size() > max_bytes) {
      ::close(fd);
      throw InputError(path + ": grew past the " + mib(max_bytes) + " an input file of this kind may have");
    }
  }
  ::close(fd);
  return text;
}

bool same_file(const std::string& a, const std::string& b) {
  struct stat sa {
  }, sb{};
  const bool a_exists = ::stat(a.c_str(), &sa) == 0, b_exists = ::stat(b.c_str(), &sb) == 0;
  if (a_exists && b_exists) return sa.st_dev == sb.st_dev && sa.st_ino == sb.st_ino;
  if (a_exists != b_exists) return false;
  std::error_code ec_a, ec_b;
  const std::filesystem::path ca = std::filesystem::weakly_canonical(std::filesystem::absolute(a), ec_a);
  const std::filesystem::path cb = std::filesystem::weakly_canonical(std::filesystem::absolute(b), ec_b);
  if (ec_a || ec_b)
    return std::filesystem::absolute(a).lexically_normal() == std::filesystem::absolute(b).lexically_normal();
  return ca == cb;
}

}  // namespace msfab
