#pragma once
// Process-wide malloc settings for the stages.
//
// glibc gives every freed block above its mmap threshold back to the
// kernel, and trims the heap top above its trim threshold. The stages
// allocate and free the same few-hundred-kilobyte arrays thousands of
// times (a homogenization per structure, an MMA evaluation per step), so
// each allocation faulted in fresh zeroed pages: the 2D auxetic gamut spent
// 49 s of a 73 s run in the kernel. Raising the thresholds keeps freed
// memory for reuse (the same run: 3 s in the kernel, 50 s wall;
// docs/BENCHMARKS.md). Arrays above 256 MB are still mapped and unmapped
// on their own, so a large run's peak does not linger.
namespace msfab {

// Applies the settings unless the user set any of glibc's MALLOC_*_
// tuning variables (those win). No effect without glibc.
void keep_freed_memory_for_reuse();

}  // namespace msfab
