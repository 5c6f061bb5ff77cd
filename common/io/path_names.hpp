#pragma once
// Names derived from paths: the suffix tests that pick a reader by file
// kind, and the stems that a stage's side outputs are named after
// (<stem>.microstructures.h5 beside <stem>.gamut.h5, <stem>.plots/, ...).
#include <initializer_list>
#include <string>

namespace msfab {

bool ends_with(const std::string& path, const std::string& suffix);

// `path` without the first of `suffixes` (tried in order) that it ends in,
// provided something is left; otherwise `path` unchanged.
std::string without_suffix(const std::string& path, std::initializer_list<const char*> suffixes);

}  // namespace msfab
