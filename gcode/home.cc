// G28 and G30 as LinuxCNC runs them (its manual's "G28, G28.1" and "G30,
// G30.1"; checked with rs274): a rapid to the point the axis words name
// (G90 or G91), then a rapid of those axes, or of all when the block has
// none, to the stored position: machine coordinates of the axes, so the
// controlled point ends a tool length offset below it. G28.1 and G30.1
// store where the axes stand. The stored positions come from a parameter
// file (#5161.., #5181..): without one the post cannot know where the tool
// goes, and refuses. The motion handed out is the rapid from where the
// tool stood to where it ends (the intermediate point lies on the
// controller's rapid, which cuts nothing).
#include <fmt/format.h>

#include "gcode/block_check.h"
#include "gcode/g_codes.h"

namespace volmap::nc {

void BlockCheck::home(int code10) {
  const int k = code10 == kG28Home || code10 == kG28_1StoreHome ? 0 : 1;
  const char* name = k == 0 ? "G28" : "G30";
  const int first_parameter = k == 0 ? 5161 : 5181;
  const Word* self = g[kNonModal];
  const bool store = code10 == kG28_1StoreHome || code10 == kG30_1StoreSecondHome;
  const char* axes = "XYZABC";
  if (g[kMotion] && (word('X') || word('Y') || word('Z')))
    fail(self, fmt::format("{} and a motion code in one block both use the axis words; split "
                           "the block",
                           name));
  consumed_axes_ = true;  // the axis words are the intermediate point's
  auto& home = s_.home[static_cast<size_t>(k)];
  auto& known = s_.home_known[static_cast<size_t>(k)];
  if (store) {
    effect_.stores_home = true;
    // The axes' machine position: the controlled point plus the tool length
    // offset on Z.
    for (int a = 0; a < 3; ++a) {
      if (!s_.axis_known[static_cast<size_t>(a)])
        fail(self, fmt::format("{}.1 stores where the axes stand, and {} is not known here; "
                               "command it first, or give `initial_position`",
                               name, axes[a]));
      home[static_cast<size_t>(a)] = s_.position_mm[a] + (a == 2 ? s_.tool_length_mm : 0.0);
      known[static_cast<size_t>(a)] = true;
    }
    for (int a = 0; a < 3; ++a) {
      home[static_cast<size_t>(a + 3)] = s_.rotary_rad[static_cast<size_t>(a)];
      known[static_cast<size_t>(a + 3)] = true;
    }
    return;
  }
  // The intermediate point, then the stored position of the axes named (all
  // of them when none is).
  const bool any = word('X') || word('Y') || word('Z') || word('A') || word('B') || word('C');
  if (!any && fanuc())
    fail(self, fmt::format("{} without axis words: a Fanuc control returns only the axes the "
                           "block names (LinuxCNC all of them); name them ({} X0. Y0. Z0. under "
                           "G91 goes straight up from where the tool stands)",
                           name, name));
  Eigen::Vector3d end = s_.position_mm;
  unsigned homed = 0;
  for (int a = 0; a < 6; ++a) {
    const Word* w = word(axes[a]);
    const bool moves =
        any ? w != nullptr : (a < 3 || setup_.rotary_axes.find(axes[a]) != std::string::npos);
    if (!moves) continue;
    if (!known[static_cast<size_t>(a)])
      fail(self, fmt::format("{} returns {} to the position stored in the controller (#{}), "
                             "which the post does not know: give the machine's parameter file "
                             "(its .var) with `var_file`",
                             name, axes[a], first_parameter + a));
    if (a >= 3) {
      s_.rotary_rad[static_cast<size_t>(a - 3)] = home[static_cast<size_t>(a)];
      continue;
    }
    if (w && !s_.absolute && !s_.axis_known[static_cast<size_t>(a)])
      fail(w, fmt::format("{} with an incremental {} from an unknown position", name, axes[a]));
    end[a] = home[static_cast<size_t>(a)] - (a == 2 ? s_.tool_length_mm : 0.0);
    homed |= 1u << a;
  }
  Motion& mo = effect_.motion;
  mo = Motion{};
  mo.kind = MotionKind::kRapid;
  mo.start_mm = s_.position_mm;
  mo.end_mm = end;
  mo.feed = s_.feed;
  effect_.has_motion = true;
  effect_.homed_axes = homed;
  s_.position_mm = end;
  for (int a = 0; a < 3; ++a)
    if (homed & (1u << a)) s_.axis_known[static_cast<size_t>(a)] = true;
  s_.position_known = s_.axis_known[0] && s_.axis_known[1] && s_.axis_known[2];
}

}  // namespace volmap::nc
