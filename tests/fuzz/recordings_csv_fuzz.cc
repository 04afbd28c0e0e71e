// libFuzzer target: the recordings CSV reader (core/recordings.h), and the
// writer on what it read. The only acceptable failure is InputError.
#include <cstddef>
#include <cstdint>
#include <sstream>
#include <string>

#include "core/input_error.h"
#include "core/recordings.h"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  std::istringstream in(std::string(reinterpret_cast<const char*>(data), size));
  try {
    const volmap::Recordings r = volmap::read_recordings_csv(in, "fuzz.csv");
    r.check_consistent();
    std::ostringstream out;
    volmap::write_recordings_csv(out, r);
  } catch (const volmap::InputError&) {
  }
  return 0;
}
