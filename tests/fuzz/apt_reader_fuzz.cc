// libFuzzer target: volmap::fuzz::apt_reader (tests/fuzz/harness.h).
#include <cstddef>
#include <cstdint>
#include <string_view>

#include "tests/fuzz/harness.h"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  volmap::fuzz::apt_reader(std::string_view(reinterpret_cast<const char*>(data), size));
  return 0;
}
