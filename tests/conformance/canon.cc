#include "tests/conformance/canon.h"

#include <cctype>
#include <cstdlib>
#include <filesystem>
#include <sstream>

#include "tests/conformance/process.h"

namespace volmap::conformance {

namespace fs = std::filesystem;

namespace {

// The numbers between the first '(' and the last ')', separated by commas
// or blanks (USE_TOOL_LENGTH_OFFSET prints "x y z, a b c, ...").
std::vector<double> numbers(const std::string& l) {
  std::vector<double> v;
  const size_t open = l.find('('), close = l.rfind(')');
  if (open == std::string::npos || close == std::string::npos || close < open) return v;
  const std::string inside = l.substr(open + 1, close - open - 1);
  const char* p = inside.c_str();
  while (*p) {
    char* end = nullptr;
    const double x = std::strtod(p, &end);
    if (end == p) {
      ++p;
      continue;
    }
    v.push_back(x);
    p = end;
  }
  return v;
}

bool has(const std::string& line, const char* call) { return line.find(call) != std::string::npos; }

struct ParseState {
  double unit = 1.0;
  int plane = 0;
  double tool_offset = 0.0;
  Eigen::Vector3d pos = Eigen::Vector3d::Zero();  // machine mm (rs274 starts at machine zero)
  Eigen::Vector3d g5x = Eigen::Vector3d::Zero(), g92 = Eigen::Vector3d::Zero();
  std::vector<CanonMove> moves;
  std::vector<UserM> user_m;

  Eigen::Vector3d machine(double x, double y, double z) const {
    return Eigen::Vector3d(x, y, z) * unit + g5x + g92;
  }
  void line_to(const Eigen::Vector3d& p, bool feed) {
    CanonMove m;
    m.motion.kind = nc::MotionKind::kLinear;
    m.motion.start_mm = pos;
    m.motion.end_mm = p;
    m.feed = feed;
    m.unit_mm = unit;
    m.tool_offset_mm = tool_offset;
    moves.push_back(m);
    pos = p;
  }
  // ARC_FEED(first_end, second_end, first_centre, second_centre, rotation,
  // axis_end, a, b, c, ...); XY: first X; XZ (G18): first Z, second X; YZ
  // (G19): first Y, second Z.
  void arc(const std::vector<double>& v) {
    static constexpr int kFirst[3] = {0, 2, 1}, kSecond[3] = {1, 0, 2}, kAxis[3] = {2, 1, 0};
    const Eigen::Vector3d off = g5x + g92;
    CanonMove c;
    nc::Motion& m = c.motion;
    m.kind = nc::MotionKind::kArc;
    m.start_mm = pos;
    m.end_mm[kFirst[plane]] = v[0] * unit + off[kFirst[plane]];
    m.end_mm[kSecond[plane]] = v[1] * unit + off[kSecond[plane]];
    m.end_mm[kAxis[plane]] = v[5] * unit + off[kAxis[plane]];
    m.center_mm = pos;
    m.center_mm[kFirst[plane]] = v[2] * unit + off[kFirst[plane]];
    m.center_mm[kSecond[plane]] = v[3] * unit + off[kSecond[plane]];
    const int rotation = static_cast<int>(v[4]);
    m.clockwise = rotation < 0;
    m.extra_turns = std::abs(rotation) - 1;
    m.plane = plane;
    c.feed = true;
    c.unit_mm = unit;
    c.tool_offset_mm = tool_offset;
    moves.push_back(c);
    pos = m.end_mm;
  }
  void line(const std::string& l) {
    if (const size_t at = l.find("COMMENT(\"user M"); at != std::string::npos) {
      const size_t from = at + 9, to = l.rfind('"');
      user_m.push_back({l.substr(from, to > from ? to - from : 0), pos});
      return;
    }
    if (has(l, "USE_LENGTH_UNITS(CANON_UNITS_INCHES)")) unit = 25.4;
    if (has(l, "USE_LENGTH_UNITS(CANON_UNITS_MM)")) unit = 1.0;
    if (has(l, "SELECT_PLANE(CANON_PLANE_XY)")) plane = 0;
    if (has(l, "SELECT_PLANE(CANON_PLANE_XZ)")) plane = 1;
    if (has(l, "SELECT_PLANE(CANON_PLANE_YZ)")) plane = 2;
    const bool traverse = has(l, "STRAIGHT_TRAVERSE("), feed = has(l, "STRAIGHT_FEED(");
    const std::vector<double> v =
        traverse || feed || has(l, "ARC_FEED(") || has(l, "OFFSET(") || has(l, "RIGID_TAP(")
            ? numbers(l)
            : std::vector<double>{};
    if (has(l, "SET_G5X_OFFSET(") && v.size() >= 4) g5x = Eigen::Vector3d(v[1], v[2], v[3]) * unit;
    if (has(l, "SET_G92_OFFSET(") && v.size() >= 3) g92 = Eigen::Vector3d(v[0], v[1], v[2]) * unit;
    if (has(l, "USE_TOOL_LENGTH_OFFSET(") && v.size() >= 3) {
      // The axes stay where they are: the controlled point (the tip) jumps
      // by minus the change.
      const double offset = v[2] * unit;
      pos.z() -= offset - tool_offset;
      tool_offset = offset;
    }
    if ((traverse || feed) && v.size() >= 3) line_to(machine(v[0], v[1], v[2]), feed);
    if (has(l, "ARC_FEED(") && v.size() >= 6) arc(v);
    if (has(l, "RIGID_TAP(") && v.size() >= 3) {  // in to the end point and back
      const Eigen::Vector3d from = pos;
      line_to(machine(v[0], v[1], v[2]), true);
      line_to(from, true);
    }
  }
};

}  // namespace

void parse_canon(const std::string& text, Canon& into) {
  ParseState s;
  std::istringstream in(text);
  for (std::string l; std::getline(in, l);) s.line(l);
  into.moves = std::move(s.moves);
  into.user_m = std::move(s.user_m);
}

std::string normalized_message(const std::string& message) {
  std::string first = message.substr(0, message.find('\n'));
  std::string out;
  bool in_number = false;
  for (char ch : first) {
    const bool digit = std::isdigit(static_cast<unsigned char>(ch)) != 0;
    if (digit || (in_number && ch == '.')) {
      if (!in_number) out += '#';
      in_number = true;
      continue;
    }
    in_number = false;
    out += ch;
  }
  while (!out.empty() && std::isspace(static_cast<unsigned char>(out.back()))) out.pop_back();
  return out;
}

Canon run_rs274(const Rs274Setup& setup, const std::string& program) {
  static thread_local int count = 0;
  const std::string tag = std::to_string(++count);
  const std::string canon_file = (fs::path(setup.scratch) / ("rs274-" + tag + ".canon")).string();
  const std::string log_file = (fs::path(setup.scratch) / ("rs274-" + tag + ".log")).string();
  ProcessSpec spec;
  spec.argv = {"rs274"};
  if (!setup.tool_table.empty()) spec.argv.insert(spec.argv.end(), {"-t", setup.tool_table});
  if (!setup.var_file.empty()) {
    // A short name: rs274 cuts a long one (about 100 characters) and then
    // starts from zeros.
    const std::string copy = (fs::path(setup.scratch) / "r.var").string();
    fs::copy_file(setup.var_file, copy, fs::copy_options::overwrite_existing);
    spec.argv.insert(spec.argv.end(), {"-v", copy});
  }
  spec.argv.insert(spec.argv.end(), {"-g", fs::path(program).filename().string(), canon_file});
  spec.cwd = fs::path(program).parent_path().string();
  spec.env = {{"HOME", setup.home}};
  spec.err_file = log_file;
  spec.timeout_s = setup.timeout_s;
  const ProcessResult r = run_process(spec);
  Canon c;
  c.timed_out = r.timed_out;
  c.ok = r.exit_code == 0 && !r.timed_out;
  // The log: "executing", then the message and the line it names.
  std::istringstream log(r.err);
  for (std::string l; std::getline(log, l);) {
    if (l == "executing" || l.empty()) continue;
    if (l.find("ariable file") != std::string::npos ||
        l.find("arameter file") != std::string::npos) {
      c.ok = false;  // a parameter file rs274 could not read or write back
    }
    c.error += (c.error.empty() ? "" : "\n") + l;
  }
  if (c.ok) c.error.clear();
  if (!c.ok && c.error.empty()) c.error = r.timed_out ? "rs274 timed out" : "rs274 failed";
  parse_canon(read_file(canon_file), c);
  fs::remove(canon_file);
  fs::remove(log_file);
  return c;
}

}  // namespace volmap::conformance
