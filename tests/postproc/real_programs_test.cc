// Real third-party programs (tests/data/real/nc, SOURCES.md says where each
// comes from) through `volmap post` on the sample machine with its errors,
// each placed in the middle of the travel (from rs274's own reading of it)
// and started where rs274 starts (the origin):
//  - a program LinuxCNC's rs274 reads is posted, rs274 reads the output,
//    and every commanded point of the output (cut starts included), moved
//    by the machine's error, lies within the tolerance of the input's
//    nominal path as rs274 runs it; or volmap refuses it with file:line for
//    a construct it does not follow yet (kNotYet, with the construct);
//  - a program rs274 refuses volmap refuses too, with file:line, unless it
//    reads it on purpose (kReadOnPurpose, with the reason).
#include <fmt/format.h>
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <map>
#include <sstream>
#include <string>
#include <vector>

#include "core/model/errors_csv.h"
#include "core/model/machine_json.h"
#include "tests/postproc/linuxcnc_canon.h"
#include "tests/support/cli_in_source.h"
#include "tests/support/cli_run.h"
#include "tests/support/rs274.h"
#include "tests/support/test_paths.h"

namespace volmap {
namespace {

const fs::path kDir = test::source_path("tests/data/real/nc");

// rs274 reads these; volmap refuses them, at the line, for what it does not
// follow yet (the message names it).
const std::map<std::string, std::string> kNotYet = {
    {"linuxcnc-nisley-door-latch-cam.ngc", "G42"},       // cutter radius compensation
    {"pcb2gcode-linuxcnc-autolevel-back.ngc", "G38.2"},  // probing: run-time values
    {"linuxcnc-daisy.ngc", "axis word A"},               // a rotary axis on a 3-axis machine
    // Cutter radius compensation (G41) after moves its own G10 puts outside
    // the travel: the post refuses the first of those.
    {"linuxcnc-mmount.ngc", "outside its travel"},
    // Not a gap: an inch program 1.3 m wide (X 1013 in) cannot run on the
    // sample machine's 500 mm travel, and the post says so at its first move.
    {"fusion360-generic-face.nc", "outside its travel 0..500 mm"},
};

// rs274 refuses these; volmap reads them on purpose.
const std::map<std::string, std::string> kReadOnPurpose = {
    // No M2/M30 at the end: rs274 reports "File ended with no percent sign
    // or program end" after running every move; the output is refused by it
    // the same way, and a controller runs both alike.
    {"estlcam-v11-circle-a.gcode", "no program end"},
    {"jscut-jsdc-engrave.gcode", "no program end"},
    {"viaconstructor-simple.ngc", "no program end"},
};

struct Program {
  std::string file, generator, dialect;
};

std::vector<Program> manifest() {
  std::ifstream f(kDir / "MANIFEST.tsv");
  std::vector<Program> v;
  std::string line;
  std::getline(f, line);  // header
  while (std::getline(f, line)) {
    std::istringstream ls(line);
    Program p;
    std::getline(ls, p.file, '\t');
    std::getline(ls, p.generator, '\t');
    std::getline(ls, p.dialect, '\t');
    if (!p.file.empty()) v.push_back(p);
  }
  return v;
}

// rs274 with a tool table (tools 1-30, length 0) and the corpus's
// subroutine folder.
Canon rs274_read(const std::string& program, const fs::path& dir, const std::string& var = "") {
  static const std::string tbl = [&] {
    const std::string t = (dir / "tools.tbl").string();
    std::ofstream o(t);
    for (int k = 1; k <= 30; ++k) o << fmt::format("T{0} P{0} Z0 D0 ;\n", k);
    return t;
  }();
  return canonical(program, tbl, var);
}

// Where a program runs, for volmap and for rs274 alike:
//  - var: G28's and G30's stored positions, the program's origin (rs274's
//    G54 is zero, its homes are zero);
//  - rs274_var, for a program with G53 only: rs274 with the same G54
//    (#5221-#5223) as volmap's --work-offset, so that a G53 move goes to
//    the same machine point in both (rs274's points stay in program
//    coordinates). Not for the others: rs274 starts at machine zero, which
//    --initial-position 0,0,0 matches only while its G54 is zero;
//  - initial: where rs274 starts (machine zero) in program coordinates.
struct Placement {
  std::string var, rs274_var, initial;
};

Placement placement(const std::string& in, const std::string& out, const Eigen::Vector3d& wo) {
  Placement pl;
  pl.var = out + ".var";
  std::string text = test::file_bytes(in);
  std::transform(text.begin(), text.end(), text.begin(), ::toupper);
  const bool g53 = text.find("G53") != std::string::npos;
  if (g53) pl.rs274_var = out + ".rs274.var";
  const Eigen::Vector3d start = g53 ? Eigen::Vector3d(-wo) : Eigen::Vector3d::Zero();
  pl.initial =
      fmt::format(" --initial-position {:.4f},{:.4f},{:.4f}", start.x(), start.y(), start.z());
  std::map<int, double> homes;
  for (int a = 0; a < 6; ++a)
    for (int first : {5161, 5181}) homes[first + a] = a < 3 ? wo[a] : 0.0;
  std::ofstream v(pl.var);
  for (const auto& [n, x] : homes) v << fmt::format("{} {:.6f}\n", n, x);
  if (g53) {
    std::map<int, double> with_g54 = homes;  // (rs274 wants the numbers in order)
    for (int a = 0; a < 3; ++a) with_g54[5221 + a] = wo[a];
    // rs274 without an INI file reads a parameter file in inches; the rotary
    // axes' values are zero.
    std::ofstream r(pl.rs274_var);
    for (const auto& [n, x] : with_g54) r << fmt::format("{} {:.8f}\n", n, x / 25.4);
  }
  return pl;
}

TEST(RealPrograms, PostedAsRs274RunsThemOrRefusedAtTheLine) {
  require_rs274();
  const fs::path dir = test::fresh_dir("real_programs");
  const std::string machine = test::source_path("samples/machines/hsu-3axis.json");
  const std::string errors = test::source_path("samples/errors/hsu-3axis.csv");
  const Machine m = load_machine_json(machine);
  const ErrorSet e = load_errors_csv(errors);
  const post::Corrector c(m, e, m.tool_length_mm, OutsidePolicy::kClamp);
  const std::vector<Program> programs = manifest();
  ASSERT_GE(programs.size(), 40u);
  std::ofstream(dir / "mm.tbl") << "";
  {
    std::ofstream t(dir / "mm.tbl");
    for (int k = 1; k <= 30; ++k) t << fmt::format("T{0} P{0} Z0 ;\n", k);
  }
  int posted = 0, refused = 0, read_by_both = 0, fanuc_verified = 0;
  for (const Program& p : programs) {
    SCOPED_TRACE(p.file);
    const std::string in = (kDir / p.file).string();
    const Canon before = rs274_read(in, dir);
    const bool rs274_reads = before.ok && before.errors.empty();
    // The middle of the program's extent (mm) at the middle of the travel.
    Eigen::Vector3d lo = Eigen::Vector3d::Constant(1e300), hi = -lo;
    for (const auto& [point, feed] : before.points) {
      lo = lo.cwiseMin(point);
      hi = hi.cwiseMax(point);
    }
    // (A program larger than the travel: its origin at the travel's edge,
    // where the post refuses the first move outside the travel; --clamp holds
    // the error tables' end values where a correction steps past them.)
    const Eigen::Vector3d wo =
        (before.points.empty() ? Eigen::Vector3d(250, 200, 150)
                               : Eigen::Vector3d(250, 200, 150) - (lo + hi) / 2)
            .cwiseMax(Eigen::Vector3d::Zero())
            .cwiseMin(Eigen::Vector3d(500, 400, 300));
    const std::string out = (dir / ("post-" + p.file)).string();
    const Placement place = placement(in, out, wo);
    const std::string& var = place.var;
    const std::string& g53_var = place.rs274_var;
    const std::string& initial = place.initial;
    const std::string cmd =
        test::volmap_binary() + " post --machine " + machine + " --errors " + errors +
        fmt::format(" --work-offset {:.4f},{:.4f},{:.4f}", wo.x(), wo.y(), wo.z()) + " --clamp" +
        initial + " --var-file " + var + " --tool-table " + (dir / "mm.tbl").string() +
        " --subroutine-path " + (kDir / "subs").string() + " " + in + " -o " + out + " 2>" + out +
        ".err";
    const bool ok = std::system(cmd.c_str()) == 0;
    const std::string err = test::file_bytes(out + ".err");
    if (!ok) {
      ++refused;
      EXPECT_FALSE(fs::exists(out)) << "nothing is written";
      // file:line, and the construct.
      EXPECT_EQ(err.rfind("volmap: " + in + ":", 0), 0u) << err;
      if (rs274_reads) {
        const auto it = kNotYet.find(p.file);
        ASSERT_NE(it, kNotYet.end()) << "rs274 reads it, volmap refuses: " << err;
        EXPECT_NE(err.find(it->second), std::string::npos) << err;
      }
      continue;
    }
    ++posted;
    if (!rs274_reads && (p.dialect == "fanuc" || p.dialect == "haas")) {
      // A Fanuc or Haas program rs274 cannot read: volmap's own reading is
      // the reference (tests/postproc/fanuc_dialect_test.cc pins it to
      // rs274 through hand translations); the output verifies within the
      // tolerance on the sample machine's errors.
      ++fanuc_verified;
      const test::CliResult v = test::run_volmap(
          "verify --machine " + machine + " --errors " + errors +
          fmt::format(" --work-offset {:.4f},{:.4f},{:.4f}", wo.x(), wo.y(), wo.z()) + " --clamp" +
          initial + " --var-file " + var + " --tool-table " + (dir / "mm.tbl").string() +
          " --subroutine-path " + (kDir / "subs").string() + " --nominal " + in + " --program " +
          out + " --json --tolerance-um 1.25");
      EXPECT_EQ(v.status, 0) << v.err;
      std::printf("%-42s %-28s verify %s\n", p.file.c_str(), p.generator.substr(0, 28).c_str(),
                  v.out.substr(0, 120).c_str());
      continue;
    }
    if (!rs274_reads) {
      EXPECT_TRUE(kReadOnPurpose.contains(p.file))
          << "rs274 refuses it (" << before.errors << "), volmap posted it";
      continue;
    }
    EXPECT_FALSE(kNotYet.contains(p.file)) << "posted now: take it off kNotYet";
    ++read_by_both;
    const Canon after = rs274_read(out, dir, g53_var);
    const Canon nominal_run = rs274_read(in, dir, g53_var);
    EXPECT_TRUE(after.ok && after.errors.empty()) << "rs274 refuses the output: " << after.errors;
    std::vector<nc::Motion> nominal = nominal_run.feeds;
    for (nc::Motion& mo : nominal) {
      mo.start_mm += wo;
      mo.end_mm += wo;
      mo.center_mm += wo;
    }
    if (nominal.empty()) continue;
    const double after_um = worst_deviation_um(after, nominal, c, wo, true);
    // 1 um tolerance, plus the output's rounding, plus rs274's 4 printed
    // decimals of the program's unit on both readings, the nominal path's
    // and the output's (0.09 um in mm, 2.2 um in inch, each).
    const double rs274_rounding_um = 0.5e-4 * after.unit_mm * 1e3 * std::sqrt(3.0);
    EXPECT_LT(after_um, 1.25 + 2 * rs274_rounding_um);
    std::printf("%-42s %-28s after %.3f um\n", p.file.c_str(), p.generator.substr(0, 28).c_str(),
                after_um);
  }
  std::printf("%d posted (%d of them read by rs274 too, %d Fanuc/Haas ones verified), %d refused\n",
              posted, read_by_both, fanuc_verified, refused);
  EXPECT_GE(posted, 20);
}

}  // namespace
}  // namespace volmap
