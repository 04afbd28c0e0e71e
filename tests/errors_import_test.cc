// Error sources in ISG CSV and the Etalon exchange format
// (core/errors_import.h): units, detection, and bad input reported with the
// original file's line.
#include <array>
#include <sstream>
#include <string>

#include <gtest/gtest.h>

#include "core/errors_import.h"
#include "core/input_error.h"

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
  EXPECT_NEAR(v[1], -0.001, 1e-15);           // mm, internal unit mm
  EXPECT_NEAR(v[4], 0.0000011, 1e-18);        // rad
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

TEST(ErrorsImport, VolmapFilesAreDetectedAsVolmap) {
  EXPECT_EQ(detect_errors_format("# volmap component errors v1\nX,EXX\n0,1\n"), ErrorsFormat::kVolmap);
  EXPECT_EQ(detect_errors_format("X,EXX\n0,1\n"), ErrorsFormat::kVolmap);
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

}  // namespace
}  // namespace volmap
