// libFuzzer target: the errors readers (core/errors_csv.h and, by format
// detection, the ISG CSV and Etalon importers of core/errors_import.h), and
// an evaluation of every table read at its ends and beyond. The only
// acceptable failure is InputError.
#include <cstddef>
#include <cstdint>
#include <sstream>
#include <string>

#include "core/errors_import.h"
#include "core/input_error.h"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  std::istringstream in(std::string(reinterpret_cast<const char*>(data), size));
  try {
    (void)volmap::read_errors(in, "fuzz.csv", volmap::ErrorsFormat::kAuto);
  } catch (const volmap::InputError&) {
  }
  return 0;
}
