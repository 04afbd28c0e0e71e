#include "postproc/five_axis/five_axis_input.h"

#include <fmt/format.h>

#include <algorithm>
#include <cctype>
#include <charconv>
#include <cmath>
#include <regex>

#include "core/common/input_error.h"
#include "gcode/nc_writer.h"

namespace volmap::post {
namespace {

constexpr double kDegToRad = M_PI / 180.0;

std::string upper(std::string s) {
  for (char& c : s) c = static_cast<char>(std::toupper(static_cast<unsigned char>(c)));
  return s;
}

std::string trim(const std::string& s) {
  size_t b = 0, e = s.size();
  while (b < e && std::isspace(static_cast<unsigned char>(s[b]))) ++b;
  while (e > b && std::isspace(static_cast<unsigned char>(s[e - 1]))) --e;
  return s.substr(b, e - b);
}

bool is_apt_statement(const std::string& line) {
  static const std::regex kApt(
      R"(^\s*(GOTO|FEDRAT|PARTNO|MULTAX|UNITS|LOADTL|SPINDL|COOLNT|CUTTER|RAPID|FINI|TLAXIS|MACHIN|FROM|INTOL|OUTTOL|PPRINT|CLDATA|TOOLNO)\s*(/|$))",
      std::regex::icase);
  return std::regex_search(line, kApt);
}

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

// Comment text that a G-code comment can hold.
std::string comment_text(const std::string& s) {
  std::string out;
  for (char c : s) out += (c == '(' ? '[' : (c == ')' ? ']' : c));
  return out;
}

}  // namespace

std::optional<InputForm> parse_input_form(const std::string& name) {
  if (name == "auto") return InputForm::kAuto;
  if (name == "tcp") return InputForm::kTcp;
  if (name == "vector") return InputForm::kToolVector;
  if (name == "apt") return InputForm::kApt;
  if (name == "axes") return InputForm::kMachineAxes;
  return std::nullopt;
}

const char* input_form_name(InputForm form) {
  switch (form) {
    case InputForm::kAuto:
      return "auto";
    case InputForm::kTcp:
      return "tcp";
    case InputForm::kToolVector:
      return "vector";
    case InputForm::kApt:
      return "apt";
    case InputForm::kMachineAxes:
      return "axes";
  }
  return "?";
}

InputForm detect_input_form(const std::vector<std::string>& lines) {
  static const std::regex kSiemens(R"([ABC]3\s*=)", std::regex::icase);
  static const std::regex kArc(R"(G0*[23](?![0-9.]))", std::regex::icase);
  static const std::regex kVector(R"([IJK]\s*[-+.0-9])", std::regex::icase);
  bool arc_modal = false;
  for (const std::string& raw : lines) {
    if (is_apt_statement(raw)) return InputForm::kApt;
    // Comments out.
    std::string l;
    int depth = 0;
    for (char c : raw) {
      if (c == ';' && depth == 0) break;
      if (c == '(')
        ++depth;
      else if (c == ')')
        depth = std::max(0, depth - 1);
      else if (depth == 0)
        l += c;
    }
    if (std::regex_search(l, kSiemens)) return InputForm::kToolVector;
    static const std::regex kLinear(R"(G0*[01](?![0-9.]))", std::regex::icase);
    if (std::regex_search(l, kArc))
      arc_modal = true;
    else if (std::regex_search(l, kLinear))
      arc_modal = false;
    if (!arc_modal && std::regex_search(l, kVector)) return InputForm::kToolVector;
  }
  return InputForm::kTcp;
}

FiveAxisReader::FiveAxisReader(std::istream& in, std::string file, const Machine& machine,
                               InputForm form, const InitialPose& initial)
    : in_(in), file_(std::move(file)), machine_(machine), form_(form) {
  q_ =
      initial.q.size() == machine.axis_count() ? initial.q : AxisVector::Zero(machine.axis_count());
  for (int k = 0; k < machine.axis_count(); ++k)
    if (!is_rotary(machine.axis_order[static_cast<size_t>(k)])) q_[k] = 0.0;
  tip_mm_ = initial.tip_mm;
  axis_ = initial.axis.normalized();
  if (form_ == InputForm::kAuto) {
    std::vector<std::string> first;
    std::string l;
    while (first.size() < 2000 && std::getline(in_, l)) {
      first.push_back(l);
      buffered_.push_back(l + (in_.eof() ? "" : "\n"));
    }
    form_ = detect_input_form(first);
  }
}

bool FiveAxisReader::read_raw(std::string& text) {
  if (!buffered_.empty()) {
    text = std::move(buffered_.front());
    buffered_.pop_front();
    newline_ = !text.empty() && text.back() == '\n';
    if (newline_) text.pop_back();
  } else {
    if (!std::getline(in_, text)) return false;
    newline_ = !in_.eof();
  }
  if (!text.empty() && text.back() == '\r') {
    text.pop_back();
    line_ending_ = "\r\n";
  }
  ++line_;
  return true;
}

void FiveAxisReader::fail(int column, const std::string& msg) const {
  throw InputError(file_, line_, column, msg);
}

bool FiveAxisReader::next(FiveAxisLine& out) {
  std::string text;
  if (!read_raw(text)) return false;
  out = FiveAxisLine{};
  out.line = line_;
  if (form_ == InputForm::kApt) {
    // `$` at the end continues the statement on the next line.
    std::string stmt = trim(text);
    while (!stmt.empty() && stmt.back() == '$') {
      stmt.pop_back();
      std::string more;
      if (!read_raw(more)) fail(0, "APT statement continued with '$' at the end of the file");
      stmt += trim(more);
    }
    apt_line(stmt, out);
  } else {
    gcode_line(text, out);
  }
  out.unit_mm = unit_mm_;
  return true;
}

void FiveAxisReader::apt_line(std::string stmt, FiveAxisLine& out) {
  out.synthetic = true;
  const std::string up = upper(stmt);
  const size_t slash = up.find('/');
  const std::string key = trim(slash == std::string::npos ? up : up.substr(0, slash));
  std::vector<std::string> args;
  if (slash != std::string::npos) {
    std::string rest = up.substr(slash + 1);
    size_t start = 0;
    for (;;) {
      const size_t comma = rest.find(',', start);
      args.push_back(
          trim(rest.substr(start, comma == std::string::npos ? std::string::npos : comma - start)));
      if (comma == std::string::npos) break;
      start = comma + 1;
    }
  }
  auto number = [&](const std::string& s, double& v) {
    const char* b = s.data() + (!s.empty() && s[0] == '+' ? 1 : 0);
    const auto r = std::from_chars(b, s.data() + s.size(), v);
    return r.ec == std::errc() && r.ptr == s.data() + s.size() && std::isfinite(v);
  };
  if (key.empty()) {
    out.text = "";
    return;
  }
  if (key == "GOTO") {
    if (args.size() != 3 && args.size() != 6)
      fail(1, "GOTO needs x,y,z or x,y,z,i,j,k; check the CLDATA export");
    std::array<double, 6> v{};
    for (size_t k = 0; k < args.size(); ++k)
      if (!number(args[k], v[k])) fail(1, fmt::format("GOTO: '{}' is not a number", args[k]));
    FiveAxisMove& m = out.move;
    m.rapid = apt_rapid_;
    apt_rapid_ = false;
    m.by_angles = false;
    m.tip.kind = nc::MotionKind::kLinear;
    m.tip.start_mm = tip_mm_;
    m.tip.end_mm = Eigen::Vector3d(v[0], v[1], v[2]) * unit_mm_;
    m.a0 = axis_;
    if (args.size() == 6) {
      const Eigen::Vector3d a(v[3], v[4], v[5]);
      if (a.norm() < 1e-9) fail(1, "GOTO: the tool axis i,j,k is zero");
      axis_ = a.normalized();
    }
    m.a1 = axis_;
    m.q0 = m.q1 = q_;
    m.feed_mode = 940;
    m.feed = feed_;
    if (!m.rapid && feed_ <= 0) fail(1, "GOTO feed move before any FEDRAT; add FEDRAT/");
    tip_mm_ = m.tip.end_mm;
    out.has_move = true;
    return;
  }
  if (key == "RAPID") {
    apt_rapid_ = true;
    out.text = "(APT: RAPID)";
    return;
  }
  if (key == "FEDRAT") {
    double f = 0;
    bool got = false;
    for (const std::string& a : args) {
      if (a == "MMPM" || a == "IPM") continue;
      if (a == "MMPR" || a == "IPR")
        fail(1, "FEDRAT per revolution is not supported; use MMPM or IPM");
      if (number(a, f))
        got = true;
      else
        fail(1, fmt::format("FEDRAT: '{}' is not understood", a));
    }
    if (!got || f <= 0) fail(1, "FEDRAT needs a positive feed");
    feed_ = f * unit_mm_;
    out.text = "(APT: " + comment_text(stmt) + ")";
    return;
  }
  if (key == "UNITS") {
    if (!args.empty() && (args[0] == "INCHES" || args[0] == "INCH"))
      unit_mm_ = 25.4;
    else if (!args.empty() && args[0] == "MM")
      unit_mm_ = 1.0;
    else
      fail(1, "UNITS/ takes MM or INCHES");
    out.text = "(APT: " + comment_text(stmt) + ")";
    return;
  }
  if (key == "SPINDL" && !args.empty()) {
    double s = 0;
    if (args[0] == "OFF")
      out.text = "M5";
    else if (number(args[0], s)) {
      const bool ccw = std::find(args.begin(), args.end(), "CCLW") != args.end();
      out.text = fmt::format("S{} {}", s, ccw ? "M4" : "M3");
    } else {
      out.text = "(APT: " + comment_text(stmt) + ")";
    }
    return;
  }
  if (key == "COOLNT" && !args.empty()) {
    out.text = args[0] == "OFF" ? "M9" : (args[0] == "MIST" ? "M7" : "M8");
    return;
  }
  if (key == "FINI") {
    out.text = "M2";
    out.ends_program = true;
    return;
  }
  out.text = "(APT: " + comment_text(stmt) + ")";
}

void FiveAxisReader::gcode_line(const std::string& raw, FiveAxisLine& out) {
  std::string text = raw;
  if (form_ == InputForm::kToolVector) replace_siemens_vector(text);
  out.block = nc::lex_block(text, line_, file_);
  const nc::Block& b = out.block;
  if (b.block_delete)
    fail(1, "block delete '/' is not supported by the five-axis post; remove the '/' or the block");
  const bool vector = form_ == InputForm::kToolVector;
  // Step 1: every word known; modal words first.
  int motion_word = -1;
  bool g93 = false, g94 = false, dwell = false;
  std::array<const nc::Word*, 26> word{};
  for (size_t k = 0; k < b.words.size(); ++k) {
    const nc::Word& w = b.words[k];
    const int col = static_cast<int>(w.begin) + 1;
    if (w.letter == 'G') {
      switch (w.code10) {
        case 0:
        case 10:
        case 20:
        case 30:
          if (motion_word >= 0) fail(col, "two motion G codes in one block");
          motion_word = w.code10;
          break;
        case 40:
          dwell = true;
          break;
        case 170:
          plane_ = 0;
          break;
        case 180:
          plane_ = 1;
          break;
        case 190:
          plane_ = 2;
          break;
        case 200:
          unit_mm_ = 25.4;
          break;
        case 210:
          unit_mm_ = 1.0;
          break;
        case 900:
          absolute_ = true;
          break;
        case 910:
          absolute_ = false;
          break;
        case 901:
          arc_absolute_ = true;
          break;
        case 911:
          arc_absolute_ = false;
          break;
        case 930:
          g93 = true;
          break;
        case 940:
          g94 = true;
          break;
        case 400:
        case 490:
        case 800:
        case 540:
        case 610:
        case 611:
        case 640:
          break;
        case 430:
        case 431:
          fail(col,
               "tool length compensation (G43) is not supported by the five-axis post: the machine "
               "file's tool is the tool; give its length there");
        default:
          if (w.code10 >= 550 && w.code10 <= 593)
            fail(col,
                 "only G54 is accepted: the program origin is one point on the table "
                 "(--part-origin); post each work offset's part separately");
          fail(col,
               fmt::format("G{} is not supported by the five-axis post; output it without from CAM",
                           nc::format_number(w.value, 4)));
      }
      continue;
    }
    if (w.letter == 'M') {
      if (w.code10 == 4280 || w.code10 == 4290 || w.code10 == 4300)
        out.strip.push_back(static_cast<int>(k));
      if (w.code10 == 20 || w.code10 == 300) out.ends_program = true;
      continue;
    }
    const char L = w.letter;
    if (L == 'N' || L == 'S' || L == 'T') continue;
    if (L == 'F' || L == 'P' || L == 'X' || L == 'Y' || L == 'Z' || L == 'I' || L == 'J' ||
        L == 'K') {
      if (word[static_cast<size_t>(L - 'A')])
        fail(col, fmt::format("word {} twice in one block", L));
      word[static_cast<size_t>(L - 'A')] = &w;
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
      if (word[static_cast<size_t>(L - 'A')])
        fail(col, fmt::format("word {} twice in one block", L));
      word[static_cast<size_t>(L - 'A')] = &w;
      continue;
    }
    if (L == 'R')
      fail(col, "R-form arcs are not supported by the five-axis post; output I J K centres");
    if (L == '@' || L == '^')
      fail(col, "polar coordinates (@ ^) are not supported by the five-axis post; output X and Y");
    fail(col, fmt::format("word {} is not supported by the five-axis post", L));
  }
  if (g93 && g94) fail(1, "G93 and G94 in one block");
  if (g93) feed_mode_ = 930;
  if (g94) feed_mode_ = 940;
  if (word['F' - 'A']) {
    const double f = word['F' - 'A']->value;
    feed_ = feed_mode_ == 930 ? f : f * unit_mm_;
  } else if (g93 || g94) {
    feed_ = 0.0;  // a new feed mode needs a new F (RS274NGC)
  }
  if (motion_word >= 0) motion_ = motion_word;
  out.motion_code = motion_word;
  // Axis words of the block.
  bool tip_word = word['X' - 'A'] || word['Y' - 'A'] || word['Z' - 'A'];
  bool rot_word = word['A' - 'A'] || word['B' - 'A'] || word['C' - 'A'];
  bool ijk = word['I' - 'A'] || word['J' - 'A'] || word['K' - 'A'];
  if (dwell) {
    if (tip_word || rot_word) fail(1, "axis words with G4");
    return;
  }
  const bool arc = motion_ == 20 || motion_ == 30;
  if (ijk && !arc && !vector)
    fail(static_cast<int>(b.find(word['I' - 'A'] ? 'I' : (word['J' - 'A'] ? 'J' : 'K'))->begin) + 1,
         "I J K in a straight move: a tool-vector program? use --input-form vector");
  if (arc && vector)
    fail(1, "arcs in a tool-vector program are not supported; linearise them in CAM");
  if (word['P' - 'A'] && !dwell)
    fail(static_cast<int>(word['P' - 'A']->begin) + 1, "P words are supported with G4 only");
  if (!tip_word && !rot_word && !(vector && ijk)) return;
  // A move.
  FiveAxisMove& m = out.move;
  m.rapid = motion_ == 0;
  m.tip.kind = nc::MotionKind::kLinear;
  m.tip.start_mm = tip_mm_;
  Eigen::Vector3d end = tip_mm_;
  for (int a = 0; a < 3; ++a) {
    if (const nc::Word* w = word[static_cast<size_t>("XYZ"[a] - 'A')])
      end[a] = absolute_ ? w->value * unit_mm_ : end[a] + w->value * unit_mm_;
  }
  m.tip.end_mm = end;
  m.q0 = q_;
  for (int k = 0; k < machine_.axis_count(); ++k) {
    const AxisName n = machine_.axis_order[static_cast<size_t>(k)];
    if (!is_rotary(n)) continue;
    if (const nc::Word* w = word[static_cast<size_t>(axis_char(n) - 'A')])
      q_[k] = absolute_ ? w->value * kDegToRad : q_[k] + w->value * kDegToRad;
  }
  m.q1 = q_;
  m.by_angles = !vector;
  m.a0 = axis_;
  if (vector && ijk) {
    Eigen::Vector3d a = Eigen::Vector3d::Zero();
    for (int c = 0; c < 3; ++c)
      if (const nc::Word* w = word[static_cast<size_t>("IJK"[c] - 'A')]) a[c] = w->value;
    if (a.norm() < 1e-9) fail(1, "the tool axis I J K is zero");
    axis_ = a.normalized();
  }
  m.a1 = axis_;
  if (arc) {
    if (!tip_word) fail(1, "an arc without end point words");
    m.tip.kind = nc::MotionKind::kArc;
    m.tip.plane = plane_;
    m.tip.clockwise = motion_ == 20;
    static constexpr int kIn[3][2] = {{0, 1}, {2, 0}, {1, 2}};
    Eigen::Vector3d c = tip_mm_;
    for (int j = 0; j < 2; ++j) {
      const int a = kIn[plane_][j];
      const nc::Word* w = word[static_cast<size_t>("IJK"[a] - 'A')];
      const double off = w ? w->value * unit_mm_ : 0.0;
      c[a] = arc_absolute_ ? off : tip_mm_[a] + off;
    }
    m.tip.center_mm = c;
    const int a0 = kIn[plane_][0], a1 = kIn[plane_][1];
    const double r0 = std::hypot(tip_mm_[a0] - c[a0], tip_mm_[a1] - c[a1]);
    const double r1 = std::hypot(end[a0] - c[a0], end[a1] - c[a1]);
    if (r0 < 1e-9) fail(1, "arc centre at its start point");
    if (std::abs(r0 - r1) > std::max(0.0127, 1e-3 * r0))
      fail(1, fmt::format("arc radius to the end ({:.4f} mm) differs from the radius to the start "
                          "({:.4f} mm)",
                          r1, r0));
  }
  m.feed_mode = feed_mode_;
  m.feed = feed_;
  if (!m.rapid) {
    if (feed_mode_ == 930 && !word['F' - 'A'])
      fail(1, "a feed move under G93 (inverse time) needs F in its block");
    if (feed_ < 0 || (feed_ == 0 && word['F' - 'A']))
      fail(1, "the feed rate must be positive; correct F");
    if (feed_ == 0) fail(1, "a feed move with no feed rate; add F");
  }
  tip_mm_ = end;
  out.has_move = true;
}

}  // namespace volmap::post
