// The post-processor's fast paths against the exact model: the error-field
// bounds (Corrector::lipschitz_bound, curvature_bound, chord_deviation_bound)
// measured on the exact HTM model, the warm-started fixed point, and the
// shortcut of plain lines (the post's plain_line) against the general post.
// The lexer's and writer's fast paths: tests/gcode/.
#include <fmt/format.h>
#include <gtest/gtest.h>

#include <algorithm>
#include <charconv>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <fstream>
#include <memory>
#include <random>
#include <sstream>

#include "core/model/errors_csv.h"
#include "core/model/machine_json.h"
#include "gcode/nc_block.h"
#include "gcode/nc_interpreter.h"
#include "gcode/nc_writer.h"
#include "postproc/three_axis/corrector.h"
#include "postproc/three_axis/post_program.h"
#include "tests/support/test_paths.h"

namespace volmap {
namespace {

using Eigen::Vector3d;

Machine hsu() { return load_machine_json(test::source_path("samples/machines/hsu-3axis.json")); }
ErrorSet hsu_errors() { return load_errors_csv(test::source_path("samples/errors/hsu-3axis.csv")); }

// Every approach-direction combination the post uses (0: the mean).
std::vector<ApproachDirections> all_directions() {
  std::vector<ApproachDirections> out;
  for (int x = -1; x <= 1; ++x)
    for (int y = -1; y <= 1; ++y)
      for (int z = -1; z <= 1; ++z)
        out.push_back({static_cast<std::int8_t>(x), static_cast<std::int8_t>(y),
                       static_cast<std::int8_t>(z), 0, 0, 0});
  return out;
}

struct Box {
  Vector3d lo, hi;
};

// The part of the machine frame where the tables hold, found by probing
// (the bound box is private): the sample errors cover the travel.
Box box_of(const post::Corrector& c, const Machine& m) {
  Box b{Vector3d(1e9, 1e9, 1e9), Vector3d(-1e9, -1e9, -1e9)};
  std::mt19937 rng(7);
  for (int k = 0; k < 20000; ++k) {
    Vector3d p;
    for (int a = 0; a < 3; ++a)
      p[a] =
          std::uniform_real_distribution<double>(m.limits[a].min - 400, m.limits[a].max + 400)(rng);
    if (!c.in_bound_box(p)) continue;
    b.lo = b.lo.cwiseMin(p);
    b.hi = b.hi.cwiseMax(p);
  }
  return b;
}

void check_bounds(const ErrorSet& errors, double tool_mm) {
  const Machine m = hsu();
  const post::Corrector c(m, errors, tool_mm, OutsidePolicy::kError);
  const double K1 = c.lipschitz_bound(), K2 = c.curvature_bound();
  ASSERT_TRUE(std::isfinite(K1) && std::isfinite(K2));
  const Box box = box_of(c, m);
  ASSERT_TRUE((box.lo.array() < box.hi.array()).all());
  std::mt19937 rng(42);
  std::uniform_real_distribution<double> unit(0.0, 1.0);
  const auto dirs = all_directions();
  double max_slope = 0, max_second = 0, max_chord_ratio = 0;
  const double h = 0.5;  // mm: the second difference of a C1 piecewise cubic is an average of e''
  for (int k = 0; k < 4000; ++k) {
    Vector3d x, v(unit(rng) - 0.5, unit(rng) - 0.5, unit(rng) - 0.5);
    v.normalize();
    for (int a = 0; a < 3; ++a) x[a] = box.lo[a] + h + (box.hi[a] - box.lo[a] - 2 * h) * unit(rng);
    const ApproachDirections& d = dirs[static_cast<size_t>(k) % dirs.size()];
    const Vector3d e0 = c.error_at(x, d), ep = c.error_at(x + h * v, d),
                   em = c.error_at(x - h * v, d);
    max_slope = std::max(max_slope, (ep - e0).norm() / h);
    max_second = std::max(max_second, (ep - 2 * e0 + em).norm() / (h * h));
    // A long chord, sampled densely: its deviation from the chord of its
    // end values stays below the bound.
    Vector3d c1;
    for (int a = 0; a < 3; ++a) c1[a] = box.lo[a] + (box.hi[a] - box.lo[a]) * unit(rng);
    const double bound = c.chord_deviation_bound(x, c1);
    ASSERT_TRUE(std::isfinite(bound));
    const Vector3d ex = c.error_at(x, d), e1 = c.error_at(c1, d);
    double dev = 0;
    for (int i = 1; i < 64; ++i) {
      const double t = i / 64.0;
      dev = std::max(dev, (c.error_at(x + t * (c1 - x), d) - ((1 - t) * ex + t * e1)).norm());
    }
    max_chord_ratio = std::max(max_chord_ratio, dev / bound);
  }
  std::printf(
      "tool %g mm: Lipschitz bound %.3g (measured %.3g), curvature bound %.3g mm^-1 "
      "(measured %.3g), worst chord deviation / bound %.3f\n",
      tool_mm, K1, max_slope, K2, max_second, max_chord_ratio);
  EXPECT_LE(max_slope, K1);
  EXPECT_LE(max_second, K2);
  EXPECT_LE(max_chord_ratio, 1.0);
  // Useful, not vacuous: a 0.5 mm piece is far inside a 1 um tolerance.
  EXPECT_LT(K2 * 0.25 / 8, 1e-6);
  EXPECT_LT(K1, 1e-2);
  // The box is the tables' range (outside it the bound is not claimed).
  EXPECT_FALSE(c.in_bound_box(box.hi + Vector3d(1, 1, 1) * 50));
}

class Bounds : public ::testing::TestWithParam<double> {};  // tool length, mm

TEST_P(Bounds, HoldOnTheExactModel) { check_bounds(hsu_errors(), GetParam()); }

INSTANTIATE_TEST_SUITE_P(ToolLengths, Bounds, ::testing::Values(100.0, 0.0, 180.0));

// Axes without a table (their box side is their travel), and no location
// errors.
TEST(PostBounds, HoldWithPartialTables) {
  ErrorSet e = hsu_errors();
  e.axis[static_cast<size_t>(AxisName::Y)].reset();
  check_bounds(e, 100.0);
  e.location.clear();
  e.axis[static_cast<size_t>(AxisName::Z)].reset();
  check_bounds(e, 100.0);
}

TEST(PostBounds, WarmStartedFixedPointIsTheExactSolution) {
  const post::Corrector c(hsu(), hsu_errors(), 100.0, OutsidePolicy::kError);
  std::mt19937 rng(3);
  std::uniform_real_distribution<double> u(50, 250);
  const auto dirs = all_directions();
  for (int k = 0; k < 500; ++k) {
    const Vector3d p(u(rng), u(rng), u(rng) * 0.8);
    const ApproachDirections& d = dirs[static_cast<size_t>(k) % dirs.size()];
    const Vector3d cold = c.command_for(p, d);
    // A neighbour's correction (0.5 mm away, other directions too) as the start.
    const Vector3d q = p + Vector3d(0.5, -0.2, 0.1);
    const Vector3d warm =
        c.command_for(p, d, c.command_for(q, dirs[(static_cast<size_t>(k) + 5) % dirs.size()]) - q);
    EXPECT_LT((cold + c.error_at(cold, d) - p).norm(), 1e-11);
    EXPECT_LT((warm + c.error_at(warm, d) - p).norm(), 1e-11);
    EXPECT_LT((warm - cold).norm(), 1e-11);
    // The post's accuracy (1e-9 mm, certified by the Lipschitz bound).
    const Vector3d warm9 = c.command_for(p, d, c.command_for(q, d) - q, 1e-9);
    EXPECT_LT((warm9 - cold).norm(), 1e-9);
  }
}

// A random program of the forms a three-axis program mixes: plain lines in
// every case and spacing, lines that are not plain, G0 and G1 with F, G91
// and G20 stretches, tool length offsets, comments, block delete, CRLF,
// short zig-zag steps (lost-motion reversals, split pieces) and long ones.
std::string random_program(std::mt19937_64& rng) {
  auto pick = [&](int n) { return static_cast<int>(rng() % static_cast<unsigned>(n)); };
  auto uni = [&](double lo, double hi) {
    return lo + (hi - lo) * static_cast<double>(rng() % 1000001) / 1e6;
  };
  std::string p = "%\nG21 G90 G17 G94\nG0 X10 Y10 Z20\nG1 F800\n";
  double x = 10, y = 10, z = 20;  // nominal, mm, G90 program coordinates
  bool inch = false, incremental = false, rapid = false;
  for (int k = 0; k < 1500; ++k) {
    const int what = pick(100);
    const char* eol = pick(50) == 0 ? "\r\n" : "\n";
    if (what < 3) {
      incremental = !incremental;
      p += incremental ? "G91" : "G90";
    } else if (what < 5) {
      inch = !inch;
      p += inch ? "G20" : "G21";
    } else if (what < 7) {
      p += pick(2) ? "G43 H1" : (pick(2) ? "G43 H2" : "G49");
    } else if (what < 9) {
      p += "(a comment)";
    } else if (what < 11) {
      p += fmt::format("G0 Z{:.3f}", (incremental ? 0.0 : z) / (inch ? 25.4 : 1.0));
      rapid = true;
    } else if (what < 13) {
      p += fmt::format("F{}", 200 + pick(2000));
    } else {
      // A move: short steps zig-zag (reversals), some long ones.
      const double step = pick(4) == 0 ? uni(5, 40) : uni(0.001, 0.8);
      double nx = std::clamp(x + (pick(2) ? step : -step), 0.0, 200.0);
      double ny = std::clamp(y + (pick(3) == 0 ? uni(-2, 2) : 0.0), 0.0, 200.0);
      double nz = std::clamp(z + (pick(2) ? uni(-1, 1) : 0.0), -20.0, 50.0);
      const int axes = 1 + pick(7);  // which of X Y Z the line names
      if (!(axes & 1)) nx = x;
      if (!(axes & 2)) ny = y;
      if (!(axes & 4)) nz = z;
      const double unit = inch ? 25.4 : 1.0;
      const int dec = inch ? 5 : 4;
      const bool lower = pick(10) == 0;
      const std::string sep = pick(8) == 0 ? "" : " ";
      std::string words;
      const double v[3] = {nx, ny, nz}, was[3] = {x, y, z};
      for (int a = 0; a < 3; ++a) {
        if (!(axes >> a & 1)) continue;
        if (!words.empty()) words += sep;
        words += lower ? "xyz"[a] : "XYZ"[a];
        words += fmt::format("{:.{}f}", (incremental ? v[a] - was[a] : v[a]) / unit, dec);
      }
      const int form = pick(20);
      if (form == 0) words = "G1 " + words, rapid = false;
      if (form == 1) words = "N" + std::to_string(k) + " " + words;
      if (form == 2) words += " (c)";
      if (form == 3) words = "/" + words;
      if (form == 4) words = "G0 " + words, rapid = true;  // plain lines in G0 follow
      if (form > 4 && rapid && pick(3) == 0) words = "G1 " + words, rapid = false;
      p += words;
      x = nx, y = ny, z = nz;  // (a block-delete line runs too: volmap executes it)
    }
    p += eol;
  }
  p += "G90 G21\nG0 Z50\nM2\n%\n";
  return p;
}

std::pair<std::string, post::PostReport> post_with(const std::string& program, const Machine& m,
                                                   const ErrorSet& e, double tol_um,
                                                   bool shortcuts) {
  nc::ProgramSetup setup;
  setup.work_offset_mm[0] =
      m.name == "hsu-3axis" ? Vector3d(150, 100, 200) : Vector3d(300, 200, 100);
  setup.tool_length_mm[1] = 12.5;
  setup.tool_length_mm[2] = -7.25;
  post::PostOptions o;
  o.tolerance_mm = tol_um * 1e-3;
  o.shortcuts = shortcuts;
  // (Byte for byte against the general path: the self-check, which refuses a
  // reversal right after a block-delete line's creep back, 1.47 um at 1 um in
  // trial 0, is tested in self_check_test.cc.)
  o.self_check = false;
  std::istringstream in(program);
  std::ostringstream out;
  const post::PostReport r = post::post_program(in, "random.ngc", out, m, e, setup, o);
  return {out.str(), r};
}

// The errors times `factor` (values, slopes and location errors).
ErrorSet scaled(ErrorSet e, double factor) {
  for (auto& axis : e.axis) {
    if (!axis) continue;
    for (AxisErrorTable* t : {&axis->plus, &axis->minus})
      for (auto* rows : {&t->value, &t->slope})
        for (auto& row : *rows)
          for (double& v : row) v *= factor;
  }
  for (auto& [name, v] : e.location) v *= factor;
  return e;
}

// The shortcut of plain lines writes what the general path writes, byte for
// byte, and counts the same, on programs that go in and out of it: on two
// machines, and with errors a hundred times smaller (corrections of about
// the output's resolution: lines kept as written and lines changed mixed).
TEST(PostShortcut, PlainLinesGiveTheGeneralPathsOutput) {
  std::mt19937_64 rng(23);
  const Machine machines[] = {
      hsu(), load_machine_json(test::source_path("samples/machines/gantry-3axis.json")), hsu()};
  const ErrorSet errors[] = {hsu_errors(),
                             load_errors_csv(test::source_path("samples/errors/gantry-3axis.csv")),
                             scaled(hsu_errors(), 0.01)};
  for (int trial = 0; trial < 9; ++trial) {
    const std::string program = random_program(rng);
    int plain = 0;
    std::istringstream lines(program);
    for (std::string l; std::getline(lines, l);) {
      nc::PlainAxisWords w;
      plain += nc::lex_plain_axis_words(l, w) ? 1 : 0;
    }
    EXPECT_GT(plain, 800);
    const int k = trial % 3;
    const double tol_um = trial < 6 ? 1.0 : 0.2;
    const auto general = post_with(program, machines[k], errors[k], tol_um, false);
    const auto shortcut = post_with(program, machines[k], errors[k], tol_um, true);
    ASSERT_EQ(shortcut.first, general.first) << "trial " << trial;
    EXPECT_EQ(shortcut.second.lines, general.second.lines);
    EXPECT_EQ(shortcut.second.lines_changed, general.second.lines_changed);
    EXPECT_EQ(shortcut.second.lines_added, general.second.lines_added);
    EXPECT_EQ(shortcut.second.points_corrected, general.second.points_corrected);
    EXPECT_EQ(shortcut.second.max_correction_mm, general.second.max_correction_mm);
    // The programs are corrected, pieces added (the small errors: some
    // lines kept, some changed).
    EXPECT_GT(general.second.lines_changed, k == 2 ? 100u : 500u) << trial;
    EXPECT_LT(general.second.lines_changed, general.second.lines - (k == 2 ? 300u : 0u)) << trial;
    if (k < 2) {
      EXPECT_GT(general.second.lines_added, 10u) << trial;
    }
  }
  // The sample and LinuxCNC's programs.
  std::vector<std::string> paths = {test::source_path("samples/programs/pocket.ngc")};
  for (const char* name : {"tort.ngc", "arcspiral.ngc", "3dtest.ngc", "cds.ngc"})
    if (std::ifstream(std::string("/usr/share/linuxcnc/ncfiles/") + name))
      paths.push_back(std::string("/usr/share/linuxcnc/ncfiles/") + name);
  for (const std::string& path : paths) {
    std::ifstream f(path, std::ios::binary);
    std::stringstream ss;
    ss << f.rdbuf();
    const auto general = post_with(ss.str(), machines[0], errors[0], 1.0, false);
    const auto shortcut = post_with(ss.str(), machines[0], errors[0], 1.0, true);
    EXPECT_EQ(shortcut.first, general.first) << path;
    EXPECT_EQ(shortcut.second.points_corrected, general.second.points_corrected) << path;
  }
}

// Lines the shortcut writes with the fewest changes (a word kept: X and Y
// change, Z not) and lines after a G1 word (renumbered in place, the G1
// kept): the general path's output and counts, on a circle of short moves
// in the forms CAM writes (the circle of bench/nc_programs.sh among them),
// and with G1 also after cutter compensation has ended.
TEST(PostShortcut, FewestChangesAndG1LinesGiveTheGeneralPathsOutput) {
  const char* const forms[] = {"X{0:.4f} Y{1:.4f}",
                               "G1 X{0:.4f} Y{1:.4f} Z-2",
                               "G01 X{0:.4f} Y{1:.4f}",
                               "g1x{0:.4f}y{1:.4f}z-2",
                               "G1 Y{1:.4f} X{0:.4f}",
                               "G1X{0:.3f}",
                               "G1 X{0:.5f} Y{1:.2f} Z-2.00004"};
  for (const bool comp : {false, true})
    for (const char* form : forms) {
      // Compensation ended before the circle: the forms with G1, which the
      // general path took before the shortcut did.
      if (comp && form[0] == 'X') continue;
      std::string p =
          fmt::format("%\nG21 G90 G17 G94\nG0 X{} Y100 Z10\nG1 Z-2 F800\n", comp ? 120 : 150);
      // A compensated stretch (X moving one way: its play is not taken up
      // under compensation) that ends where the circle begins.
      if (comp) p += "G1 X125\nG41.1 D0.2 X130 Y100\nG1 X140 Y105\nG40 G1 X150 Y100\n";
      const double step = 2 * M_PI / 1000.5;
      for (int n = 1; n <= 3000; ++n)
        p += fmt::format(fmt::runtime(form), 100 + 50 * std::cos(n * step),
                         100 + 50 * std::sin(n * step)) +
             "\n";
      // Long moves that need pieces (the tolerance decides how many).
      for (int n = 0; n < 20; ++n) p += fmt::format("G1 X{} Y{} Z-2\n", n % 2 ? 20 : 220, 30 + n);
      p += "G0 Z10\nM2\n%\n";
      const auto general = post_with(p, hsu(), hsu_errors(), 1.0, false);
      const auto shortcut = post_with(p, hsu(), hsu_errors(), 1.0, true);
      ASSERT_EQ(shortcut.first, general.first) << form << " comp " << comp;
      EXPECT_EQ(shortcut.second.lines_changed, general.second.lines_changed) << form;
      EXPECT_EQ(shortcut.second.lines_added, general.second.lines_added) << form;
      EXPECT_EQ(shortcut.second.points_corrected, general.second.points_corrected) << form;
      EXPECT_EQ(shortcut.second.max_correction_mm, general.second.max_correction_mm) << form;
      EXPECT_EQ(shortcut.second.max_deviation_mm, general.second.max_deviation_mm) << form;
      EXPECT_GT(general.second.lines_changed, 2900u) << form;
      EXPECT_GT(general.second.lines_added, 20u) << form;
    }
}

}  // namespace
}  // namespace volmap
