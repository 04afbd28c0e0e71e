// Five-axis TCP programs of other controllers and their tape frames: the
// same tool path written with LinuxCNC's M428, Fanuc's G43.4, Haas's G234,
// Heidenhain's M128 and Siemens's TRAORI gives the same machine program;
// moves outside the switched-on part, tilted work planes and dynamic work
// offsets are refused with file:line; a listing header, '%' lines, a
// program number and a byte-order mark pass as they are.
#include <gtest/gtest.h>

#include <array>
#include <cstring>
#include <fstream>
#include <sstream>

#include "core/common/input_error.h"
#include "postproc/five_axis/five_axis_post.h"
#include "postproc/five_axis/five_axis_verify.h"
#include "tests/support/samples.h"
#include "tests/support/test_paths.h"

namespace volmap {
namespace {

std::string post_text(const std::string& program) {
  static const Machine m = test::sample_machine("lei-hsu-xyzac");
  static const ErrorSet e = test::sample_errors("lei-hsu-xyzac");
  post::FiveAxisPostOptions o;
  o.form = post::InputForm::kTcp;
  std::istringstream in(program);
  std::ostringstream out;
  post::post_five_axis(in, "p.ngc", out, m, e, o);
  return out.str();
}

std::string refusal(const std::string& program) {
  try {
    post_text(program);
  } catch (const InputError& e) {
    return e.what();
  }
  return "";
}

// The lines of the output that command axes.
std::vector<std::string> axis_lines(const std::string& text) {
  std::vector<std::string> out;
  std::istringstream in(text);
  std::string l;
  while (std::getline(in, l))
    if (l.find('X') != std::string::npos && l.find('(') == std::string::npos) out.push_back(l);
  return out;
}

const char* kPath =
    "G0 X10 Y0 Z30 A0 C0\nG1 X10 Y5 Z20 A-20 C30 F500\nG1 X0 Y5 Z20 A-35 C75\nG0 Z40\n";

TEST(FiveAxisDialects, EveryControllersTcpGivesTheSameMachineProgram) {
  const std::string body = std::string("G21 G90 G94\n") + kPath;
  const std::vector<std::string> linuxcnc = axis_lines(post_text("M428\n" + body + "M429\nM30\n"));
  ASSERT_GT(linuxcnc.size(), 4u);
  for (const auto& [on, off] :
       std::vector<std::pair<std::string, std::string>>{{"G43.4 H1\n", "G49\n"},
                                                        {"G43.5 H1\n", "G49\n"},
                                                        {"G234 H1\n", "G49\n"},
                                                        {"M128\n", "M129\n"},
                                                        {"N5 TRAORI\n", "TRAFOOF\n"},
                                                        {"TRAORI(1)\n", "TRAFOOF\n"}}) {
    SCOPED_TRACE(on);
    const std::string text = post_text(on + body + off + "M30\n");
    EXPECT_EQ(axis_lines(text), linuxcnc);
    EXPECT_EQ(text.find("G43.4"), std::string::npos);
    EXPECT_EQ(text.find("M128"), std::string::npos);
    EXPECT_EQ(text.find("H1"), std::string::npos);
    EXPECT_NE(text.find("removed"), std::string::npos);
  }
}

TEST(FiveAxisDialects, MovesOutsideTheTcpPartAreRefused) {
  EXPECT_EQ(refusal("G21 G90\nG0 X0 Y0 Z60 A0 C0\nG43.4 H1\nG0 Z50\nG49\nM30\n")
                .rfind("p.ngc:2:1: a move outside the program's TCP part", 0),
            0u);
  EXPECT_EQ(refusal("G21 G90\nG43.4 H1\nG0 X0 Y0 Z50 A0 C0\nG49\nG0 Z100\nM30\n")
                .rfind("p.ngc:5:1: a move outside", 0),
            0u);
  EXPECT_EQ(refusal("TRAORI\nG0 X0 Y0 Z50 A0 C0\nTRAFOOF\nG0 Z100\n").rfind("p.ngc:4:1:", 0), 0u);
  // H without a TCP code: a tool length the five-axis post does not read.
  EXPECT_EQ(refusal("G21 G90\nG0 X0 Y0 Z50 A0 C0 H1\n").rfind("p.ngc:2:", 0), 0u);
}

TEST(FiveAxisDialects, TiltedPlanesAndDynamicWorkOffsetsAreRefused) {
  for (const auto& [program, message] : std::vector<std::pair<std::string, std::string>>{
           {"G21 G90\nG68.2 X0 Y0 Z0 I0 J45 K0\n", "p.ngc:2:1: tilted work planes (3+2"},
           {"G21 G90\nG69\n", "p.ngc:2:1: tilted work planes"},
           {"CYCLE800(1,\"TABLE\",0,57,0,0,0,0,45,0,0,0,0,1,100,1)\n", "p.ngc:1:1: CYCLE800"},
           {"G21 G90\nG254\n", "p.ngc:2:1: Haas's dynamic work offset"},
           {":0097\nG21\n", "p.ngc:1:1: a ':' program number"}}) {
    SCOPED_TRACE(program);
    EXPECT_EQ(refusal(program).rfind(message, 0), 0u) << refusal(program);
  }
}

TEST(FiveAxisDialects, TapeFramePassesAsItIs) {
  const std::string program =
      "\xEF\xBB\xBFInformation listing created by NX\nPost: haas umc\n%\nO0001 (PART)\n"
      "G21 G90\nG43.4 H1\nG0 X10. Y0 Z30. A0 C0\nG49\nM30\n%\ntext after the tape\n";
  const std::string text = post_text(program);
  EXPECT_EQ(text.rfind("\xEF\xBB\xBFInformation listing created by NX\nPost: haas umc\n%\n"
                       "O0001 (PART)\nG21 G90\n",
                       0),
            0u)
      << text;
  EXPECT_NE(text.find("M30\n%\ntext after the tape\n"), std::string::npos) << text;
  // It opens with a Fanuc program number: every number written has its
  // point, and one read without it (least input increments there) is refused.
  const std::size_t move = text.find("\nG0 X");
  ASSERT_NE(move, std::string::npos) << text;
  const std::string line = text.substr(move + 1, text.find('\n', move + 1) - move - 1);
  for (std::size_t k = 0; k < line.size(); ++k)
    if (std::strchr("XYZAC", line[k])) {
      EXPECT_NE(line.find('.', k), std::string::npos) << line;
    }
  std::string integer = program;
  integer.replace(integer.find("X10."), 4, "X10");
  EXPECT_NE(refusal(integer).find("X has no decimal point"), std::string::npos) << refusal(integer);
}

// The sample tool-vector cone on the A-B dual-rotary table (A about -X
// carries the part, B about -Y the cradle) and on the head-head bridge mill
// (C and B in the spindle head): posted with their errors, verify finds the
// tip tens of um off before and within the tolerance after.
TEST(FiveAxisMachines, TableTableAndHeadHeadPostWithinTheTolerance) {
  std::ifstream f(test::source_path("samples/programs/cone-vector.ngc"));
  std::stringstream program;
  program << f.rdbuf();
  for (const char* name : {"xyzab-tdr", "bridgemill-bc-head"}) {
    SCOPED_TRACE(name);
    const Machine m = test::sample_machine(name);
    const ErrorSet e = test::sample_errors(name);
    std::istringstream in(program.str());
    std::ostringstream out;
    post::post_five_axis(in, "cone-vector.ngc", out, m, e, post::FiveAxisPostOptions{});
    EXPECT_NE(out.str().find(" B"), std::string::npos);
    std::istringstream nominal(program.str()), compensated(out.str());
    const post::FiveAxisVerifyResult r = post::verify_five_axis(
        nominal, "cone-vector.ngc", compensated, "out.ngc", m, e, post::FiveAxisVerifyOptions{});
    EXPECT_GT(r.before.max_um, 20.0);
    EXPECT_LT(r.after.max_um, 1.0);
    EXPECT_LT(r.after.max_urad, 50.0);
  }
}

// Real TCP programs (tests/data/real/tcp, SOURCES.md): each refused at the
// first line volmap cannot read exactly, with the reason; none is posted
// into something else.
TEST(FiveAxisDialects, RealTcpProgramsAreRefusedAtTheirLine) {
  const std::vector<std::array<std::string, 3>> cases = {
      {"linuxcnc-xyzab-tdr-demo.ngc", "xyzab-tdr", ":6:1: G10 is not supported"},
      {"linuxcnc-xyzac-switchkins-test2.ngc", "lei-hsu-xyzac", ":3:1: # parameters"},
      {"nx-haas-umc750-g234-final-toolpath.txt", "bc-table-table",
       ":7:1: 'OFINAL TOOLPATH' is not a program number"},
      {"sinumerik840d-cam-spinner-u5-achskreuz-traori.mpf", "bc-table-table",
       ":3:1: Siemens variable definitions (DEF)"}};
  for (const auto& [file, machine, message] : cases) {
    SCOPED_TRACE(file);
    const Machine m = test::sample_machine(machine);
    const ErrorSet e = test::sample_errors(machine);
    std::ifstream in(test::source_path("tests/data/real/tcp/" + file), std::ios::binary);
    std::ostringstream out;
    try {
      post::post_five_axis(in, file, out, m, e, post::FiveAxisPostOptions{});
      ADD_FAILURE() << "posted";
    } catch (const InputError& err) {
      EXPECT_EQ(std::string(err.what()).rfind(file + message, 0), 0u) << err.what();
    }
  }
}

}  // namespace
}  // namespace volmap
