// Paths of the repository and the built executable, independent of the
// working folder (set by tests/CMakeLists.txt).
#pragma once

#include <string>

namespace volmap::test {
inline std::string source_path(const std::string& relative) {
  return std::string(VOLMAP_SOURCE_DIR) + "/" + relative;
}
inline std::string volmap_binary() { return VOLMAP_BINARY; }
}  // namespace volmap::test
