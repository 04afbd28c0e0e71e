// The APT / CLDATA reader, record by record, against paths derived by hand
// from each record's documented meaning (docs/post-five-axis.md "APT /
// CLDATA"), and its refusals: each names file:line and what to do.
#include <gtest/gtest.h>

#include <cmath>
#include <sstream>

#include "core/common/input_error.h"
#include "gcode/nc_path.h"
#include "postproc/five_axis/five_axis_input.h"
#include "postproc/five_axis/five_axis_post.h"
#include "tests/support/samples.h"

namespace volmap {
namespace {

using Eigen::Vector3d;

struct Read {
  std::vector<post::FiveAxisLine> lines;
  std::vector<post::FiveAxisMove> moves;
  std::string text;  ///< the G-code text of the lines without a move, one per line
};

Read read_apt(const std::string& apt, double chord_mm = 1e-3) {
  static const Machine m = test::sample_machine("lei-hsu-xyzac");
  std::istringstream in(apt);
  post::FiveAxisReader reader(in, "t.apt", m, post::InputForm::kApt, post::InitialPose{}, chord_mm);
  Read r;
  post::FiveAxisLine l;
  while (reader.next(l)) {
    if (l.has_move)
      r.moves.push_back(l.move);
    else
      r.text += l.text + "\n";
    r.lines.push_back(l);
  }
  return r;
}

// The message of the refusal, "" when the file is read.
std::string refusal(const std::string& apt) {
  try {
    read_apt(apt);
  } catch (const InputError& e) {
    return e.what();
  }
  return "";
}

void expect_near(const Vector3d& a, const Vector3d& b, double tol = 1e-9) {
  EXPECT_LT((a - b).norm(), tol) << a.transpose() << " vs " << b.transpose();
}

// A straight move's end, rapid or not, and feed (mm/min).
struct Expect {
  Vector3d end;
  bool rapid;
  double feed;
};
void expect_moves(const std::vector<post::FiveAxisMove>& got, const std::vector<Expect>& want) {
  ASSERT_EQ(got.size(), want.size());
  for (size_t i = 0; i < got.size(); ++i) {
    SCOPED_TRACE(i);
    EXPECT_EQ(got[i].tip.kind, nc::MotionKind::kLinear);
    expect_near(got[i].tip.end_mm, want[i].end);
    EXPECT_EQ(got[i].rapid, want[i].rapid);
    if (!want[i].rapid) {
      EXPECT_DOUBLE_EQ(got[i].feed, want[i].feed);
    }
    if (i > 0) expect_near(got[i].tip.start_mm, got[i - 1].tip.end_mm);
  }
}

TEST(AptReader, GotoUnitsFeedAndOneShotRapid) {
  // Inches: every length times 25.4; FEDRAT in either order; RAPID only for
  // the next motion record.
  const Read r = read_apt(
      "PARTNO test part\nUNITS/INCHES\nFEDRAT/10,IPM\nRAPID\nGOTO/1,2,3\nGOTO  / 2,2,3,0,0,1\n"
      "FEDRAT/IPM,20\nGOTO/2,3,3\nFINI\n");
  expect_moves(r.moves, {{{25.4, 50.8, 76.2}, true, 0},
                         {{50.8, 50.8, 76.2}, false, 254},
                         {{50.8, 76.2, 76.2}, false, 508}});
  EXPECT_NE(r.text.find("M2"), std::string::npos);
  EXPECT_TRUE(r.lines.back().ends_program);
  // The output is in mm whatever the CL file's units.
  for (const auto& l : r.lines) EXPECT_EQ(l.unit_mm, 1.0);
  // NX writes no UNITS record: its first FEDRAT's unit word says, for the
  // GOTOs before it too; a unit word that contradicts the units is refused.
  const Read nx = read_apt("TOOL PATH/X\nRAPID\nGOTO/1,0,0\nFEDRAT/IPM,10.0000\nGOTO/2,0,0\n");
  expect_moves(nx.moves, {{{25.4, 0, 0}, true, 0}, {{50.8, 0, 0}, false, 254}});
  EXPECT_NE(nx.text.find("no UNITS record; lengths in inches, as FEDRAT/ on line 4 says"),
            std::string::npos);
  EXPECT_NE(refusal("UNITS/MM\nFEDRAT/IPM,10\n").find("t.apt:2: a feed in IPM while the lengths"),
            std::string::npos);
}

TEST(AptReader, FromGodltaGohomeAndToolAxis) {
  const Read r = read_apt(
      "FROM/10,20,30\nFEDRAT/MMPM,100\nGODLTA/5\nGODLTA/1,2,3\nGODLTA/0,0,1,0,0.6,0.8\n"
      "GOHOME/0,0,50\nTLAXIS/1,0,0\nGOTO/0,0,60\n");
  expect_moves(r.moves, {{{10, 20, 35}, false, 100},
                         {{11, 22, 38}, false, 100},
                         {{11, 22, 39}, false, 100},
                         {{0, 0, 50}, true, 0},
                         {{0, 0, 60}, false, 100}});
  EXPECT_FALSE(r.moves[0].by_angles);
  expect_near(r.moves[2].a0, Vector3d::UnitZ());
  expect_near(r.moves[2].a1, Vector3d(0, 0.6, 0.8));
  expect_near(r.moves[4].a1, Vector3d::UnitX());
  // One value along a tilted tool axis: NX and the textbooks differ.
  EXPECT_NE(refusal("TLAXIS/1,0,0\nFEDRAT/100\nGODLTA/5\n").find("t.apt:3: GODLTA/"),
            std::string::npos);
  EXPECT_NE(refusal("FEDRAT/100\nGOTO/1,0,0\nFROM/5,5,5\n").find("t.apt:3:"), std::string::npos);
}

// The arc of a CIRCLE and its GOTO: kind, plane, direction, sweep.
nc::ArcGeometry arc_of(const post::FiveAxisMove& m) {
  EXPECT_EQ(m.tip.kind, nc::MotionKind::kArc);
  return nc::arc_geometry(m.tip);
}

TEST(AptReader, CircleDirectionByDialect) {
  const std::string start = "FEDRAT/100\nGOTO/10,0,0\n";
  // SOLIDWORKS CAM (6 values): counter-clockwise about +axis: 90 degrees
  // from +X to +Y, the middle at 45 degrees.
  Read r = read_apt(start + "CIRCLE/0,0,0,0,0,1\nGOTO/0,10,0\n");
  ASSERT_EQ(r.moves.size(), 2u);
  EXPECT_NEAR(arc_of(r.moves[1]).sweep, M_PI / 2, 1e-12);
  expect_near(nc::point_on(r.moves[1].tip, 0.5), Vector3d(10 / std::sqrt(2), 10 / std::sqrt(2), 0));
  // NX (11 values): clockwise about +axis: 270 degrees the other way.
  r = read_apt(start + "CIRCLE/0,0,0,0,0,1,10,0.01,0.5,10,0\nGOTO/0,10,0\n");
  EXPECT_NEAR(arc_of(r.moves[1]).sweep, -1.5 * M_PI, 1e-12);
  expect_near(nc::point_on(r.moves[1].tip, 1.0 / 3), Vector3d(0, -10, 0), 1e-9);
  // Creo (7 values, split by '$'): counter-clockwise about its axis, here -Z.
  r = read_apt(start + "CIRCLE / 0, 0, 0,  $\n0, 0, -1,  10\nGOTO / 0, 10, 0\n");
  EXPECT_NEAR(arc_of(r.moves[1]).sweep, -1.5 * M_PI, 1e-12);
  // The GOTO after the arc is a straight move again.
  r = read_apt(start + "CIRCLE/0,0,0,0,0,1\nGOTO/0,10,0\nGOTO/0,20,0\n");
  EXPECT_EQ(r.moves[2].tip.kind, nc::MotionKind::kLinear);
}

TEST(AptReader, FullCircleHelixAndSidePlanes) {
  // Back to the start: a whole turn.
  Read r = read_apt("FEDRAT/100\nGOTO/10,0,0\nCIRCLE/0,0,0,0,0,1\nGOTO/10,0,0\n");
  EXPECT_NEAR(arc_of(r.moves[1]).sweep, 2 * M_PI, 1e-12);
  // A helix: the end lower along the axis, halfway at half the drop.
  r = read_apt("FEDRAT/100\nGOTO/10,0,0\nCIRCLE/0,0,0,0,0,1\nGOTO/0,10,-2\n");
  EXPECT_NEAR(nc::point_on(r.moves[1].tip, 0.5).z(), -1.0, 1e-12);
  // About -X (SOLIDWORKS CAM's side faces): from +Y a quarter turn
  // counter-clockwise about -X reaches -Z.
  r = read_apt("FEDRAT/100\nGOTO/78,24,-29\nCIRCLE/78.,19.,-29.,-1.,0,0\nGOTO/78,19,-34\n");
  EXPECT_EQ(r.moves[1].tip.plane, 2);  // YZ
  EXPECT_NEAR(arc_of(r.moves[1]).sweep, -M_PI / 2, 1e-12);
  expect_near(nc::point_on(r.moves[1].tip, 0.5),
              Vector3d(78, 19 + 5 / std::sqrt(2), -29 - 5 / std::sqrt(2)), 1e-9);
}

TEST(AptReader, ArcAboutATiltedAxisBecomesChordsOnTheArc) {
  // Axis (0, 0.6, 0.8), start 10 mm along +X: a quarter turn ends at
  // n x (10, 0, 0) = (0, 8, -6).
  const double chord_mm = 1e-3;
  const Read r = read_apt("FEDRAT/100\nGOTO/10,0,0\nCIRCLE/0,0,0,0,.6,.8\nGOTO/0,8,-6\n", chord_mm);
  const int want = static_cast<int>(std::ceil((M_PI / 2) / (2 * std::acos(1 - chord_mm / 10))));
  ASSERT_EQ(static_cast<int>(r.moves.size()), 1 + want);
  const Vector3d n(0, 0.6, 0.8);
  for (size_t i = 1; i < r.moves.size(); ++i) {
    const Vector3d p = r.moves[i].tip.end_mm;
    EXPECT_NEAR(p.norm(), 10.0, 1e-9);
    EXPECT_NEAR(p.dot(n), 0.0, 1e-9);
    // The chord's middle stands off the arc by at most chord_mm.
    const Vector3d mid = 0.5 * (p + r.moves[i].tip.start_mm);
    EXPECT_LE(10.0 - mid.norm(), chord_mm + 1e-12);
  }
  expect_near(r.moves.back().tip.end_mm, Vector3d(0, 8, -6));
}

TEST(AptReader, CircleRefusals) {
  EXPECT_NE(refusal("FEDRAT/100\nGOTO/10,0,0\nCIRCLE/0,0,0,0,0,1\nGOTO/0,11,0\n")
                .find("t.apt:4: the GOTO/ after CIRCLE/ (line 3) is not on the circle"),
            std::string::npos);
  EXPECT_NE(refusal("FEDRAT/100\nGOTO/10,0,0\nCIRCLE/0,0,0,0,0,1,10,.01,.5,10,0,TIMES,3\n")
                .find("t.apt:3: CIRCLE/ with TIMES"),
            std::string::npos);
  EXPECT_NE(refusal("FEDRAT/100\nGOTO/10,0,0\nCIRCLE/0,0,0,10\nGOTO/0,10,0\n").find("t.apt:3:"),
            std::string::npos);
  EXPECT_NE(refusal("FEDRAT/100\nGOTO/10,0,0\nCIRCLE/0,0,0,0,0,1\nRAPID\nGOTO/0,10,0\n")
                .find("t.apt:4: RAPID between CIRCLE/"),
            std::string::npos);
  EXPECT_NE(refusal("FEDRAT/100\nGOTO/10,0,0\nCIRCLE/0,0,0,0,0,1\n").find("t.apt:3: the CIRCLE/"),
            std::string::npos);
  // What one record may expand to is bounded.
  EXPECT_NE(refusal("FEDRAT/100\nGOTO/1e9,0,0\nCIRCLE/0,0,0,0,.6,.8\nGOTO/0,8e8,-6e8\n")
                .find("t.apt:4: the arc of CIRCLE/ (line 3), 1e+09 mm about a tilted axis"),
            std::string::npos);
}

TEST(AptReader, SolidworksDrillCycleIsWrittenOutHoleByHole) {
  // SupPetriLED.apt's first cycle: holes 6 mm deep below their tops at
  // z = -24, R 3 mm above, back to 49 mm above (z = 25) after each.
  const Read r = read_apt(
      "UNIT/MM\nRAPID/\nGOTO/0,0,25.\nCYCLE/INIT\n"
      "CYCLE/DRILL,FEDTO,6.,MMPM,200,RAPTO,3.,RTRCTO,49.,DWELL,0\n"
      "GOTO/0,0,-24.\nGOTO/10,0,-24.\nCYCLE/OFF\n");
  expect_moves(r.moves, {{{0, 0, 25}, true, 0},
                         {{0, 0, -21}, true, 0},
                         {{0, 0, -30}, false, 200},
                         {{0, 0, 25}, true, 0},
                         {{10, 0, 25}, true, 0},
                         {{10, 0, -21}, true, 0},
                         {{10, 0, -30}, false, 200},
                         {{10, 0, 25}, true, 0}});
}

TEST(AptReader, PecksDwellAndATiltedHole) {
  // DEEP2: first peck 4, then 3 each; between pecks back to R and down
  // again to 0.254 mm above the last depth; the dwell at the bottom.
  Read r = read_apt(
      "UNIT/MM\nRAPID/\nGOTO/0,0,5\n"
      "CYCLE/DEEP2,FEDTO,10,1STPECK,4,SUBPECK,3,MMPM,100,RAPTO,2,RTRCTO,5,DWELL,0.5\n"
      "GOTO/0,0,0\nCYCLE/OFF\n");
  expect_moves(r.moves, {{{0, 0, 5}, true, 0},
                         {{0, 0, 2}, true, 0},
                         {{0, 0, -4}, false, 100},
                         {{0, 0, 2}, true, 0},
                         {{0, 0, -3.746}, true, 0},
                         {{0, 0, -7}, false, 100},
                         {{0, 0, 2}, true, 0},
                         {{0, 0, -6.746}, true, 0},
                         {{0, 0, -10}, false, 100},
                         {{0, 0, 5}, true, 0}});
  EXPECT_NE(r.text.find("G4 P0.5"), std::string::npos);
  // Sacrifice-Board.apt: drilled from below, tool axis -Z: the retract
  // level 27.5 along the axis from z = -27.5 is z = -55.
  r = read_apt(
      "UNIT/MM\nRAPID/\nGOTO/390.,145.,-55.,0,0,-1.\n"
      "CYCLE/DRILL,FEDTO,8,MMPM,300,RAPTO,3.,RTRCTO,27.5\nGOTO/390.,145.,-27.5,0,0,-1.\n"
      "CYCLE/OFF\n");
  expect_moves(r.moves, {{{390, 145, -55}, true, 0},
                         {{390, 145, -30.5}, true, 0},
                         {{390, 145, -19.5}, false, 300},
                         {{390, 145, -55}, true, 0}});
}

TEST(AptReader, NxCycleDepthIsAnOffsetAlongTheToolAxis) {
  // NX: FEDTO is added along the tool axis; no RTRCTO: back to R.
  const Read r = read_apt(
      "TOOL PATH/DRILLING,TOOL,D5\nTLDATA/DRILL,5,0,50,118,0\nMSYS/0,0,0,1,0,0,0,1,0\n"
      "RAPID\nGOTO/0,0,20,0,0,1\nCYCLE/DRILL,RAPTO,3.0000,FEDTO,-5.0000,MMPM,250.0000\n"
      "GOTO/0,0,0\nCYCLE/OFF\nEND-OF-PATH\n");
  expect_moves(r.moves, {{{0, 0, 20}, true, 0},
                         {{0, 0, 3}, true, 0},
                         {{0, 0, -5}, false, 250},
                         {{0, 0, 3}, true, 0}});
  EXPECT_NE(refusal("TOOL PATH/DRILLING\nFEDRAT/100\nCYCLE/DRILL,RAPTO,3,FEDTO,5,MMPM,250\n"
                    "GOTO/0,0,0\n")
                .find("t.apt:3:"),
            std::string::npos);
}

TEST(AptReader, CyclesItCannotWriteOutExactlyAreRefused) {
  const char* cases[][2] = {
      {"CYCLE / DEEP, DEPTH, 3.5, STEP, 1, MMPM, 50, CLEAR,$\n 1.0\n", "t.apt:1: Creo's CYCLE/"},
      {"CYCLE/TAP,FEDTO,5,MMPM,100,RAPTO,2\n", "t.apt:1: CYCLE/TAP: the spindle must reverse"},
      {"CYCLE/BORE,FEDTO,5,MMPM,100,RAPTO,2\n", "t.apt:1: CYCLE/BORE"},
      {"CYCLE/DRILL,5,MMPM,100,2\n", "t.apt:1: CYCLE/ in the positional form"},
      {"CYCLE/DEEP,FEDTO,5,MMPM,100,RAPTO,2\n", "t.apt:1: CYCLE/DEEP needs its peck depths"},
      {"CYCLE/DRILL,FEDTO,5,MMPR,.1,RAPTO,2\n", "per revolution"},
      {"CYCLE/DRILL,FEDTO,5,MMPM,100\n", "RAPTO"},
      {"CYCLE/FACE,FEDTO,5,MMPM,100,RAPTO,2\n", "not a cycle volmap writes out"},
      {"CYCLE/ON\n", "before any cycle"},
      {"UNIT/MM\nCYCLE/DEEP,FEDTO,1000,INCR,.001,MMPM,100,RAPTO,2\n", "more than 10000 pecks"},
      // FEDTO's sign differs between NX and SOLIDWORKS CAM: unknown writer.
      {"CYCLE/DRILL,FEDTO,5,MMPM,100,RAPTO,2\nGOTO/0,0,0\n", "cannot tell"},
  };
  for (const auto& c : cases)
    EXPECT_NE(refusal(c[0]).find(c[1]), std::string::npos) << c[0] << refusal(c[0]);
}

TEST(AptReader, FramesAreReadOrRefused) {
  // SOLIDWORKS CAM: the GOTO points are in the part frame; its CSYS's third
  // column is the tool axis of the GOTOs that follow (shimemcunha.apt).
  const std::string sw = "UNIT/MM\nTRNTYP/WORLD,0,0,0\n";
  EXPECT_EQ(refusal(sw + "CSYS/0,.999987,.005061,0,-1.,0,0,0,0,-0.005061,.999987,0\n"
                         "RAPID/\nGOTO/-52.36,15.63,25.45,.005061,0,.999987\n"),
            "");
  EXPECT_NE(refusal(sw + "CSYS/0,.999987,.005061,0,-1.,0,0,0,0,-0.005061,.999987,0\n"
                         "RAPID/\nGOTO/-52.36,15.63,25.45,0,0,1\n")
                .find("t.apt:5: the tool axis differs from the third column of the CSYS/"),
            std::string::npos);
  // A GOTO without i,j,k takes the setup's axis (SOLIDWORKS CAM writes them
  // only where it is not +Z).
  const Read r = read_apt(sw + "CSYS/-1.,0,0,0,0,1.,0,0,0,0,-1.,0\nRAPID/\nGOTO/1,2,3\n");
  ASSERT_EQ(r.moves.size(), 1u);
  expect_near(r.moves[0].a1, Vector3d(0, 0, -1));
  // Elsewhere only the identity is read.
  EXPECT_EQ(refusal("CSYS/1,0,0,0,0,1,0,0,0,0,1,0\n"), "");
  EXPECT_NE(refusal("CSYS/1,0,0,5,0,1,0,0,0,0,1,0\n").find("t.apt:1: CSYS/ that is not"),
            std::string::npos);
  for (const char* k : {"TRANS/1,0,0,5,0,1,0,0,0,0,1,0\n", "TRACUT/1,0,0,5,0,1,0,0,0,0,1,0\n",
                        "COPY/1,TRANSL,5,0,0,2\n"})
    EXPECT_NE(refusal(k).find("t.apt:1:"), std::string::npos) << k;
  EXPECT_EQ(refusal("TRACUT/NOMORE\n"), "");
}

TEST(AptReader, ToolsSpindleCoolantAndCutcom) {
  const Read r = read_apt(
      "LOAD/TOOL,3,ADJUST,3\nSELECT/TOOL,4\nSPINDL/3500,RPM,CCLW\nCOOLNT/FLOOD\nCUTCOM/LEFT\n"
      "CUTCOM/OFF\nSPINDL/OFF\nCOOLNT/OFF\nOPSTOP\nSTOP\nDELAY/2.5\nLOAD/TOOL,3\n");
  EXPECT_NE(r.text.find("S3500 M4\nM8\n"), std::string::npos) << r.text;
  EXPECT_NE(r.text.find("tool centre: no G41/G42"), std::string::npos);
  EXPECT_NE(r.text.find("M5\nM9\nM1\nM0\nG4 P2.5\n"), std::string::npos) << r.text;
  // Tool changes are marked for the post (which knows the tool table).
  int changes = 0;
  for (const auto& l : r.lines) changes += l.tool == 3 ? 1 : 0;
  EXPECT_EQ(changes, 2);
  EXPECT_NE(refusal("SPINDL/200,SMM\n").find("surface speed"), std::string::npos);
  // Creo with contour points: CUTCOM expects the controller to offset.
  EXPECT_NE(refusal("$$-> CUTCOM_GEOMETRY_TYPE / OUTPUT_ON_PROFILE\nCUTCOM/LEFT\n")
                .find("t.apt:2: CUTCOM/"),
            std::string::npos);
}

TEST(AptReader, LexicalForms) {
  // Creo: a `$$` comment that ends in `$` goes on over lines of numbers;
  // NCL: PARTNO without a slash, `GOTO  /` with blanks; a line of numbers
  // after a GOTO: more points; CRLF; the NX listing's last line.
  const Read r = read_apt(
      "$$*          Pro/CLfile  Version 8.0 - 8.0.3.0\r\n"
      "$$-> CSYS / 1.0, 0.0, 0.0, 0.0,  $\r\n            0.0, 1.0, 0.0, 0.0,  $\r\n"
      "            0.0, 0.0, 1.0, 0.0\r\nPARTNO test\r\nFEDRAT / 400.0,  MMPM\r\n"
      "GOTO  / 1, 2, 3\r\n 4, 5, 6\r\nGOTO/7,8,9 $$ a comment\r\n"
      "Tool Path Listing has 388 lines.");
  expect_moves(r.moves,
               {{{1, 2, 3}, false, 400}, {{4, 5, 6}, false, 400}, {{7, 8, 9}, false, 400}});
  EXPECT_NE(refusal("1,2,3\n").find("t.apt:1: a line of numbers"), std::string::npos);
  EXPECT_NE(refusal("PARTNO x\nGOTO/1,2,$\n").find("t.apt:2:"), std::string::npos);
}

TEST(AptReader, UnknownRecordsAreRefusedNeverComments) {
  for (const char* rec :
       {"FOO/1,2\n", "NURBS/\n", "MOVARC/0,0,0,0,0,1,5,ANGLE,90\n", "FEDRAT/INVERS,AUTO\n",
        "FEDRAT/.1,MMPR\n", "GOTO/1,2\n", "GOTO/1,x,3\n", "UNITS/FEET\n"}) {
    const std::string why = refusal(std::string("PARTNO/T\n") + rec);
    EXPECT_EQ(why.rfind("t.apt:2: ", 0), 0u) << rec << " -> " << why;
  }
  // Bytes outside printable ASCII are shown escaped, on one line.
  for (const char* bad : {"GOTO/1,\x01\xff,3\n", "FEDRAT/\x01\xff\n", "CYCLE/DRILL,\x01\xff,3\n",
                          "CYCLE/\x01\xff\n"}) {
    const std::string why = refusal(bad);
    EXPECT_NE(why.find("\\x01\\xFF"), std::string::npos) << why;
  }
}

// The post of a CL file with two tools: without a tool table refused at the
// second; with one, each tool's length: the same tip 10 mm lower in tool 2's
// terms is Z 10 mm higher (the tool along Z at A = 0), and T2 M6 written.
TEST(AptPost, ToolLengthsFromTheToolTable) {
  const Machine m = test::sample_machine("lei-hsu-xyzac");
  const std::string apt = "LOADTL/1\nRAPID\nGOTO/0,0,50\nLOADTL/2\nRAPID\nGOTO/0,0,50\nFINI\n";
  auto post = [&](const std::map<int, double>& table, std::string& text) {
    post::FiveAxisPostOptions o;
    o.form = post::InputForm::kApt;
    o.tool_offsets_mm = table;
    std::istringstream in(apt);
    std::ostringstream out;
    post::post_five_axis(in, "t.apt", out, m, ErrorSet{}, o);
    text = out.str();
  };
  std::string text;
  try {
    post({}, text);
    ADD_FAILURE() << "posted without a tool table";
  } catch (const InputError& e) {
    EXPECT_EQ(std::string(e.what()).rfind("t.apt:4: a second tool (T2 after T1)", 0), 0u)
        << e.what();
  }
  post({{1, 0.0}, {2, 10.0}}, text);
  std::vector<double> z;
  std::istringstream lines(text);
  std::string l;
  while (std::getline(lines, l))
    if (l.rfind("G0 ", 0) == 0 || l.rfind("X", 0) == 0)
      z.push_back(std::stod(l.substr(l.find('Z') + 1)));
  ASSERT_EQ(z.size(), 2u) << text;
  EXPECT_NEAR(z[1] - z[0], 10.0, 1e-4);
  EXPECT_NE(text.find("T2 M6 (APT: LOADTL/2)"), std::string::npos) << text;
  // A tool the table does not have; a feed move right after the change.
  EXPECT_THROW(post({{1, 0.0}}, text), InputError);
  const std::string feed_after = "FEDRAT/100\nLOADTL/1\nGOTO/0,0,50\nLOADTL/2\nGOTO/0,0,40\n";
  post::FiveAxisPostOptions o;
  o.form = post::InputForm::kApt;
  o.tool_offsets_mm = {{1, 0.0}, {2, 10.0}};
  std::istringstream in(feed_after);
  std::ostringstream out;
  EXPECT_THROW(post::post_five_axis(in, "t.apt", out, m, ErrorSet{}, o), InputError);
}

}  // namespace
}  // namespace volmap
