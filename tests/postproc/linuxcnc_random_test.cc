// LinuxCNC's interpreter (rs274) on random programs: volmap post refuses
// what rs274 refuses and accepts what it accepts, rs274 accepts every
// output, and a CAM program's output passes through the input's points.
//
// rs274 missing: the test is skipped on a developer machine, and fails when
// VOLMAP_REQUIRE_RS274 is set (CI sets it and installs linuxcnc-uspace).
#include <fmt/format.h>
#include <gtest/gtest.h>
#include <unistd.h>

#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <nlohmann/json.hpp>
#include <random>
#include <regex>
#include <sstream>
#include <tuple>

#include "core/model/errors_csv.h"
#include "core/model/machine_json.h"
#include "gcode/nc_block.h"
#include "gcode/nc_interpreter.h"
#include "gcode/nc_path.h"
#include "postproc/three_axis/corrector.h"
#include "tests/postproc/linuxcnc_canon.h"
#include "tests/support/cli_in_source.h"
#include "tests/support/rs274.h"
#include "tests/support/test_paths.h"

namespace volmap {
namespace {

// Random programs of the words volmap reads, as a fuzzer writes them (any
// order, words no code uses, arcs with stray centres, cycles without their
// words, zero and negative P Q L): volmap post refuses every program rs274
// refuses, with file:line, accepts those rs274 accepts except where it
// says a construct is not supported (or is a post-processing policy: a
// stop code beside a feed move), and rs274 accepts every program volmap
// writes. Found and fixed with it: words no code uses, K in a G17 arc, R
// with I J K, a lone G2, a peck depth Q of zero or less.
TEST(LinuxCnc, RandomProgramsAreAcceptedAndRefusedAsRs274Does) {
  require_rs274();
  const std::string tbl = "/usr/share/doc/linuxcnc/examples/sample-configs/sim/axis/simpockets.tbl";
  const fs::path dir = test::fresh_dir("random");
  std::mt19937 rng(20261201);
  const auto chance = [&](double p) {
    return std::uniform_real_distribution<double>(0, 1)(rng) < p;
  };
  const auto pick = [&](std::initializer_list<const char*> v) {
    return std::string(v.begin()[std::uniform_int_distribution<size_t>(0, v.size() - 1)(rng)]);
  };
  const auto number = [&](double lo, double hi) {
    const int decimals = std::uniform_int_distribution<int>(0, 3)(rng);
    return fmt::format("{:.{}f}", std::uniform_real_distribution<double>(lo, hi)(rng), decimals);
  };
  double wild = 1.0;  // a program of stray words, or (0.1) one of mostly plain moves
  const auto block = [&] {
    std::vector<std::string> words;
    if (chance(0.35))
      words.push_back(pick({"G0", "G1", "G2", "G3", "G2", "G3", "G81", "G82", "G83", "G73", "G85",
                            "G89", "G80", "G86", "G84", "G74", "G1", "G0"}));
    if (chance(0.15 * wild))
      words.push_back(pick({"G90", "G91",    "G20", "G21", "G17",     "G18",   "G19",
                            "G98", "G99",    "G93", "G94", "G90.1",   "G91.1", "G54",
                            "G55", "G43 H1", "G49", "G53", "G4 P0.5", "G61",   "G64"}));
    for (const char* L : {"X", "Y", "Z"})
      if (chance(0.5)) words.push_back(L + number(-20, 20));
    if (chance(0.05 * wild)) words.push_back(pick({"@", "^"}) + number(-20, 20));
    for (const char* L : {"I", "J", "K", "R"})
      if (chance(0.25 * wild)) words.push_back(L + number(-10, 10));
    for (const auto& [L, lo, hi] :
         {std::tuple{"Q", -2.0, 5.0}, {"P", -1.0, 3.0}, {"L", -1.0, 4.0}, {"F", -10.0, 500.0}})
      if (chance(0.06 * wild)) words.push_back(L + number(lo, hi));
    if (chance(0.03 * wild))
      words.push_back(pick({"M3 S1000", "M4 S800", "M5", "M8", "M9", "M0", "M1"}));
    std::shuffle(words.begin(), words.end(), rng);
    std::string b;
    for (const std::string& w : words) b += (b.empty() ? "" : " ") + w;
    return b;
  };
  const std::string in = (dir / "random.ngc").string(), out = (dir / "random-post.ngc").string();
  int both = 0, refused = 0;
  for (int n = 0; n < 300; ++n) {
    wild = chance(0.5) ? 1.0 : 0.1;
    std::string program = "G21 G90 G17 F200\nG0 X0 Y0 Z30\n";
    for (int k = std::uniform_int_distribution<int>(1, 6)(rng); k > 0; --k)
      program += block() + "\n";
    program += "M2\n";
    std::ofstream(in, std::ios::binary) << program;
    const bool rs274_ok = canonical(in, tbl).ok;
    const std::string log = out + ".err";
    const std::string cmd = hsu_post_command("--work-offset 250,200,100 --clamp --tool-table " +
                                             tbl + " " + in + " -o " + out + " 2>" + log);
    fs::remove(out);
    const bool volmap_ok = std::system(cmd.c_str()) == 0;
    const std::string err = test::file_bytes(log);
    SCOPED_TRACE(program + "volmap: " + err);
    if (!rs274_ok) {
      EXPECT_FALSE(volmap_ok) << "rs274 refuses the program, volmap post read it";
      EXPECT_NE(err.find(in + ":"), std::string::npos);
      ++refused;
      continue;
    }
    if (!volmap_ok) {
      const bool by_design = err.find("not supported") != std::string::npos ||
                             err.find("stop code") != std::string::npos;
      EXPECT_TRUE(by_design) << "rs274 reads the program, volmap post refused it";
      continue;
    }
    ++both;
    EXPECT_TRUE(canonical(out, tbl).ok) << "rs274 refuses volmap's output";
  }
  // Both kinds were met many times (the test has teeth both ways).
  EXPECT_GT(both, 30);
  EXPECT_GT(refused, 100);
  std::printf("random programs: %d read by both, %d refused by rs274 (and volmap)\n", both,
              refused);
}

// A random program that a CAM system could write (see below), mm and inch,
// G90 and G91, from rng.
std::string random_cam_program(std::mt19937& rng) {
  const auto uniform = [&](double lo, double hi) {
    return std::uniform_real_distribution<double>(lo, hi)(rng);
  };
  const auto chance = [&](double p) { return uniform(0, 1) < p; };
  const auto integer = [&](int lo, int hi) {
    return std::uniform_int_distribution<int>(lo, hi)(rng);
  };
  std::string p = "G21 G90 G17 G94 F300\nG0 X10 Y10 Z20\n";
  double x = 10, y = 10, z = 20;  // mm
  bool inch = false, incremental = false;
  int plane = 0;                  // 0 XY, 1 XZ, 2 YZ
  double active_offset_mm = 0.0;  // tool length offset (G43 H1: 25.4 mm)
  for (int n = integer(3, 12); n > 0; --n) {
    const double k = uniform(0, 1), u = inch ? 25.4 : 1.0;
    const auto num = [&](double v) {
      return fmt::format("{:.{}f}", v, integer(0, 2) == 0 ? 1 : 4);
    };
    if (k < 0.25) {
      const double nx = x + uniform(-15, 15), ny = y + uniform(-15, 15), nz = z + uniform(-5, 5);
      if (incremental)
        p +=
            "G1 X" + num((nx - x) / u) + " Y" + num((ny - y) / u) + " Z" + num((nz - z) / u) + "\n";
      else
        p += "G1 X" + num(nx / u) + " Y" + num(ny / u) + " Z" + num(nz / u) + "\n";
      x = nx, y = ny, z = nz;
    } else if (k < 0.30 && !incremental) {
      plane = integer(0, 2);
      p += plane == 0 ? "G17\n" : plane == 1 ? "G18\n" : "G19\n";
    } else if (k < 0.45 && !incremental) {
      // In-plane axes (a0, a1) and their centre words, as RS274NGC pairs them.
      static constexpr int kA0[3] = {0, 2, 1}, kA1[3] = {1, 0, 2};
      static constexpr char kW0[3] = {'I', 'K', 'J'}, kW1[3] = {'J', 'I', 'K'};
      double pos[3] = {x, y, z};
      const double r = uniform(2, 15), a0 = uniform(0, 2 * M_PI), sweep = uniform(0.3, 5);
      const double c0 = pos[kA0[plane]] - r * std::cos(a0), c1 = pos[kA1[plane]] - r * std::sin(a0);
      const bool cw = chance(0.5);
      const double a1 = cw ? a0 - sweep : a0 + sweep;
      double end[3] = {x, y, z};
      end[kA0[plane]] = c0 + r * std::cos(a1);
      end[kA1[plane]] = c1 + r * std::sin(a1);
      if (chance(0.3)) end[3 - kA0[plane] - kA1[plane]] += uniform(-3, 3);
      p += fmt::format("{} X{:.4f} Y{:.4f} Z{:.4f} {}{:.4f} {}{:.4f}\n", cw ? "G2" : "G3",
                       end[0] / u, end[1] / u, end[2] / u, kW0[plane], (c0 - pos[kA0[plane]]) / u,
                       kW1[plane], (c1 - pos[kA1[plane]]) / u);
      x = end[0], y = end[1], z = end[2];
    } else if (k < 0.55 && !incremental && plane == 0) {
      static const char* kCycles[] = {
          "G81",      "G82 P0.2",         "G83 Q1.5",    "G73 Q0.7",        "G85",
          "G89 P0.1", "M3 S900 G86 P0.3", "M3 S900 G84", "M4 S900 G74 P0.2"};
      const double hz = z - uniform(3, 8), rz = z - uniform(0, 1), nx = x + uniform(-10, 10),
                   ny = y + uniform(-10, 10);
      p += fmt::format("{} {} X{:.4f} Y{:.4f} Z{:.4f} R{:.4f}{}\nG80\nG0 Z{:.4f}\n",
                       chance(0.5) ? "G98" : "G99", kCycles[integer(0, 8)], nx / u, ny / u, hz / u,
                       rz / u, chance(0.2) ? fmt::format(" L{}", integer(2, 3)) : "", z / u);
      x = nx, y = ny;
    } else if (k < 0.62) {
      inch = !inch;
      p += inch ? "G20\n" : "G21\n";
    } else if (k < 0.68) {
      incremental = !incremental;
      p += incremental ? "G91\n" : "G90\n";
    } else if (k < 0.73 && !incremental) {
      x += uniform(-10, 10), y += uniform(-10, 10), z += uniform(0, 5);
      p += fmt::format("G0 X{:.4f} Y{:.4f} Z{:.4f}\n", x / u, y / u, z / u);
    } else if (k < 0.78 && !incremental && plane == 0) {
      const double radius = std::hypot(x, y) + uniform(-3, 3);
      const double angle = std::atan2(y, x) * 180 / M_PI + uniform(-20, 20);
      p += fmt::format("G1 @{:.4f} ^{:.4f}\n", radius / u, angle);
      x = radius * std::cos(angle * M_PI / 180), y = radius * std::sin(angle * M_PI / 180);
    } else if (k < 0.83) {
      static const char* kCodes[] = {"G43 H1", "G49",       "M3 S2000", "M8",
                                     "M9",     "G64 P0.01", "G61",      "G4 P0.2"};
      const std::string code = kCodes[integer(0, 7)];
      p += code + "\n";
      // The controlled point jumps by minus the change of offset (LinuxCNC).
      const double offset_mm = code == "G43 H1" ? 25.4 : code == "G49" ? 0.0 : active_offset_mm;
      z -= offset_mm - active_offset_mm;
      active_offset_mm = offset_mm;
    } else if (k < 0.88 && !incremental) {
      p += fmt::format("G93 G1 X{:.4f} Y{:.4f} F{:.2f}\nG94 F300\n", (x + 3) / u, (y - 2) / u,
                       uniform(5, 50));
      x += 3, y -= 2;
    } else {
      const double nx = x + uniform(-5, 5);
      p += fmt::format("X{:.4f}\n", incremental ? (nx - x) / u : nx / u);
      x = nx;
    }
  }
  return p + "M2\n";
}

// Random programs that a CAM system could write (lines, arcs with exact
// centres in all three planes, canned cycles, G20/G21, G91, polar moves,
// G43/G49, G93), posted and run by rs274: rs274 and volmap accept the same
// ones, rs274 accepts every output, and the output passes through every
// point the input does (rs274's canonical end points, in order, within
// 0.05 mm: the correction is micrometres). Every other program is posted
// with --keep-arcs, and its output, run on the model by volmap verify,
// keeps the tolerance between the points too.
TEST(LinuxCnc, RandomCamProgramsPostedPassThroughTheSamePoints) {
  require_rs274();
  const fs::path dir = test::fresh_dir("cam");
  const auto [tbl_inch, tbl_mm] = tool_tables(dir, {1.0});
  std::mt19937 rng(20261202);
  const std::string in = (dir / "cam.ngc").string(), out = (dir / "cam-post.ngc").string();
  int both = 0, kept_arcs = 0;  // kept_arcs: outputs with arcs in them
  for (int n = 0; n < 150; ++n) {
    const std::string text = random_cam_program(rng);
    std::ofstream(in, std::ios::binary) << text;
    const Canon input = canonical(in, tbl_inch);
    const std::string log = out + ".err";
    fs::remove(out);
    // Every other program keeps its arcs as arcs (--keep-arcs).
    const std::string keep = n % 2 ? "--keep-arcs " : "";
    const bool volmap_ok =
        std::system(hsu_post_command("--work-offset 250,200,150 --clamp " + keep + "--tool-table " +
                                     tbl_mm + " " + in + " -o " + out + " 2>" + log)
                        .c_str()) == 0;
    const std::string err = test::file_bytes(log);
    SCOPED_TRACE(keep + text + "volmap: " + err);
    EXPECT_EQ(volmap_ok, input.ok);
    if (!input.ok || !volmap_ok) continue;
    ++both;
    const Canon posted = canonical(out, tbl_inch);
    ASSERT_TRUE(posted.ok) << "rs274 refuses volmap's output";
    for (const nc::Motion& mo : posted.feeds)
      if (mo.kind == nc::MotionKind::kArc) {
        ++kept_arcs;
        break;
      }
    size_t next = 0;
    for (const auto& [p, feed] : input.points) {
      while (next < posted.points.size() &&
             (posted.points[next].first - p).cwiseAbs().maxCoeff() >= 0.05)
        ++next;
      ASSERT_LT(next, posted.points.size()) << "the output never passes through " << p.transpose();
      ++next;
    }
    // (verify refuses a program without feed moves: nothing to measure.)
    if (keep.empty() || input.feeds.empty()) continue;
    // Kept arcs pass through the same end points even when wrong (a full
    // circle instead of a sliver): the machine's path, sampled between the
    // points too, keeps the tolerance (1 um, plus the rounding of inch
    // numbers).
    const test::CliResult r = test::run_volmap_in_source(
        "verify --machine samples/machines/hsu-3axis.json --errors samples/errors/hsu-3axis.csv "
        "--work-offset 250,200,150 --clamp --tool-table " +
        tbl_mm + " --nominal " + in + " --program " + out + " --json");
    ASSERT_EQ(r.status, 0) << r.err;
    const double after_um = nlohmann::json::parse(r.out)["after"]["max_um"].get<double>();
    EXPECT_LT(after_um, 1.5) << r.out;
  }
  EXPECT_GT(both, 100);
  EXPECT_GT(kept_arcs, 20);
  std::printf(
      "random CAM programs: %d of 150 posted (every other with --keep-arcs: %d outputs with arcs "
      "kept) and run "
      "through the same points by rs274\n",
      both, kept_arcs);
}

}  // namespace
}  // namespace volmap
