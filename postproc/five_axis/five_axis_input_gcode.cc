// The G-code forms of the five-axis input (kTcp, kToolVector, kMachineAxes):
// one line into a nominal move (five_axis_input.h).
#include <fmt/format.h>

#include <algorithm>
#include <array>
#include <cctype>
#include <cmath>
#include <cstring>
#include <regex>

#include "core/common/units.h"
#include "gcode/dialect.h"
#include "gcode/g_codes.h"
#include "gcode/nc_writer.h"
#include "postproc/five_axis/apt_reader.h"
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

// TCP codes of other controllers (x10, as nc::Word::code10).
constexpr int kG43_4Tcp = 434, kG43_5Tcp = 435, kG234Tcp = 2340;
constexpr int kM128Tcp = 1280, kM129TcpOff = 1290;

}  // namespace

std::string gcode_code_of(const std::string& line) {
  std::string out;
  int depth = 0;
  for (char c : line) {
    if (c == ';' && depth == 0) break;
    if (c == '(')
      ++depth;
    else if (c == ')')
      depth = std::max(0, depth - 1);
    else if (depth == 0 && c != '\r' && c != '\n')
      out += static_cast<char>(std::toupper(static_cast<unsigned char>(c)));
  }
  const size_t b = out.find_first_not_of(" \t"), e = out.find_last_not_of(" \t");
  return b == std::string::npos ? std::string() : out.substr(b, e - b + 1);
}

void FiveAxisReader::scan_tape() {
  // Tape leader: text before a first '%' that is not the first line.
  int n = 0;
  bool text_before = false;
  for (const std::string& raw : buffered_) {
    ++n;
    const std::string t = gcode_code_of(raw);
    if (!t.empty() && t[0] == '%') {
      if (text_before) leader_lines_ = n - 1;
      break;
    }
    if (raw.find_first_not_of(" \t\r\n") != std::string::npos) text_before = true;
  }
  std::string head;  // (after the leader)
  for (std::size_t k = static_cast<std::size_t>(leader_lines_); k < buffered_.size(); ++k)
    head += buffered_[k];
  fanuc_head_ = nc::detect_dialect(head, leader_lines_ + 1).dialect == nc::Dialect::kFanuc;
  static const std::regex kTcpOn(
      R"((^|[^A-Z0-9.])(M0*428|G0*43\.[45]|G0*234|M0*128|TRAORI)(?![0-9.]))");
  for (const std::string& raw : buffered_)
    if (std::regex_search(gcode_code_of(raw), kTcpOn)) {
      tcp_program_ = true;
      break;
    }
}

bool FiveAxisReader::frame_line(const std::string& text, FiveAxisLine& out) {
  const std::string t = gcode_code_of(text);
  auto verbatim = [&] {
    out.synthetic = true;
    out.text = text;
    return true;
  };
  if (line_ <= leader_lines_ || tape_closed_) return verbatim();
  if (!t.empty() && t[0] == '%') {
    tape_closed_ = tape_opened_;
    tape_opened_ = true;
    return verbatim();
  }
  static const std::regex kProgramNumber(R"(O\s*[0-9]+)");
  if (!moved_ && std::regex_match(t, kProgramNumber)) return verbatim();  // Fanuc, LinuxCNC
  if (!t.empty() && t[0] == ':')
    fail(1, "a ':' program number (Fanuc tape) is not read; write it as O<number>");
  if (t.size() > 1 && t[0] == 'O' && std::isalpha(static_cast<unsigned char>(t[1])))
    fail(1, "'" + apt_shown(t.substr(0, 40)) +
                "' is not a program number O<number> (nor a LinuxCNC O-word); correct it in the "
                "post-processor that wrote it");
  if (t.rfind("DEF ", 0) == 0 || t.find(" DEF ") != std::string::npos)
    fail(1,
         "Siemens variable definitions (DEF) are not read: the five-axis post needs literal "
         "numbers; output the program without variables");
  // Siemens: TRAORI / TRAFOOF switch the transformation (TCP) on and off.
  static const std::regex kSiemens(R"((N[0-9]+\s*)?(TRAORI\s*(\(\s*[0-9]*\s*\))?|TRAFOOF))");
  std::smatch m;
  if (std::regex_match(t, m, kSiemens)) {
    tcp_on_ = m[2].str().rfind("TRAORI", 0) == 0;
    out.synthetic = true;
    out.text = "(volmap post: " + m[2].str() + " removed: the output commands the machine axes)";
    return true;
  }
  if (t.find("CYCLE800") != std::string::npos)
    fail(1,
         "CYCLE800 (a swivelled work plane, 3+2) is not supported; output the tool path in "
         "the workpiece frame with TRAORI, or post each plane's part separately");
  return false;
}

/// The words of a G-code line (read_gcode_words).
struct FiveAxisReader::GcodeWords {
  int motion_word = -1;
  bool g93 = false, g94 = false, dwell = false;
  bool tcp_on = false, tcp_off = false;  ///< a TCP switch in the block
  bool tcp_on_g = false;                 ///< by a G code (G49 ends it)
  int h_word = -1;                       ///< index of an H word
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
  if (fanuc_head_)
    for (const nc::Word& w : b.words)
      if (std::strchr("XYZABCIJKR", w.letter) && w.value != 0.0 &&
          b.text.find('.', w.begin) >= w.end)
        fail(static_cast<int>(w.begin) + 1,
             std::string(1, w.letter) +
                 " has no decimal point, in a program that opens with a Fanuc program number: "
                 "the control reads it in least input increments unless parameter 3401#0 is "
                 "set; write the number with its point");
  GcodeWords words;
  read_gcode_words(b, out, words);
  if (words.g93 && words.g94) fail(1, "G93 and G94 in one block");
  if (const nc::Word* f = words['F']; f && f->value <= 0)
    fail(static_cast<int>(f->begin) + 1, "the feed rate must be positive; correct F");
  check_gcode_motion(b, words);
  // H belongs to the TCP code it came with (G43.4 H1, G234 H1): the tool is
  // the machine file's (or the tool table's T).
  if (words.h_word >= 0) {
    if (!words.tcp_on)
      fail(static_cast<int>(b.words[static_cast<size_t>(words.h_word)].begin) + 1,
           "word H is not supported by the five-axis post");
    out.strip.push_back(words.h_word);
    std::sort(out.strip.begin(), out.strip.end());
  }
  if (words.tcp_on) tcp_on_ = true, tcp_by_g_code_ = words.tcp_on_g;
  if (words.tcp_off) tcp_on_ = false;
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
  if (out.has_move && tcp_program_ && !tcp_on_ && form_ != InputForm::kMachineAxes)
    fail(1,
         "a move outside the program's TCP part (before its TCP code, M428 G43.4 G234 M128 "
         "TRAORI, or after it is switched off): its axis words are not the tool tip; move it "
         "into the TCP part or remove it");
  moved_ = moved_ || out.has_move;
}

void FiveAxisReader::read_gcode_words(const nc::Block& b, FiveAxisLine& out,
                                      GcodeWords& words) const {
  const bool vector = form_ == InputForm::kToolVector;
  for (size_t k = 0; k < b.words.size(); ++k) {
    const nc::Word& w = b.words[k];
    const int col = static_cast<int>(w.begin) + 1;
    if (w.letter == 'G') {
      // TCP on (Fanuc G43.4, G43.5; Haas G234): read like LinuxCNC's M428.
      if (w.code10 == kG43_4Tcp || w.code10 == kG43_5Tcp || w.code10 == kG234Tcp) {
        out.strip.push_back(static_cast<int>(k));
        words.tcp_on = words.tcp_on_g = true;
        continue;
      }
      if (w.code10 == nc::kG49ToolLengthCancel && tcp_on_ && tcp_by_g_code_) words.tcp_off = true;
      gcode_g_word(w, col, words);
      continue;
    }
    if (w.letter == 'H') {
      words.h_word = static_cast<int>(k);
      continue;
    }
    if (w.letter == 'M') {
      if (w.code10 == nc::kM428KinematicsSwitch || w.code10 == nc::kM429KinematicsSwitch ||
          w.code10 == nc::kM430KinematicsSwitch || w.code10 == kM128Tcp || w.code10 == kM129TcpOff)
        out.strip.push_back(static_cast<int>(k));
      if (w.code10 == nc::kM428KinematicsSwitch || w.code10 == kM128Tcp) words.tcp_on = true;
      if (w.code10 == nc::kM429KinematicsSwitch || w.code10 == kM129TcpOff) words.tcp_off = true;
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
      if (w.code10 == 682 || w.code10 == 683 || w.code10 == 684 || w.code10 == 690)
        fail(col,
             "tilted work planes (3+2: G68.2, G68.3, G68.4, G69) are not supported; output the "
             "tool path in the workpiece frame with TCP (G43.4) or post each plane's part "
             "separately");
      if (w.code10 == 2540 || w.code10 == 2550)
        fail(col,
             "Haas's dynamic work offset (G254, G255) is not supported: the program origin is "
             "one point on the table (`part_origin`)");
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
