// Offsets set from the program, as LinuxCNC sets them (its manual's "G10
// L2", "G10 L20", "G92, G92.1, G92.2, G92.3"):
//  - G10 L2 P<n> X Y Z: coordinate system n (1 = G54 .. 9 = G59.3, 0 = the
//    active one) gets its origin at those machine coordinates (program
//    units), the axes not named unchanged; R (a rotation) is refused.
//  - G10 L20 P<n> X Y Z: the same, so that where the tool stands has those
//    coordinates in system n.
//  - G92 X Y Z: an offset on top of every coordinate system, so that where
//    the tool stands has those coordinates; the axes not named keep theirs.
//    G92.1 clears it, G92.2 suspends it, G92.3 applies it again.
//  - G52 X Y Z: the same offset (LinuxCNC keeps both in #5211-#5213), set
//    to the values given (program units, absolute under G91 too); the axes
//    not named keep the offset in effect (zero while suspended); applied.
//  - G10 L1 P<tool> Z R: the tool table's row of that tool gets the length
//    offset Z and the radius R (program units; the diameter is 2 R), as
//    rs274 sets them (SET_TOOL_TABLE_ENTRY): an offset in effect stays
//    until the next G43. X Y (a lathe's offsets), I J Q (its angles and
//    orientation) are refused, and so are L10 L11 (rows set from where the
//    tool stands: touch-off, not a CAM program's).
// Fanuc (Series 0i-MF operator's manual, B-64604EN): G10 L2 P1-P6 sets G54-
// G59, and under G91 adds to the offset; P0 (the external offset), L20
// (the additional systems G54.1 P..), G52 under G91, G92.2/G92.3 and G52
// and G92 in one program (separate shifts there, one here) are refused.
#include <fmt/format.h>

#include <cmath>

#include "gcode/block_check.h"
#include "gcode/g_codes.h"

namespace volmap::nc {

void BlockCheck::offsets(int code10) {
  const Word* self = g[kNonModal];
  const bool any = word('X') || word('Y') || word('Z');
  if (any && g[kMotion])
    fail(self, "offsets and a motion code in one block both use the axis words; split the block");
  if (word('A') || word('B') || word('C'))
    fail(self, "offsets of rotary axes are not supported; set them in the parameter file");
  consumed_axes_ = any;
  auto known_position = [&](int a) {
    if (!s_.axis_known[static_cast<size_t>(a)])
      fail(word("XYZ"[a]), fmt::format("an offset set from where the tool stands, and {} is not "
                                       "known here; command it first, or give `initial_position`",
                                       "XYZ"[a]));
  };
  if (fanuc()) fanuc_offsets(code10);
  if (code10 == kG10SetOffsets) {
    const Word* l = word('L');
    const Word* p = word('P');
    if (l && l->value == 1 && !fanuc()) {
      tool_table_row();
      return;
    }
    if (!l || (l->value != 2 && l->value != 20))
      fail(l ? l : self,
           "G10 sets work offsets with L2 or L20 and tool table rows with L1 here; rows set "
           "from where the tool stands (L10 L11) are not supported: give them with "
           "`tool_table`");
    if (!p || p->value != std::floor(p->value) || p->value < 0 || p->value > 9)
      fail(p ? p : self, "G10 needs P0 (the active system) to P9 (G59.3)");
    if (const Word* r = word('R'); r && r->value != 0.0)
      fail(r, "G10 R (a rotation of the coordinate system) is not supported");
    const int n = p->value == 0 ? s_.coord_system : static_cast<int>(p->value) - 1;
    Eigen::Vector3d& offset = s_.coord_offset_mm[static_cast<size_t>(n)];
    for (int a = 0; a < 3; ++a) {
      const Word* w = word("XYZ"[a]);
      if (!w) continue;
      if (l->value == 2) {
        // (Fanuc under G91: added to the offset, which must be known.)
        const unsigned bit = 1u << (3 * n + a);
        if (fanuc() && !s_.absolute && !(s_.fanuc_offsets_set & bit) &&
            !setup_.parameters.contains(5221 + 20 * n + a))
          fail(w,
               "G10 L2 under G91 adds to an offset the program has not set (it is the "
               "control's): set it under G90 first, or give it in a parameter file");
        s_.fanuc_offsets_set |= bit;
        offset[a] = (fanuc() && !s_.absolute ? offset[a] : 0.0) + w->value * s_.unit_mm;
      } else {
        known_position(a);
        offset[a] =
            s_.position_mm[a] - (s_.g92_applied ? s_.g92_mm[a] : 0.0) - w->value * s_.unit_mm;
        effect_.offsets_from_position = true;
      }
    }
  } else if (code10 == kG92AxisOffset) {
    if (!any) fail(self, "G92 needs an axis word");
    const Eigen::Vector3d& coord = s_.coord_offset_mm[static_cast<size_t>(s_.coord_system)];
    if (!s_.g92_applied) s_.g92_mm.setZero();
    for (int a = 0; a < 3; ++a) {
      const Word* w = word("XYZ"[a]);
      if (!w) continue;
      known_position(a);
      s_.g92_mm[a] = s_.position_mm[a] - coord[a] - w->value * s_.unit_mm;
    }
    s_.g92_applied = true;
    effect_.offsets_from_position = true;
  } else if (code10 == kG52LocalOffset) {
    if (!any) fail(self, "G52 needs an axis word (LinuxCNC: \"All axes missing with g52\")");
    if (!s_.g92_applied) s_.g92_mm.setZero();
    for (int a = 0; a < 3; ++a)
      if (const Word* w = word("XYZ"[a])) s_.g92_mm[a] = w->value * s_.unit_mm;
    s_.g92_applied = true;
  } else {
    if (any) fail(self, "G92.1, G92.2 and G92.3 take no axis words");
    if (code10 == kG92_1AxisOffsetReset) s_.g92_mm.setZero();
    s_.g92_applied = code10 == kG92_3AxisOffsetRestore;
  }
  s_.update_origin();
}

void BlockCheck::fanuc_offsets(int code10) {
  const Word* self = g[kNonModal];
  if (code10 == kG10SetOffsets) {
    const Word* l = word('L');
    const Word* p = word('P');
    if (l && l->value == 20)
      fail(l,
           "Fanuc's G10 L20 sets an additional work offset (G54.1 P..), which volmap does "
           "not read; use G54-G59 (G10 L2 P1-P6)");
    if (p && l && l->value == 2 && (p->value == 0 || p->value > 6))
      fail(p,
           "Fanuc's G10 L2 takes P1 (G54) to P6 (G59); P0 is the external work offset, "
           "which volmap does not read");
  }
  if ((code10 == kG92_2AxisOffsetSuspend || code10 == kG92_3AxisOffsetRestore))
    fail(self, "G92.2 and G92.3 are LinuxCNC's, not Fanuc's");
  if (code10 == kG52LocalOffset && !s_.absolute)
    fail(self,
         "G52 under G91: whether its values add to the local offset differs between "
         "controls; give them under G90");
  const int shift = code10 == kG52LocalOffset ? 2 : code10 == kG92AxisOffset ? 1 : 0;
  if (shift != 0 && s_.fanuc_shift != 0 && s_.fanuc_shift != shift)
    fail(self,
         "G52 and G92 in one program: a Fanuc control keeps them apart (G92 cancels the "
         "local offset), volmap as one shift; use one of them");
  if (shift != 0) s_.fanuc_shift = shift;
}

void BlockCheck::tool_table_row() {
  const Word* self = g[kNonModal];
  const Word* p = word('P');
  // LinuxCNC: P a tool of the table (rs274: "P value out of range with G10
  // L1", "Requested tool 9 not found in the tool table").
  if (!p || p->value != std::floor(p->value) || p->value < 0 || p->value > kMaxToolNumber)
    fail(p ? p : self, "G10 L1 needs P, a tool number (P value out of range with G10 L1)");
  const int tool = static_cast<int>(p->value);
  if (!setup_.tool_length_mm.contains(tool))
    fail(p, fmt::format("G10 L1 sets tool {}, which the tool table does not list (LinuxCNC "
                        "refuses it); give the tool in `tool_table`",
                        tool));
  for (char L : {'X', 'Y', 'I', 'J', 'Q'})
    if (const Word* w = word(L); w && w->value != 0.0)
      fail(w, fmt::format("G10 L1 {}: a lathe tool's offset or angle; the post reads a mill's "
                          "length offset Z and radius R only",
                          L));
  ToolTableWrite& row = effect_.tool_row;
  row.tool = tool;
  if (const Word* z = word('Z')) row.length_mm = z->value * s_.unit_mm;
  if (const Word* r = word('R')) row.diameter_mm = 2 * r->value * s_.unit_mm;
}

}  // namespace volmap::nc
