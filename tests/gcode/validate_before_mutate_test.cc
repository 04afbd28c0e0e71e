// grbl's discipline, which nc_interpreter.h promises: validate before
// mutate. A block the interpreter refuses leaves its state exactly as it
// was (every field of State), whatever step refused it.
#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>
#include <sstream>
#include <string>
#include <vector>

#include "core/common/input_error.h"
#include "gcode/nc_interpreter.h"

namespace volmap::nc {
namespace {

namespace fs = std::filesystem;

std::string source_path(const std::string& relative) {
  return std::string(VOLMAP_SOURCE_DIR) + "/" + relative;
}

// The setup the bad-input catalogue's NC cases run with (tests/cli/
// bad_inputs_test.cc): --work-offset 250,200,100 --tool-table tests/bad/tool.tbl.
ProgramSetup catalogue_setup() {
  ProgramSetup setup;
  setup.work_offset_mm[0] = Eigen::Vector3d(250, 200, 100);
  read_tool_table(source_path("tests/bad/tool.tbl"), setup);
  return setup;
}

// Runs `lines` through an interpreter until a block is refused. Returns
// whether the interpreter refused one (a line the lexer refuses ends the
// run without); `state_kept` says whether the refusal left the state as it
// was before the block.
bool refusal_keeps_state(const std::vector<std::string>& lines, const std::string& name,
                         bool& state_kept) {
  Interpreter interp(catalogue_setup(), name);
  BlockEffect effect;
  for (size_t k = 0; k < lines.size(); ++k) {
    Block b;
    try {
      b = lex_block(lines[k], static_cast<int>(k) + 1, name);
    } catch (const InputError&) {
      return false;
    }
    const State before = interp.state();
    try {
      interp.execute(b, effect);
    } catch (const InputError&) {
      state_kept = interp.state() == before;
      return true;
    }
  }
  return false;
}

std::vector<std::string> split_lines(const std::string& text) {
  std::vector<std::string> lines;
  std::istringstream in(text);
  for (std::string line; std::getline(in, line);) lines.push_back(line);
  return lines;
}

TEST(ValidateBeforeMutate, EveryRefusalOfTheBadInputCatalogueKeepsTheState) {
  int refusals = 0;
  for (const fs::directory_entry& e : fs::directory_iterator(source_path("tests/bad/nc"))) {
    if (e.path().extension() != ".ngc") continue;
    std::ifstream in(e.path());
    std::stringstream text;
    text << in.rdbuf();
    bool state_kept = false;
    if (!refusal_keeps_state(split_lines(text.str()), e.path().filename().string(), state_kept))
      continue;  // refused by the lexer or the post-processor, not the interpreter
    ++refusals;
    EXPECT_TRUE(state_kept) << e.path().filename();
  }
  EXPECT_GE(refusals, 40);  // the catalogue's interpreter cases all ran
}

// Blocks whose refusal comes after a word the block had already taken in
// (a feed rate, units, a plane, a tool length, a distance mode, a motion
// mode, a cycle's R and Z, a spindle change): the state keeps none of it.
TEST(ValidateBeforeMutate, ARefusedBlockTakesInNoneOfItsWords) {
  const char* cases[] = {
      "G0 X0 Y0 Z0\nG1 X5 F200 T-1",                    // F, then T refused
      "G0 X0 Y0 Z0\nG20 G18 G43 H9",                    // units and plane, then tool 9 unknown
      "G0 X0 Y0 Z50\nG43 H1 G91 G53 X1",                // tool length, G91, then G53 refused
      "G0 X0 Y0 Z5\nM3 G99 F10 G81 X1 Y1 Z5 R1",        // spindle, G99, R Z, bottom above R
      "G0 X0 Y0 Z5\nG93 G1 X1 Y1 F2 I4",                // feed mode, motion, then I unused
      "G0 X1 Y1 Z5\nF10 G2 X10 Y0 I3 J0",               // motion mode G2, then the radii
      "G0 X1 Y1 Z5 M3\nM5 F10 G86 X2 Y2 Z-1 R1 P1",     // the spindle stopped in the block
      "G0 X0 Y0 Z0\nG55 G90.1 G98 G19 G1 X1 Y1 F5 L2",  // modes, then L unused
  };
  for (const char* text : cases) {
    bool state_kept = false;
    ASSERT_TRUE(refusal_keeps_state(split_lines(text), "p.ngc", state_kept)) << text;
    EXPECT_TRUE(state_kept) << text;
  }
}

// check() is a dry run: it computes the state after a block and leaves the
// interpreter's; execute() then takes that state on.
TEST(ValidateBeforeMutate, CheckComputesTheStateExecuteTakesOn) {
  Interpreter interp(catalogue_setup(), "p.ngc");
  BlockEffect effect;
  interp.execute(lex_block("G0 X0 Y0 Z0", 1, "p.ngc"), effect);
  const State before = interp.state();
  const Block b = lex_block("G20 G91 G1 X1 F30", 2, "p.ngc");
  const State after = interp.check(b, effect);
  EXPECT_TRUE(interp.state() == before);
  EXPECT_FALSE(after == before);
  EXPECT_EQ(after.unit_mm, 25.4);
  interp.execute(b, effect);
  EXPECT_TRUE(interp.state() == after);
}

}  // namespace
}  // namespace volmap::nc
