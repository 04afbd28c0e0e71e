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

namespace {

// kAuto: the form of the first 2000 lines, which stay in `buffered`.
InputForm resolve_form(std::istream& in, InputForm form, std::deque<std::string>& buffered) {
  if (form != InputForm::kAuto) return form;
  std::vector<std::string> first;
  std::string l;
  while (first.size() < 2000 && std::getline(in, l)) {
    first.push_back(l);
    buffered.push_back(l + (in.eof() ? "" : "\n"));
  }
  return detect_input_form(first);
}

// The rotary angles of `initial` (rad, AxisVector order), zero where the
// pose gives none and for the linear axes.
AxisVector initial_angles(const Machine& machine, const InitialPose& initial) {
  AxisVector q =
      initial.q.size() == machine.axis_count() ? initial.q : AxisVector::Zero(machine.axis_count());
  for (int k = 0; k < machine.axis_count(); ++k)
    if (!is_rotary(machine.axis_order[static_cast<size_t>(k)])) q[k] = 0.0;
  return q;
}

// The interpreter's setup for the G-code forms: program coordinates (no
// work offsets), the machine's rotary axis words, I J K as the tool axis in
// tool-vector programs, the tool where `initial` puts it.
nc::ProgramSetup gcode_setup(const Machine& machine, InputForm form, const InitialPose& initial) {
  nc::ProgramSetup setup;
  setup.initial_position_mm = initial.tip_mm;
  const AxisVector q = initial_angles(machine, initial);
  for (int k = 0; k < machine.axis_count(); ++k) {
    const AxisName n = machine.axis_order[static_cast<size_t>(k)];
    if (!is_rotary(n)) continue;
    const char letter = axis_char(n);
    setup.rotary_axes += letter;
    setup.initial_rotary_rad[static_cast<size_t>(letter - 'A')] = q[k];
  }
  setup.tool_axis_words = form == InputForm::kToolVector;
  setup.initial_tool_axis = initial.axis.normalized();
  return setup;
}

}  // namespace

FiveAxisReader::FiveAxisReader(std::istream& in, std::string file, const Machine& machine,
                               InputForm form, const InitialPose& initial)
    : in_(in),
      file_(std::move(file)),
      machine_(machine),
      form_(resolve_form(in, form, buffered_)),
      interp_(gcode_setup(machine, form_, initial), file_) {
  apt_.q = initial_angles(machine, initial);
  apt_.tip_mm = initial.tip_mm;
  apt_.axis = initial.axis.normalized();
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
  out.unit_mm = form_ == InputForm::kApt ? apt_.unit_mm : interp_.state().unit_mm;
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
    m.rapid = apt_.rapid;
    apt_.rapid = false;
    m.by_angles = false;
    m.tip.kind = nc::MotionKind::kLinear;
    m.tip.start_mm = apt_.tip_mm;
    m.tip.end_mm = Eigen::Vector3d(v[0], v[1], v[2]) * apt_.unit_mm;
    m.a0 = apt_.axis;
    if (args.size() == 6) {
      const Eigen::Vector3d a(v[3], v[4], v[5]);
      if (a.norm() < 1e-9) fail(1, "GOTO: the tool axis i,j,k is zero");
      apt_.axis = a.normalized();
    }
    m.a1 = apt_.axis;
    m.q0 = m.q1 = apt_.q;
    m.feed_mode = nc::kG94UnitsPerMinute;
    m.feed = apt_.feed;
    if (!m.rapid && apt_.feed <= 0) fail(1, "GOTO feed move before any FEDRAT; add FEDRAT/");
    apt_.tip_mm = m.tip.end_mm;
    out.has_move = true;
    return;
  }
  if (key == "RAPID") {
    apt_.rapid = true;
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
    apt_.feed = f * apt_.unit_mm;
    out.text = "(APT: " + comment_text(stmt) + ")";
    return;
  }
  if (key == "UNITS") {
    if (!args.empty() && (args[0] == "INCHES" || args[0] == "INCH"))
      apt_.unit_mm = 25.4;
    else if (!args.empty() && args[0] == "MM")
      apt_.unit_mm = 1.0;
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

}  // namespace volmap::post
