// Flattened programs against LinuxCNC's own interpreter. The programs of
// tests/data/flatten were written one construct each and run through rs274
// (SEMANTICS.md there records what it did); here, for each:
//  - rs274 runs the program and volmap's flat output of it (zero errors):
//    the canonical calls must be the same, line for line;
//  - volmap posts it with the sample machine's errors, and rs274 accepts
//    the result;
//  - the programs rs274 refuses (err-*) volmap refuses too, except the few
//    volmap reads on purpose (listed below, with the reason).
#include <gtest/gtest.h>

#include <algorithm>
#include <filesystem>
#include <fstream>
#include <set>
#include <sstream>
#include <string>
#include <vector>

#include "core/common/input_error.h"
#include "core/model/errors_import.h"
#include "core/model/machine_json.h"
#include "postproc/three_axis/post_program.h"
#include "tests/postproc/linuxcnc_canon.h"
#include "tests/support/rs274.h"
#include "tests/support/test_paths.h"

namespace volmap {
namespace {

const fs::path kDir = test::source_path("tests/data/flatten");

struct Rs274Run {
  bool ok = false;
  std::vector<std::string> calls;  ///< canonical calls without their numbering
};

// rs274 on `program` from tests/data/flatten (its subs.ini gives the
// subroutine path, relative to that folder).
Rs274Run rs274(const fs::path& program) {
  static const fs::path out_dir = test::fresh_dir("flatten_canon");
  static int count = 0;
  const fs::path out = out_dir / (std::to_string(++count) + ".canon");
  const std::string cmd =
      "cd " + kDir.string() + " && " +
      test::rs274_command("-i subs.ini -g " + program.string() + " " + out.string()) + " >" +
      out.string() + ".log 2>&1";
  Rs274Run r;
  r.ok = std::system(cmd.c_str()) == 0;
  std::ifstream f(out);
  std::string line;
  while (std::getline(f, line)) {
    const std::size_t at = line.find("N..... ");
    r.calls.push_back(at == std::string::npos ? line : line.substr(at + 7));
    if (line.find("rror") != std::string::npos && line.find("COMMENT(") == std::string::npos)
      r.ok = false;
  }
  return r;
}

std::string post(const fs::path& program, const ErrorSet& errors) {
  static const Machine m = load_machine_json(test::source_path("samples/machines/hsu-3axis.json"));
  std::ifstream in(program, std::ios::binary);
  std::ostringstream out;
  nc::ProgramSetup setup;
  setup.work_offset_mm[0] = Eigen::Vector3d(250, 200, 100);
  setup.initial_position_mm = setup.work_offset_mm[0];  // rs274 starts at the origin
  post::PostOptions opt;
  opt.subroutine_path = {(kDir / "subs").string()};
  post::post_program(in, program.string(), out, m, errors, setup, opt);
  return out.str();
}

std::vector<fs::path> programs(bool errors) {
  std::vector<fs::path> v;
  for (const auto& e : fs::directory_iterator(kDir))
    if (e.path().extension() == ".ngc" &&
        e.path().filename().string().starts_with("err-") == errors &&
        !e.path().filename().string().starts_with("quirk-"))
      v.push_back(e.path());
  std::sort(v.begin(), v.end());
  return v;
}

// Programs that read offset parameters (#5221, #5211, #5161...): rs274 on
// its own is an inch machine and keeps them in inches (SEMANTICS.md), where
// a metric LinuxCNC machine, and volmap, keep them in mm. Their canonical
// calls differ by that, not by the flattening: compared by the offsets
// test of linuxcnc_test.cc instead (tests/data/linuxcnc/offsets.ngc).
const std::set<std::string> kInchParameters = {"offset-params.ngc", "system-params.ngc"};

TEST(FlattenRs274, FlatOutputRunsAsTheProgramDoes) {
  require_rs274();
  const fs::path dir = test::fresh_dir("flatten_out");
  const ErrorSet hsu = load_errors(test::source_path("samples/errors/hsu-3axis.csv"));
  int checked = 0;
  for (const fs::path& p : programs(false)) {
    SCOPED_TRACE(p.filename().string());
    const Rs274Run original = rs274(p);
    ASSERT_TRUE(original.ok) << "rs274 refuses the test program itself";
    const fs::path flat = dir / p.filename();
    if (kInchParameters.contains(p.filename().string())) continue;
    const std::string flat_text = post(p, ErrorSet{});
    std::ofstream(flat, std::ios::binary) << flat_text;
    const Rs274Run flattened = rs274(flat);
    EXPECT_TRUE(flattened.ok);
    EXPECT_EQ(flattened.calls, original.calls);
    const fs::path corrected = dir / ("corrected-" + p.filename().string());
    std::ofstream(corrected, std::ios::binary) << post(p, hsu);
    EXPECT_TRUE(rs274(corrected).ok) << "rs274 refuses the corrected program";
    ++checked;
  }
  EXPECT_GE(checked, 25);
}

// Refused by rs274, read by volmap on purpose:
//  - err-bom: the byte-order mark is an encoding's, not the program's
//    (volmap reads past it and writes it back);
//  - err-k-word-xy-arc: K0 on a G17 arc moves nothing (FreeCAD writes it);
//  - err-duplicate-label: two `o1 if` blocks one after the other; the
//    labels do not overlap, so what runs is not in doubt;
//  - err-sub-illegal-location: a subroutine defined after its call and
//    reached again by the program: volmap skips it as any definition.
const std::set<std::string> kReadOnPurpose = {"err-bom.ngc", "err-k-word-xy-arc.ngc",
                                              "err-duplicate-label.ngc",
                                              "err-sub-illegal-location.ngc"};

TEST(FlattenRs274, WhatRs274RefusesVolmapRefuses) {
  require_rs274();
  int checked = 0;
  for (const fs::path& p : programs(true)) {
    SCOPED_TRACE(p.filename().string());
    EXPECT_FALSE(rs274(p).ok);
    if (kReadOnPurpose.contains(p.filename().string())) continue;
    EXPECT_THROW(post(p, ErrorSet{}), InputError);
    ++checked;
  }
  EXPECT_GE(checked, 10);
  // LinuxCNC 2.9's break leak (quirk-break-leak.ngc): refused, not guessed.
  EXPECT_THROW(post(kDir / "quirk-break-leak.ngc", ErrorSet{}), InputError);
}

}  // namespace
}  // namespace volmap
