#include "gcode/dialect.h"

#include <stdexcept>

namespace volmap::nc {
namespace {

bool blank(char c) { return c == ' ' || c == '\t' || c == '\r'; }
bool digit(char c) { return c >= '0' && c <= '9'; }

// Only spaces, ( ) comments and ';' (a Fanuc block's end) from i on.
bool only_comments(std::string_view t, std::size_t i) {
  while (i < t.size()) {
    if (blank(t[i]) || t[i] == ';') {
      ++i;
    } else if (t[i] == '(') {
      const std::size_t close = t.find(')', i);
      if (close == std::string_view::npos) return false;
      i = close + 1;
    } else {
      return false;
    }
  }
  return true;
}

}  // namespace

Dialect parse_dialect(std::string_view name) {
  if (name == "auto") return Dialect::kAuto;
  if (name == "linuxcnc") return Dialect::kLinuxCnc;
  if (name == "fanuc") return Dialect::kFanuc;
  throw std::invalid_argument("the dialect is auto, linuxcnc or fanuc");
}

const char* dialect_name(Dialect d) {
  switch (d) {
    case Dialect::kAuto:
      return "auto";
    case Dialect::kLinuxCnc:
      return "linuxcnc";
    case Dialect::kFanuc:
      return "fanuc";
  }
  return "auto";
}

bool is_program_number_line(std::string_view t, std::string_view* digits) {
  std::size_t i = 0;
  while (i < t.size() && blank(t[i])) ++i;
  if (i >= t.size() || (t[i] != 'O' && t[i] != 'o' && t[i] != ':')) return false;
  const std::size_t begin = ++i;
  while (i < t.size() && digit(t[i])) ++i;
  if (i == begin || !only_comments(t, i)) return false;
  if (digits) *digits = t.substr(begin, i - begin);
  return true;
}

DialectChoice detect_dialect(std::string_view head, int first_line) {
  DialectChoice c;
  c.detected = true;
  int line = first_line;
  std::size_t b = 0;
  while (b < head.size()) {
    const std::size_t e = head.find('\n', b);
    if (e == std::string_view::npos) break;  // cut: not looked at
    const std::string_view t = head.substr(b, e - b);
    std::size_t i = 0;
    while (i < t.size() && blank(t[i])) ++i;
    // (';' lines: LinuxCNC's comments, a Fanuc control's empty blocks.)
    const bool skip = i == t.size() || t[i] == '%' || t[i] == ';' || only_comments(t, i);
    if (!skip) {
      if (is_program_number_line(t)) {
        c.dialect = Dialect::kFanuc;
        c.line = line;
        std::string_view shown = t.substr(i);
        while (!shown.empty() && blank(shown.back())) shown.remove_suffix(1);
        const std::size_t paren = shown.find('(');
        if (paren != std::string_view::npos) shown = shown.substr(0, paren);
        while (!shown.empty() && blank(shown.back())) shown.remove_suffix(1);
        c.reason = "program number " + std::string(shown) + " at line " + std::to_string(line);
        return c;
      }
      c.line = line;
      c.reason = "no Fanuc program number O1234 or :1234 opens it (line " + std::to_string(line) +
                 "); give --dialect fanuc for a Fanuc or Haas program";
      return c;
    }
    ++line;
    b = e + 1;
  }
  c.reason = "no block in its first lines; give --dialect fanuc for a Fanuc or Haas program";
  return c;
}

}  // namespace volmap::nc
