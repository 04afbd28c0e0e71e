// libFuzzer target: the NC reader, lexing and interpretation
// (gcode/nc_block.h, gcode/nc_interpreter.h), line by line as volmap post
// and verify read a program. The only acceptable failure is InputError;
// anything else (another exception, a crash, a leak, undefined behaviour,
// a non-finite coordinate in a motion) is a bug.
#include <cmath>
#include <cstddef>
#include <cstdint>
#include <cstdlib>
#include <string>
#include <string_view>

#include "core/input_error.h"
#include "gcode/nc_block.h"
#include "gcode/nc_interpreter.h"

namespace {

bool finite(const Eigen::Vector3d& v) { return v.allFinite(); }

void check_motion(const volmap::nc::Motion& m) {
  if (!finite(m.start_mm) || !finite(m.end_mm) || !finite(m.center_mm) ||
      !std::isfinite(m.r_mm) || !std::isfinite(m.clear_mm) || !std::isfinite(m.feed))
    std::abort();  // a non-finite number would reach the output
}

void run(std::string_view program, bool with_initial_position) {
  volmap::nc::ProgramSetup setup;
  setup.work_offset_mm[0] = Eigen::Vector3d(250, 200, 100);
  setup.tool_length_mm[1] = 50.0;
  setup.tool_length_mm[2] = 120.5;
  if (with_initial_position) setup.initial_position_mm = Eigen::Vector3d(0, 0, 300);
  volmap::nc::Interpreter interp(setup, "fuzz.ngc");
  volmap::nc::BlockEffect fx;
  int number = 0;
  size_t pos = 0;
  while (pos <= program.size()) {
    size_t eol = program.find('\n', pos);
    if (eol == std::string_view::npos) eol = program.size();
    std::string_view text = program.substr(pos, eol - pos);
    if (!text.empty() && text.back() == '\r') text.remove_suffix(1);
    ++number;
    const volmap::nc::Block b = volmap::nc::lex_block(text, number, "fuzz.ngc");
    interp.execute(b, fx);
    if (fx.has_motion) check_motion(fx.motion);
    pos = eol + 1;
  }
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  const std::string_view program(reinterpret_cast<const char*>(data), size);
  for (bool initial : {false, true}) {
    try {
      run(program, initial);
    } catch (const volmap::InputError&) {
      // refused with a message: fine
    }
  }
  return 0;
}
