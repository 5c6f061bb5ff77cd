#pragma once
// How much memory a run may use, and the up-front refusal of runs that
// would not fit. Each stage estimates its dominant arrays from its inputs
// (cell voxels, grid elements, population, sweep, sample counts) before any
// work and asks StageContext::check_memory(); a run that cannot fit exits 2
// with the estimate and the limit instead of ending in bad_alloc, swapping,
// or being killed hours later.
//
// The limit is the memory available now (MemAvailable of /proc/meminfo,
// lowered by a cgroup's memory.max when the process runs in one), or the
// size given with --memory-limit (e.g. 64G, 512M, or a byte count), which
// overrides it in both directions: larger on a machine where the kernel's
// estimate is too cautious, smaller to keep room for other jobs.
#include <cstdint>
#include <string>

namespace msfab {

// Bytes the system can give this process now; 0 if it cannot tell.
std::uint64_t available_memory_bytes();

// "64G", "1.5G", "512M", "800K", "1000000" (bytes); powers of 1024.
// InputError naming `what` for anything else, zero, or beyond 2^60 bytes.
std::uint64_t parse_memory_size(const std::string& text, const std::string& what);

// "1.50 GiB", "312 MiB", "17 kiB", "100 B".
std::string format_bytes(double bytes);

}  // namespace msfab
