#include "io/atomic_file.hpp"

#include <fcntl.h>
#include <sys/random.h>
#include <sys/stat.h>
#include <unistd.h>

#include <cerrno>
#include <cstring>
#include <filesystem>
#include <random>
#include <stdexcept>

#include "core/errors.hpp"

namespace msfab {
namespace {

namespace fs = std::filesystem;

// Draws from the kernel's random source; the name of a temporary must not be
// predictable from the process id or the time.
std::uint64_t random_word() {
  std::uint64_t word = 0;
  if (::getrandom(&word, sizeof word, 0) == static_cast<ssize_t>(sizeof word)) return word;
  std::random_device device;
  return (std::uint64_t(device()) << 32) ^ device();
}

std::string hex16(std::uint64_t word) {
  static const char kDigits[] = "0123456789abcdef";
  std::string text(16, '0');
  for (int i = 15; i >= 0; --i, word >>= 4) text[std::size_t(i)] = kDigits[word & 0xf];
  return text;
}

std::string error_text(int err) { return std::strerror(err); }

}  // namespace

// Some file systems do not allow opening or syncing a folder; that is not an
// error of ours.
void sync_directory(const std::string& directory) {
  const int fd = ::open(directory.c_str(), O_RDONLY | O_DIRECTORY | O_CLOEXEC);
  if (fd < 0) return;
  (void)::fsync(fd);
  ::close(fd);
}

std::string parent_directory(const std::string& path) {
  const fs::path parent = fs::path(path).parent_path();
  return parent.empty() ? std::string(".") : parent.string();
}

AtomicFile::AtomicFile(std::string final_path) : path_(std::move(final_path)) {
  if (path_.empty()) throw InputError("empty output path");
  const std::string directory = parent_directory(path_);
  struct stat st {};
  if (::lstat(path_.c_str(), &st) == 0 && S_ISDIR(st.st_mode))
    throw InputError(path_ + ": is a folder, expected the path of a file to write");
  if (fs::path(path_).filename().empty())
    throw InputError(path_ + ": names a folder, expected the path of a file to write");
  for (int attempt = 0; attempt < 16; ++attempt) {
    tmp_path_ = path_ + "." + hex16(random_word()) + ".tmp";
    fd_ = ::open(tmp_path_.c_str(), O_WRONLY | O_CREAT | O_EXCL | O_NOFOLLOW | O_CLOEXEC, 0666);
    if (fd_ >= 0) return;
    const int err = errno;
    if (err == EEXIST || err == EINTR) continue;  // taken (or planted): draw another name
    tmp_path_.clear();
    switch (err) {
      case ENOENT: throw InputError(path_ + ": output folder does not exist (" + directory + ")");
      case ENOTDIR: throw InputError(path_ + ": '" + directory + "' is not a folder");
      case EACCES:
      case EPERM:
      case EROFS:
        throw InputError(path_ + ": output folder is not writable (" + directory + ": " + error_text(err) + ")");
      default:
        throw std::runtime_error(path_ + ": cannot create a temporary file in '" + directory + "' (" + error_text(err) +
                                 ")");
    }
  }
  tmp_path_.clear();
  throw std::runtime_error(path_ + ": no free temporary name after 16 attempts");
}

AtomicFile::~AtomicFile() {
  if (!committed_) discard();
}

void AtomicFile::write(const void* data, std::size_t size) {
  if (fd_ < 0) throw std::logic_error(path_ + ": write to a closed AtomicFile");
  const char* bytes = static_cast<const char*>(data);
  while (size > 0) {
    const ssize_t n = ::write(fd_, bytes, size);
    if (n < 0) {
      if (errno == EINTR) continue;
      throw std::runtime_error(path_ + ": writing " + tmp_path_ + " failed (" + error_text(errno) + ")");
    }
    bytes += n;
    size -= std::size_t(n);
  }
}

void AtomicFile::write_at(std::uint64_t offset, const void* data, std::size_t size) {
  if (fd_ < 0) throw std::logic_error(path_ + ": write to a closed AtomicFile");
  const char* bytes = static_cast<const char*>(data);
  while (size > 0) {
    const ssize_t n = ::pwrite(fd_, bytes, size, off_t(offset));
    if (n < 0) {
      if (errno == EINTR) continue;
      throw std::runtime_error(path_ + ": writing " + tmp_path_ + " failed (" + error_text(errno) + ")");
    }
    bytes += n;
    size -= std::size_t(n);
    offset += std::uint64_t(n);
  }
}

void AtomicFile::check_is_this_file(int other_fd) const {
  struct stat mine {
  }, theirs{};
  if (fd_ < 0 || ::fstat(fd_, &mine) != 0 || ::fstat(other_fd, &theirs) != 0 || mine.st_dev != theirs.st_dev ||
      mine.st_ino != theirs.st_ino)
    throw std::runtime_error(path_ + ": the temporary " + tmp_path_ + " was replaced while it was being opened");
}

void AtomicFile::sync() {
  if (committed_) throw std::logic_error(path_ + ": sync() after commit()");
  if (synced_) return;
  if (fd_ < 0) throw std::logic_error(path_ + ": sync() after discard()");
  if (::fsync(fd_) != 0)
    throw std::runtime_error(path_ + ": fsync of " + tmp_path_ + " failed (" + error_text(errno) + ")");
  const int status = ::close(fd_);
  fd_ = -1;
  if (status != 0) throw std::runtime_error(path_ + ": closing " + tmp_path_ + " failed (" + error_text(errno) + ")");
  synced_ = true;
}

std::string AtomicFile::release() {
  if (!synced_ || committed_) throw std::logic_error(path_ + ": release() needs sync() and no commit()");
  std::string tmp = tmp_path_;
  tmp_path_.clear();
  committed_ = true;  // nothing left for the destructor to do
  return tmp;
}

void AtomicFile::commit() {
  if (committed_) throw std::logic_error(path_ + ": commit() called twice");
  sync();
  if (::rename(tmp_path_.c_str(), path_.c_str()) != 0) {
    const int err = errno;
    throw std::runtime_error("cannot rename " + tmp_path_ + " to " + path_ + " (" + error_text(err) + ")");
  }
  committed_ = true;
  sync_directory(parent_directory(path_));
}

void AtomicFile::discard() noexcept {
  if (fd_ >= 0) {
    ::close(fd_);
    fd_ = -1;
  }
  if (!tmp_path_.empty() && !committed_) ::unlink(tmp_path_.c_str());
  tmp_path_.clear();
}

void write_file_atomically(const std::string& path, const std::string& contents) {
  AtomicFile out(path);
  out.write(contents);
  out.commit();
}

}  // namespace msfab
