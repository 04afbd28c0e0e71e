// Arcs kept as arcs (the post's default; --linearize-arcs writes lines):
// cut only where lost motion or the field needs it, within the tolerance on
// the model machine, refused with file:line where a linearised arc would
// need too many pieces.
#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>
#include <sstream>
#include <string>

#include "core/common/input_error.h"
#include "core/model/errors_csv.h"
#include "core/model/machine_json.h"
#include "gcode/nc_block.h"
#include "gcode/nc_interpreter.h"
#include "postproc/three_axis/post_program.h"
#include "postproc/verify/verify.h"
#include "tests/support/cli_in_source.h"
#include "tests/support/samples.h"
#include "tests/support/test_paths.h"

namespace volmap {
namespace {

Machine hsu() { return test::sample_machine("hsu-3axis"); }
ErrorSet hsu_errors() { return test::sample_errors("hsu-3axis"); }

nc::ProgramSetup offset_setup(double x, double y, double z) {
  nc::ProgramSetup s;
  s.work_offset_mm[0] = Eigen::Vector3d(x, y, z);
  return s;
}

const char* kNcFiles = "/usr/share/linuxcnc/ncfiles/";

// Arcs in every plane, G91, G90.1, R form, helices, an inch arc, a full
// circle, arcs over several quadrants. Each stays one arc where the field
// allows, and is cut where an axis with play turns round (take-up steps
// between the pieces) or where the field bends too much for one arc, with
// corrected ends and centres; the real machine runs the whole within the
// tolerance. Where an arc cannot be kept the output is the linearised one
// (keep_arc puts back what it tried).
std::string arc_program() {
  return test::file_bytes(test::source_path("tests/data/linuxcnc/arcs.ngc"));
}

int arc_blocks(const std::string& program) {
  int n = 0;
  std::istringstream in(program);
  for (std::string line; std::getline(in, line);) {
    const nc::Block b = nc::lex_block(line, 1, "x.ngc");
    for (const nc::Word& w : b.words)
      n += w.letter == 'G' && (w.code10 == 20 || w.code10 == 30) ? 1 : 0;
  }
  return n;
}

TEST(PostArcs, KeptWhereTheFieldAllowsWithinTheTolerance) {
  const nc::ProgramSetup s = offset_setup(150, 100, 200);
  for (double tol_um : {1.0, 5.0}) {
    SCOPED_TRACE(tol_um);
    const std::string program = arc_program();
    std::istringstream in(program);
    std::ostringstream out;
    post::PostOptions o;
    o.tolerance_mm = tol_um * 1e-3;
    o.keep_arcs = true;
    const post::PostReport report =
        post::post_program(in, "arcs.ngc", out, hsu(), hsu_errors(), s, o);
    // All ten arcs kept. The full circle must be cut where X turns round
    // (X's play, 3 um, exceeds a quarter of either tolerance): at least
    // eleven arcs; fewer than one per quadrant (16), where Y, without
    // play, turns round uncut.
    EXPECT_EQ(report.arcs_linearized, 0u) << out.str();
    EXPECT_GE(arc_blocks(out.str()), 11) << out.str();
    EXPECT_LT(arc_blocks(out.str()), 16) << out.str();
    std::istringstream a(program), b(out.str());
    const post::VerifyResult r =
        post::verify_programs(a, "arcs.ngc", b, "out.ngc", hsu(), hsu_errors(), s, {});
    EXPECT_GT(r.before.max_um, 20.0);
    EXPECT_LT(r.after.max_um, tol_um + 0.25) << "worst at line " << r.after.worst_line;
  }
  // LinuxCNC's programs: arcspiral's 2 mm arcs and tort's helices in three
  // planes.
  for (const char* name : {"arcspiral.ngc", "tort.ngc"}) {
    const std::string path = std::string(kNcFiles) + name;
    if (!std::filesystem::exists(path)) GTEST_SKIP() << "LinuxCNC programs not installed";
    const std::string program = test::file_bytes(path);
    const nc::ProgramSetup s2 = offset_setup(250, 200, 100);
    post::PostOptions o;
    o.keep_arcs = true;
    std::istringstream in(program);
    std::ostringstream kept;
    post::post_program(in, name, kept, hsu(), hsu_errors(), s2, o);
    std::istringstream in2(program);
    std::ostringstream linearised;
    o.keep_arcs = false;
    post::post_program(in2, name, linearised, hsu(), hsu_errors(), s2, o);
    const std::string lines = linearised.str();
    std::istringstream a(program), b(kept.str());
    const post::VerifyResult r =
        post::verify_programs(a, name, b, "out.ngc", hsu(), hsu_errors(), s2, {});
    EXPECT_LT(r.after.max_um, 1.25) << name << " worst at line " << r.after.worst_line;
    EXPECT_GT(arc_blocks(kept.str()), 5) << name;
    EXPECT_LT(kept.str().size(), lines.size()) << name;
    if (std::string(name) == "arcspiral.ngc") {
      EXPECT_LT(kept.str().size() * 4, lines.size());
    }
  }
}

TEST(PostArcs, CutWhereTheFieldNeedsItLinearisedWhereInverseTimeWould) {
  // A quarter of a 150 mm circle over which the error field is not affine
  // enough for one arc: cut into arcs (halved until each keeps the
  // tolerance), not linearised; and a half circle under inverse time (G93),
  // which would take two arcs (X turns round inside it, with 3 um of play),
  // each needing its own F: linearised, as --linearize-arcs writes it.
  const std::string program =
      "G21 G90 G17 F300\nG0 X0 Y0 Z5\nG1 Z-1\nG1 X50\nG2 X200 Y150 I150 J0\nG1 X210\n"
      "G93 G3 X230 Y150 I10 J0 F30\nG94 G1 X240 F300\nM2\n";
  const nc::ProgramSetup s = offset_setup(150, 100, 200);
  std::string outs[2];
  post::PostReport reports[2];
  for (int k = 0; k < 2; ++k) {
    std::istringstream in(program);
    std::ostringstream out;
    post::PostOptions o;
    o.keep_arcs = k == 1;
    reports[k] = post::post_program(in, "circles.ngc", out, hsu(), hsu_errors(), s, o);
    outs[k] = out.str();
  }
  EXPECT_EQ(reports[0].arcs_linearized, 2u);
  EXPECT_EQ(reports[1].arcs_split, 1u) << outs[1];
  EXPECT_EQ(reports[1].arcs_linearized, 1u) << outs[1];
  const std::size_t g93[2] = {outs[0].find("G93"), outs[1].find("G93")};
  ASSERT_NE(g93[1], std::string::npos);
  EXPECT_EQ(outs[1].substr(g93[1]), outs[0].substr(g93[0]));
  EXPECT_GE(arc_blocks(outs[1]), 2);
  EXPECT_LT(outs[1].size(), outs[0].size());
  std::istringstream a(program), b(outs[1]);
  const post::VerifyResult r =
      post::verify_programs(a, "circles.ngc", b, "out.ngc", hsu(), hsu_errors(), s, {});
  EXPECT_LT(r.after.max_um, 1.25) << "worst at line " << r.after.worst_line;
}

TEST(PostArcs, LinearisedArcOfTooManyPiecesIsRefusedAtItsLine) {
  // A circle of radius 100 mm at a tolerance of 0.01 nm: --linearize-arcs
  // would need about 220 000 chords, more than 65 536 pieces.
  std::istringstream in("G21 G90 G17 G54\nG0 X-50 Y0 Z20\nG2 X-50 Y0 I100 J0 F100\nM2\n");
  std::ostringstream out;
  post::PostOptions o;
  o.keep_arcs = false;
  o.tolerance_mm = 1e-8;
  try {
    post::post_program(in, "tight.ngc", out, hsu(), hsu_errors(), offset_setup(200, 200, 100), o);
    ADD_FAILURE() << "written";
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find("tight.ngc:3"), std::string::npos) << e.what();
    EXPECT_NE(std::string(e.what()).find("more than 65536 pieces"), std::string::npos) << e.what();
  }
}

// Every commanded position is checked against the machine's travel, --clamp
// or not, and the message says first what is likely wrong: a circle of
// radius 1 000 km (a centre far off) leaves the 500 mm travel of X on its
// way round; the end point alone lies inside.
TEST(PostArcs, AnArcThatLeavesTheTravelIsRefusedAtItsLine) {
  for (bool clamp : {false, true}) {
    std::istringstream in("G21 G90 G17 G54\nG0 X10 Y10 Z20\nG2 X10 Y10 I1000000 J0 F100\nM2\n");
    std::ostringstream out;
    post::PostOptions o;
    o.outside = clamp ? OutsidePolicy::kClamp : OutsidePolicy::kError;
    try {
      post::post_program(in, "far.ngc", out, hsu(), hsu_errors(), offset_setup(100, 100, 100), o);
      ADD_FAILURE() << "written";
    } catch (const InputError& e) {
      EXPECT_EQ(
          std::string(e.what()),
          "far.ngc:3: this block moves X to 2000110.0000 mm, outside its travel 0..500 mm "
          "(machine hsu-3axis); the program lies outside the travel at its origin 100,100,100 "
          "mm (--work-offset, G10, G92): check the work offset");
    }
  }
  // No work offset: the program's coordinates are the machine's.
  std::istringstream in("G21 G90 G17 G54\nG0 X10 Y10 Z20\nG1 X-5 F100\nM2\n");
  std::ostringstream out;
  try {
    post::post_program(in, "raw.ngc", out, hsu(), hsu_errors(), {}, {});
    ADD_FAILURE() << "written";
  } catch (const InputError& e) {
    EXPECT_NE(
        std::string(e.what()).find("raw.ngc:3: this block moves X to -5.0000 mm, outside its "
                                   "travel 0..500 mm (machine hsu-3axis); the program's origin "
                                   "is the machine's zero"),
        std::string::npos)
        << e.what();
  }
}

// The travel is checked on every path that writes a line: a plain line of
// axis words (the post's shortcut, docs/post.md "Speed") included. With
// travel narrower than the error table, a move past the travel's end is
// inside the table: only the travel check can refuse it.
TEST(PostArcs, APlainLineOutsideTheTravelIsRefusedOnTheShortcutToo) {
  Machine narrow = hsu();
  narrow.limits[0].max = 300.0;  // the table measures X to 500 mm
  for (bool shortcuts : {true, false}) {
    std::istringstream in("G21 G90 G17 G54\nG0 X10 Y10 Z20\nG1 X20 F100\nX250\nX210\n");
    std::ostringstream out;
    post::PostOptions o;
    o.shortcuts = shortcuts;
    try {
      post::post_program(in, "narrow.ngc", out, narrow, hsu_errors(), offset_setup(60, 100, 100),
                         o);
      ADD_FAILURE() << "written with shortcuts " << shortcuts;
    } catch (const InputError& e) {
      EXPECT_EQ(std::string(e.what()),
                "narrow.ngc:4: this block moves X to 310.0000 mm, outside its travel 0..300 mm "
                "(machine hsu-3axis); the program lies outside the travel at its origin "
                "60,100,100 mm (--work-offset, G10, G92): check the work offset");
    }
  }
}

}  // namespace
}  // namespace volmap
