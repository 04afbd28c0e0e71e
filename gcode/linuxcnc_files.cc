#include "gcode/linuxcnc_files.h"

#include <fmt/format.h>

#include <cmath>
#include <fstream>
#include <optional>
#include <sstream>
#include <stdexcept>

#include "core/common/input_error.h"

namespace volmap::nc {
namespace {

// Calls read_line(line, number) for every line of one of LinuxCNC's files
// (numbers from 1); `what` names the file when it cannot be opened.
template <class ReadLine>
void for_each_line(const std::string& path, const char* what, ReadLine read_line) {
  std::ifstream in(path);
  if (!in) throw InputError(path, 0, fmt::format("cannot open the {}; check the path", what));
  std::string line;
  int n = 0;
  while (std::getline(in, line)) read_line(line, ++n);
}

}  // namespace

void read_var_file(const std::string& path, ProgramSetup& setup) {
  for_each_line(path, "parameter (.var) file", [&](const std::string& line, int n) {
    std::istringstream ls(line);
    int param;
    double value;
    if (!(ls >> param)) return;
    if (!(ls >> value) || !std::isfinite(value))
      throw InputError(path, n, "expected \"<parameter> <value>\"");
    setup.parameters[param] = value;
    // G54: 5221..5223, each following system 20 further, up to G59.3 (5381).
    if (param >= 5221 && param <= 5383) {
      const int k = (param - 5221) / 20, a = (param - 5221) % 20;
      if (a < 3 && k < 9) setup.work_offset_mm[static_cast<size_t>(k)][a] = value;
    }
  });
}

void read_tool_table(const std::string& path, ProgramSetup& setup) {
  for_each_line(path, "tool table (.tbl)", [&](std::string line, int n) {
    const size_t semi = line.find(';');
    if (semi != std::string::npos) line.resize(semi);
    std::istringstream ls(line);
    std::string tok;
    int tool = -1;
    std::optional<double> z, d, q;
    while (ls >> tok) {
      const char L = static_cast<char>(std::toupper(static_cast<unsigned char>(tok[0])));
      double v = 0;
      try {
        size_t used = 0;
        v = std::stod(tok.substr(1), &used);
        if (used != tok.size() - 1) throw std::invalid_argument("x");
      } catch (const std::exception&) {
        throw InputError(
            path, n,
            fmt::format("bad entry \"{}\"; expected letter and number (T1 P1 Z12.5)", tok));
      }
      if (!std::isfinite(v))  // std::stod reads nan and inf
        throw InputError(
            path, n,
            fmt::format("bad entry \"{}\": not a finite number; give the tool length offset in mm",
                        tok));
      if (L == 'T' && (v < 0 || v != std::floor(v) || v > kMaxToolNumber))
        throw InputError(path, n,
                         fmt::format("bad entry \"{}\": a tool number is an integer from 0 to {}",
                                     tok, kMaxToolNumber));
      if (L == 'T') tool = static_cast<int>(v);
      if (L == 'Z') z = v;
      if (L == 'D') d = v;
      if (L == 'Q') q = v;
    }
    if (tool < 0) return;
    setup.tool_length_mm[tool] = z.value_or(0.0);
    if (d) setup.tool_diameter_mm[tool] = *d;
    if (q && *q != 0 && *q != 9) setup.tool_orientation[tool] = static_cast<int>(*q);
  });
}

}  // namespace volmap::nc
