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

/// The words of a G-code line (read_gcode_words).
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
  if (const nc::Word* f = words['F']; f && f->value <= 0)
    fail(static_cast<int>(f->begin) + 1, "the feed rate must be positive; correct F");
  check_gcode_motion(b, words);
  // The interpreter runs the block without the kinematics switches.
  nc::Block stripped;
  if (!out.strip.empty()) {
    stripped = b;
    for (auto k = out.strip.rbegin(); k != out.strip.rend(); ++k)
      stripped.words.erase(stripped.words.begin() + *k);
  }
  const nc::State before = interp_.state();
  nc::BlockEffect effect;
  interp_.execute(out.strip.empty() ? b : stripped, effect);
  out.motion_code = words.motion_word;
  if (interp_.state().tool != before.tool) out.tool = interp_.state().tool;  // M6
  gcode_move(words, before, effect, out);
}

void FiveAxisReader::read_gcode_words(const nc::Block& b, FiveAxisLine& out,
                                      GcodeWords& words) const {
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
                         "(or use `input_form` tcp)",
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

void FiveAxisReader::gcode_g_word(const nc::Word& w, int col, GcodeWords& words) const {
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
    case nc::kG93InverseTime:
      words.g93 = true;
      return;
    case nc::kG94UnitsPerMinute:
      words.g94 = true;
      return;
    case nc::kG17PlaneXY:
    case nc::kG18PlaneZX:
    case nc::kG19PlaneYZ:
    case nc::kG20Inch:
    case nc::kG21Millimetre:
    case nc::kG90Absolute:
    case nc::kG91Incremental:
    case nc::kG90_1ArcCentreAbsolute:
    case nc::kG91_1ArcCentreIncremental:
    case nc::kG40CutterCompOff:
    case nc::kG49ToolLengthCancel:
    case nc::kG80CycleCancel:
    case nc::kG54WorkOffset1:
    case nc::kG61ExactPath:
    case nc::kG61_1ExactStop:
    case nc::kG64Blending:
      return;  // the interpreter's
    case nc::kG43ToolLength:
    case nc::kG43_1DynamicToolLength:
      fail(col,
           "tool length compensation (G43) is not supported by the five-axis post: the machine "
           "file's tool is the tool; give its length there");
    default:
      if (w.code10 >= nc::kG55WorkOffset2 && w.code10 <= nc::kG59_3WorkOffset9)
        fail(col,
             "only G54 is accepted: the program origin is one point on the table "
             "(`part_origin`); post each work offset's part separately");
      fail(col,
           fmt::format("G{} is not supported by the five-axis post; output it without from CAM",
                       nc::format_number(w.value, 4)));
  }
}

void FiveAxisReader::check_gcode_motion(const nc::Block& b, const GcodeWords& words) const {
  const bool vector = form_ == InputForm::kToolVector;
  const bool tip_word = words['X'] || words['Y'] || words['Z'];
  const bool rot_word = words['A'] || words['B'] || words['C'];
  const bool ijk = words['I'] || words['J'] || words['K'];
  if (words.dwell) {
    if (tip_word || rot_word) fail(1, "axis words with G4");
    return;
  }
  const int motion = words.motion_word >= 0 ? words.motion_word : interp_.state().motion;
  const bool arc = motion == nc::kG2ArcClockwise || motion == nc::kG3ArcCounterClockwise;
  if (ijk && !arc && !vector)
    fail(static_cast<int>(b.find(words['I'] ? 'I' : (words['J'] ? 'J' : 'K'))->begin) + 1,
         "I J K in a straight move: a tool-vector program? use `input_form` vector");
  if (arc && vector && (tip_word || ijk))
    fail(1, "arcs in a tool-vector program are not supported; linearise them in CAM");
  if (words['P'])
    fail(static_cast<int>(words['P']->begin) + 1, "P words are supported with G4 only");
  if (arc && !tip_word && (rot_word || ijk)) fail(1, "an arc without end point words");
}

void FiveAxisReader::gcode_move(const GcodeWords& words, const nc::State& before,
                                const nc::BlockEffect& effect, FiveAxisLine& out) const {
  if (!effect.has_motion) return;
  const nc::State& after = interp_.state();
  FiveAxisMove& m = out.move;
  m.rapid = effect.motion.kind == nc::MotionKind::kRapid;
  m.tip = effect.motion;
  if (m.tip.kind == nc::MotionKind::kRapid) m.tip.kind = nc::MotionKind::kLinear;
  m.tip.feed = 0.0;  // (the move's feed is m.feed, in mm/min)
  m.q0 = m.q1 = AxisVector::Zero(machine_.axis_count());
  for (int k = 0; k < machine_.axis_count(); ++k) {
    const AxisName n = machine_.axis_order[static_cast<size_t>(k)];
    if (!is_rotary(n)) continue;
    const size_t r = static_cast<size_t>(axis_char(n) - 'A');
    m.q0[k] = before.rotary_rad[r];
    m.q1[k] = after.rotary_rad[r];
  }
  m.by_angles = form_ != InputForm::kToolVector;
  m.a0 = before.tool_axis;
  m.a1 = after.tool_axis;
  m.feed_mode = after.feed_mode;
  m.feed = after.feed_mode == nc::kG93InverseTime ? after.feed : after.feed * after.unit_mm;
  if (!m.rapid && after.feed_mode == nc::kG93InverseTime && !words['F'])
    fail(1, "a feed move under G93 (inverse time) needs F in its block");
  out.has_move = true;
}

}  // namespace volmap::post
