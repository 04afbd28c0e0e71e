// libFuzzer target: the machine definition reader (core/machine_json.h)
// and the nominal forward transformation of what it read at its home
// position. The only acceptable failure is InputError.
#include <cstddef>
#include <cstdint>
#include <cstdlib>
#include <sstream>
#include <string>

#include "core/input_error.h"
#include "core/machine_json.h"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  std::istringstream in(std::string(reinterpret_cast<const char*>(data), size));
  try {
    const volmap::Machine m = volmap::read_machine_json(in, "fuzz.json");
    volmap::AxisVector u(m.axis_count());
    for (int i = 0; i < m.axis_count(); ++i) {
      const volmap::AxisLimits& L = m.limits[static_cast<std::size_t>(i)];
      u[i] = L.unlimited ? 0.0 : 0.5 * (L.min + L.max);
    }
    const volmap::ToolPose p = volmap::nominal_forward(m, u);
    if (!p.tip_mm.allFinite() || !p.axis.allFinite()) std::abort();  // would reach an output
  } catch (const volmap::InputError&) {
  }
  return 0;
}
