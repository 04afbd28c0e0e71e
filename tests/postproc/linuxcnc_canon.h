// rs274, LinuxCNC's interpreter, as the tests of tests/postproc/linuxcnc*
// use it: whether it is installed, its canonical calls read back (the
// nominal feeds and every commanded end point), `volmap post` on the sample
// machine, and tool tables for both.
#pragma once

#include <fmt/format.h>
#include <gtest/gtest.h>

#include <algorithm>
#include <cctype>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <initializer_list>
#include <sstream>
#include <string>
#include <utility>
#include <vector>

#include "gcode/nc_path.h"
#include "postproc/three_axis/corrector.h"
#include "tests/support/rs274.h"
#include "tests/support/test_paths.h"

namespace volmap {

namespace fs = std::filesystem;

inline bool have_rs274() { return std::system("command -v rs274 >/dev/null 2>&1") == 0; }

inline void require_rs274() {
  if (have_rs274()) return;
  if (std::getenv("VOLMAP_REQUIRE_RS274"))
    FAIL() << "rs274 (linuxcnc-uspace) is required but missing";
  GTEST_SKIP() << "rs274 not installed (apt-get install linuxcnc-uspace)";
}

struct Canon {
  double unit_mm = 1.0;           ///< rs274 prints 4 decimals in the program's unit
  std::vector<nc::Motion> feeds;  // nominal path, program units -> mm
  std::vector<std::pair<Eigen::Vector3d, bool>> points;  // every commanded end point, feed?
  bool ok = true;
  std::string errors;
};

// Runs rs274 on a program and reads its canonical calls.
/// `var_file` (a copy is given to rs274, which may write it back): the
/// parameters it starts from (work offsets, G28/G30 homes).
inline Canon canonical(const std::string& program, const std::string& tool_table,
                       const std::string& var_file = "") {
  // Written under this test run's temporary folder, never beside the program
  // (LinuxCNC's own programs are in a system folder other runs share).
  static const fs::path dir = test::fresh_dir("canon");
  static int count = 0;
  const std::string out =
      (dir / (std::to_string(++count) + "-" + fs::path(program).filename().string() + ".canon"))
          .string();
  std::string var_option;
  if (!var_file.empty()) {
    // A short name: rs274 cuts a long one (about 100 characters) and then
    // starts from zeros.
    const std::string copy = (dir / (std::to_string(count) + ".var")).string();
    fs::copy_file(var_file, copy, fs::copy_options::overwrite_existing);
    var_option = "-v " + copy + " ";
  }
  const std::string cmd = "cd " + fs::path(program).parent_path().string() + " && " +
                          test::rs274_command((tool_table.empty() ? "" : "-t " + tool_table + " ") +
                                              var_option + "-g " + program + " " + out) +
                          " >" + out + ".log 2>&1";
  Canon c;
  c.ok = std::system(cmd.c_str()) == 0;
  if (!var_file.empty()) {  // a parameter file rs274 could not read or write back
    std::ifstream log(out + ".log");
    for (std::string l; std::getline(log, l);)
      if (l.find("ariable file") != std::string::npos ||
          l.find("arameter file") != std::string::npos) {
        c.ok = false;
        c.errors += l + "\n";
      }
  }
  std::ifstream f(out);
  std::string line;
  double unit = 1.0;
  int plane = 0;
  Eigen::Vector3d pos = Eigen::Vector3d::Zero();
  // rs274 prints positions in the program's coordinates: the G92 offset
  // (G92, G52) in effect is added, so the points are relative to the work
  // offset alone.
  Eigen::Vector3d g92 = Eigen::Vector3d::Zero();
  auto numbers = [](const std::string& l) {
    std::vector<double> v;
    const size_t open = l.find('('), close = l.rfind(')');
    std::stringstream ss(l.substr(open + 1, close - open - 1));
    std::string tok;
    while (std::getline(ss, tok, ',')) v.push_back(std::strtod(tok.c_str(), nullptr));
    return v;
  };
  while (std::getline(f, line)) {
    if (line.find("USE_LENGTH_UNITS(CANON_UNITS_INCHES)") != std::string::npos)
      unit = c.unit_mm = 25.4;
    if (line.find("USE_LENGTH_UNITS(CANON_UNITS_MM)") != std::string::npos) unit = 1.0;
    if (line.find("SELECT_PLANE(CANON_PLANE_XY)") != std::string::npos) plane = 0;
    if (line.find("SELECT_PLANE(CANON_PLANE_XZ)") != std::string::npos) plane = 1;
    if (line.find("SELECT_PLANE(CANON_PLANE_YZ)") != std::string::npos) plane = 2;
    if (line.find("rror") != std::string::npos) c.errors += line + "\n";
    if (line.find("SET_G92_OFFSET(") != std::string::npos) {
      const std::vector<double> v = numbers(line);
      g92 = Eigen::Vector3d(v[0], v[1], v[2]) * unit;
    }
    const bool traverse = line.find("STRAIGHT_TRAVERSE(") != std::string::npos;
    const bool feed = line.find("STRAIGHT_FEED(") != std::string::npos;
    if (traverse || feed) {
      const std::vector<double> v = numbers(line);
      const Eigen::Vector3d p = Eigen::Vector3d(v[0], v[1], v[2]) * unit + g92;
      if (feed) {
        nc::Motion m;
        m.kind = nc::MotionKind::kLinear;
        m.start_mm = pos;
        m.end_mm = p;
        c.feeds.push_back(m);
      }
      c.points.push_back({p, feed});
      pos = p;
    }
    if (line.find("ARC_FEED(") != std::string::npos) {
      // ARC_FEED(first_end, second_end, first_centre, second_centre,
      //          rotation, axis_end, a, b, c); XY: first X; XZ (G18): first
      // Z, second X; YZ (G19): first Y, second Z.
      const std::vector<double> v = numbers(line);
      static constexpr int kFirst[3] = {0, 2, 1}, kSecond[3] = {1, 0, 2}, kAxis[3] = {2, 1, 0};
      nc::Motion m;
      m.kind = nc::MotionKind::kArc;
      m.start_mm = pos;
      m.end_mm[kFirst[plane]] = v[0] * unit;
      m.end_mm[kSecond[plane]] = v[1] * unit;
      m.end_mm[kAxis[plane]] = v[5] * unit;
      m.end_mm += g92;
      m.center_mm = pos;
      m.center_mm[kFirst[plane]] = v[2] * unit + g92[kFirst[plane]];
      m.center_mm[kSecond[plane]] = v[3] * unit + g92[kSecond[plane]];
      const int rotation = static_cast<int>(v[4]);
      m.clockwise = rotation < 0;
      m.extra_turns = std::abs(rotation) - 1;
      // volmap's planes: 0 XY (I J), 1 ZX (K I), 2 YZ (J K).
      m.plane = plane;
      c.feeds.push_back(m);
      // The commanded end of an arc; its interior is the controller's.
      c.points.push_back({m.end_mm, true});
      pos = m.end_mm;
    }
  }
  return c;
}

// The commanded points of a run (rs274's canonical calls), moved by the
// machine's error with the play of each axis as the run's moves leave it:
// the farthest, in um, from the nominal feeds (wo: work offset, mm).
// `cut_starts`: also the end of each rapid that a feed follows, and the
// run starts at the program's origin (rs274's start; the post is given the
// same with --initial-position), so the first move sets the play too.
inline double worst_deviation_um(const Canon& run, const std::vector<nc::Motion>& nominal,
                                 const post::Corrector& c, const Eigen::Vector3d& wo,
                                 bool cut_starts = false) {
  Eigen::Vector3d h = Eigen::Vector3d::Zero(), prev = wo;
  bool first = !cut_starts;
  size_t cursor = 0;
  double max_um = 0;
  for (std::size_t k = 0; k < run.points.size(); ++k) {
    const auto& [p_prog, feed] = run.points[k];
    const Eigen::Vector3d p = p_prog + wo;
    for (int a = 0; a < 3 && !first; ++a) {
      const double step = p[a] - prev[a];
      if (step == 0 || !c.bidirectional(a)) continue;
      const double w = c.play_width_mm(a, p);
      h[a] = w < 1e-9 ? (step > 0 ? 1 : -1) : std::clamp(h[a] + 2 * step / w, -1.0, 1.0);
    }
    first = false;
    prev = p;
    const bool cut_start =
        cut_starts && !feed && k + 1 < run.points.size() && run.points[k + 1].second;
    if (!feed && !cut_start) continue;
    // A feed that moves nothing (rs274 prints one for `G1 F600`) leaves the
    // tool where it stood: no command of the post's can be there.
    if (feed && cut_starts &&
        p_prog == (k > 0 ? run.points[k - 1].first : Eigen::Vector3d::Zero().eval()))
      continue;
    const Eigen::Vector3d actual = p + c.error_with_play(p, h);
    double best = 1e9;
    size_t best_i = cursor;
    for (size_t i = cursor > 3 ? cursor - 3 : 0; i < std::min(nominal.size(), cursor + 6); ++i) {
      const double d = nc::distance_to_path(nominal[i], actual);
      if (d < best) {
        best = d;
        best_i = i;
      }
    }
    // A path that comes back over itself can take the cursor past the
    // segment a point belongs to: then the whole path is searched.
    if (best > 2e-3)
      for (size_t i = 0; i < nominal.size(); ++i) {
        const double d = nc::distance_to_path(nominal[i], actual);
        if (d < best) {
          best = d;
          best_i = i;
        }
      }
    cursor = best_i;
    // VOLMAP_DEBUG_DEVIATION=1: every point over 1.25 um, with its play
    // state and error, on stdout (to find where a run strays).
    if (std::getenv("VOLMAP_DEBUG_DEVIATION") && best > 1.25e-3)
      std::printf(
          "point %zu (%s) at %.4f %.4f %.4f: %.3f um (h %.2f %.2f %.2f, actual-p %.4f %.4f %.4f "
          "um)\n",
          k, feed ? "feed" : "cut start", p_prog.x(), p_prog.y(), p_prog.z(), best * 1e3, h.x(),
          h.y(), h.z(), (actual - p).x() * 1e3, (actual - p).y() * 1e3, (actual - p).z() * 1e3);
    max_um = std::max(max_um, best * 1e3);
  }
  return max_um;
}

// `volmap post` on the sample three-axis machine with its errors, args after
// (work offset, input, -o output, ...), for std::system.
inline std::string hsu_post_command(const std::string& args) {
  return test::volmap_binary() + " post --machine " +
         test::source_path("samples/machines/hsu-3axis.json") + " --errors " +
         test::source_path("samples/errors/hsu-3axis.csv") + " " + args;
}

// The same tool table twice, for rs274 (which reads it in inches) and for
// volmap (mm): {inch file, mm file}, tools numbered from 1 with the offsets
// given in inches.
inline std::pair<std::string, std::string> tool_tables(const fs::path& dir,
                                                       std::initializer_list<double> offsets_inch) {
  const std::string inch = (dir / "inch.tbl").string(), mm = (dir / "mm.tbl").string();
  std::ofstream fi(inch), fm(mm);
  int tool = 0;
  for (double z : offsets_inch) {
    ++tool;
    fi << fmt::format("T{0} P{0} Z{1} ;\n", tool, z);
    fm << fmt::format("T{0} P{0} Z{1} ;\n", tool, z * 25.4);
  }
  return {inch, mm};
}

// The sample's errors (hsu-3axis.csv) without X's lost motion (its +
// direction only), written into dir: for tests whose check needs no play.
inline std::string errors_without_lost_motion(const fs::path& dir) {
  const std::string path = (dir / "hsu-one-direction.csv").string();
  std::ifstream in(test::source_path("samples/errors/hsu-3axis.csv"));
  std::ofstream out(path);
  bool x_block = false;
  for (std::string l; std::getline(in, l);) {
    if (l.rfind("X,dir,", 0) == 0) {
      x_block = true;
      out << "X," << l.substr(6) << "\n";
      continue;
    }
    if (x_block && (l.empty() || !(std::isdigit(static_cast<unsigned char>(l[0])) || l[0] == '-')))
      x_block = false;
    if (!x_block) {
      out << l << "\n";
      continue;
    }
    const size_t c1 = l.find(','), c2 = l.find(',', c1 + 1);
    if (l.substr(c1 + 1, c2 - c1 - 1) == "+1") out << l.substr(0, c1) << l.substr(c2) << "\n";
  }
  return path;
}

}  // namespace volmap
