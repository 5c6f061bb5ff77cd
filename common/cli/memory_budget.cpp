#include "cli/memory_budget.hpp"

#include <unistd.h>

#include <algorithm>
#include <cctype>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <fstream>
#include <sstream>

#include "core/errors.hpp"

namespace msfab {
namespace {

// MemAvailable in bytes, 0 when /proc/meminfo does not say.
std::uint64_t mem_available_from_proc() {
  std::ifstream in("/proc/meminfo");
  std::string line;
  while (std::getline(in, line)) {
    if (line.rfind("MemAvailable:", 0) != 0) continue;
    std::istringstream fields(line.substr(13));
    std::uint64_t kib = 0;
    if (fields >> kib) return kib * 1024;
  }
  return 0;
}

// What the process's cgroup (v2) still allows: memory.max - memory.current;
// 0 when there is no limit or no cgroup file.
std::uint64_t cgroup_headroom() {
  std::ifstream max_file("/sys/fs/cgroup/memory.max"), current_file("/sys/fs/cgroup/memory.current");
  std::string max_text;
  std::uint64_t current = 0;
  if (!(max_file >> max_text) || max_text == "max" || !(current_file >> current)) return 0;
  char* end = nullptr;
  const unsigned long long max = std::strtoull(max_text.c_str(), &end, 10);
  if (end == max_text.c_str() || max <= current) return 0;
  return max - current;
}

}  // namespace

std::uint64_t available_memory_bytes() {
  std::uint64_t available = mem_available_from_proc();
  if (available == 0) {
    const long pages = ::sysconf(_SC_AVPHYS_PAGES), page = ::sysconf(_SC_PAGESIZE);
    if (pages > 0 && page > 0) available = std::uint64_t(pages) * std::uint64_t(page);
  }
  const std::uint64_t headroom = cgroup_headroom();
  if (headroom > 0) available = available > 0 ? std::min(available, headroom) : headroom;
  return available;
}

std::uint64_t parse_memory_size(const std::string& text, const std::string& what) {
  const auto bad = [&] {
    return InputError(what + " '" + text + "': expected a size such as 64G, 512M or a byte count (> 0, < 2^60)");
  };
  if (text.empty()) throw bad();
  std::string number = text;
  double scale = 1;
  const char last = char(std::toupper(static_cast<unsigned char>(text.back())));
  if (last == 'K' || last == 'M' || last == 'G' || last == 'T') {
    number.pop_back();
    scale = last == 'K' ? 0x1p10 : last == 'M' ? 0x1p20 : last == 'G' ? 0x1p30 : 0x1p40;
  }
  if (number.empty() || number.find_first_not_of("0123456789.") != std::string::npos) throw bad();
  char* end = nullptr;
  const double value = std::strtod(number.c_str(), &end) * scale;
  if (end != number.c_str() + number.size() || !(value >= 1) || value >= 0x1p60) throw bad();
  return std::uint64_t(value);
}

std::string format_bytes(double bytes) {
  char text[32];
  if (bytes >= 0x1p30)
    std::snprintf(text, sizeof text, "%.2f GiB", bytes / 0x1p30);
  else if (bytes >= 0x1p20)
    std::snprintf(text, sizeof text, "%.0f MiB", bytes / 0x1p20);
  else if (bytes >= 0x1p10)
    std::snprintf(text, sizeof text, "%.0f kiB", bytes / 0x1p10);
  else
    std::snprintf(text, sizeof text, "%.0f B", bytes);
  return text;
}

}  // namespace msfab
