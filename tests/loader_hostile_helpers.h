// Helpers shared by the hostile-input tests of the scene loaders (gltf_hostile_test.cpp,
// pbrt_hostile_test.cpp): a warning callback that keeps the warnings, and a substring test.
#pragma once

#include <string>
#include <vector>

namespace caustica::test {

inline std::vector<std::string> g_warnings;
inline void collect(const std::string& w) { g_warnings.push_back(w); }

inline bool contains(const std::string& text, const std::string& part) {
  return text.find(part) != std::string::npos;
}

}  // namespace caustica::test
