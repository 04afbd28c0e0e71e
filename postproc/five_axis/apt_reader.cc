// AptReader: the records, the dialect, the machine and frame records
// (apt_motion.cc: GOTO, CIRCLE, CYCLE). docs/post-five-axis.md "APT /
// CLDATA" gives each record's source.
#include "postproc/five_axis/apt_reader.h"

#include <fmt/format.h>

#include <cctype>
#include <charconv>
#include <cmath>

#include "core/common/input_error.h"

namespace volmap::post {
namespace {

std::string trim(const std::string& s) {
  size_t b = 0, e = s.size();
  while (b < e && std::isspace(static_cast<unsigned char>(s[b]))) ++b;
  while (e > b && std::isspace(static_cast<unsigned char>(s[e - 1]))) --e;
  return s.substr(b, e - b);
}

std::string upper(std::string s) {
  for (char& c : s) c = static_cast<char>(std::toupper(static_cast<unsigned char>(c)));
  return s;
}

// Blanks collapsed to one: "TOOL  PATH" -> "TOOL PATH".
std::string collapse_blanks(const std::string& s) {
  std::string out;
  for (char c : s) {
    const bool blank = std::isspace(static_cast<unsigned char>(c));
    if (blank && (out.empty() || out.back() == ' ')) continue;
    out += blank ? ' ' : c;
  }
  return trim(out);
}

// Comment text that a G-code comment can hold.
std::string comment_text(const std::string& s) {
  std::string out;
  for (char c : s) {
    const auto u = static_cast<unsigned char>(c);
    out += c == '(' ? '[' : c == ')' ? ']' : (u < 0x20 || u == 0x7f) ? ' ' : c;
  }
  return out;
}

// Records that move nothing and set nothing volmap uses: written as
// comments (docs/post-five-axis.md gives each one's meaning).
bool comment_only(const std::string& key) {
  static const char* const kKeys[] = {
      "PARTNO", "PPRINT", "INSERT", "REMARK",    "MACHIN",    "INTOL",       "OUTTOL", "TOLER",
      "CUTTER", "TLDATA", "TOOLNO", "PAINT",     "TOOL PATH", "END-OF-PATH", "SETUP",  "CLRSRF",
      "AUTOPS", "CLDATA", "SELECT", "OPERATION", "PLABEL",    "DISPLY",      "CUTCOM", "TRNTYP"};
  for (const char* k : kKeys)
    if (key == k) return true;
  // SOLIDWORKS CAM's tool data (CSI_SET_FLUTE_LENGTH/32., ...).
  return key.rfind("CSI_SET_", 0) == 0;
}

}  // namespace

const char* apt_dialect_name(AptDialect d) {
  switch (d) {
    case AptDialect::kNx:
      return "Siemens NX";
    case AptDialect::kSolidworks:
      return "SOLIDWORKS CAM";
    case AptDialect::kCreo:
      return "Creo";
    case AptDialect::kNcl:
      return "NCL";
    case AptDialect::kUnknown:
      break;
  }
  return "unknown";
}

// The record as a message shows it: at most 60 characters, bytes outside
// printable ASCII as \xNN.
std::string apt_shown(const std::string& text) {
  std::string out;
  for (size_t i = 0; i < text.size() && i < 60; ++i) {
    const auto c = static_cast<unsigned char>(text[i]);
    out +=
        c >= 0x20 && c < 0x7f ? std::string(1, static_cast<char>(c)) : fmt::format("\\x{:02X}", c);
  }
  return text.size() > 60 ? out + "..." : out;
}

bool apt_number(const std::string& s, double& v) {
  if (s.empty()) return false;
  const char* b = s.data() + (s[0] == '+' ? 1 : 0);
  const char* e = s.data() + s.size();
  if (b == e || *b == '+') return false;
  const auto r = std::from_chars(b, e, v);
  return r.ec == std::errc() && r.ptr == e && std::isfinite(v);
}

AptRecord parse_apt_record(const std::string& statement) {
  AptRecord r;
  r.text = trim(statement);
  const size_t slash = r.text.find('/');
  // KEY/args, or KEY [text] (PARTNO test, RAPID, FINI).
  size_t word_end = 0;
  while (word_end < r.text.size() && !std::isspace(static_cast<unsigned char>(r.text[word_end])))
    ++word_end;
  if (slash == std::string::npos || word_end < slash) {
    // "TOOL PATH/..." and "GOTO  /..." have blanks before the slash.
    const bool blanks_then_slash =
        slash != std::string::npos &&
        r.text.substr(word_end, slash - word_end).find_first_not_of(" \t") == std::string::npos;
    const bool two_words = slash != std::string::npos &&
                           upper(collapse_blanks(r.text.substr(0, slash))) == "TOOL PATH";
    if (!blanks_then_slash && !two_words) {
      r.key = upper(r.text.substr(0, word_end));
      r.args.clear();
      const std::string rest = trim(r.text.substr(word_end));
      if (!rest.empty()) r.args.push_back(upper(rest));
      return r;
    }
  }
  r.slash = true;
  r.key = upper(collapse_blanks(r.text.substr(0, slash)));
  const std::string rest = upper(r.text.substr(slash + 1));
  size_t start = 0;
  for (;;) {
    const size_t comma = rest.find(',', start);
    r.args.push_back(
        trim(rest.substr(start, comma == std::string::npos ? std::string::npos : comma - start)));
    if (comma == std::string::npos) break;
    start = comma + 1;
  }
  if (r.args.size() == 1 && r.args[0].empty()) r.args.clear();  // "RAPID/", "END-OF-PATH/"
  return r;
}

AptReader::AptReader(std::string file, const AxisVector& q, const InitialPose& initial,
                     double chord_mm)
    : file_(std::move(file)),
      chord_mm_(chord_mm),
      tip_mm_(initial.tip_mm),
      q_(q),
      axis_(initial.axis.normalized()) {}

void AptReader::fail(const std::string& msg) const { throw InputError(file_, line_, msg); }

void AptReader::add_text(const std::string& g_code, std::deque<FiveAxisLine>& out) const {
  FiveAxisLine l;
  l.line = line_;
  l.synthetic = true;
  l.text = g_code;
  out.push_back(std::move(l));
}

void AptReader::add_comment(const AptRecord& r, std::deque<FiveAxisLine>& out) const {
  add_text("(APT: " + comment_text(r.text) + ")", out);
}

std::vector<double> AptReader::numbers(const AptRecord& r, size_t from) const {
  std::vector<double> v;
  for (size_t k = from; k < r.args.size(); ++k) {
    double x = 0;
    if (!apt_number(r.args[k], x))
      fail(fmt::format("{}: '{}' is not a number (in '{}')", r.key, apt_shown(r.args[k]),
                       apt_shown(r.text)));
    v.push_back(x);
  }
  return v;
}

// The records each CAM system writes and the others do not.
void AptReader::note_dialect(const AptRecord& r) {
  if (dialect_ != AptDialect::kUnknown) return;
  const std::string& k = r.key;
  if (k == "TOOL PATH" || k == "TLDATA" || k == "MSYS" || k == "END-OF-PATH" || k == "PAINT")
    dialect_ = AptDialect::kNx;
  else if (k == "TRNTYP" || k == "UNIT" || k.rfind("CSI_SET_", 0) == 0 ||
           (k == "CYCLE" && !r.args.empty() && (r.args[0] == "INIT" || r.args[0] == "CLEAR")))
    dialect_ = AptDialect::kSolidworks;
  else if (k == "REMARK" && !r.args.empty() && r.args[0].find("NCLCAM") != std::string::npos)
    dialect_ = AptDialect::kNcl;
}

void AptReader::comment(const std::string& text, int line, std::deque<FiveAxisLine>& out) {
  line_ = line;
  const std::string up = upper(text);
  if (dialect_ == AptDialect::kUnknown && up.find("PRO/CLFILE") != std::string::npos)
    dialect_ = AptDialect::kCreo;
  // Creo: "$$-> CUTCOM_GEOMETRY_TYPE / OUTPUT_ON_CENTER" (or the tool edge).
  const size_t cg = up.find("CUTCOM_GEOMETRY_TYPE");
  if (cg != std::string::npos)
    creo_profile_points_ = up.find("OUTPUT_ON_CENTER", cg) == std::string::npos;
  add_text("(APT: $$" + comment_text(text) + ")", out);
}

void AptReader::preset_units(double unit_mm, int line, std::deque<FiveAxisLine>& out) {
  unit_mm_ = unit_mm;
  add_text(fmt::format("(volmap post: no UNITS record; lengths in {}, as FEDRAT/ on line {} says)",
                       unit_mm == 25.4 ? "inches" : "mm", line),
           out);
}

void AptReader::finish(int line, std::deque<FiveAxisLine>& out) {
  line_ = line;
  if (circle_ && !circle_goto_)
    throw InputError(file_, line,
                     fmt::format("the CIRCLE/ of line {} has no GOTO/ after it: the file is cut "
                                 "short; export the CL file again",
                                 circle_->line));
  if (ended_) return;
  ended_ = true;
  add_text("M2 (volmap post: the CL file ends without FINI)", out);
  out.back().ends_program = true;
}

void AptReader::statement(const std::string& text, int line, std::deque<FiveAxisLine>& out) {
  line_ = line;
  const AptRecord r = parse_apt_record(text);
  note_dialect(r);
  if (upper(collapse_blanks(text)).rfind("TOOL PATH LISTING HAS ", 0) == 0) {
    add_comment(r, out);  // the last line of NX's listing window, saved with it
    return;
  }
  if (r.key != "GOTO") {
    goto_open_ = false;
    if (circle_goto_) circle_.reset(), circle_goto_ = false;  // the arc's GOTO is over
  }
  if (circle_ && !circle_goto_ && r.key != "GOTO" && r.key != "FEDRAT" && !comment_only(r.key))
    fail(
        fmt::format("{} between CIRCLE/ (line {}) and the GOTO/ that ends the arc; the arc's "
                    "end is undefined: export the CL file again",
                    apt_shown(r.key), circle_->line));
  if (machine_record(r, out) || frame_record(r, out)) return;
  if (r.key == "CUTCOM") {
    // CL points are the tool centre (Creo, NX by default; SOLIDWORKS CAM:
    // see docs): the compensation the CAM system computed is in them.
    if (!r.args.empty() && r.args[0] != "OFF" && creo_profile_points_)
      fail(
          "CUTCOM/ with CUTCOM_GEOMETRY_TYPE other than OUTPUT_ON_CENTER: the CL points are the "
          "part contour, not the tool centre; set the Output Point to Tool Center in Creo");
    add_text("(APT: " + comment_text(r.text) +
                 " -- the CL points are the tool centre: no G41/G42 written)",
             out);
    return;
  }
  if (comment_only(r.key)) {
    add_comment(r, out);
    return;
  }
  motion_record(r, out);
}

// Spindle, coolant, stops, tools, program end. True when `r` was one.
bool AptReader::machine_record(const AptRecord& r, std::deque<FiveAxisLine>& out) {
  const std::string& k = r.key;
  if (k == "SPINDL") {
    bool off = false, on = false;
    for (const std::string& a : r.args) {
      double s = 0;
      if (a == "OFF")
        off = true;
      else if (a == "ON")
        on = true;
      else if (a == "CLW")
        spindle_ccw_ = false;
      else if (a == "CCLW")
        spindle_ccw_ = true;
      else if (a == "RPM")
        continue;
      else if (a == "SFM" || a == "SMM")
        fail("SPINDL/ in surface speed (SFM/SMM) needs the tool diameter at the cut; write RPM");
      else if (apt_number(a, s) && s >= 0)
        spindle_rpm_ = s, on = true;
      else
        fail(fmt::format("SPINDL/: '{}' is not understood (RPM, CLW, CCLW, OFF, ON, a speed)",
                         apt_shown(a)));
    }
    if (off)
      add_text("M5", out);
    else if (on)
      add_text(fmt::format("S{} {}", spindle_rpm_, spindle_ccw_ ? "M4" : "M3"), out);
    else
      fail("SPINDL/ without a speed, ON or OFF");
    return true;
  }
  if (k == "COOLNT") {
    const std::string a = r.args.empty() ? "ON" : r.args[0];
    if (a == "ON" || a == "FLOOD")
      add_text("M8", out);
    else if (a == "MIST")
      add_text("M7", out);
    else if (a == "OFF")
      add_text("M9", out);
    else
      add_text("(APT: " + comment_text(r.text) + " -- coolant mode with no M code here)", out);
    return true;
  }
  if (k == "STOP" || k == "OPSTOP") {
    add_text(k == "STOP" ? "M0" : "M1", out);
    return true;
  }
  if (k == "DELAY") {
    const std::vector<double> v = numbers(r);
    if (v.size() != 1 || v[0] < 0) fail("DELAY/ takes one time in seconds (DELAY/REV is refused)");
    add_text(fmt::format("G4 P{}", v[0]), out);
    return true;
  }
  if (k == "FINI") {
    ended_ = true;
    add_text("M2", out);
    out.back().ends_program = true;
    return true;
  }
  if (k == "END") {
    add_comment(r, out);
    return true;
  }
  if (k == "LOAD" || k == "LOADTL") {
    // LOAD/TOOL,n[,ADJUST,h] (NX, SOLIDWORKS CAM), LOADTL/n (Creo, NCL).
    const size_t at = k == "LOAD" ? 1 : 0;
    double n = 0;
    if ((k == "LOAD" && (r.args.empty() || r.args[0] != "TOOL")) || r.args.size() <= at ||
        !apt_number(r.args[at], n))
      fail(fmt::format("'{}': a tool load is LOAD/TOOL,n or LOADTL/n", apt_shown(r.text)));
    if (n < 0 || n != std::floor(n) || n > 99999)
      fail(fmt::format("'{}': the tool number must be a whole number", apt_shown(r.text)));
    add_comment(r, out);
    out.back().tool = static_cast<int>(n);
    return true;
  }
  return false;
}

// Coordinate frames. True when `r` was one.
bool AptReader::frame_record(const AptRecord& r, std::deque<FiveAxisLine>& out) {
  const std::string& k = r.key;
  if (k == "MSYS") {
    // NX: the machine coordinate system of the operation, in NX's absolute
    // frame; GOTO and CIRCLE are written in it, and it is the frame the
    // program's work offset names (NX's posts output MCS coordinates).
    numbers(r);
    add_text("(APT: " + comment_text(r.text) + " -- NX MCS: the GOTO points are in it)", out);
    return true;
  }
  if (k == "CSYS") {
    const std::vector<double> v = numbers(r);
    if (v.size() != 12) fail("CSYS/ takes 12 numbers (a 3x4 matrix, row by row)");
    const bool identity = v == std::vector<double>{1, 0, 0, 0, 0, 1, 0, 0, 0, 0, 1, 0};
    if (!identity && dialect_ != AptDialect::kSolidworks)
      fail(
          fmt::format("CSYS/ that is not the identity, from {}: whether the GOTO points after it "
                      "are in this frame or the base frame is not established for this CAM "
                      "system; output the CL data in one frame (no CSYS)",
                      apt_dialect_name(dialect_)));
    // SOLIDWORKS CAM writes the GOTO points in the part frame; CSYS's third
    // column is the setup's tool axis: that of the GOTOs after it, which
    // carry i,j,k only where it is not +Z (checked at the next GOTO).
    if (dialect_ == AptDialect::kSolidworks) {
      const Eigen::Vector3d z(v[2], v[6], v[10]);
      if (z.norm() < 1e-9) fail("CSYS/: the third column (the tool axis) is zero");
      axis_ = z.normalized();
      csys_axis_ = axis_;
    }
    add_text("(APT: " + comment_text(r.text) + " -- the GOTO points are in the part frame)", out);
    return true;
  }
  if (k == "TRACUT" || k == "TRANS" || k == "COPY" || k == "INDEX" || k == "REFSYS" ||
      k == "ORIGIN") {
    if (k == "TRACUT" && r.args.size() == 1 && r.args[0] == "NOMORE") {
      add_comment(r, out);
      return true;
    }
    fail(
        fmt::format("{}/ moves or copies the path by a transformation whose use differs between "
                    "CAM systems; have the CAM system apply it (output the transformed GOTO "
                    "points)",
                    k));
  }
  return false;
}

}  // namespace volmap::post
