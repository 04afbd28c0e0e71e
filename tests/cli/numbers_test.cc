// Numbers (issue 8): NaN and infinity never reach an output (refused with a
// message, from files and from options alike); positions outside an error
// table follow the stated policy (docs/model.md: an error naming the file
// and line by default, the end value held with --clamp); singular poses of
// the five-axis sample give finite numbers, never a division by zero.
// Non-finite cells in each file format are in the bad-input catalogue
// (tests/bad, bad_inputs_test); this file covers options and outputs.
#include <gtest/gtest.h>

#include <cmath>
#include <filesystem>
#include <fstream>
#include <nlohmann/json.hpp>
#include <regex>
#include <string>
#include <vector>

#include "tests/support/cli_in_source.h"

namespace volmap::test {
namespace {

namespace fs = std::filesystem;

const char* kHsu =
    "--machine samples/machines/hsu-3axis.json --errors samples/errors/hsu-3axis.csv";
const char* kLei =
    "--machine samples/machines/lei-hsu-xyzac.json --errors samples/errors/lei-hsu-xyzac.csv";

// A word that is not a finite number in an output: nan, inf, infinity (any
// case, any sign).
bool has_non_finite(const std::string& text) {
  static const std::regex re("(^|[^A-Za-z_])[+-]?(nan|inf|infinity)([^A-Za-z_]|$)",
                             std::regex::icase);
  return std::regex_search(text, re);
}

TEST(Numbers, TheNonFiniteDetectorWorks) {
  EXPECT_TRUE(has_non_finite("1,nan,2"));
  EXPECT_TRUE(has_non_finite("X-inf Y0"));
  EXPECT_TRUE(has_non_finite("\"a\": Infinity"));
  EXPECT_FALSE(has_non_finite("info: 1.5 (inference)"));
}

struct OptionCase {
  std::string args;  ///< {OUT} is replaced by an output path
};

// Every numeric option given nan, inf or an overflowing number is refused
// before anything is written.
TEST(Numbers, NonFiniteOptionsAreRefused) {
  const fs::path d = fresh_dir("numbers_options");
  const std::string out = (d / "out").string();
  const std::string post = std::string("post ") + kHsu + " ";
  std::vector<std::string> cases;
  for (const char* bad : {"nan", "inf", "-inf", "1e400"}) {
    const std::string b = bad;
    cases.push_back(post + "--work-offset " + b + ",200,100 samples/programs/pocket.ngc -o " + out);
    cases.push_back(post + "--work-offset 250,200,100 --tolerance-um " + b +
                    " samples/programs/pocket.ngc -o " + out);
    cases.push_back(post + "--initial-position 0," + b + ",0 samples/programs/pocket.ngc -o " +
                    out);
    cases.push_back(std::string("map ") + kHsu + " --spacing 100," + b + ",100 -o " + out);
    cases.push_back(std::string("map ") + kHsu + " --tolerance-um " + b + " -o " + out);
    cases.push_back(std::string("map ") + kHsu + " --spacing 100,100,100 --repeatability-um " + b +
                    " -o " + out);
    cases.push_back(std::string("map ") + kLei + " --tolerance-urad " + b + " -o " + out);
    cases.push_back(std::string("map ") + kHsu + " --spacing 100,100,100 --max-table-gib " + b +
                    " -o " + out);
    cases.push_back("kinematics --machine samples/machines/hsu-3axis.json --forward 1," + b + ",2");
    cases.push_back("kinematics --machine samples/machines/lei-hsu-xyzac.json --backward 0,0,0,0," +
                    b + ",1");
    cases.push_back("sensitivity --machine samples/machines/hsu-3axis.json --at " + b + ",1,1");
  }
  for (const std::string& a : cases) {
    const CliResult r = run_volmap_in_source(a);
    EXPECT_NE(r.status, 0) << a << "\n" << r.out;
    EXPECT_FALSE(has_non_finite(r.out)) << a << "\n" << r.out;
    EXPECT_EQ(std::count(r.err.begin(), r.err.end(), '\n'), 1) << a << "\n" << r.err;
    EXPECT_TRUE(fs::is_empty(d)) << a << " wrote something";
    fs::remove_all(d);
    fs::create_directories(d);
  }
  fs::remove_all(d);
}

// Zero or negative tolerances and spacings are usage mistakes, not a
// silent default.
TEST(Numbers, NonPositiveTolerancesAndSpacingsAreRefused) {
  const fs::path d = fresh_dir("numbers_nonpositive");
  const std::string out = (d / "out").string();
  for (const std::string& a :
       {std::string("post ") + kHsu +
            " --work-offset 250,200,100 --tolerance-um 0 samples/programs/pocket.ngc -o " + out,
        std::string("post ") + kHsu +
            " --work-offset 250,200,100 --tolerance-um -1 samples/programs/pocket.ngc -o " + out,
        std::string("map ") + kHsu + " --spacing 0,100,100 -o " + out,
        std::string("map ") + kHsu + " --spacing -50,100,100 -o " + out,
        std::string("map ") + kHsu + " --tolerance-um -1 -o " + out}) {
    const CliResult r = run_volmap_in_source(a);
    EXPECT_NE(r.status, 0) << a;
    EXPECT_TRUE(fs::is_empty(d)) << a << " wrote something";
    fs::remove_all(d);
    fs::create_directories(d);
  }
  fs::remove_all(d);
}

// What volmap writes from the samples holds finite numbers only.
TEST(Numbers, OutputsOfTheSamplesAreFinite) {
  const fs::path d = fresh_dir("numbers_outputs");
  const auto ok = [](const std::string& a) {
    const CliResult r = run_volmap_in_source(a);
    EXPECT_EQ(r.status, 0) << a << "\n" << r.err;
    return r;
  };
  ok(std::string("post ") + kHsu + " --work-offset 250,200,100 samples/programs/pocket.ngc -o " +
     (d / "pocket.ngc").string());
  EXPECT_FALSE(has_non_finite(file_bytes(d / "pocket.ngc")));
  // Five axes: the grid includes A = 0, where C is singular.
  ok(std::string("map ") + kLei + " --spacing 150,125,125,26,90 -o " + (d / "lei.vmt").string());
  ok("export --table " + (d / "lei.vmt").string() + " --format csv -o " + (d / "lei").string());
  for (const fs::directory_entry& e : fs::directory_iterator(d / "lei")) {
    const std::string text = file_bytes(e.path());
    EXPECT_FALSE(text.empty());
    EXPECT_FALSE(has_non_finite(text)) << e.path();
  }
  const CliResult json = ok(std::string("map ") + kHsu + " --spacing 100,100,100 --json -o " +
                            (d / "hsu.vmt").string());
  EXPECT_FALSE(has_non_finite(json.out)) << json.out;
  fs::remove_all(d);
}

// The singular pose of the X'Y'ZA'C' sample: A = 0 (tool axis along the C
// axis), where C is undetermined. Backward gives finite solutions, and the
// correction there is finite (the outer rotary correction is suppressed).
TEST(Numbers, SingularPosesGiveFiniteNumbers) {
  for (const char* pose : {"0,0,0,0,0,1", "10,20,30,0,0,1", "0,0,110,0,0,1", "0,0,0,0,0,-1"}) {
    const CliResult r = run_volmap_in_source(
        std::string("kinematics --machine samples/machines/lei-hsu-xyzac.json --errors "
                    "samples/errors/lei-hsu-xyzac.csv --backward ") +
        pose + " --json");
    if (r.status != 0) {  // a pose out of reach is refused with a message
      EXPECT_EQ(std::count(r.err.begin(), r.err.end(), '\n'), 1) << r.err;
      continue;
    }
    EXPECT_FALSE(has_non_finite(r.out)) << pose << ": " << r.out;
    const nlohmann::json doc = nlohmann::json::parse(r.out);
    EXPECT_FALSE(doc["solutions"].empty()) << pose;
  }
  for (const char* at : {"0,0,0,0,0", "10,20,30,0,45", "-100,50,300,0,-170"}) {
    const CliResult f = run_volmap_in_source(
        std::string("kinematics --machine samples/machines/lei-hsu-xyzac.json --errors "
                    "samples/errors/lei-hsu-xyzac.csv --forward ") +
        at + " --json");
    ASSERT_EQ(f.status, 0) << f.err;
    EXPECT_FALSE(has_non_finite(f.out)) << at << ": " << f.out;
    const CliResult s = run_volmap_in_source(
        std::string("sensitivity --machine samples/machines/lei-hsu-xyzac.json --at ") + at +
        " --json");
    ASSERT_EQ(s.status, 0) << s.err;
    EXPECT_FALSE(has_non_finite(s.out)) << at << ": " << s.out;
  }
}

// An errors table that covers X 0..200 only (the machine travels to 500).
std::string short_table(const fs::path& d) {
  const fs::path p = d / "short.csv";
  std::ofstream(p) << "X,EXX,EYX\n0,0.0,0.0\n100,2.0,1.0\n200,3.0,1.5\n\n"
                      "Y,EYY\n0,0.0\n400,4.0\n\nZ,EZZ\n0,0.0\n300,-3.0\n";
  return p.string();
}

TEST(Numbers, OutsideTheTableIsAnErrorByDefaultAndHeldWithClamp) {
  const fs::path d = fresh_dir("numbers_outside");
  const std::string errors = short_table(d);
  const fs::path prog = d / "p.ngc";
  std::ofstream(prog) << "G21 G90\nG0 X10 Y10 Z10\nG1 X100 F100\nG1 X250\nM2\n";
  const std::string base = "post --machine samples/machines/hsu-3axis.json --errors " + errors +
                           " --work-offset 0,0,0 " + prog.string() + " -o " +
                           (d / "out.ngc").string();
  const CliResult refused = run_volmap_in_source(base);
  EXPECT_EQ(refused.status, 1);
  EXPECT_FALSE(fs::exists(d / "out.ngc"));
  // Names the program line (4: G1 X250) and the table's range.
  EXPECT_NE(refused.err.find(prog.string() + ":4"), std::string::npos) << refused.err;
  EXPECT_NE(refused.err.find("200"), std::string::npos) << refused.err;
  EXPECT_EQ(std::count(refused.err.begin(), refused.err.end(), '\n'), 1) << refused.err;

  const CliResult clamped = run_volmap_in_source(base + " --clamp");
  ASSERT_EQ(clamped.status, 0) << clamped.err;
  const std::string out = file_bytes(d / "out.ngc");
  EXPECT_FALSE(has_non_finite(out));
  // Beyond 200 the X error holds its end value (3 um): X250 becomes 249.997.
  EXPECT_NE(out.find("X249.997"), std::string::npos) << out;

  // map refuses a table that does not cover the travel (no silent extrapolation).
  const CliResult map =
      run_volmap_in_source("map --machine samples/machines/hsu-3axis.json --errors " + errors +
                           " --spacing 100,100,100 -o " + (d / "t.vmt").string());
  EXPECT_EQ(map.status, 1) << map.err;
  EXPECT_FALSE(fs::exists(d / "t.vmt"));
  fs::remove_all(d);
}

}  // namespace
}  // namespace volmap::test
