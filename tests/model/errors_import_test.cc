// Error sources in ISG CSV and the Etalon exchange format
// (core/errors_import.h): units, detection, and bad input reported with the
// original file's line.
#include "core/model/errors_import.h"

#include <gtest/gtest.h>

#include <array>
#include <sstream>
#include <string>

#include "core/common/input_error.h"
#include "tests/support/cli_in_source.h"
#include "tests/support/cli_run.h"
#include "tests/support/test_paths.h"

namespace volmap {
namespace {

ErrorSet read(const std::string& text, ErrorsFormat f = ErrorsFormat::kAuto) {
  std::istringstream in(text);
  return read_errors(in, "test.txt", f);
}

std::array<double, kComponentCount> at(const ErrorSet& e, AxisName a, double q) {
  std::array<double, kComponentCount> v{};
  evaluate_axis(*e.errors_of(a), q, 0, OutsidePolicy::kError, v);
  return v;
}

// The layout of the ISG documentation's examples: blank-separated, "//"
// comments, "#" between blocks, position errors without the E.
const char* kIsg =
    "// position errors\n"
    "Y0A\tZ0A  C0X\n"
    "0.1\t0.2  0.00001\n"
    "#\n"
    "// component errors of the X axis\n"
    "X      EXX    EYX    EZX    EAX    EBX    ECX\n"
    "0.0    0.002  0.001  0.007  0.00   0.0000042 0.000003\n"
    "10.0   0.000  -0.001 0.001  0.00   0.0000011 0.000002   // a trailing comment\n"
    "20.0   0.001  0.000  0.000  0.00   0.0       0.0\n";

TEST(ErrorsImport, IsgCsvUnitsAreMillimetresAndRadians) {
  EXPECT_EQ(detect_errors_format(kIsg), ErrorsFormat::kIsgCsv);
  const ErrorSet e = read(kIsg);
  EXPECT_EQ(e.metadata.at("format"), "isg-csv");
  const auto v = at(e, AxisName::X, 10.0);
  EXPECT_DOUBLE_EQ(v[0], 0.000);
  EXPECT_NEAR(v[1], -0.001, 1e-15);     // mm, internal unit mm
  EXPECT_NEAR(v[4], 0.0000011, 1e-18);  // rad
  EXPECT_NEAR(e.location_error("EC0X"), 1e-5, 1e-18);
  EXPECT_NEAR(e.location_error("EY0A"), 0.1, 1e-15);
}

TEST(ErrorsImport, IsgCsvRotaryArgumentsAreDegrees) {
  const ErrorSet e = read("C EXC ECC\n0 0.001 0.00001\n90 0.002 0.00002\n180 0.001 0.0\n");
  const auto v = at(e, AxisName::C, M_PI / 2);  // 90 degrees
  EXPECT_NEAR(v[0], 0.002, 1e-15);
  EXPECT_NEAR(v[5], 0.00002, 1e-18);
}

TEST(ErrorsImport, EtalonVendorVariant) {
  const std::string text =
      "// Etalon exchange format, Vendor\n"
      "[C0B]\n"
      "VALUE = 0.000022355737\n"
      "[A0B]\n"
      "VALUE = 0.000047622950\n"
      "[EXY]\n"
      "Gridpoints = {\n"
      "   -280.0 -0.001358635132\n"
      "   -270.0 -0.000240680764\n"
      "   -260.0 0.000877273605 // comment\n"
      "}  // end of EXY\n"
      "[MACHINE]\n"
      "NAME = test\n";
  EXPECT_EQ(detect_errors_format(text), ErrorsFormat::kEtalon);
  const ErrorSet e = read(text);
  EXPECT_NEAR(at(e, AxisName::Y, -270.0)[0], -0.000240680764, 1e-15);
  EXPECT_NEAR(e.location_error("EC0B"), 0.000022355737, 1e-15);
  EXPECT_NEAR(e.location_error("EA0B"), 0.000047622950, 1e-15);
  EXPECT_EQ(e.metadata.at("skipped"), "MACHINE");
}

TEST(ErrorsImport, TablesNameTheOriginalLineInLaterMessages) {
  const ErrorSet e = read("// c\n\n[EXX]\nGridpoints = {\n0 0\n100 0.001\n}\n");
  EXPECT_EQ(e.errors_of(AxisName::X)->plus.source, "test.txt:3");
  const ErrorSet i = read("// c\nX EXX\n0 0\n100 0.001\n");
  EXPECT_EQ(i.errors_of(AxisName::X)->plus.source, "test.txt:2");
}

TEST(ErrorsImport, VolmapFilesAreDetectedAsVolmap) {
  EXPECT_EQ(detect_errors_format("# volmap component errors v1\nX,EXX\n0,1\n"),
            ErrorsFormat::kVolmap);
  EXPECT_EQ(detect_errors_format("X,EXX\n0,1\n"), ErrorsFormat::kVolmap);
  // One name alone: errors.md and ISG CSV write a one-column location
  // block alike (values 1e6 apart); a # comment before it says errors.md,
  // nothing else tells them apart, and read_errors refuses it.
  int ambiguous = -1;
  EXPECT_EQ(detect_errors_format("# volmap component errors v1\nEC0X\n12.0\n", &ambiguous),
            ErrorsFormat::kVolmap);
  EXPECT_EQ(ambiguous, 0);
  detect_errors_format("\nEC0X\n12.0\n", &ambiguous);
  EXPECT_EQ(ambiguous, 2);
  EXPECT_EQ(detect_errors_format("X EXX\n0 1\n", &ambiguous), ErrorsFormat::kIsgCsv);
  EXPECT_EQ(ambiguous, 0);
  std::istringstream one("EC0X\n12.0\n");
  EXPECT_THROW(read_errors(one, "one.csv"), InputError);
  std::istringstream told("EC0X\n12.0\n");
  EXPECT_NEAR(read_errors(told, "one.csv", ErrorsFormat::kVolmap).location.at("EC0X"), 12e-6,
              1e-18);
  EXPECT_EQ(parse_errors_format("etalon"), ErrorsFormat::kEtalon);
  EXPECT_THROW(parse_errors_format("xls"), std::invalid_argument);
}

void expect_error_at(const std::string& text, const std::string& where) {
  try {
    read(text);
    FAIL() << "accepted: " << text;
  } catch (const InputError& e) {
    EXPECT_EQ(std::string(e.what()).rfind("test.txt:" + where + ":", 0), 0u) << e.what();
  }
}

TEST(ErrorsImport, BadInputNamesTheOriginalLine) {
  // Not increasing, in the original's line 4.
  expect_error_at("// c\nX EXX\n0 0.001\n0 0.002\n", "4");
  // Two arguments: a functional dependency volmap does not model.
  expect_error_at("Z X EXX\n0 0 0.001\n", "1:2");
  // Unknown name.
  expect_error_at("X EQX\n0 0.001\n", "1:2");
  // A non-numeric cell, Etalon, line 4.
  expect_error_at("[EXX]\nGridpoints = {\n0 0.0\nten 0.1\n}\n", "4");
  // A Gridpoints row with three numbers.
  expect_error_at("[EXX]\nGridpoints = {\n0 0.0 1\n}\n", "3");
  // An open grid.
  expect_error_at("[EXX]\nGridpoints = {\n0 0.0\n", "3");
}

// The same errors written in the three formats (tests/data/errors/formats/).
std::string formats_file(const std::string& name) {
  return test::source_path("tests/data/errors/formats/" + name);
}

TEST(ErrorsImport, TheThreeFormatsOfTheSameErrorsAgree) {
  const ErrorSet v = load_errors(formats_file("hsu-small.csv"));
  const ErrorSet i = load_errors(formats_file("hsu-small.isg.csv"));
  const ErrorSet e = load_errors(formats_file("hsu-small.etalon.txt"));
  EXPECT_EQ(i.metadata.at("format"), "isg-csv");
  EXPECT_EQ(e.metadata.at("format"), "etalon");
  EXPECT_EQ(e.metadata.at("skipped"), "INFO");
  for (AxisName a : {AxisName::X, AxisName::Y, AxisName::Z})
    for (double q : {0.0, 37.5, 150.0, 199.0, 300.0}) {
      const auto want = at(v, a, q);
      for (const ErrorSet* other : {&i, &e}) {
        const auto got = at(*other, a, q);
        for (int c = 0; c < kComponentCount; ++c)
          EXPECT_NEAR(got[static_cast<size_t>(c)], want[static_cast<size_t>(c)], 1e-15)
              << axis_char(a) << q << c;
      }
    }
  for (const char* n : {"EC0X", "EB0Z", "EA0Z"}) {
    EXPECT_NEAR(i.location_error(n), v.location_error(n), 1e-18) << n;
    EXPECT_NEAR(e.location_error(n), v.location_error(n), 1e-18) << n;
  }
}

TEST(ErrorsImport, PostWritesTheSameProgramFromEveryFormat) {
  std::string reference;
  for (const char* f : {"hsu-small.csv", "hsu-small.isg.csv", "hsu-small.etalon.txt"}) {
    const test::CliResult r =
        test::run_volmap("post --machine " + test::source_path("samples/machines/hsu-3axis.json") +
                         " --errors " + formats_file(f) + " --work-offset 100,100,50 " +
                         test::source_path("samples/programs/pocket.ngc") + " -o -");
    ASSERT_EQ(r.status, 0) << f << ": " << r.err;
    if (reference.empty()) reference = r.out;
    EXPECT_EQ(r.out, reference) << f;
  }
  EXPECT_NE(reference, test::file_bytes(test::source_path("samples/programs/pocket.ngc")))
      << "corrected";
  // An explicit format that does not match is an error naming the file.
  const test::CliResult r = test::run_volmap(
      "post --machine " + test::source_path("samples/machines/hsu-3axis.json") + " --errors " +
      formats_file("hsu-small.etalon.txt") + " --errors-format volmap --work-offset 100,100,50 " +
      test::source_path("samples/programs/pocket.ngc") + " -o -");
  EXPECT_EQ(r.status, 1);
  EXPECT_NE(r.err.find("hsu-small.etalon.txt"), std::string::npos) << r.err;
}

}  // namespace
}  // namespace volmap
