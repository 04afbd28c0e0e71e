#include "postproc/five_axis/five_axis_input.h"

#include <fmt/format.h>

#include <algorithm>
#include <cctype>
#include <charconv>
#include <cmath>
#include <regex>

#include "core/common/input_error.h"
#include "gcode/nc_writer.h"
#include "postproc/five_axis/apt_reader.h"

namespace volmap::post {
namespace {

constexpr std::string_view kByteOrderMark = "\xEF\xBB\xBF";

std::string trim(const std::string& s) {
  size_t b = 0, e = s.size();
  while (b < e && std::isspace(static_cast<unsigned char>(s[b]))) ++b;
  while (e > b && std::isspace(static_cast<unsigned char>(s[e - 1]))) --e;
  return s.substr(b, e - b);
}

bool is_apt_statement(const std::string& line) {
  static const std::regex kApt(
      R"(^\s*((GOTO|FEDRAT|PARTNO|MULTAX|UNITS?|LOADTL|LOAD|SPINDL|COOLNT|CUTTER|RAPID|FINI|TLAXIS|MACHIN|FROM|INTOL|OUTTOL|PPRINT|CLDATA|TOOLNO|CIRCLE|CYCLE|CSYS|MSYS|TLDATA|TOOL\s+PATH|CUTCOM|SELECT)\s*(/|$)|PARTNO\s|REMARK\s|\$\$))",
      std::regex::icase);
  return std::regex_search(line, kApt);
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
    const std::string l = gcode_code_of(raw);
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
  std::vector<std::string> first;
  std::string l;
  while (first.size() < 2000 && std::getline(in, l)) {
    first.push_back(l);
    buffered.push_back(l + (in.eof() ? "" : "\n"));
  }
  // A UTF-8 byte-order mark is not part of the program (FiveAxisReader
  // takes it off the first line).
  if (!first.empty() && first.front().rfind(kByteOrderMark, 0) == 0)
    first.front().erase(0, kByteOrderMark.size());
  return form == InputForm::kAuto ? detect_input_form(first) : form;
}

// APT without UNITS/ before its first FEDRAT/ (NX CLSF): the units of that
// FEDRAT's unit word, and its line (0: none found, or UNITS/ comes first).
std::pair<double, int> apt_units_from_feed(const std::deque<std::string>& lines) {
  int n = 0;
  for (const std::string& raw : lines) {
    ++n;
    std::string t;
    for (char c : raw.substr(0, raw.find("$$")))
      if (!std::isspace(static_cast<unsigned char>(c)))
        t += static_cast<char>(std::toupper(static_cast<unsigned char>(c)));
    if (t.rfind("UNITS/", 0) == 0 || t.rfind("UNIT/", 0) == 0) return {1.0, 0};
    if (t.rfind("FEDRAT/", 0) != 0) continue;
    if (t.find("IPM") != std::string::npos || t.find("IPR") != std::string::npos) return {25.4, n};
    if (t.find("MMPM") != std::string::npos || t.find("MMPR") != std::string::npos) return {1.0, n};
  }
  return {1.0, 0};
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
                               InputForm form, const InitialPose& initial, double arc_chord_mm)
    : in_(in),
      file_(std::move(file)),
      machine_(machine),
      form_(resolve_form(in, form, buffered_)),
      interp_(gcode_setup(machine, form_, initial), file_) {
  if (!buffered_.empty() && buffered_.front().rfind(kByteOrderMark, 0) == 0) {
    byte_order_mark_ = true;
    buffered_.front().erase(0, kByteOrderMark.size());
  }
  if (form_ != InputForm::kApt) scan_tape();
  if (form_ == InputForm::kApt) {
    apt_ =
        std::make_unique<AptReader>(file_, initial_angles(machine, initial), initial, arc_chord_mm);
    if (const auto [unit_mm, line] = apt_units_from_feed(buffered_); line > 0)
      apt_->preset_units(unit_mm, line, pending_);
  }
}

FiveAxisReader::~FiveAxisReader() = default;

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
  if (form_ == InputForm::kApt) {
    if (pending_.empty() && !apt_statement()) return false;
    out = std::move(pending_.front());
    pending_.pop_front();
    out.unit_mm = 1.0;  // the output is in mm (G21)
    return true;
  }
  std::string text;
  if (!read_raw(text)) return false;
  out = FiveAxisLine{};
  out.line = line_;
  if (!frame_line(text, out)) gcode_line(text, out);
  out.unit_mm = interp_.state().unit_mm;
  return true;
}

// APT's lexical rules: `$$` starts a comment to the end of the line (one
// that ends in `$` goes on over the next lines: Creo); a statement ending in
// a single `$` goes on on the next line; a line of numbers only gives more
// points of the GOTO before it.
bool FiveAxisReader::apt_statement() {
  std::string text;
  while (pending_.empty()) {
    if (!read_raw(text)) {
      apt_->finish(line_, pending_);
      return !pending_.empty();
    }
    const int first = line_;
    std::string code = text, comment;
    const size_t cc = text.find("$$");
    const bool has_comment = cc != std::string::npos;
    if (has_comment) {
      code = text.substr(0, cc);
      comment = text.substr(cc + 2);
      std::string more;
      while (!trim(comment).empty() && trim(comment).back() == '$' && read_raw(more))
        comment = trim(comment).substr(0, trim(comment).size() - 1) + " " + trim(more);
    }
    code = trim(code);
    while (!code.empty() && code.back() == '$') {
      code.pop_back();
      std::string more;
      if (!read_raw(more)) fail(0, "APT statement continued with '$' at the end of the file");
      const size_t c2 = more.find("$$");
      code += trim(c2 == std::string::npos ? more : more.substr(0, c2));
    }
    if (!code.empty()) {
      if (code.find_first_not_of("0123456789+-.,eE \t") == std::string::npos &&
          code.find_first_of("0123456789") != std::string::npos) {
        if (!apt_->more_points(code, first, pending_))
          throw InputError(file_, first,
                           "a line of numbers with no record before it (a GOTO/ or a statement "
                           "ending in '$'); check the CL export");
      } else {
        apt_->statement(code, first, pending_);
      }
    }
    if (has_comment) apt_->comment(comment, first, pending_);
    if (code.empty() && !has_comment) {
      FiveAxisLine blank;
      blank.line = first;
      blank.synthetic = true;
      pending_.push_back(std::move(blank));
    }
  }
  return true;
}

}  // namespace volmap::post
