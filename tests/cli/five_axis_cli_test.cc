// `volmap post` and `volmap verify` on five-axis machines as scripts call
// them (shared/spec/cli.md): the five-axis path is taken for a machine with
// rotary axes; options, exit statuses, one-line errors, nothing written on
// failure, verify's JSON keys.
#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>
#include <nlohmann/json.hpp>
#include <sstream>
#include <string>

#include "tests/support/cli_run.h"
#include "tests/support/test_paths.h"

namespace {

namespace fs = std::filesystem;
using volmap::test::run_volmap;

std::string sample(const std::string& rel) { return volmap::test::source_path("samples/" + rel); }

std::string write_temp(const std::string& name, const std::string& text) {
  const std::string path = ::testing::TempDir() + "volmap5cli_" + name;
  std::ofstream(path, std::ios::binary) << text;
  return path;
}

std::string read(const std::string& path) {
  std::ifstream f(path, std::ios::binary);
  std::stringstream ss;
  ss << f.rdbuf();
  return ss.str();
}

const std::string kMachine = " --machine " + sample("machines/lei-hsu-xyzac.json");
const std::string kErrors = " --errors " + sample("errors/lei-hsu-xyzac.csv");

const char* kTcp =
    "G21 G90 G94\nG0 X10 Y0 Z30 A0 C0\nG1 X10 Y5 Z20 A-30 C20 F500\nG2 X20 Y15 I10 J0 F300\nG1 X0 "
    "Y5 Z20 A-45 "
    "C90\nM30\n";

TEST(FiveAxisCli, PostAndVerifyTcpProgram) {
  const std::string in = write_temp("tcp.ngc", kTcp),
                    out = ::testing::TempDir() + "volmap5cli_tcp_out.ngc";
  fs::remove(out);
  const auto r =
      run_volmap("post" + kMachine + kErrors + " --part-origin 5,-5,20 " + in + " -o " + out);
  ASSERT_EQ(r.status, 0) << r.err;
  const std::string text = read(out);
  EXPECT_NE(text.find("G93"), std::string::npos);
  EXPECT_EQ(text.find(" I"), std::string::npos);  // the arc is linearised
  const auto v = run_volmap("verify" + kMachine + kErrors + " --part-origin 5,-5,20 --nominal " +
                            in + " --program " + out + " --json");
  ASSERT_EQ(v.status, 0) << v.err;
  const auto j = nlohmann::json::parse(v.out);
  for (const char* side : {"before", "after"})
    for (const char* k : {"max_um", "rms_um", "max_urad", "rms_urad", "samples", "worst_line"})
      EXPECT_TRUE(j[side].contains(k)) << side << " " << k;
  EXPECT_GT(j["before"]["max_um"].get<double>(), 5.0);
  EXPECT_LT(j["after"]["max_um"].get<double>(), 1.0);
  // The human form names both.
  const auto h = run_volmap("verify" + kMachine + kErrors + " --part-origin 5,-5,20 --nominal " +
                            in + " --program " + out);
  ASSERT_EQ(h.status, 0) << h.err;
  EXPECT_NE(h.out.find("before"), std::string::npos);
  EXPECT_NE(h.out.find("µrad"), std::string::npos);
  EXPECT_EQ(h.out.find("urad"), std::string::npos);  // units as µm, µrad in all text
}

TEST(FiveAxisCli, PerMinuteFeedsAndStdout) {
  const std::string in = write_temp("tcp2.ngc", kTcp);
  const auto r =
      run_volmap("post" + kMachine + kErrors + " --feed-output per-minute " + in + " -o -");
  ASSERT_EQ(r.status, 0) << r.err;
  EXPECT_EQ(r.out.find("G93"), std::string::npos);
  EXPECT_NE(r.out.find(" F"), std::string::npos);
}

TEST(FiveAxisCli, ErrorsAreOneLineAndWriteNothing) {
  const std::string out = ::testing::TempDir() + "volmap5cli_bad_out.ngc";
  fs::remove(out);
  const std::string bad = write_temp("bad.ngc", "G0 X0 Y0 Z0 A0 C0\nG43 H1\n");
  auto r = run_volmap("post" + kMachine + kErrors + " " + bad + " -o " + out);
  EXPECT_EQ(r.status, 1);
  EXPECT_NE(r.err.find("bad.ngc:2"), std::string::npos) << r.err;
  EXPECT_FALSE(fs::exists(out));
  // A part out of the travel names the axis and what to do.
  const std::string far = write_temp("far.ngc", "G0 X0 Y0 Z0 A0 C0\nG0 X400\n");
  r = run_volmap("post" + kMachine + kErrors + " " + far + " -o " + out);
  EXPECT_EQ(r.status, 1);
  EXPECT_NE(r.err.find("--part-origin"), std::string::npos) << r.err;
  EXPECT_FALSE(fs::exists(out));
  // Three-axis options do not apply; --five-axis needs rotary axes.
  const std::string ok = write_temp("ok.ngc", kTcp);
  r = run_volmap("post" + kMachine + kErrors + " --work-offset 1,2,3 " + ok + " -o " + out);
  EXPECT_EQ(r.status, 2);  // usage: an option that does not apply
  EXPECT_NE(r.err.find("--part-origin"), std::string::npos) << r.err;
  r = run_volmap("post --machine " + sample("machines/hsu-3axis.json") + " --errors " +
                 sample("errors/hsu-3axis.csv") + " --five-axis " + ok + " -o " + out);
  EXPECT_EQ(r.status, 2);
  EXPECT_NE(r.err.find("no rotary axes"), std::string::npos) << r.err;
  r = run_volmap("post" + kMachine + kErrors + " --input-form nonsense " + ok + " -o " + out);
  EXPECT_EQ(r.status, 2);
  EXPECT_FALSE(fs::exists(out));
}

TEST(FiveAxisCli, HelpListsTheFiveAxisOptions) {
  const auto r = run_volmap("post --help");
  ASSERT_EQ(r.status, 0);
  for (const char* o :
       {"--five-axis", "--input-form", "--part-origin", "--angle-tolerance-urad", "--feed-output"})
    EXPECT_NE(r.out.find(o), std::string::npos) << o;
}

}  // namespace

namespace volmap {
namespace {

// Every F the five-axis post writes is a positive number that reads as one:
// a slow inverse-time feed keeps its digits (never F0), a move to where the
// tool already is gets a bounded F (6 ms), and F0 or a negative F
// in the input is refused as what it is.
TEST(FiveAxisCli, FeedWordsArePositiveAndBounded) {
  const std::string in = write_temp("feeds.ngc",
                                    "G21 G90 G94\nG0 X10 Y0 Z30 A0 C0\nG93 G1 X11 F0.000001\nG94 "
                                    "G1 X11 F500\nG1 X12 A-10 F500\nM30\n");
  const std::string out = ::testing::TempDir() + "volmap5cli_feeds_out.ngc";
  const auto r = run_volmap("post" + kMachine + kErrors + " " + in + " -o " + out);
  ASSERT_EQ(r.status, 0) << r.err;
  std::ifstream f(out);
  int feeds = 0;
  for (std::string line; std::getline(f, line);) {
    const size_t at = line.find('F');
    if (at == std::string::npos || line.find('(') != std::string::npos) continue;
    const double v = std::strtod(line.c_str() + at + 1, nullptr);
    ++feeds;
    EXPECT_GT(v, 0.0) << line;
    if (line.find("X-11.0407") != std::string::npos && line.find("C0 ") != std::string::npos &&
        line.find("G93") == std::string::npos) {
      EXPECT_EQ(v, 1e4) << line;  // the move to where the tool is: 6 ms
    }
  }
  EXPECT_GT(feeds, 0);
  for (const char* bad : {"G21 G90 G94\nG0 X10 Y0 Z30 A0 C0\nG1 X11 F0\nM30\n",
                          "G21 G90 G94\nG0 X10 Y0 Z30 A0 C0\nG1 X11 F-5\nM30\n"}) {
    const auto b = run_volmap("post" + kMachine + kErrors + " " + write_temp("badfeed.ngc", bad) +
                              " -o " + out + "2");
    EXPECT_EQ(b.status, 1);
    EXPECT_NE(b.err.find("must be positive"), std::string::npos) << b.err;
  }
}

}  // namespace
}  // namespace volmap
