// Recordings CSV (shared/spec/recordings.md): the spec's examples, free
// column order, extra columns, every bad-input rule with file:line, and the
// writer (hand-derived expected text, round trip, same bytes every run).
#include "core/measure/recordings.h"

#include <gtest/gtest.h>

#include <cmath>
#include <numbers>
#include <sstream>
#include <string>

#include "core/common/input_error.h"
#include "tests/support/test_paths.h"

namespace volmap {
namespace {

std::string data(const std::string& rel) {
  return test::source_path("tests/data/recordings/" + rel);
}
constexpr double kDeg = std::numbers::pi / 180.0;
constexpr std::size_t X = 0, C = 5;

TEST(Recordings, SpecLaserExample) {
  const Recordings r = load_recordings_csv(data("spec_laser.csv"));
  ASSERT_EQ(r.size(), 7u);
  EXPECT_EQ(r.line.front(), 3);
  EXPECT_EQ(r.line.back(), 9);
  EXPECT_DOUBLE_EQ(r.position[X][2], 200.0);
  EXPECT_DOUBLE_EQ(r.position[1][0], 200.0);
  EXPECT_EQ(r.dir[X][2], 1);
  EXPECT_EQ(r.dir[X][3], -1);
  EXPECT_DOUBLE_EQ(r.e_um[0][3], 8.2);
  EXPECT_FALSE(r.has_component(1));
  EXPECT_FALSE(r.has_axis(AxisName::A));
  EXPECT_DOUBLE_EQ(r.t_s[6], 72.0);
  ASSERT_EQ(r.run_names.size(), 2u);
  EXPECT_EQ(r.run_names[static_cast<std::size_t>(r.run[6])], "2");
  EXPECT_EQ(r.frame, RecordingFrame::kWorkpiece);
}

TEST(Recordings, SpecProbeBallExampleConvertsDegrees) {
  const Recordings r = load_recordings_csv(data("spec_probe_ball.csv"));
  ASSERT_EQ(r.size(), 2u);
  EXPECT_NEAR(r.position[3][1], -30.0 * kDeg, 1e-15);
  EXPECT_NEAR(r.position[C][1], 45.0 * kDeg, 1e-15);
  EXPECT_DOUBLE_EQ(r.e_um[2][1], 6.6);
  EXPECT_EQ(r.metadata.at("frame"), "workpiece");
}

TEST(Recordings, FreeOrderExtraColumnsProjectionAndMetadata) {
  const Recordings r = load_recordings_csv(data("free_order.csv"));
  ASSERT_EQ(r.size(), 3u);
  EXPECT_EQ(r.frame, RecordingFrame::kMachine);
  EXPECT_EQ(r.metadata.at("machine"), "m.json");
  EXPECT_EQ(r.metadata.count("a prose comment"), 0u);
  EXPECT_EQ(r.line[0], 7);   // BOM, CRLF, comments and a blank line before
  EXPECT_EQ(r.line[2], 10);  // a comment between rows is skipped
  EXPECT_DOUBLE_EQ(r.e_um[2][0], 1.5);
  EXPECT_TRUE(std::isnan(r.e_um[2][1]));  // empty cell: not recorded
  EXPECT_FALSE(r.has_component(0));
  EXPECT_NEAR(r.position[C][1], std::numbers::pi, 1e-15);
  ASSERT_TRUE(r.has_projection());
  EXPECT_TRUE(std::isnan(r.e_along_n_um[0]));
  EXPECT_DOUBLE_EQ(r.e_along_n_um[1], 2.25);
  EXPECT_DOUBLE_EQ(r.n[1][1], 0.8);
  EXPECT_DOUBLE_EQ(r.weight[0], 2.0);
  EXPECT_DOUBLE_EQ(r.weight[1], 1.0);  // empty weight: 1
  EXPECT_DOUBLE_EQ(r.feed_mm_min[0], 1000.0);
  EXPECT_DOUBLE_EQ(r.tool_mm[0], 100.5);
  EXPECT_EQ(r.dir[C][0], -1);
  EXPECT_EQ(r.dir[C][1], 0);  // empty dir: 0
  ASSERT_EQ(r.temperature_c.size(), 1u);
  EXPECT_EQ(r.temperature_c[0].name, "temp_air_c");
  EXPECT_DOUBLE_EQ(r.temperature_c[0].values[2], 21.0);
  ASSERT_EQ(r.extra.size(), 1u);
  EXPECT_EQ(r.extra[0].name, "operator");
  EXPECT_EQ(r.extra[0].text[1], "bob");
  EXPECT_EQ(r.extra[0].text[2], "");
  EXPECT_TRUE(std::isnan(r.extra[0].value[0]));
}

TEST(Recordings, ColumnNamesAreCaseSensitive) {
  std::istringstream in("X_MM,x_mm,EX_UM,ex_um\n1,2,3,4\n");
  const Recordings r = read_recordings_csv(in, "case.csv");
  EXPECT_DOUBLE_EQ(r.position[X][0], 2.0);
  EXPECT_DOUBLE_EQ(r.e_um[0][0], 4.0);
  ASSERT_EQ(r.extra.size(), 2u);
  EXPECT_EQ(r.extra[0].name, "X_MM");
  EXPECT_DOUBLE_EQ(r.extra[1].value[0], 3.0);
}

struct BadCase {
  const char* file;
  int line;
  const char* says;
};

class BadRecordings : public ::testing::TestWithParam<BadCase> {};

TEST_P(BadRecordings, NamesFileLineAndWhatToDo) {
  const BadCase& c = GetParam();
  const std::string path = data(std::string("bad/") + c.file);
  try {
    (void)load_recordings_csv(path);
    FAIL() << c.file << " was accepted";
  } catch (const InputError& e) {
    const std::string msg = e.what();
    EXPECT_EQ(e.line(), c.line) << msg;
    EXPECT_EQ(msg.rfind(path + ":" + std::to_string(c.line) + ":", 0), 0u) << msg;
    EXPECT_NE(msg.find(c.says), std::string::npos) << msg;
    EXPECT_EQ(msg.find('\n'), std::string::npos);
    EXPECT_NE(msg.find(';'), std::string::npos) << "no hint: " << msg;
  }
}

INSTANTIATE_TEST_SUITE_P(
    Rules, BadRecordings,
    ::testing::Values(
        BadCase{"no_axis_column.csv", 1, "no axis column"},
        BadCase{"no_deviation_column.csv", 1, "no deviation column"},
        BadCase{"incomplete_projection.csv", 1, "missing nz"},
        BadCase{"wrong_cell_count.csv", 4, "row has 3 cells"},
        BadCase{"not_a_number.csv", 3, "ex_um 'abc' is not a number"},
        BadCase{"position_not_a_number.csv", 3, "x_mm '1O' is not a number"},
        BadCase{"not_unit.csv", 3, "not 1 within 0.001"}, BadCase{"bad_dir.csv", 3, "-1, 0 or +1"},
        BadCase{"fractional_dir.csv", 2, "-1, 0 or +1"},
        BadCase{"nan_deviation.csv", 3, "ex_um is nan"},
        BadCase{"inf_position.csv", 3, "x_mm is inf"}, BadCase{"inf_time.csv", 2, "t_s is inf"},
        BadCase{"empty_position.csv", 3, "x_mm is empty"},
        BadCase{"duplicate_column.csv", 1, "duplicate column ex_um"},
        BadCase{"empty_header_cell.csv", 1, "empty column name"},
        BadCase{"projection_missing_n.csv", 2, "nx is empty"},
        BadCase{"negative_weight.csv", 2, "negative"}, BadCase{"bad_frame.csv", 1, "frame 'table'"},
        BadCase{"no_header.csv", 2, "no header row"}),
    [](const auto& info) {
      std::string n = info.param.file;
      return n.substr(0, n.find('.'));
    });

Recordings small() {
  Recordings r;
  r.metadata["machine"] = "m.json";
  r.line = {0, 0};
  r.run = {r.run_index("a"), -1};
  r.t_s = {1.5, std::nan("")};
  r.position[X] = {100.0, -0.0000001};
  r.position[C] = {90.0 * kDeg, -45.0 * kDeg};
  r.dir[X] = {1, -1};
  r.e_um[0] = {1.25, std::nan("")};
  r.e_um[2] = {-0.0000000001, 3.0};
  r.extra.push_back({"note", {"x", ""}, {std::nan(""), std::nan("")}});
  return r;
}

TEST(RecordingsWriter, FixedDecimalsAsDocumented) {
  std::ostringstream out;
  write_recordings_csv(out, small());
  // Written by hand from the documented layout: column order, 6 decimals
  // for mm, 9 for degrees and um, 3 for seconds, empty for NaN, -0 as 0,
  // frame line for a recording with rotary axes.
  const std::string expected =
      "# volmap recordings v1\n"
      "# frame: workpiece\n"
      "# machine: m.json\n"
      "run,t_s,x_mm,c_deg,dir_x,ex_um,ez_um,note\n"
      "a,1.500,100.000000,90.000000000,+1,1.250000000,0.000000000,x\n"
      ",,0.000000,-45.000000000,-1,,3.000000000,\n";
  EXPECT_EQ(out.str(), expected);
}

TEST(RecordingsWriter, RoundTripAndSameBytes) {
  const Recordings a = load_recordings_csv(data("free_order.csv"));
  std::ostringstream once, twice;
  write_recordings_csv(once, a);
  write_recordings_csv(twice, a);
  EXPECT_EQ(once.str(), twice.str());
  std::istringstream in(once.str());
  const Recordings b = read_recordings_csv(in, "again.csv");
  ASSERT_EQ(b.size(), a.size());
  EXPECT_EQ(b.frame, a.frame);
  EXPECT_EQ(b.metadata, a.metadata);
  for (std::size_t i = 0; i < a.size(); ++i) {
    EXPECT_NEAR(b.position[C][i], a.position[C][i], 1e-12);
    EXPECT_EQ(std::isnan(b.e_um[2][i]), std::isnan(a.e_um[2][i]));
    if (!std::isnan(a.e_um[2][i])) {
      EXPECT_DOUBLE_EQ(b.e_um[2][i], a.e_um[2][i]);
    }
    EXPECT_EQ(b.dir[C][i], a.dir[C][i]);
    EXPECT_EQ(b.extra[0].text[i], a.extra[0].text[i]);
    EXPECT_EQ(std::isnan(b.e_along_n_um[i]), std::isnan(a.e_along_n_um[i]));
    EXPECT_DOUBLE_EQ(b.weight[i], a.weight[i]);
    const double ta = a.temperature_c[0].values[i], tb = b.temperature_c[0].values[i];
    EXPECT_TRUE(ta == tb || (std::isnan(ta) && std::isnan(tb)));
  }
  std::ostringstream again;
  write_recordings_csv(again, b);
  EXPECT_EQ(again.str(), once.str());
}

TEST(RecordingsWriter, QuantizedPositionSurvivesTheFile) {
  const double q = quantize_recorded_position(AxisName::C, 0.123456789012345);
  Recordings r;
  r.line = {0};
  r.position[C] = {q};
  r.e_um[0] = {0.0};
  std::ostringstream out;
  write_recordings_csv(out, r);
  std::istringstream in(out.str());
  EXPECT_EQ(read_recordings_csv(in, "q.csv").position[C][0], q);
  EXPECT_EQ(quantize_recorded_position(AxisName::Z, 1.23456789), 1.234568);
}

TEST(RecordingsWriter, LargeFileIsColumnar) {
  Recordings r;
  const std::size_t n = 100000;
  r.line.assign(n, 0);
  for (std::size_t i = 0; i < n; ++i) {
    r.position[X].push_back(static_cast<double>(i) * 0.01);
    r.e_um[0].push_back(std::sin(static_cast<double>(i)));
  }
  std::stringstream io;
  write_recordings_csv(io, r);
  const Recordings b = read_recordings_csv(io, "big.csv");
  ASSERT_EQ(b.size(), n);
  EXPECT_NEAR(b.e_um[0][n - 1], std::sin(static_cast<double>(n - 1)), 1e-9);
}

}  // namespace
}  // namespace volmap
