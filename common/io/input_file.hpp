#pragma once
// Input files a stage reads: regular files of bounded size, opened so that
// a FIFO, a device (/dev/zero, /dev/stdin) or a folder is refused at once
// instead of read forever; and the same-file test behind the rule that an
// output may never be one of the run's inputs.
#include <cstdint>
#include <string>

namespace msfab {

// Largest YAML config a stage reads (real ones are a few kB).
inline constexpr std::uint64_t kMaxConfigBytes = std::uint64_t(16) << 20;
// Largest text input (voxel cells, marker tracks); a 512^3 cell of
// one-digit ids is 256 MiB.
inline constexpr std::uint64_t kMaxTextInputBytes = std::uint64_t(256) << 20;

// InputError naming `path` unless it exists, can be opened for reading and
// is a regular file (symlinks followed) of at most max_bytes (0: no limit).
// The check opens the file without blocking, so a FIFO with no writer does
// not hang it.
void require_regular_file(const std::string& path, std::uint64_t max_bytes = 0);

// The whole file as text, after the checks above; a file that grows past
// max_bytes while being read is refused too.
std::string read_text_file(const std::string& path, std::uint64_t max_bytes);

// True when both paths name the same file: the same device and inode when
// both exist (hard links and symlinks included), else the same normalized
// absolute path.
bool same_file(const std::string& a, const std::string& b);

}  // namespace msfab
