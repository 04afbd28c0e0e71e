// libFuzzer target: volmap::fuzz::post (tests/fuzz/harness.h).
#include <cstddef>
#include <cstdint>
#include <string_view>

#include "tests/fuzz/harness.h"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  volmap::fuzz::post(std::string_view(reinterpret_cast<const char*>(data), size));
  return 0;
}
