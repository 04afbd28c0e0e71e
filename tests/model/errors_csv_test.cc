// Reader for the errors CSV (spec: shared/spec/errors.md): the spec's example
// in internal units, every block form, and one file per bad-input rule with
// its message checked for file name, line number and key words.
#include "core/model/errors_csv.h"

#include <gtest/gtest.h>

#include <array>
#include <cmath>
#include <filesystem>
#include <numbers>
#include <set>
#include <sstream>
#include <string>
#include <vector>

#include "core/common/input_error.h"

namespace volmap {
namespace {

constexpr double kDeg = std::numbers::pi / 180.0;
constexpr double kUm = 1e-3;    // um in mm
constexpr double kUrad = 1e-6;  // urad in rad

std::string data_path(const std::string& name) {
  return std::string(VOLMAP_SOURCE_DIR) + "/tests/data/errors/" + name;
}

std::array<double, kComponentCount> at(const AxisErrors& e, double q, int dir = 1) {
  std::array<double, kComponentCount> out{};
  evaluate_axis(e, q, dir, OutsidePolicy::kError, out);
  return out;
}

constexpr int EX = 0, EY = 1, EZ = 2, EA = 3, EB = 4, EC = 5;

TEST(ErrorsCsv, SpecExampleInInternalUnits) {
  const std::string path = data_path("spec_example.csv");
  const ErrorSet set = load_errors_csv(path);
  EXPECT_EQ(set.file, path);
  ASSERT_EQ(set.metadata.size(), 2u);
  EXPECT_EQ(set.metadata.at("machine"), "samples/machines/hsu-3axis.json");
  EXPECT_EQ(set.metadata.at("source"), "laser interferometer, 2026-03-02, 20.1 C");

  const AxisErrors* x = set.errors_of(AxisName::X);
  ASSERT_NE(x, nullptr);
  EXPECT_EQ(x->axis, AxisName::X);
  EXPECT_FALSE(x->bidirectional());
  for (bool p : x->present) EXPECT_TRUE(p);
  EXPECT_EQ(x->plus.position, (std::vector<double>{0.0, 100.0, 200.0}));
  EXPECT_EQ(x->plus.source, path + ":5");
  EXPECT_FALSE(x->plus.periodic);
  // Knot values, exactly as tabulated, converted.
  EXPECT_DOUBLE_EQ(x->plus.value[1][EX], 2.1 * kUm);
  EXPECT_DOUBLE_EQ(x->plus.value[1][EY], -0.8 * kUm);
  EXPECT_DOUBLE_EQ(x->plus.value[1][EZ], 0.5 * kUm);
  EXPECT_DOUBLE_EQ(x->plus.value[1][EA], 1.2 * kUrad);
  EXPECT_DOUBLE_EQ(x->plus.value[1][EB], -3.0 * kUrad);
  EXPECT_DOUBLE_EQ(x->plus.value[2][EC], 0.9 * kUrad);
  const std::array<double, kComponentCount> x100 = at(*x, 100.0);
  EXPECT_DOUBLE_EQ(x100[EX], 2.1 * kUm);
  EXPECT_DOUBLE_EQ(x100[EB], -3.0 * kUrad);
  const std::array<double, kComponentCount> x200 = at(*x, 200.0);
  EXPECT_DOUBLE_EQ(x200[EX], 3.9 * kUm);
  EXPECT_DOUBLE_EQ(x200[EB], -5.5 * kUrad);

  // Two rows: linear.
  const AxisErrors* y = set.errors_of(AxisName::Y);
  ASSERT_NE(y, nullptr);
  const std::array<double, kComponentCount> y50 = at(*y, 50.0);
  EXPECT_NEAR(y50[EY], 0.25 * 4.4 * kUm, 1e-15);
  EXPECT_NEAR(y50[EC], 0.25 * 3.1 * kUrad, 1e-18);

  // Bidirectional Z with three of six components.
  const AxisErrors* z = set.errors_of(AxisName::Z);
  ASSERT_NE(z, nullptr);
  EXPECT_TRUE(z->bidirectional());
  EXPECT_EQ(z->present, (std::array<bool, kComponentCount>{true, true, true, false, false, false}));
  EXPECT_DOUBLE_EQ(at(*z, 150.0, +1)[EZ], -3.3 * kUm);
  EXPECT_DOUBLE_EQ(at(*z, 150.0, -1)[EZ], -1.1 * kUm);
  EXPECT_DOUBLE_EQ(at(*z, 0.0, -1)[EZ], 2.0 * kUm);
  EXPECT_DOUBLE_EQ(at(*z, 0.0, 0)[EZ], 1.0 * kUm);
  EXPECT_DOUBLE_EQ(at(*z, 150.0, -1)[EX], 0.6 * kUm);
  EXPECT_EQ(at(*z, 75.0, -1)[EA], 0.0);  // missing component: zero

  EXPECT_EQ(set.errors_of(AxisName::A), nullptr);
  EXPECT_EQ(set.errors_of(AxisName::C), nullptr);

  // Location errors: angular, urad -> rad.
  ASSERT_EQ(set.location.size(), 3u);
  EXPECT_DOUBLE_EQ(set.location_error("EC0X"), 12.0 * kUrad);
  EXPECT_DOUBLE_EQ(set.location_error("EB0Z"), -5.0 * kUrad);
  EXPECT_DOUBLE_EQ(set.location_error("EA0Z"), 3.0 * kUrad);
  EXPECT_EQ(set.location_error("EA0Y"), 0.0);
}

TEST(ErrorsCsv, CrlfBomLetterOWhitespaceAndPlusSigns) {
  const std::string path = data_path("crlf_bom.csv");
  const ErrorSet set = load_errors_csv(path);
  EXPECT_EQ(set.metadata.at("machine"), "crlf-machine");
  EXPECT_EQ(set.metadata.at("operator"), "Jane Doe");
  const AxisErrors* x = set.errors_of(AxisName::X);
  ASSERT_NE(x, nullptr);
  EXPECT_EQ(x->plus.source, path + ":3");  // the BOM does not shift lines
  EXPECT_DOUBLE_EQ(at(*x, 0.0)[EX], 1.5 * kUm);
  EXPECT_DOUBLE_EQ(at(*x, 50.0)[EB], -4.0 * kUrad);
  EXPECT_EQ(x->present,
            (std::array<bool, kComponentCount>{true, false, false, false, true, false}));
  // ECOX / EBOZ: letter O read as the zero, stored by canonical name.
  EXPECT_DOUBLE_EQ(set.location_error("EC0X"), 7.0 * kUrad);
  EXPECT_DOUBLE_EQ(set.location_error("EB0Z"), -8.0 * kUrad);
  EXPECT_EQ(set.location.count("ECOX"), 0u);
}

TEST(ErrorsCsv, StreamInputAndTranslationalLocationErrors) {
  std::istringstream in(
      "\xEF\xBB\xBF"
      "C,ECC\r\n0,0\r\n90,1\r\n\r\nEX0C,EY0C,EC0C\r\n5,-6,7\r\n");
  const ErrorSet set = read_errors_csv(in, "mem.csv");
  EXPECT_EQ(set.file, "mem.csv");
  EXPECT_DOUBLE_EQ(set.location_error("EX0C"), 5.0 * kUm);
  EXPECT_DOUBLE_EQ(set.location_error("EY0C"), -6.0 * kUm);
  EXPECT_DOUBLE_EQ(set.location_error("EC0C"), 7.0 * kUrad);
  const AxisErrors* c = set.errors_of(AxisName::C);
  ASSERT_NE(c, nullptr);
  // Rotary positions: degrees -> rad.
  EXPECT_DOUBLE_EQ(c->plus.max_position(), 90.0 * kDeg);
  EXPECT_DOUBLE_EQ(at(*c, 45.0 * kDeg)[EC], 0.5 * kUrad);
  EXPECT_FALSE(c->plus.periodic);
  EXPECT_EQ(c->plus.axis, AxisName::C);
}

TEST(ErrorsCsv, EmptyAndCommentOnlyInputsGiveAnEmptySet) {
  std::istringstream in("# only: metadata\n\n   \n# and comments\n");
  const ErrorSet set = read_errors_csv(in, "empty.csv");
  EXPECT_EQ(set.metadata.at("only"), "metadata");
  for (const auto& a : set.axis) EXPECT_FALSE(a.has_value());
  EXPECT_TRUE(set.location.empty());
}

TEST(ErrorsCsv, MetadataOnlyBeforeTheFirstBlock) {
  std::istringstream in(
      "# machine: m1\n# a remark: with a colon is prose, not metadata\n"
      "#key:value\nX,EXX\n0,0\n# late: ignored\n1,1\n");
  const ErrorSet set = read_errors_csv(in, "m.csv");
  EXPECT_EQ(set.metadata.size(), 2u);
  EXPECT_EQ(set.metadata.at("machine"), "m1");
  EXPECT_EQ(set.metadata.at("key"), "value");
  EXPECT_EQ(set.metadata.count("late"), 0u);
}

TEST(ErrorsCsv, SeveralBlocksPerAxisMergeOntoTheUnionOfKnots) {
  const ErrorSet set = load_errors_csv(data_path("multi_block.csv"));
  EXPECT_EQ(set.metadata.at("machine"), "multi");
  const AxisErrors* x = set.errors_of(AxisName::X);
  ASSERT_NE(x, nullptr);
  EXPECT_EQ(x->plus.source, data_path("multi_block.csv") + ":3");
  EXPECT_EQ(x->plus.position, (std::vector<double>{0.0, 50.0, 100.0, 150.0, 200.0, 300.0}));
  EXPECT_EQ(x->present, (std::array<bool, kComponentCount>{true, true, true, false, false, true}));
  // Every component hits its own knots exactly.
  EXPECT_DOUBLE_EQ(at(*x, 200.0)[EX], 3.0 * kUm);
  EXPECT_DOUBLE_EQ(at(*x, 300.0)[EY], -2.0 * kUm);
  EXPECT_DOUBLE_EQ(at(*x, 50.0)[EZ], 2.0 * kUm);
  EXPECT_DOUBLE_EQ(at(*x, 150.0)[EZ], 0.5 * kUm);
  EXPECT_DOUBLE_EQ(at(*x, 100.0)[EC], 5.0 * kUrad);
  EXPECT_DOUBLE_EQ(at(*x, 200.0)[EC], 6.0 * kUrad);
  // ECX (100..200, two rows: linear) is held at its end values beyond its
  // own range, at every merged knot...
  EXPECT_DOUBLE_EQ(at(*x, 0.0)[EC], 5.0 * kUrad);
  EXPECT_DOUBLE_EQ(at(*x, 50.0)[EC], 5.0 * kUrad);
  EXPECT_DOUBLE_EQ(at(*x, 300.0)[EC], 6.0 * kUrad);
  // ...and constant from the first merged knot past its end on (0..50).
  EXPECT_DOUBLE_EQ(at(*x, 25.0)[EC], 5.0 * kUrad);
  // Inside its range it stays linear.
  EXPECT_NEAR(at(*x, 150.0)[EC], 5.5 * kUrad, 1e-18);
  EXPECT_NEAR(at(*x, 125.0)[EC], 5.25 * kUrad, 1e-18);
}

TEST(ErrorsCsv, BidirectionalAndOneDirectionBlocks) {
  const ErrorSet set = load_errors_csv(data_path("bidirectional.csv"));
  const AxisErrors* y = set.errors_of(AxisName::Y);
  ASSERT_NE(y, nullptr);
  ASSERT_TRUE(y->bidirectional());
  EXPECT_DOUBLE_EQ(at(*y, 100.0, +1)[EY], 10.0 * kUm);
  EXPECT_DOUBLE_EQ(at(*y, 100.0, -1)[EY], 6.0 * kUm);
  EXPECT_DOUBLE_EQ(at(*y, 100.0, 0)[EY], 8.0 * kUm);
  // EXY was given with dir=-1 rows only: it serves both directions.
  EXPECT_NEAR(at(*y, 100.0, +1)[EX], 2.0 * kUm, 1e-15);
  EXPECT_NEAR(at(*y, 100.0, -1)[EX], 2.0 * kUm, 1e-15);
  EXPECT_NEAR(at(*y, 100.0, 0)[EX], 2.0 * kUm, 1e-15);

  // A dir block with +1 rows only is not bidirectional: one table for both.
  const AxisErrors* z = set.errors_of(AxisName::Z);
  ASSERT_NE(z, nullptr);
  EXPECT_FALSE(z->bidirectional());
  EXPECT_DOUBLE_EQ(at(*z, 100.0, -1)[EZ], 4.0 * kUm);
  EXPECT_DOUBLE_EQ(at(*z, 100.0, 0)[EA], 2.0 * kUrad);
}

TEST(ErrorsCsv, FullTurnRotaryTableIsPeriodic) {
  const ErrorSet set = load_errors_csv(data_path("periodic_c.csv"));
  const AxisErrors* c = set.errors_of(AxisName::C);
  ASSERT_NE(c, nullptr);
  EXPECT_TRUE(c->plus.periodic);
  EXPECT_DOUBLE_EQ(at(*c, 90.0 * kDeg)[EC], 10.0 * kUrad);
  EXPECT_DOUBLE_EQ(at(*c, 90.0 * kDeg)[EX], 2.0 * kUm);
  // Wraps: -90 degrees is 270, 450 is 90; nothing is outside.
  EXPECT_NEAR(at(*c, -90.0 * kDeg)[EC], -8.0 * kUrad, 1e-15);
  EXPECT_NEAR(at(*c, 450.0 * kDeg)[EC], 10.0 * kUrad, 1e-15);
  // The B table (-30..90 degrees) is not a full turn.
  const AxisErrors* b = set.errors_of(AxisName::B);
  ASSERT_NE(b, nullptr);
  EXPECT_FALSE(b->plus.periodic);
  EXPECT_DOUBLE_EQ(at(*b, -30.0 * kDeg)[EB], 1.0 * kUrad);
  std::array<double, kComponentCount> out{};
  EXPECT_THROW(evaluate_axis(*b, 91.0 * kDeg, 1, OutsidePolicy::kError, out), std::out_of_range);
}

TEST(ErrorsCsv, MissingFileIsAnInputError) {
  try {
    load_errors_csv(data_path("no_such_file.csv"));
    FAIL() << "no exception";
  } catch (const InputError& e) {
    const std::string what = e.what();
    EXPECT_NE(what.find("no_such_file.csv"), std::string::npos) << what;
    EXPECT_NE(what.find("cannot open"), std::string::npos) << what;
  }
}

// ---------------------------------------------------------------------------
// Bad input: one file per rule.

struct BadCase {
  const char* file;
  int line;
  std::vector<std::string> words;  // each must appear in the message
};

void PrintTo(const BadCase& c, std::ostream* os) { *os << c.file; }

class BadInput : public testing::TestWithParam<BadCase> {};

TEST_P(BadInput, ReportsFileLineAndWhatToDo) {
  const BadCase& c = GetParam();
  const std::string path = data_path(std::string("bad/") + c.file);
  try {
    load_errors_csv(path);
    FAIL() << c.file << ": no exception";
  } catch (const InputError& e) {
    const std::string what = e.what();
    EXPECT_EQ(e.file(), path);
    EXPECT_EQ(e.line(), c.line) << what;
    EXPECT_EQ(what.rfind(path + ":" + std::to_string(c.line) + ":", 0), 0u) << what;
    for (const std::string& w : c.words)
      EXPECT_NE(what.find(w), std::string::npos) << "'" << w << "' not in: " << what;
    EXPECT_NE(what.find("; "), std::string::npos) << "no advice in: " << what;
    EXPECT_EQ(what.find('\n'), std::string::npos);
  }
}

std::vector<BadCase> bad_cases() {
  return {
      BadCase{"unknown_name.csv", 1, {"unknown error name", "'EQX'"}},
      BadCase{"unknown_convention.csv", 2, {"unknown convention", "'lei-hsu'", "iso230-1", "link"}},
      BadCase{"wrong_axis.csv", 2, {"EYY", "belongs to the Y axis", "X axis"}},
      BadCase{"not_increasing.csv", 4, {"strictly increasing", "100", "line 3"}},
      BadCase{"not_increasing_dir.csv", 6, {"strictly increasing", "dir=-1", "40", "line 5"}},
      BadCase{"no_data_row.csv", 5, {"no data row"}},
      BadCase{"no_data_row_at_end.csv", 5, {"no data row"}},
      BadCase{"non_numeric.csv", 3, {"non-numeric", "'1.2.3'", "column EXX"}},
      BadCase{"nan_cell.csv", 3, {"non-finite", "'nan'", "column EYX"}},
      BadCase{"inf_cell.csv", 3, {"non-finite", "'inf'", "column EXX"}},
      BadCase{"empty_cell.csv", 3, {"empty cell", "column EXX"}},
      BadCase{"bad_dir.csv", 4, {"dir", "'0'", "+1", "-1"}},
      BadCase{"wrong_cell_count.csv", 3, {"2 cells", "header (line 1) has 3"}},
      BadCase{"duplicate_name.csv", 5, {"duplicate error name EXX", "line 1"}},
      BadCase{"duplicate_location.csv", 5, {"duplicate error name EC0X", "line 2"}},
      BadCase{"duplicate_column.csv", 1, {"duplicate column EXX"}},
      BadCase{"duplicate_dir.csv", 1, {"duplicate column dir"}},
      BadCase{"location_two_rows.csv", 3, {"exactly one data row"}},
      BadCase{"location_in_component.csv", 1, {"location error EC0X", "component-error block"}},
      BadCase{
          "component_in_location.csv", 1, {"component error EXX", "location-error block", "X,EXX"}},
      BadCase{
          "unmodelled_location.csv", 1, {"EA0X", "not a location error volmap models", "itself"}},
      BadCase{"empty_header_cell.csv", 1, {"empty column name", "column 3"}},
      BadCase{"periodic_open.csv", 4, {"periodic table must close", "ECC", "line 2"}},
      BadCase{"periodic_mismatch.csv", 6, {"EXC", "same full turn", "line 1"}},
      BadCase{"header_is_data.csv", 4, {"data row, not a header"}},
      BadCase{"missing_blank_line.csv", 4, {"'Y'", "blank line"}},
      BadCase{"axis_not_first.csv", 1, {"axis column X", "first column"}},
      BadCase{"no_error_column.csv", 1, {"no error column", "EXX"}}};
}

INSTANTIATE_TEST_SUITE_P(ErrorsCsv, BadInput, testing::ValuesIn(bad_cases()),
                         [](const testing::TestParamInfo<BadCase>& info) {
                           std::string name = info.param.file;
                           return name.substr(0, name.find('.'));
                         });

TEST(ErrorsCsv, EveryBadFileHasACase) {
  std::set<std::string> listed;
  for (const BadCase& c : bad_cases()) listed.insert(c.file);
  int files = 0;
  for (const auto& entry : std::filesystem::directory_iterator(data_path("bad"))) {
    ++files;
    EXPECT_EQ(listed.count(entry.path().filename().string()), 1u)
        << entry.path() << " has no case in bad_cases()";
  }
  EXPECT_EQ(files, static_cast<int>(listed.size()));
}

TEST(ErrorsCsv, NumberSyntax) {
  auto read = [](const std::string& cell) {
    std::istringstream in("X,EXX\n0," + cell + "\n");
    return read_errors_csv(in, "n.csv").errors_of(AxisName::X)->plus.value[0][0];
  };
  EXPECT_DOUBLE_EQ(read("+2.5"), 2.5 * kUm);
  EXPECT_DOUBLE_EQ(read("-2.5e1"), -25.0 * kUm);
  EXPECT_DOUBLE_EQ(read(" 3 "), 3.0 * kUm);
  for (const char* bad :
       {"+-1", "++1", "0x10", "1,5", "1 5", "-inf", "infinity", "NaN", "2um", "--1", "+"}) {
    EXPECT_THROW(read(bad), InputError) << bad;
  }
}

}  // namespace
}  // namespace volmap
