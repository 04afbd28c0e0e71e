// LinuxCNC's rigid tap G33.1, read as rs274 reads it (checked against rs274's
// RIGID_TAP calls): each tap's end, as the output commands it and moved by
// the machine's error, lands on the input's; what rs274 refuses, volmap
// refuses.
#include <fmt/format.h>
#include <gtest/gtest.h>

#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <string>
#include <vector>

#include "core/model/errors_csv.h"
#include "core/model/machine_json.h"
#include "postproc/three_axis/corrector.h"
#include "tests/postproc/linuxcnc_canon.h"
#include "tests/support/cli_in_source.h"
#include "tests/support/cli_run.h"
#include "tests/support/rs274.h"
#include "tests/support/test_paths.h"

namespace volmap {
namespace {

const fs::path& dir() {
  static const fs::path d = test::fresh_dir("rigid_tap");
  return d;
}

std::string write_program(const std::string& name, const std::string& text) {
  const std::string path = (dir() / name).string();
  std::ofstream(path) << text;
  return path;
}

// rs274's RIGID_TAP(x, y, z) calls of a program (program coordinates, mm);
// false when rs274 refuses it.
bool rigid_taps(const std::string& program, std::vector<Eigen::Vector3d>& taps) {
  const std::string out = program + ".canon";
  const std::string cmd = test::rs274_command("-g " + program + " " + out) + " >/dev/null 2>&1";
  const bool ok = std::system(cmd.c_str()) == 0;
  std::ifstream f(out);
  for (std::string l; std::getline(f, l);) {
    const size_t at = l.find("RIGID_TAP(");
    if (at == std::string::npos) continue;
    double x = 0, y = 0, z = 0;
    std::sscanf(l.c_str() + at, "RIGID_TAP(%lf, %lf, %lf)", &x, &y, &z);
    taps.emplace_back(x, y, z);
  }
  return ok;
}

constexpr const char* kTaps =
    "G21 G90 G17\nG0 X10 Y10 Z5\nM3 S500\nG33.1 Z-10 K1.25\nG0 X60 Y40\nG33.1 Z-15 K1\n"
    "G91 G0 X30\nG33.1 Z-20 K1.5 I2\nG90 G0 Z20\nM4\nG0 X200 Y150 Z2\nG33.1 Z-8 K-1\nM5\nM2\n";

TEST(RigidTap, EachTapEndsWhereTheInputsDoesOnTheMachine) {
  require_rs274();
  const std::string machine = test::source_path("samples/machines/hsu-3axis.json");
  const std::string errors = errors_without_lost_motion(dir());
  const Machine m = load_machine_json(machine);
  const post::Corrector c(m, load_errors_csv(errors), m.tool_length_mm, OutsidePolicy::kError);
  const std::string in = write_program("taps.ngc", kTaps);
  const std::string out = (dir() / "taps-out.ngc").string();
  const test::CliResult r = test::run_volmap(
      fmt::format("post --machine {} --errors {} --work-offset 100,100,100 {} -o {}", machine,
                  errors, in, out));
  ASSERT_EQ(r.status, 0) << r.err;
  std::vector<Eigen::Vector3d> nominal, commanded;
  ASSERT_TRUE(rigid_taps(in, nominal));
  ASSERT_TRUE(rigid_taps(out, commanded));
  ASSERT_EQ(nominal.size(), 4u);  // G91's tap too, and the one under M4 with K < 0
  ASSERT_EQ(commanded.size(), nominal.size());
  const Eigen::Vector3d wo(100, 100, 100);
  for (size_t k = 0; k < nominal.size(); ++k) {
    const Eigen::Vector3d p = commanded[k] + wo;
    const Eigen::Vector3d actual = p + c.error_at(p, {0, 0, -1});
    const double before_um =
        ((nominal[k] + wo) + c.error_at(nominal[k] + wo, {0, 0, -1}) - (nominal[k] + wo)).norm() *
        1e3;
    // 1 um tolerance and rs274's 4 decimals (0.09 um in space).
    EXPECT_LT((actual - (nominal[k] + wo)).norm() * 1e3, 1.1) << "tap " << k;
    EXPECT_GT(before_um, 5.0) << "tap " << k;
  }
}

TEST(RigidTap, AZeroErrorMachineGetsTheProgramBackByteForByte) {
  const std::string in = write_program("taps-zero.ngc", kTaps);
  const std::string zero = write_program("zero.csv", "# machine: hsu-3axis\n");
  const std::string out = (dir() / "taps-zero-out.ngc").string();
  const test::CliResult r = test::run_volmap(
      fmt::format("post --machine {} --errors {} --work-offset 100,100,100 {} -o {}",
                  test::source_path("samples/machines/hsu-3axis.json"), zero, in, out));
  ASSERT_EQ(r.status, 0) << r.err;
  EXPECT_EQ(test::file_bytes(out), kTaps);
}

TEST(RigidTap, WhatRs274RefusesVolmapRefuses) {
  require_rs274();
  const struct {
    const char* body;
    const char* message;
  } kRefused[] = {
      {"G33.1 Z-10 K1.25\n", "spindle not turning in G33.1"},
      {"M3 S500\nG33.1 Z-10\n", "K word missing with g33/g33.1"},
      {"M3 S500\nG33.1 Z-10 K1.25\nZ-12\n", "K word missing with g33/g33.1"},
      {"M3 S500\nG33.1 Z-10 K1.25 F100\n", "F word used with a g33/g33.1"},
      {"M3 S500\nG33.1 Z-10 K1.25 R2\n", "R word with no"},
      {"M3 S500\nG33.1 Z-10 K1.25 J1\n", "J word with no"},
  };
  int n = 0;
  for (const auto& k : kRefused) {
    SCOPED_TRACE(k.body);
    const std::string name = fmt::format("refused-{}.ngc", ++n);
    const std::string in =
        write_program(name, std::string("G21 G90\nG0 X10 Y10 Z5\n") + k.body + "M2\n");
    std::vector<Eigen::Vector3d> taps;
    EXPECT_FALSE(rigid_taps(in, taps));
    const std::string out = (dir() / ("out-" + name)).string();
    const test::CliResult r = test::run_volmap(
        fmt::format("post --machine {} --errors {} --work-offset 100,100,100 {} -o {}",
                    test::source_path("samples/machines/hsu-3axis.json"),
                    test::source_path("samples/errors/hsu-3axis.csv"), in, out));
    EXPECT_EQ(r.status, 1);
    EXPECT_NE(r.err.find(name + ":"), std::string::npos) << r.err;
    EXPECT_NE(r.err.find(k.message), std::string::npos) << r.err;
    EXPECT_FALSE(fs::exists(out));
  }
}

}  // namespace
}  // namespace volmap
