#pragma once
// Wall-clock seconds for the stages' reports and timings.
#include <chrono>

namespace msfab {

inline double seconds_since(std::chrono::steady_clock::time_point start) {
  return std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
}

}  // namespace msfab
