// G and M codes by name, in the form the lexer gives them (Word::code10):
// the code times ten, compared as an integer, never as a float (grbl's
// way): G1 -> 10, G38.2 -> 382, G59.3 -> 593, M30 -> 300, M428 -> 4280.
// The one place that says which number a code is; logic names them.
#pragma once

namespace volmap::nc {

// Motion (modal group 1).
inline constexpr int kG0Rapid = 0;
inline constexpr int kG1Linear = 10;
inline constexpr int kG2ArcClockwise = 20;
inline constexpr int kG3ArcCounterClockwise = 30;
inline constexpr int kG73PeckDrillChipBreak = 730;
inline constexpr int kG80CycleCancel = 800;
inline constexpr int kG81Drill = 810;
inline constexpr int kG82DrillDwell = 820;
inline constexpr int kG83PeckDrill = 830;
inline constexpr int kG85Bore = 850;
inline constexpr int kG86BoreSpindleStop = 860;
inline constexpr int kG89BoreDwell = 890;
// Non-modal.
inline constexpr int kG4Dwell = 40;
inline constexpr int kG53MachineCoordinates = 530;
// Plane (group 2).
inline constexpr int kG17PlaneXY = 170;
inline constexpr int kG18PlaneZX = 180;
inline constexpr int kG19PlaneYZ = 190;
// Distance mode (group 3) and arc centre distance mode (group 4).
inline constexpr int kG90Absolute = 900;
inline constexpr int kG91Incremental = 910;
inline constexpr int kG90_1ArcCentreAbsolute = 901;
inline constexpr int kG91_1ArcCentreIncremental = 911;
// Feed rate mode (group 5).
inline constexpr int kG93InverseTime = 930;
inline constexpr int kG94UnitsPerMinute = 940;
inline constexpr int kG95UnitsPerRevolution = 950;
// Units (group 6).
inline constexpr int kG20Inch = 200;
inline constexpr int kG21Millimetre = 210;
// Cutter radius compensation (group 7).
inline constexpr int kG40CutterCompOff = 400;
inline constexpr int kG41CutterCompLeft = 410;
inline constexpr int kG41_1DynamicCutterCompLeft = 411;
inline constexpr int kG42CutterCompRight = 420;
inline constexpr int kG42_1DynamicCutterCompRight = 421;
// Tool length offset (group 8).
inline constexpr int kG43ToolLength = 430;
inline constexpr int kG43_1DynamicToolLength = 431;
inline constexpr int kG49ToolLengthCancel = 490;
// Canned cycle return mode (group 10).
inline constexpr int kG98ReturnToInitialLevel = 980;
inline constexpr int kG99ReturnToR = 990;
// Coordinate system (group 12): G54 .. G59.3, index 0 .. 8.
inline constexpr int kG54WorkOffset1 = 540;
inline constexpr int kG55WorkOffset2 = 550;
inline constexpr int kG56WorkOffset3 = 560;
inline constexpr int kG57WorkOffset4 = 570;
inline constexpr int kG58WorkOffset5 = 580;
inline constexpr int kG59WorkOffset6 = 590;
inline constexpr int kG59_1WorkOffset7 = 591;
inline constexpr int kG59_2WorkOffset8 = 592;
inline constexpr int kG59_3WorkOffset9 = 593;
inline constexpr int kWorkOffsetCodes[9] = {
    kG54WorkOffset1, kG55WorkOffset2,   kG56WorkOffset3,   kG57WorkOffset4,  kG58WorkOffset5,
    kG59WorkOffset6, kG59_1WorkOffset7, kG59_2WorkOffset8, kG59_3WorkOffset9};
// Path control (group 13).
inline constexpr int kG61ExactPath = 610;
inline constexpr int kG61_1ExactStop = 611;
inline constexpr int kG64Blending = 640;
// Spindle speed mode (group 14).
inline constexpr int kG96ConstantSurfaceSpeed = 960;
inline constexpr int kG97SpindleRpm = 970;

// G codes volmap refuses (each with its reason, gcode/modal_groups.cc).
inline constexpr int kG5CubicSpline = 50;
inline constexpr int kG5_1QuadraticSpline = 51;
inline constexpr int kG5_2Nurbs = 52;
inline constexpr int kG7LatheDiameter = 70;
inline constexpr int kG8LatheRadius = 80;
inline constexpr int kG10SetOffsets = 100;
inline constexpr int kG15PolarOff = 150;
inline constexpr int kG16PolarOn = 160;
inline constexpr int kG28Home = 280;
inline constexpr int kG28_1StoreHome = 281;
inline constexpr int kG30SecondHome = 300;
inline constexpr int kG30_1StoreSecondHome = 301;
inline constexpr int kG33SpindleSynchronised = 330;
inline constexpr int kG33_1RigidTap = 331;
inline constexpr int kG38_2Probe = 382;
inline constexpr int kG38_3Probe = 383;
inline constexpr int kG38_4Probe = 384;
inline constexpr int kG38_5Probe = 385;
inline constexpr int kG52LocalOffset = 520;
inline constexpr int kG68Rotation = 680;
inline constexpr int kG69RotationCancel = 690;
inline constexpr int kG74LeftHandTap = 740;
inline constexpr int kG76Threading = 760;
inline constexpr int kG84RightHandTap = 840;
inline constexpr int kG87BackBore = 870;
inline constexpr int kG88BoreManualRetract = 880;
inline constexpr int kG92AxisOffset = 920;
inline constexpr int kG92_1AxisOffsetReset = 921;
inline constexpr int kG92_2AxisOffsetSuspend = 922;
inline constexpr int kG92_3AxisOffsetRestore = 923;

// M codes (x 10 as well: M30 -> 300).
inline constexpr int kM0ProgramPause = 0;
inline constexpr int kM1OptionalPause = 10;
inline constexpr int kM2ProgramEnd = 20;
inline constexpr int kM30ProgramEndRewind = 300;
inline constexpr int kM60PalletPause = 600;
inline constexpr int kM3SpindleClockwise = 30;
inline constexpr int kM4SpindleCounterClockwise = 40;
inline constexpr int kM5SpindleStop = 50;
inline constexpr int kM19SpindleOrient = 190;
inline constexpr int kM6ToolChange = 60;
inline constexpr int kM7MistCoolant = 70;
inline constexpr int kM8FloodCoolant = 80;
inline constexpr int kM9CoolantOff = 90;
inline constexpr int kM48OverridesOn = 480;
inline constexpr int kM49OverridesOff = 490;
inline constexpr int kM50FeedOverride = 500;
inline constexpr int kM51SpindleOverride = 510;
inline constexpr int kM52AdaptiveFeed = 520;
inline constexpr int kM53FeedStop = 530;
/// M61 .. M68 (tool number, digital and analog I/O) and M70 .. M73 (modal
/// state save and restore): LinuxCNC's, passed through.
inline constexpr int kM61SetToolNumber = 610;
inline constexpr int kM62FirstMotionOutput = 620;  ///< M62-M65 digital outputs
inline constexpr int kM68AnalogOutput = 680;
inline constexpr int kM70SaveModalState = 700;
inline constexpr int kM73SaveAutorestore = 730;
inline constexpr int kM98SubprogramCall = 980;
inline constexpr int kM99SubprogramReturn = 990;
/// M100 .. M199: user-defined M codes (LinuxCNC runs a program of that name).
inline constexpr int kM100FirstUserCode = 1000;
inline constexpr int kM199LastUserCode = 1990;
/// LinuxCNC's kinematics switches (its switchable-kinematics demos).
inline constexpr int kM428KinematicsSwitch = 4280;
inline constexpr int kM429KinematicsSwitch = 4290;
inline constexpr int kM430KinematicsSwitch = 4300;

}  // namespace volmap::nc
