#pragma once
// Output files that appear whole or not at all, through temporaries nobody
// else can claim. Every file a stage writes (artifacts, checkpoints, XDMF
// sidecars, CSV, PNG, STL) goes through AtomicFile.
//
// The temporary is "<dir>/<name>.<16 random hex digits>.tmp" beside the
// final path, created with O_CREAT | O_EXCL | O_NOFOLLOW, so it is always a
// new regular file made by this process: a file or symlink planted under any
// name is never followed or overwritten (its name would have to be guessed,
// and even then the exclusive create fails and another name is drawn), and
// two writers of the same output never share a temporary. commit() writes
// the data to the disk (fsync), renames the temporary over the final path
// (a symlink there is replaced, not written through) and syncs the folder,
// so after a crash or power loss the final path holds either the old or the
// new content. Destroyed without commit(), the temporary is removed and the
// final path is left as it was.
//
//   AtomicFile out(path);                 // InputError if the folder refuses
//   out.write(text);
//   out.commit();
//
// For files written by a library that opens them by name (HDF5), create the
// AtomicFile first, let the library open tmp_path() (it exists, so it is
// truncated, not created) and call check_is_this_file() with the library's
// descriptor: it fails unless the library opened this very file.
#include <cstddef>
#include <cstdint>
#include <string>

namespace msfab {

class AtomicFile {
 public:
  // Creates the temporary. A folder that is missing, not a folder, or not
  // writable is an InputError naming `final_path`; other failures throw
  // std::runtime_error.
  explicit AtomicFile(std::string final_path);
  AtomicFile(const AtomicFile&) = delete;
  AtomicFile& operator=(const AtomicFile&) = delete;
  ~AtomicFile();

  const std::string& path() const { return path_; }
  const std::string& tmp_path() const { return tmp_path_; }
  int fd() const { return fd_; }
  bool committed() const { return committed_; }

  // Appends bytes (std::runtime_error on a write error, e.g. a full disk).
  void write(const void* data, std::size_t size);
  void write(const std::string& text) { write(text.data(), text.size()); }
  // Writes at an absolute offset (patching a header); the append position
  // is not moved.
  void write_at(std::uint64_t offset, const void* data, std::size_t size);

  // std::runtime_error unless `other_fd` refers to the temporary (same
  // device and inode), i.e. nobody swapped another file in under its name
  // between its creation and a library opening it by name.
  void check_is_this_file(int other_fd) const;

  // fsync, rename over path(), fsync of the folder. Throws
  // std::runtime_error if the data cannot be made durable; path() then
  // still holds its previous content.
  void commit();
  // The first half of commit(): fsync and close the temporary, which then
  // holds its final content on disk (further writes are logic errors).
  void sync();
  // After sync(): hands the temporary over to someone else (a commit group's
  // journal, io/commit_group.hpp) and returns its name; the destructor no
  // longer removes it.
  std::string release();
  // Closes and removes the temporary now (the destructor's job otherwise).
  void discard() noexcept;

 private:
  std::string path_;
  std::string tmp_path_;
  int fd_ = -1;
  bool synced_ = false;
  bool committed_ = false;
};

// The whole of `contents` under `path`, atomically (an AtomicFile).
void write_file_atomically(const std::string& path, const std::string& contents);

// The folder a path lies in ("." for a bare file name).
std::string parent_directory(const std::string& path);

// Pushes a folder's entries (renames, removals) to the disk, so they
// survive a power loss.
void sync_directory(const std::string& directory);

}  // namespace msfab
