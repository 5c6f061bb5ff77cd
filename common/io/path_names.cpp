#include "io/path_names.hpp"

namespace msfab {

bool ends_with(const std::string& path, const std::string& suffix) {
  return path.size() >= suffix.size() && path.compare(path.size() - suffix.size(), suffix.size(), suffix) == 0;
}

std::string without_suffix(const std::string& path, std::initializer_list<const char*> suffixes) {
  for (const std::string suffix : suffixes)
    if (path.size() > suffix.size() && ends_with(path, suffix)) return path.substr(0, path.size() - suffix.size());
  return path;
}

}  // namespace msfab
