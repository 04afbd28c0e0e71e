// Modal groups of the G and M codes volmap reads (RS274NGC / LinuxCNC
// numbering), and why it refuses the others: step 2 of the interpreter's
// validation (nc_interpreter.h), a G or M code per group and block.
#pragma once

namespace volmap::nc {

// Modal groups of G codes (code x 10), RS274NGC / LinuxCNC numbering.
enum GGroup {
  kNonModal = 0,
  kMotion = 1,
  kPlane = 2,
  kDistance = 3,
  kArcDistance = 4,
  kFeedMode = 5,
  kUnits = 6,
  kCutterComp = 7,
  kToolLength = 8,
  kReturnMode = 10,
  kCoordSystem = 12,
  kPathControl = 13,
  kSpindleMode = 14,
  kGroupCount = 16
};

enum MGroup {
  kMStop = 0,
  kMTool = 1,
  kMSpindle = 2,
  kMCoolant = 3,
  kMOverride = 4,
  kMOther = 5,
  kMGroupCount = 6
};

/// The group of a supported G code (Word::code10), or -1 with `why` set
/// for one volmap refuses.
int g_group(int code10, const char** why);
/// The group of a supported M code (Word::code10), or -1 with `why` set.
int m_group(int code10, const char** why);

/// G73 or G81 .. G89: a canned cycle.
bool is_cycle(int motion_code10);
/// G2 or G3.
bool is_arc(int motion_code10);

}  // namespace volmap::nc
