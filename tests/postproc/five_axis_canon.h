// Five-axis programs as LinuxCNC's rs274 reads them: its canonical feed
// points, the feed points volmap wrote, and how far the tool tip at each
// stands from a nominal path on the error model. Shared by the tests of real
// TCP programs and real APT files.
#pragma once

#include <algorithm>
#include <cmath>
#include <cstdlib>
#include <fstream>
#include <sstream>
#include <string>
#include <vector>

#include "core/model/error_model.h"
#include "gcode/nc_block.h"
#include "gcode/nc_path.h"

namespace volmap::test {

inline bool have_rs274() { return std::system("command -v rs274 >/dev/null 2>&1") == 0; }

struct Pose5 {
  double x, y, z, a, c;
};

// STRAIGHT_FEED(x, y, z, a, b, c) points of rs274's canonical output.
inline std::vector<Pose5> canonical_feeds(const std::string& canon, std::string& errors) {
  std::ifstream f(canon);
  std::string line;
  std::vector<Pose5> out;
  while (std::getline(f, line)) {
    if (line.find("rror") != std::string::npos) errors += line + "\n";
    const size_t at = line.find("STRAIGHT_FEED(");
    if (at == std::string::npos) continue;
    std::vector<double> v;
    std::stringstream ss(line.substr(at + 14, line.rfind(')') - at - 14));
    std::string tok;
    while (std::getline(ss, tok, ',')) v.push_back(std::strtod(tok.c_str(), nullptr));
    if (v.size() >= 6) out.push_back({v[0], v[1], v[2], v[3], v[5]});
  }
  return out;
}

// Feed positions volmap wrote (X Y Z A C, modal words carried).
inline std::vector<Pose5> written_feeds(const std::string& program) {
  std::ifstream f(program);
  std::string line;
  std::vector<Pose5> out;
  int motion = -1, n = 0;
  while (std::getline(f, line)) {
    const nc::Block b = nc::lex_block(line, ++n, program);
    Pose5 p{};
    bool move = false;
    for (const nc::Word& w : b.words) {
      if (w.letter == 'G' && (w.code10 == 0 || w.code10 == 10)) motion = w.code10;
      if (w.letter == 'X') p.x = w.value, move = true;
      if (w.letter == 'Y') p.y = w.value;
      if (w.letter == 'Z') p.z = w.value;
      if (w.letter == 'A') p.a = w.value;
      if (w.letter == 'C') p.c = w.value;
    }
    if (move && motion == 10) out.push_back(p);
  }
  return out;
}

// The farthest of rs274's feed points, run on the real machine (model), from
// the nominal path (mm); slack_mm: what rs274's printed decimals allow.
inline double worst_tip_distance_mm(const std::vector<Pose5>& feeds,
                                    const std::vector<nc::Motion>& path, const ErrorModel& model,
                                    double slack_mm) {
  size_t cursor = 0;
  double worst = 0;
  for (const Pose5& p : feeds) {
    AxisVector u(5);
    u << p.x, p.y, p.z, p.a * M_PI / 180, p.c * M_PI / 180;
    const Eigen::Vector3d tip = model.actual(u).tip_mm;
    // The first move from the cursor on that the point lies on (a path
    // that comes back over itself has end points on several moves), else
    // the nearest in the window.
    double best = 1e300;
    size_t best_k = cursor;
    for (size_t k = cursor; k < std::min(path.size(), cursor + 12); ++k) {
      const double d = nc::distance_to_path(path[k], tip);
      if (d <= 1e-3 + slack_mm) {
        best = d;
        best_k = k;
        break;
      }
      if (d < best) {
        best = d;
        best_k = k;
      }
    }
    cursor = best_k;
    worst = std::max(worst, best);
  }
  return worst;
}

}  // namespace volmap::test
