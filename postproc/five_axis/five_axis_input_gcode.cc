// The G-code forms of the five-axis input (kTcp, kToolVector, kMachineAxes):
// one line into a nominal move (five_axis_input.h).
#include <fmt/format.h>

#include <algorithm>
#include <array>
#include <cctype>
#include <cmath>

#include "core/common/units.h"
#include "gcode/g_codes.h"
#include "gcode/nc_writer.h"
#include "postproc/five_axis/five_axis_input.h"

namespace volmap::post {
namespace {

// Replaces Siemens A3= B3= C3= by I, J, K padded to the same length, so that
// byte spans stay those of the original line.
bool replace_siemens_vector(std::string& text) {
  bool any = false;
  for (size_t i = 0; i + 2 < text.size(); ++i) {
    const char c = static_cast<char>(std::toupper(static_cast<unsigned char>(text[i])));
    if ((c == 'A' || c == 'B' || c == 'C') && text[i + 1] == '3' && text[i + 2] == '=') {
      text[i] = c == 'A' ? 'I' : (c == 'B' ? 'J' : 'K');
      text[i + 1] = ' ';
      text[i + 2] = ' ';
      any = true;
    }
  }
  return any;
}

}  // namespace

/// The words of a G-code line (step 1 of gcode_line).
struct FiveAxisReader::GcodeWords {
  int motion_word = -1;
  bool g93 = false, g94 = false, dwell = false;
  std::array<const nc::Word*, 26> word{};
  const nc::Word* operator[](char L) const { return word[static_cast<size_t>(L - 'A')]; }
};

void FiveAxisReader::gcode_line(const std::string& raw, FiveAxisLine& out) {
  std::string text = raw;
  if (form_ == InputForm::kToolVector) replace_siemens_vector(text);
  out.block = nc::lex_block(text, line_, file_);
  const nc::Block& b = out.block;
  if (b.block_delete)
    fail(1, "block delete '/' is not supported by the five-axis post; remove the '/' or the block");
  GcodeWords words;
  read_gcode_words(b, out, words);
  if (words.g93 && words.g94) fail(1, "G93 and G94 in one block");
  if (words.g93) feed_mode_ = nc::kG93InverseTime;
  if (words.g94) feed_mode_ = nc::kG94UnitsPerMinute;
  if (words['F']) {
    const double f = words['F']->value;
    feed_ = feed_mode_ == nc::kG93InverseTime ? f : f * unit_mm_;
  } else if (words.g93 || words.g94) {
    feed_ = 0.0;  // a new feed mode needs a new F (RS274NGC)
  }
  if (words.motion_word >= 0) motion_ = words.motion_word;
  out.motion_code = words.motion_word;
  gcode_move(b, words, out);
}

void FiveAxisReader::read_gcode_words(const nc::Block& b, FiveAxisLine& out, GcodeWords& words) {
  // Step 1: every word known; modal words first.
  const bool vector = form_ == InputForm::kToolVector;
  for (size_t k = 0; k < b.words.size(); ++k) {
    const nc::Word& w = b.words[k];
    const int col = static_cast<int>(w.begin) + 1;
    if (w.letter == 'G') {
      gcode_g_word(w, col, words);
      continue;
    }
    if (w.letter == 'M') {
      if (w.code10 == nc::kM428KinematicsSwitch || w.code10 == nc::kM429KinematicsSwitch ||
          w.code10 == nc::kM430KinematicsSwitch)
        out.strip.push_back(static_cast<int>(k));
      if (w.code10 == nc::kM2ProgramEnd || w.code10 == nc::kM30ProgramEndRewind)
        out.ends_program = true;
      continue;
    }
    const char L = w.letter;
    if (L == 'N' || L == 'S' || L == 'T') continue;
    if (L == 'F' || L == 'P' || L == 'X' || L == 'Y' || L == 'Z' || L == 'I' || L == 'J' ||
        L == 'K') {
      if (words[L]) fail(col, fmt::format("word {} twice in one block", L));
      words.word[static_cast<size_t>(L - 'A')] = &w;
      continue;
    }
    if (L == 'A' || L == 'B' || L == 'C') {
      const auto axis = axis_from_char(L);
      if (vector)
        fail(col,
             fmt::format("rotary word {} in a tool-vector program; give the tool axis as I J K "
                         "(or use --input-form tcp)",
                         L));
      if (!axis || !machine_.index_of(*axis))
        fail(col, fmt::format("the machine has no axis {}", L));
      if (words[L]) fail(col, fmt::format("word {} twice in one block", L));
      words.word[static_cast<size_t>(L - 'A')] = &w;
      continue;
    }
    if (L == 'R')
      fail(col, "R-form arcs are not supported by the five-axis post; output I J K centres");
    if (L == '@' || L == '^')
      fail(col, "polar coordinates (@ ^) are not supported by the five-axis post; output X and Y");
    fail(col, fmt::format("word {} is not supported by the five-axis post", L));
  }
}

void FiveAxisReader::gcode_g_word(const nc::Word& w, int col, GcodeWords& words) {
  switch (w.code10) {
    case nc::kG0Rapid:
    case nc::kG1Linear:
    case nc::kG2ArcClockwise:
    case nc::kG3ArcCounterClockwise:
      if (words.motion_word >= 0) fail(col, "two motion G codes in one block");
      words.motion_word = w.code10;
      return;
    case nc::kG4Dwell:
      words.dwell = true;
      return;
    case nc::kG17PlaneXY:
      plane_ = 0;
      return;
    case nc::kG18PlaneZX:
      plane_ = 1;
      return;
    case nc::kG19PlaneYZ:
      plane_ = 2;
      return;
    case nc::kG20Inch:
      unit_mm_ = 25.4;
      return;
    case nc::kG21Millimetre:
      unit_mm_ = 1.0;
      return;
    case nc::kG90Absolute:
      absolute_ = true;
      return;
    case nc::kG91Incremental:
      absolute_ = false;
      return;
    case nc::kG90_1ArcCentreAbsolute:
      arc_absolute_ = true;
      return;
    case nc::kG91_1ArcCentreIncremental:
      arc_absolute_ = false;
      return;
    case nc::kG93InverseTime:
      words.g93 = true;
      return;
    case nc::kG94UnitsPerMinute:
      words.g94 = true;
      return;
    case nc::kG40CutterCompOff:
    case nc::kG49ToolLengthCancel:
    case nc::kG80CycleCancel:
    case nc::kG54WorkOffset1:
    case nc::kG61ExactPath:
    case nc::kG61_1ExactStop:
    case nc::kG64Blending:
      return;
    case nc::kG43ToolLength:
    case nc::kG43_1DynamicToolLength:
      fail(col,
           "tool length compensation (G43) is not supported by the five-axis post: the machine "
           "file's tool is the tool; give its length there");
    default:
      if (w.code10 >= nc::kG55WorkOffset2 && w.code10 <= nc::kG59_3WorkOffset9)
        fail(col,
             "only G54 is accepted: the program origin is one point on the table "
             "(--part-origin); post each work offset's part separately");
      fail(col,
           fmt::format("G{} is not supported by the five-axis post; output it without from CAM",
                       nc::format_number(w.value, 4)));
  }
}

void FiveAxisReader::gcode_move(const nc::Block& b, const GcodeWords& words, FiveAxisLine& out) {
  const bool vector = form_ == InputForm::kToolVector;
  // Axis words of the block.
  bool tip_word = words['X'] || words['Y'] || words['Z'];
  bool rot_word = words['A'] || words['B'] || words['C'];
  bool ijk = words['I'] || words['J'] || words['K'];
  if (words.dwell) {
    if (tip_word || rot_word) fail(1, "axis words with G4");
    return;
  }
  const bool arc = motion_ == nc::kG2ArcClockwise || motion_ == nc::kG3ArcCounterClockwise;
  if (ijk && !arc && !vector)
    fail(static_cast<int>(b.find(words['I'] ? 'I' : (words['J'] ? 'J' : 'K'))->begin) + 1,
         "I J K in a straight move: a tool-vector program? use --input-form vector");
  if (arc && vector)
    fail(1, "arcs in a tool-vector program are not supported; linearise them in CAM");
  if (words['P'] && !words.dwell)
    fail(static_cast<int>(words['P']->begin) + 1, "P words are supported with G4 only");
  if (!tip_word && !rot_word && !(vector && ijk)) return;
  // A move.
  FiveAxisMove& m = out.move;
  m.rapid = motion_ == nc::kG0Rapid;
  m.tip.kind = nc::MotionKind::kLinear;
  m.tip.start_mm = tip_mm_;
  Eigen::Vector3d end = tip_mm_;
  for (int a = 0; a < 3; ++a) {
    if (const nc::Word* w = words["XYZ"[a]])
      end[a] = absolute_ ? w->value * unit_mm_ : end[a] + w->value * unit_mm_;
  }
  m.tip.end_mm = end;
  m.q0 = q_;
  for (int k = 0; k < machine_.axis_count(); ++k) {
    const AxisName n = machine_.axis_order[static_cast<size_t>(k)];
    if (!is_rotary(n)) continue;
    if (const nc::Word* w = words[axis_char(n)])
      q_[k] = absolute_ ? w->value * units::kRadPerDeg : q_[k] + w->value * units::kRadPerDeg;
  }
  m.q1 = q_;
  m.by_angles = !vector;
  m.a0 = axis_;
  if (vector && ijk) {
    Eigen::Vector3d a = Eigen::Vector3d::Zero();
    for (int c = 0; c < 3; ++c)
      if (const nc::Word* w = words["IJK"[c]]) a[c] = w->value;
    if (a.norm() < 1e-9) fail(1, "the tool axis I J K is zero");
    axis_ = a.normalized();
  }
  m.a1 = axis_;
  if (arc) {
    if (!tip_word) fail(1, "an arc without end point words");
    arc_centre(words, end, m.tip);
  }
  m.feed_mode = feed_mode_;
  m.feed = feed_;
  if (!m.rapid) {
    if (feed_mode_ == nc::kG93InverseTime && !words['F'])
      fail(1, "a feed move under G93 (inverse time) needs F in its block");
    if (feed_ < 0 || (feed_ == 0 && words['F']))
      fail(1, "the feed rate must be positive; correct F");
    if (feed_ == 0) fail(1, "a feed move with no feed rate; add F");
  }
  tip_mm_ = end;
  out.has_move = true;
}

void FiveAxisReader::arc_centre(const GcodeWords& words, const Eigen::Vector3d& end,
                                nc::Motion& tip) const {
  tip.kind = nc::MotionKind::kArc;
  tip.plane = plane_;
  tip.clockwise = motion_ == nc::kG2ArcClockwise;
  static constexpr int kIn[3][2] = {{0, 1}, {2, 0}, {1, 2}};
  Eigen::Vector3d c = tip_mm_;
  for (int j = 0; j < 2; ++j) {
    const int a = kIn[plane_][j];
    const nc::Word* w = words["IJK"[a]];
    const double off = w ? w->value * unit_mm_ : 0.0;
    c[a] = arc_absolute_ ? off : tip_mm_[a] + off;
  }
  tip.center_mm = c;
  const int a0 = kIn[plane_][0], a1 = kIn[plane_][1];
  const double r0 = std::hypot(tip_mm_[a0] - c[a0], tip_mm_[a1] - c[a1]);
  const double r1 = std::hypot(end[a0] - c[a0], end[a1] - c[a1]);
  if (r0 < 1e-9) fail(1, "arc centre at its start point");
  if (std::abs(r0 - r1) > std::max(0.0127, 1e-3 * r0))
    fail(1, fmt::format("arc radius to the end ({:.4f} mm) differs from the radius to the start "
                        "({:.4f} mm)",
                        r1, r0));
}

}  // namespace volmap::post
