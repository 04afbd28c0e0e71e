// Features that change the controller's setup (gen_state.h): units, the arc
// centre mode, offsets (G52, G92, G10, G55/G56), homes (G28/G30), G53,
// tool changes with G43, and codes that do not move.
#include <fmt/format.h>

#include <cmath>

#include "tests/conformance/gen_state.h"
#include "tests/conformance/setup_files.h"

namespace volmap::conformance::gen {

void units_feature(Gen& g) {
  g.feature(g.inch ? "G21-switch" : "G20-switch");
  g.set_units(!g.inch);
  lines_feature(g);
  if (g.chance(0.5)) {
    g.set_units(!g.inch);
    lines_feature(g);
  }
}

void arc_distance_feature(Gen& g) {
  g.feature("G90.1");
  g.emit(g.code("G90.1"));
  g.arc_absolute = true;
  if (g.chance(0.5))
    contour_feature(g);
  else
    circle_feature(g);
  g.emit(g.code("G91.1"));
  g.arc_absolute = false;
}

// The moves of a feature in a shifted frame (the region stays where it is).
void shifted_moves(Gen& g) {
  const int k = g.integer(0, 3);
  if (k == 0) contour_feature(g);
  if (k == 1) lines_feature(g);
  if (k == 2) circle_feature(g);
  if (k == 3) drill_feature(g);
}

void local_offset_feature(Gen& g) {
  g.feature("G52");
  g.set_absolute();
  const double u = g.unit();
  const Vec off(g.uniform(-30, 30), g.uniform(-30, 30), g.uniform(-5, 5));
  std::vector<std::string> words = {g.code("G52")};
  for (int a = 0; a < 3; ++a) {
    if (a == 2 && g.chance(0.5)) continue;
    const double v = g.rounded(off[a] / u);
    words.push_back(g.word("XYZ"[a], v));
    g.g92_shift[a] = v * u;
  }
  g.emit(g.join(words));
  g.update_shift();
  shifted_moves(g);
  g.set_absolute();
  g.emit(g.chance(0.5) ? g.code("G92.1")
                       : g.join({g.code("G52"), g.word('X', 0), g.word('Y', 0), g.word('Z', 0)}));
  g.g92_shift = Vec::Zero();
  g.update_shift();
}

void g92_feature(Gen& g) {
  g.feature("G92");
  g.set_absolute();
  if (!g.known) return;
  const double u = g.unit();
  std::vector<std::string> words = {g.code("G92")};
  for (int a = 0; a < 3; ++a) {
    if (a == 2 && g.chance(0.4)) continue;
    // The current point gets these coordinates.
    const double v = g.rounded(g.uniform(-20, 20) / u);
    words.push_back(g.word("XYZ"[a], v));
    g.g92_shift[a] = g.w[a] - g.cs_shift[a] - v * u;
  }
  g.emit(g.join(words));
  g.update_shift();
  shifted_moves(g);
  if (g.chance(0.4)) {  // suspended and restored
    g.set_absolute();
    g.emit(g.code("G92.2"));
    const Vec kept = g.g92_shift;
    g.g92_shift = Vec::Zero();
    g.update_shift();
    lines_feature(g);
    g.emit(g.code("G92.3"));
    g.g92_shift = kept;
    g.update_shift();
    lines_feature(g);
  }
  g.set_absolute();
  g.emit(g.code("G92.1"));
  g.g92_shift = Vec::Zero();
  g.update_shift();
}

void g10_feature(Gen& g) {
  g.set_absolute();
  const double u = g.unit();
  const int k = g.integer(0, 3);
  std::string select = "G55";
  if (k == 0) {  // G55 from the parameter file
    g.feature("G55");
    g.cs_shift = kG55FromG54Mm;
  } else if (k == 1) {  // G56 from the parameter file
    g.feature("G56");
    select = "G56";
    g.cs_shift = kG56FromG54Mm;
  } else if (k == 2) {  // G10 L2 P2: G55's origin in machine coordinates
    g.feature("G10 L2");
    const Vec d(g.uniform(-30, 30), g.uniform(-30, 30), g.uniform(-8, 8));
    std::vector<std::string> words = {g.code("G10"), g.code("L2"), g.code("P2")};
    for (int a = 0; a < 3; ++a) {
      const double v = g.rounded((kWorkOffsetMm[a] + d[a]) / u);
      words.push_back(g.word("XYZ"[a], v));
      g.cs_shift[a] = v * u - kWorkOffsetMm[a];
    }
    g.emit(g.join(words));
  } else {  // G10 L20 P2: where the tool stands has these coordinates in G55
    g.feature("G10 L20");
    if (!g.known || g.g92_shift != Vec::Zero()) return;
    std::vector<std::string> words = {g.code("G10"), g.code("L20"), g.code("P2")};
    for (int a = 0; a < 3; ++a) {
      const double v = g.rounded(g.uniform(-20, 20) / u);
      words.push_back(g.word("XYZ"[a], v));
      g.cs_shift[a] = g.w[a] - v * u;
    }
    g.emit(g.join(words));
  }
  g.emit(g.code(select));
  g.update_shift();
  shifted_moves(g);
  g.set_absolute();
  g.emit(g.code("G54"));
  g.cs_shift = Vec::Zero();
  g.update_shift();
}

// G28/G30: through a point, to the home of the parameter file.
void home_feature(Gen& g) {
  const bool g30 = g.chance(0.4);
  g.feature(g30 ? "G30" : "G28");
  g.set_absolute();
  g.retract();
  const Vec home = (g30 ? kG30HomeMm : kG28HomeMm) - kWorkOffsetMm;
  const std::string c = g.code(g30 ? "G30" : "G28");
  const int k = g.integer(0, 2);
  bool all = true;
  if (k == 0) {
    g.emit(c);  // every axis, from where it stands
  } else if (k == 1) {
    g.emit(g.join({g.code("G91"), c, g.word('Z', 0)}));  // Z alone, the classic
    g.emit(g.code("G90"));
    all = false;
  } else {
    const Vec p = g.program(g.w) / g.unit();
    g.emit(g.join({c, g.word('X', p.x()), g.word('Y', p.y()), g.word('Z', p.z() + 5 / g.unit())}));
  }
  // The axes stand at the home: the tip a tool length offset below it.
  if (all) g.w.head(2) = home.head(2);
  g.w.z() = home.z() - g.tool_offset;  // (the modal motion stays)
}

void tool_change_feature(Gen& g) {
  g.feature("tool change");
  g.set_absolute();
  g.retract();
  const int tool = g.integer(1, 6);
  const int k = g.integer(0, 3);
  if (k == 0)
    g.emit(g.join({g.code(fmt::format("T{}", tool)), g.code("M6")}));
  else if (k == 1)
    g.emit(g.join({g.code("M6"), g.code(fmt::format("T{}", tool))}));
  else {
    g.emit(g.code(fmt::format("T{}", tool)));
    g.emit(g.code("M6"));
  }
  g.tool = tool;
  g.spindle = 0;  // M6 stops the spindle
  const double before = g.tool_offset;
  const int h = g.integer(0, 5);
  if (h <= 2) {
    g.emit(g.join({g.code("G43"), g.code(fmt::format("H{}", tool))}));
    g.tool_offset = kTools[tool - 1].z_mm;
  } else if (h == 3) {
    g.emit(g.code("G43"));  // the tool in the spindle
    g.tool_offset = kTools[tool - 1].z_mm;
  } else if (h == 4) {
    const double z = g.rounded(g.uniform(-5, 20) / g.unit());
    g.emit(g.join({g.code("G43.1"), g.word('Z', z)}));
    g.tool_offset = z * g.unit();
  } else {
    g.emit(g.code("G49"));
    g.tool_offset = 0;
  }
  // The controlled point jumps by minus the change (the axes stay).
  g.w.z() -= g.tool_offset - before;
  g.emit(g.join({g.code("M3"), g.word('S', g.integer(5, 40) * 100, 0)}));
  g.spindle = 3;
}

void g53_feature(Gen& g) {
  g.feature("G53");
  g.set_absolute();
  // A retract in machine coordinates, then back over the part.
  const double z_machine = kWorkOffsetMm.z() + g.uniform(60, 120);
  g.emit(g.join({g.code("G53"), g.code("G0"), g.word('Z', z_machine / g.unit())}));
  g.w.z() = g.rounded(z_machine / g.unit()) * g.unit() - kWorkOffsetMm.z() - g.tool_offset;
  g.motion = 0;
}

void misc_feature(Gen& g) {
  g.feature("misc codes");
  const double u = g.unit();
  for (int n = g.integer(1, 3); n > 0; --n) {
    const int k = g.integer(0, 11);
    if (k == 0) g.emit(g.code(g.pick(std::vector<std::string>{"M7", "M8", "M9"})));
    if (k == 1) g.emit(g.join({g.code("G4"), g.word('P', g.uniform(0, 1.5), 2)}));
    if (k == 2) g.emit(g.join({g.code("G64"), g.word('P', 0.01 / u, 4)}));
    if (k == 3) g.emit(g.code(g.chance(0.5) ? "G61" : "G61.1"));
    if (k == 4) g.emit(g.word('S', g.integer(5, 40) * 100, 0));
    if (k == 5) g.emit(g.word('F', (g.inch ? g.uniform(5, 60) : g.uniform(100, 1500)), 1));
    if (k == 6)
      g.emit("(" + std::string(g.chance(0.5) ? "operation: finish" : "TOOL CHANGE?") + ")");
    if (k == 7) g.emit("; a comment");
    if (k == 8) g.emit(g.code(g.chance(0.5) ? "M1" : "M0"));
    if (k == 9) g.emit(g.join({g.code("M48")}));
    if (k == 10 && g.known) {  // inverse time feed: one move in F minutes^-1
      g.emit(g.join({g.code("G93"), g.code("G1"), g.word('X', (g.w.x() - g.shift.x()) / u + 1),
                     g.word('F', g.uniform(5, 100), 1)}));
      g.w.x() = (g.rounded((g.w.x() - g.shift.x()) / u + 1)) * u + g.shift.x();
      g.emit(g.join({g.code("G94"), g.word('F', g.inch ? 20 : 500, 0)}));
      g.motion = 1;
    }
    if (k == 11 && g.known && g.chance(0.3)) {  // block delete: the switch is off, it runs
      const Vec t = g.clamp(g.w + Vec(g.uniform(-10, 10), g.uniform(-10, 10), 0));
      g.emit("/" + g.join({g.code("G1"), g.word('X', (t.x() - g.shift.x()) / u),
                           g.word('Y', (t.y() - g.shift.y()) / u), g.feed_word()}));
      g.w.x() = g.rounded((t.x() - g.shift.x()) / u) * u + g.shift.x();
      g.w.y() = g.rounded((t.y() - g.shift.y()) / u) * u + g.shift.y();
      g.motion = 1;
    }
  }
}

// Programs rs274 refuses: both must refuse, volmap with file:line.
void invalid_feature(Gen& g) {
  g.feature("invalid");
  const double u = g.unit();
  const Vec p = g.program(g.w) / u;
  switch (g.integer(0, 9)) {
    case 0:
      g.emit(g.join({g.code("G2"), g.word('X', p.x() + 5), g.word('I', 1), g.word('J', 0)}));
      break;  // radius to the end differs
    case 1:
      g.emit(g.join({g.code("G0"), g.code("G1"), g.word('X', p.x() + 1)}));
      break;  // two codes of one group
    case 2:
      g.emit(g.join({g.code("G1"), g.word('X', p.x() + 1), g.word('I', 2)}));
      break;  // a word no code uses
    case 3:
      g.emit(g.join({g.code("G83"), g.word('Z', p.z() - 3), g.word('R', p.z()), g.word('Q', 0)}));
      break;  // zero peck
    case 4:
      g.emit(g.join({g.code("G1"), g.word('X', p.x() + 1), g.word('@', 5)}));
      break;  // X with @
    case 5:
      g.emit(g.code("G18"));
      g.emit(g.join({g.code("G1"), g.word('@', 5), g.word('^', 30)}));
      break;  // polar outside G17
    case 6:
      g.emit(g.join({g.code("M3"), g.code("M4")}));
      break;  // two spindle codes
    case 7:
      g.emit(g.join({g.code("G1"), g.word('X', p.x() + 1), g.word('F', -5, 0)}));
      break;  // negative feed
    case 8:
      g.emit(g.code("G999"));
      break;
    default:
      g.emit(g.join({g.code("G2"), g.word('X', p.x())}));
      break;  // an arc without a centre
  }
}

}  // namespace volmap::conformance::gen
