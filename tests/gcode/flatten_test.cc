// The flattener (gcode/flatten/) and the program reader (gcode/program_reader.h):
// parameters, expressions and O-word control flow evaluated as LinuxCNC's
// manual defines them, each expected value worked out by hand from the
// manual's rules (cited per test); the tape frame (byte-order mark, leader,
// trailer). tests/postproc/flatten_rs274_test.cc compares with rs274 itself.
#include <fmt/format.h>
#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>
#include <sstream>
#include <string>
#include <vector>

#include "core/common/input_error.h"
#include "gcode/nc_interpreter.h"
#include "gcode/program_reader.h"
#include "tests/support/cli_in_source.h"
#include "tests/support/nc_read.h"

namespace volmap {
namespace {

struct Read {
  std::string out;  ///< the lines handed out, each with '\n' (verbatim: as they are)
  std::vector<Eigen::Vector3d> ends;  ///< end of every motion, machine mm
  nc::ReadReport report;
};

// Reads `program` as the post does: each line to the interpreter as soon as
// it comes (the system parameters are its state).
Read read(const std::string& program, std::vector<std::string> path = {},
          nc::ProgramSetup setup = {}) {
  std::istringstream in(program);
  const test::NcReading n = test::read_nc(in, "p.ngc", setup, std::move(path));
  Read r{n.out, {}, n.report};
  for (const nc::BlockEffect& fx : n.moves) r.ends.push_back(fx.motion.end_mm);
  return r;
}

std::string flat(const std::string& program) { return read(program).out; }
// Read as LinuxCNC whatever its head (a program number O1001 would make
// --dialect auto read it as Fanuc).
std::string flat_linuxcnc(const std::string& program) {
  nc::ProgramSetup setup;
  setup.dialect = nc::Dialect::kLinuxCnc;
  return read(program, {}, setup).out;
}

std::string error_of(const std::string& program, std::vector<std::string> path = {}) {
  try {
    read(program, std::move(path));
  } catch (const InputError& e) {
    return e.what();
  }
  return "no error";
}

TEST(Flatten, AFlatProgramComesOutAsItIs) {
  const std::string p = "%\r\nG21 G90 (a comment with # and [ and o)\r\nG0 X1 Y2 Z3\r\nM2\r\n%\r\n";
  const Read r = read(p);
  EXPECT_EQ(r.out, p);
  EXPECT_EQ(r.report.flattened_from, 0);
}

// Manual, "Parameters": numbered parameters; assignments on a line take
// effect after the whole line is read ("#1=1 #2=#1" gives #2 the old #1).
TEST(Flatten, AssignmentsTakeEffectAfterTheLine) {
  EXPECT_EQ(flat("#1=3\n#1=5 #2=#1\nG0 X#1 Y#2 Z0\n"), "G0 X5 Y3 Z0\n");
  // Unset numbered parameters read 0.
  EXPECT_EQ(flat("G0 X#7 Y0 Z0\n"), "G0 X0 Y0 Z0\n");
  // Named: local and global, case and spaces folded.
  EXPECT_EQ(flat("#<Depth Of Cut> = 1.5\n#<_safe>=10\nG0 X#<depthofcut> Y#<_SAFE> Z0\n"),
            "G0 X1.5 Y10 Z0\n");
  // Indirection: ##1 is the parameter #1 names; #[1+1] is #2.
  EXPECT_EQ(flat("#1=2\n#2=7\nG0 X##1 Y#[1+1] Z0\n"), "G0 X7 Y7 Z0\n");
}

// Manual, "Expressions", binary operators: ** first; then * / MOD; then
// + -; then the comparisons; then AND OR XOR; left to right within a
// level. 1+2*3**2 = 1+2*9 = 19; 2**3**2 = (2**3)**2 = 64; 10-4-3 = 3;
// 7 MOD 3 = 1, and MOD of a negative gives a value in [0, |b|): -7 MOD 3 = 2.
TEST(Flatten, OperatorPrecedenceAndAssociativity) {
  EXPECT_EQ(flat("G0 X[1+2*3**2] Y[2**3**2] Z[10-4-3]\n"), "G0 X19 Y64 Z3\n");
  EXPECT_EQ(flat("G0 X[7 MOD 3] Y[-7 MOD 3] Z[1 + 2 GT 2]\n"), "G0 X1 Y2 Z1\n");
  // EQ within 0.0001 (TOLERANCE_EQUAL); AND OR XOR on any non-zero value.
  EXPECT_EQ(flat("G0 X[1 EQ 1.00005] Y[2 AND 0.5] Z[1 XOR 1]\n"), "G0 X1 Y1 Z0\n");
  // Unary minus before a parameter and before a bracket.
  EXPECT_EQ(flat("#1=2\nG0 X-#1 Y-[1+2] Z[-#1*3]\n"), "G0 X-2 Y-3 Z-6\n");
}

// Manual, "Functions": degrees for trig; ATAN[y]/[x] is atan2; FIX rounds
// down, FUP up; ROUND to the nearest, halves away from zero.
TEST(Flatten, Functions) {
  EXPECT_EQ(flat("G0 X[ATAN[1]/[1]] Y[ATAN[1]/[-1]] Z[ASIN[1]]\n"), "G0 X45 Y135 Z90\n");
  EXPECT_EQ(flat("G0 X[FIX[-1.5]] Y[FUP[-1.5]] Z[ROUND[-2.5]]\n"), "G0 X-2 Y-1 Z-3\n");
  EXPECT_EQ(flat("G0 X[ROUND[2.5]] Y[SQRT[16]] Z[ABS[-3]]\n"), "G0 X3 Y4 Z3\n");
  EXPECT_EQ(flat("G0 X[EXP[0]] Y[LN[1]] Z[COS[0]*2]\n"), "G0 X1 Y0 Z2\n");
  // COS[60] is 0.5000000000000001 in double, as in rs274 (its printf shows 0.5000).
  EXPECT_EQ(flat("G0 X[COS[60]] Y0 Z0\n"), "G0 X0.5000000000000001 Y0 Z0\n");
  // SIN[30] is 0.49999999999999994 in double: written exactly, not rounded.
  EXPECT_EQ(flat("G0 X[SIN[30]] Y0 Z0\n"), "G0 X0.49999999999999994 Y0 Z0\n");
  EXPECT_EQ(flat("#<a>=1\nG0 X[EXISTS[#<a>]] Y[EXISTS[#<b>]] Z0\n"), "G0 X1 Y0 Z0\n");
}

TEST(Flatten, ValuesTheControllerRefusesAreRefused) {
  EXPECT_NE(error_of("G0 X[SQRT[-1]]\n").find("p.ngc:1:"), std::string::npos);
  EXPECT_NE(error_of("G0 X[1/0]\n").find("division by zero"), std::string::npos);
  EXPECT_NE(error_of("G0 X[LN[0]]\n").find("LN"), std::string::npos);
  EXPECT_NE(error_of("G0 X[ACOS[2]]\n").find("out of range"), std::string::npos);
  EXPECT_NE(error_of("G0 X#<nothing>\n").find("#<nothing> is not defined"), std::string::npos);
  EXPECT_NE(error_of("G0 X[1+2\n").find("not closed"), std::string::npos);
  EXPECT_NE(error_of("G0 X[1 FOO 2]\n").find("'foo' is not an operator"), std::string::npos);
  // Run-time values: a probe result, a HAL pin.
  EXPECT_NE(error_of("G0 X#5061\n").find("probe"), std::string::npos);
  EXPECT_NE(error_of("G0 X#<_hal[motion.probe-input]>\n").find("run time"), std::string::npos);
  // Offsets are set by G codes, not directly; #5420.. are read-only.
  EXPECT_NE(error_of("#5221=10\n").find("G10"), std::string::npos);
  EXPECT_NE(error_of("#5420=10\n").find("read-only"), std::string::npos);
  // A run-time parameter the program set itself is known.
  EXPECT_EQ(flat("#5399=4\nG0 X#5399 Y0 Z0\n"), "G0 X4 Y0 Z0\n");
  // The column is the file's: line 2, column of the '#'.
  EXPECT_NE(error_of("G21\nG0  X#<nothing>\n").find("p.ngc:2:6:"), std::string::npos);
}

// Lines are written with their words in order, computed values as literals,
// assignments dropped, comments kept; a line that only assigns comes out as
// its comment or as nothing.
TEST(Flatten, EvaluatedLinesKeepTheirShape) {
  EXPECT_EQ(flat("G0 X0 Y0 Z0\n#1=2 (set)\ng1x[#1*2]y1f100 (cut)\n"),
            "G0 X0 Y0 Z0\n(set)\ng1x4y1f100 (cut)\n");
  EXPECT_EQ(flat("G0 X0 Y0 Z0\n#1=1\nN10 G1 X#1 Y2.50 F100 ; end\n"),
            "G0 X0 Y0 Z0\nN10 G1 X1 Y2.50 F100 ; end\n");
  EXPECT_EQ(flat("#1=0.1\nG0 X[#1+0.2] Y0 Z0\n"), "G0 X0.30000000000000004 Y0 Z0\n");
}

// Manual, "O Codes".
TEST(Flatten, Loops) {
  const std::string w =
      "#1=0\n"
      "o101 while [#1 LT 3]\n"
      "G0 X#1 Y0 Z0\n"
      "#1=[#1+1]\n"
      "o101 endwhile\n"
      "M2\n";
  EXPECT_EQ(flat(w), "G0 X0 Y0 Z0\nG0 X1 Y0 Z0\nG0 X2 Y0 Z0\nM2\n");
  // do/while runs its body once before the test.
  EXPECT_EQ(flat("#1=5\no1 do\nG0 X#1 Y0 Z0\n#1=[#1+1]\no1 while [#1 LT 3]\nM2\n"),
            "G0 X5 Y0 Z0\nM2\n");
  EXPECT_EQ(flat("o2 repeat [3]\nG91 G0 X1\no2 endrepeat\nM2\n"),
            "G91 G0 X1\nG91 G0 X1\nG91 G0 X1\nM2\n");
  // break and continue, inside an if.
  const std::string bc =
      "#1=0\n"
      "o1 while [1]\n"
      "#1=[#1+1]\n"
      "o2 if [#1 EQ 2]\n"
      "o1 continue\n"
      "o2 endif\n"
      "o3 if [#1 GT 3]\n"
      "o1 break\n"
      "o3 endif\n"
      "G0 X#1 Y0 Z0\n"
      "o1 endwhile\n"
      "M2\n";
  EXPECT_EQ(flat(bc), "G0 X1 Y0 Z0\nG0 X3 Y0 Z0\nM2\n");
}

TEST(Flatten, Conditionals) {
  const std::string p =
      "o1 if [#1 EQ 0]\n(zero)\no1 elseif [#1 EQ 1]\n(one)\no1 else\n(other)\no1 endif\n";
  EXPECT_EQ(flat(p), "(zero)\n");
  EXPECT_EQ(flat("#1=1\n" + p), "(one)\n");
  EXPECT_EQ(flat("#1=7\n" + p), "(other)\n");
}

// Subroutines: arguments in #1-#30, local to the call (the caller's come
// back); named locals per call; the value of endsub/return in #<_value>.
TEST(Flatten, Subroutines) {
  const std::string p =
      "o<square> sub\n"
      "#<half> = [#1 / 2]\n"
      "G0 X[-#<half>] Y[-#<half>] Z#2\n"
      "G0 X#<half>\n"
      "o<square> endsub [#1 * #1]\n"
      "#1 = 99\n"
      "o<square> call [10] [5]\n"
      "G0 X#1 Y#<_value> Z0\n"
      "M2\n";
  EXPECT_EQ(flat(p), "G0 X-5 Y-5 Z5\nG0 X5\nG0 X99 Y100 Z0\nM2\n");
  // A subroutine defined after the call.
  EXPECT_EQ(flat("o100 call [2]\nM2\no100 sub\nG0 X#1 Y0 Z0\no100 endsub\n"), "G0 X2 Y0 Z0\nM2\n");
  // Recursion (a countdown).
  const std::string rec =
      "o<down> sub\n"
      "o1 if [#1 GT 0]\n"
      "G0 X#1 Y0 Z0\n"
      "o<down> call [#1 - 1]\n"
      "o1 endif\n"
      "o<down> endsub\n"
      "o<down> call [3]\n"
      "M2\n";
  EXPECT_EQ(flat(rec), "G0 X3 Y0 Z0\nG0 X2 Y0 Z0\nG0 X1 Y0 Z0\nM2\n");
  // return leaves early, with a value.
  EXPECT_EQ(flat("o1 sub\no1 return [7]\nG0 X1\no1 endsub\no1 call\nG0 X#<_value> Y0 Z0\n"),
            "G0 X7 Y0 Z0\n");
}

TEST(Flatten, SubroutineFilesOnThePath) {
  const std::filesystem::path dir = test::fresh_dir("flatten_subs");
  std::ofstream(dir / "peck.ngc") << "(a subroutine file)\no<peck> sub\nG0 X#1 Y0 Z0\nG0 Z[-#2]\n"
                                     "o<peck> endsub\nM2\n";
  EXPECT_EQ(read("o<peck> call [4] [2]\nM2\n", {"/nonexistent", dir.string()}).out,
            "G0 X4 Y0 Z0\nG0 Z-2\nM2\n");
  // An error inside the file names the file and its line.
  std::ofstream(dir / "bad.ngc") << "o<bad> sub\nG0 X#<undefined>\no<bad> endsub\n";
  const std::string e = error_of("o<bad> call\n", {dir.string()});
  EXPECT_NE(e.find((dir / "bad.ngc").string() + ":2:"), std::string::npos) << e;
  EXPECT_NE(error_of("o<missing> call\n", {dir.string()}).find("--subroutine-path"),
            std::string::npos);
}

// SEMANTICS.md: LinuxCNC 2.9 runs Fanuc-style subprograms by default:
// M98 P<n> L<count> runs the lines after a bare O<n> up to M99, #1-#30
// shared with the caller; a bare O<n> reached in the main program (a
// program number) is passed over.
TEST(Flatten, FanucSubprograms) {
  const std::string p =
      "O1001 (program number)\n"
      "G0 X0 Y0 Z0\n"
      "#1=1\n"
      "M98 P200 L2\n"
      "G0 X#1 Y0 Z0\n"
      "M30\n"
      "O200\n"
      "G91 G0 X#1\n"
      "#1=[#1+1]\n"
      "G90\n"
      "M99\n";
  EXPECT_EQ(flat_linuxcnc(p),
            "O1001 (program number)\nG0 X0 Y0 Z0\nG91 G0 X1\nG90\nG91 G0 X2\nG90\n"
            "G0 X3 Y0 Z0\nM30\n");
  EXPECT_NE(error_of("G0 X0 Y0 Z0\nM99\n").find("M30"), std::string::npos);
  EXPECT_NE(error_of("M98 P7\n").find("no O7 line"), std::string::npos);
}

TEST(Flatten, StructureErrorsNameTheLine) {
  EXPECT_NE(error_of("o1 while [1]\nG0 X1\n").find("endwhile"), std::string::npos);
  EXPECT_NE(error_of("o1 if [1]\no2 endif\n").find("p.ngc:2:"), std::string::npos);
  EXPECT_NE(error_of("o1 foo\n").find("unknown O-word keyword 'foo'"), std::string::npos);
  EXPECT_NE(error_of("o<a>\nG0 X1\n").find("needs one"), std::string::npos);
  EXPECT_NE(error_of("o1 endsub\n").find("outside a call"), std::string::npos);
  EXPECT_NE(error_of("o<r> sub\no<r> call\no<r> endsub\no<r> call\n").find("deeper than"),
            std::string::npos);
}

// LinuxCNC's #5420-#5422: the current position in program coordinates
// (work offset taken off); #5220 the coordinate system (G54 = 1).
TEST(Flatten, SystemParametersAreTheInterpretersState) {
  nc::ProgramSetup setup;
  setup.work_offset_mm[0] = Eigen::Vector3d(100, 200, 300);
  const Read r = read("G21 G90 G0 X1 Y2 Z3\nG0 X[#5420 + 1] Y[#5421 * 2] Z#5220\n", {}, setup);
  EXPECT_EQ(r.out, "G21 G90 G0 X1 Y2 Z3\nG0 X2 Y4 Z1\n");
  ASSERT_EQ(r.ends.size(), 2u);
  EXPECT_EQ(r.ends[1], Eigen::Vector3d(102, 204, 301));
  EXPECT_NE(error_of("G0 X#5420\n").find("not known"), std::string::npos);
}

TEST(ProgramReader, TapeFrameAndByteOrderMark) {
  // A Fanuc tape's leader (skipped by the control's label skip) and trailer.
  nc::ProgramSetup fanuc;
  fanuc.dialect = nc::Dialect::kFanuc;
  const std::string p =
      "\xEF\xBB\xBFNX listing\nheader line\n%\nG0 X1. Y2. Z3.\n%\ntrailing text\n";
  const Read r = read(p, {}, fanuc);
  EXPECT_EQ(r.out, p);  // every byte, the mark included
  EXPECT_TRUE(r.report.byte_order_mark);
  EXPECT_EQ(r.report.leader_lines, 2);
  EXPECT_EQ(r.report.trailer_lines, 1);
  ASSERT_EQ(r.ends.size(), 1u);
  // LinuxCNC has no leader: blank lines only before the opening '%'
  // (tests/postproc/never_silent_test.cc has the refusals).
  const std::string l = "\xEF\xBB\xBF\n%\nG0 X1 Y2 Z3\n%\ntrailing text\n";
  const Read lr = read(l);
  EXPECT_EQ(lr.out, l);
  EXPECT_EQ(lr.report.leader_lines, 0);
  EXPECT_EQ(lr.report.trailer_lines, 1);
  ASSERT_EQ(lr.ends.size(), 1u);
  // Also when the program is flattened: the trailer stays out of it.
  const Read f = read("%\n#1=4\nG0 X#1 Y0 Z0\n%\nG0 X[1/0]\n");
  EXPECT_EQ(f.out, "%\nG0 X4 Y0 Z0\n%\nG0 X[1/0]\n");
  EXPECT_EQ(f.report.trailer_lines, 1);
}

}  // namespace
}  // namespace volmap
