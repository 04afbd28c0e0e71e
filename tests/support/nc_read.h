// A program read as the post reads it: each line from the program reader
// to the interpreter as soon as it comes (the system parameters are its
// state), for the tests of the NC language (tests/gcode, tests/postproc).
#pragma once

#include <istream>
#include <string>
#include <vector>

#include "gcode/nc_interpreter.h"
#include "gcode/program_reader.h"

namespace volmap::test {

struct NcReading {
  std::string out;                     ///< the lines handed out, each with '\n'
  std::vector<nc::BlockEffect> moves;  ///< the blocks that moved, in order
  nc::State state;                     ///< after the last line
  nc::ReadReport report;
};

/// Throws InputError as the post does.
inline NcReading read_nc(std::istream& in, const std::string& name, const nc::ProgramSetup& setup,
                         std::vector<std::string> subroutine_path = {}) {
  nc::Interpreter interp(setup, name);
  nc::ProgramReader reader(in, name, interp, std::move(subroutine_path));
  NcReading r;
  nc::ProgramLine l;
  nc::BlockEffect fx;
  while (reader.next(l)) {
    r.out.append(l.text);
    if (l.newline) r.out += '\n';
    if (l.verbatim) continue;
    nc::Block b = nc::lex_block(nc::flatten::without_cr(l.text), l.line, *l.file);
    b.evaluated = l.rewritten;
    interp.execute(b, fx);
    if (fx.has_motion) r.moves.push_back(fx);
  }
  r.state = interp.state();
  r.report = reader.report();
  return r;
}

}  // namespace volmap::test
