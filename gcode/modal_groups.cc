#include "gcode/modal_groups.h"

#include "gcode/g_codes.h"

namespace volmap::nc {
namespace {

// The group of a G code volmap reads, or -1.
int supported_g_group(int code10) {
  switch (code10) {
    case kG0Rapid:
    case kG1Linear:
    case kG2ArcClockwise:
    case kG3ArcCounterClockwise:
    case kG73PeckDrillChipBreak:
    case kG80CycleCancel:
    case kG81Drill:
    case kG82DrillDwell:
    case kG83PeckDrill:
    case kG84RightHandTap:
    case kG74LeftHandTap:
    case kG85Bore:
    case kG86BoreSpindleStop:
    case kG89BoreDwell:
    case kG33_1RigidTap:
      return kMotion;
    case kG17PlaneXY:
    case kG18PlaneZX:
    case kG19PlaneYZ:
      return kPlane;
    case kG90Absolute:
    case kG91Incremental:
      return kDistance;
    case kG90_1ArcCentreAbsolute:
    case kG91_1ArcCentreIncremental:
      return kArcDistance;
    case kG93InverseTime:
    case kG94UnitsPerMinute:
    case kG95UnitsPerRevolution:
      return kFeedMode;
    case kG20Inch:
    case kG21Millimetre:
      return kUnits;
    case kG40CutterCompOff:
    case kG41CutterCompLeft:
    case kG42CutterCompRight:
    case kG41_1DynamicCutterCompLeft:
    case kG42_1DynamicCutterCompRight:
      return kCutterComp;
    case kG43ToolLength:
    case kG43_1DynamicToolLength:
    case kG49ToolLengthCancel:
      return kToolLength;
    case kG98ReturnToInitialLevel:
    case kG99ReturnToR:
      return kReturnMode;
    case kG54WorkOffset1:
    case kG55WorkOffset2:
    case kG56WorkOffset3:
    case kG57WorkOffset4:
    case kG58WorkOffset5:
    case kG59WorkOffset6:
    case kG59_1WorkOffset7:
    case kG59_2WorkOffset8:
    case kG59_3WorkOffset9:
      return kCoordSystem;
    case kG61ExactPath:
    case kG61_1ExactStop:
    case kG64Blending:
      return kPathControl;
    case kG96ConstantSurfaceSpeed:
    case kG97SpindleRpm:
      return kSpindleMode;
    case kG4Dwell:
    case kG53MachineCoordinates:
    case kG28Home:
    case kG28_1StoreHome:
    case kG30SecondHome:
    case kG30_1StoreSecondHome:
    case kG10SetOffsets:
    case kG92AxisOffset:
    case kG92_1AxisOffsetReset:
    case kG92_2AxisOffsetSuspend:
    case kG92_3AxisOffsetRestore:
    case kG52LocalOffset:
      return kNonModal;
    default:
      return -1;
  }
}

// Why volmap refuses a G code it does not read.
const char* g_refusal(int code10) {
  switch (code10) {
    case kG38_2Probe:
    case kG38_3Probe:
    case kG38_4Probe:
    case kG38_5Probe:
      return "probing moves (G38.x) cannot be compensated; run them uncompensated";
    case kG33SpindleSynchronised:
    case kG76Threading:
      return "spindle-synchronised threading (G33, G76) is not supported: its passes are "
             "tied to the spindle's turns, which a correction would break; post the threads "
             "uncompensated (rigid tapping G33.1, G84 and G74 are read)";
    case kG87BackBore:
    case kG88BoreManualRetract:
      return "back boring (G87) and boring with a manual retract (G88) are not supported; "
             "bore with G85, G86 or G89";
    case kG5CubicSpline:
    case kG5_1QuadraticSpline:
    case kG5_2Nurbs:
    case kG7LatheDiameter:
    case kG8LatheRadius:
    case kG15PolarOff:
    case kG16PolarOn:
    case kG68Rotation:
    case kG69RotationCancel:
      return "splines, lathe diameter mode, polar and rotated coordinates are not supported";
    default:
      return "unknown G code";
  }
}

}  // namespace

int g_group(int code10, const char** why) {
  const int group = supported_g_group(code10);
  if (group < 0) *why = g_refusal(code10);
  return group;
}

int m_group(int code10, const char** why) {
  if (code10 % 10 != 0) {
    *why = "M codes have no decimals";
    return -1;
  }
  switch (code10) {
    case kM0ProgramPause:
    case kM1OptionalPause:
    case kM2ProgramEnd:
    case kM30ProgramEndRewind:
    case kM60PalletPause:
      return kMStop;
    case kM6ToolChange:
    case kM61SetToolNumber:  // LinuxCNC's modal group 6, with M6 (M61 Q2 M64 P1 is read)
      return kMTool;
    case kM3SpindleClockwise:
    case kM4SpindleCounterClockwise:
    case kM5SpindleStop:
    case kM19SpindleOrient:
      return kMSpindle;
    case kM7MistCoolant:
    case kM8FloodCoolant:
    case kM9CoolantOff:
      return kMCoolant;
    case kM48OverridesOn:
    case kM49OverridesOff:
    case kM50FeedOverride:
    case kM51SpindleOverride:
    case kM52AdaptiveFeed:
    case kM53FeedStop:
      return kMOverride;
    case kM98SubprogramCall:
    case kM99SubprogramReturn:
      *why = "M98/M99 subroutine calls are not supported; expand them in CAM";
      return -1;
    default:
      if (code10 >= kM70SaveModalState && code10 <= kM73SaveAutorestore) {
        // (M73 restores at a subroutine's return, which the flat output
        // does not have; M72 restores modes, cutter compensation among them.)
        *why =
            "saving and restoring the modal state (M70-M73) is not supported: volmap writes "
            "subroutines flat, and M72/M73 would restore modes it does not follow; set the "
            "modes explicitly";
        return -1;
      }
      if ((code10 >= kM61SetToolNumber && code10 <= kM68AnalogOutput) ||
          (code10 >= kM100FirstUserCode && code10 <= kM199LastUserCode))
        return kMOther;
      *why = "unknown M code";
      return -1;
  }
}

bool is_cycle(int motion_code10) {
  return motion_code10 == kG73PeckDrillChipBreak || motion_code10 == kG74LeftHandTap ||
         (motion_code10 >= kG81Drill && motion_code10 <= kG89BoreDwell);
}

bool is_arc(int motion_code10) {
  return motion_code10 == kG2ArcClockwise || motion_code10 == kG3ArcCounterClockwise;
}

}  // namespace volmap::nc
