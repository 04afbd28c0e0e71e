// libFuzzer target: volmap::fuzz::nc_fanuc, the flattener in the Fanuc dialect (Custom
// Macro B, tests/fuzz/harness.h); seeded from tests/data/fanuc too
// (.ci/fuzz).
#include <cstddef>
#include <cstdint>
#include <string_view>

#include "tests/fuzz/harness.h"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  volmap::fuzz::nc_fanuc(std::string_view(reinterpret_cast<const char*>(data), size));
  return 0;
}
