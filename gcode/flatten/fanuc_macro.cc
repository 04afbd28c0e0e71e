// Fanuc Custom Macro B in the flattener (flattener.h, Flattener::set_fanuc),
// after Fanuc's Series 0i-MF operator's manual (B-64604EN), "Custom macro":
// - macro statements, one per block: `#i = expression` (it takes effect at
//   once), `GOTO n`, `IF [condition] GOTO n`, `IF [condition] THEN #i = ...`,
//   `WHILE [condition] DO m` ... `END m` and `DO m` ... `END m`;
// - GOTO n looks for the block with sequence number N n in the current
//   program: from the block after the GOTO to the program's end, then from
//   its start; it may leave a loop, not enter one;
// - G65 and M98 calls (calls.cc);
// - an NC block's address with a variable or an expression takes its
//   value in program units (the point implied); an address whose variable
//   is vacant is left out of the block (`G00 X#24` with #24 vacant is
//   `G00`).
// Evaluated values are written with a decimal point and at most 4
// decimals (a Fanuc control rounds an address to its least input
// increment, 0.001 mm on IS-B, 0.0001 on IS-C). What differs between
// controls or depends on their parameters is refused with the reason
// (docs/post.md, "Dialects").
#include <fmt/format.h>

#include <cmath>
#include <cstring>

#include "core/common/input_error.h"
#include "gcode/dialect.h"
#include "gcode/flatten/flattener.h"

namespace volmap::nc::flatten {
namespace {

bool digit(char c) { return c >= '0' && c <= '9'; }

// Past a sequence number N<digits> at i (normalized text).
std::size_t skip_sequence_number(const std::string& t, std::size_t i) {
  if (i < t.size() && t[i] == 'n' && i + 1 < t.size() && digit(t[i + 1])) {
    ++i;
    while (i < t.size() && digit(t[i])) ++i;
  }
  return i;
}

bool starts_with(const std::string& t, std::size_t i, std::string_view w) {
  return t.compare(i, w.size(), w) == 0;
}

// A value as a Fanuc address writes it: at most 4 decimals, always a point.
void append_fanuc_number(std::string& out, double v) {
  std::string s = fmt::format("{:.4f}", v);
  while (s.back() == '0') s.pop_back();
  if (s == "-0.") s = "0.";
  out += s;
}

// GOTO's sequence number: an integer value (GOTO 10, GOTO #5, GOTO [#5+1]).
long sequence_number(const ValueReader& r, std::size_t& i) {
  const std::size_t at = i;
  const double v = r.statement_value(i);
  if (is_vacant(v) || v != std::floor(v) || v < 1 || v > 99999)
    throw ValueError{"GOTO's sequence number is a whole number from 1 to 99999", at};
  return static_cast<long>(v);
}

}  // namespace

bool Flattener::program_label(std::string_view raw, std::string& label) const {
  std::string_view digits;
  if (!is_program_number_line(without_cr(raw), &digits)) return false;
  std::size_t k = 0;
  while (k + 1 < digits.size() && digits[k] == '0') ++k;
  label.assign(digits.substr(k));
  return true;
}

bool Flattener::fanuc_line(const Position& p, FlatLine& out) {
  const Source& s = *sources_[p.source];
  const std::string_view raw = s.line(p.line);
  std::string label;
  const bool number_line = program_label(raw, label);
  bool rewritten = false;
  if (!number_line) {
    if (fanuc_statement(p)) return false;
    rewritten = fanuc_evaluate(p);
    if (fanuc_call(p) || fanuc_g65(p)) return false;
    if (rewritten && line_.empty()) return false;
  }
  out.text = rewritten ? std::string_view(line_) : raw;
  out.file = &s.file;
  out.line = s.first_line + static_cast<int>(p.line);
  out.newline = s.newline[p.line] || p.source != 0 || !frames_.empty();
  out.rewritten = rewritten;
  out.verbatim = number_line;
  return true;
}

bool Flattener::fanuc_statement(const Position& p) {
  normalize(without_cr(sources_[p.source]->line(p.line)), norm_);
  const std::string& t = norm_.text;
  std::size_t i = 0;
  const bool skip = i < t.size() && t[i] == '/';
  if (skip) ++i;
  i = skip_sequence_number(t, i);
  const bool statement = starts_with(t, i, "if[") || starts_with(t, i, "while[") ||
                         starts_with(t, i, "goto") ||
                         (starts_with(t, i, "do") && i + 2 < t.size() && digit(t[i + 2])) ||
                         (starts_with(t, i, "end") && i + 3 < t.size() && digit(t[i + 3])) ||
                         (i < t.size() && t[i] == '#');
  if (!statement) return false;
  if (skip)
    fail(p, 0,
         "block skip '/' before a macro statement: whether it runs depends on the "
         "operator's switch; remove the '/'");
  try {
    ValueReader r(t, params_, fanuc_, false);
    if (t[i] == '#') {
      fanuc_assignment(p, r, i);
    } else if (starts_with(t, i, "if[")) {
      i += 2;
      const bool holds = fanuc_condition(r, i);
      if (starts_with(t, i, "goto")) {
        i += 4;
        const std::size_t at = i;
        const long n = sequence_number(r, i);
        only_comment_from(p, i);
        if (holds) pc_ = fanuc_goto(p, n, at);
      } else if (starts_with(t, i, "then")) {
        i += 4;
        if (i >= t.size() || t[i] != '#')
          fail(p, i, "IF ... THEN takes an assignment (#i = ...) here");
        if (holds) fanuc_assignment(p, r, i);
      } else {
        fail(p, i, "IF [condition] needs GOTO n or THEN #i = ...");
      }
    } else if (starts_with(t, i, "while[")) {
      i += 5;
      const bool holds = fanuc_condition(r, i);
      if (!starts_with(t, i, "do")) fail(p, i, "WHILE [condition] needs DO m");
      i += 2;
      const int m = fanuc_loop_id(p, i);
      const bool again = !frames_.empty() && frames_.back().kind == Frame::kFanucLoop &&
                         frames_.back().start.source == p.source &&
                         frames_.back().start.line == p.line;
      if (holds && !again) push_fanuc_loop(p, m, false);
      if (!holds) {
        if (again) frames_.pop_back();
        pc_ = after(fanuc_find_end(p, m));
      }
    } else if (starts_with(t, i, "do")) {
      i += 2;
      const int m = fanuc_loop_id(p, i);
      push_fanuc_loop(p, m, true);
    } else if (starts_with(t, i, "end")) {
      i += 3;
      const int m = fanuc_loop_id(p, i);
      if (frames_.empty() || frames_.back().kind != Frame::kFanucLoop ||
          frames_.back().label != std::to_string(m))
        fail(p, i,
             fmt::format("END{} without its WHILE ... DO{} or DO{} (a GOTO into a loop, "
                         "or loops crossed?)",
                         m, m, m));
      const Frame& f = frames_.back();
      pc_ = f.taken ? after(f.start) : f.start;  // DO m: again; WHILE: its condition again
    } else {                                     // goto
      i += 4;
      const std::size_t at = i;
      const long n = sequence_number(r, i);
      only_comment_from(p, i);
      pc_ = fanuc_goto(p, n, at);
    }
  } catch (const ValueError& e) {
    fail(p, e.at, e.message);
  }
  return true;
}

void Flattener::push_fanuc_loop(const Position& p, int m, bool do_only) {
  Frame f;
  f.kind = Frame::kFanucLoop;
  f.label = std::to_string(m);
  f.start = f.target = p;
  f.taken = do_only;
  frames_.push_back(f);
}

void Flattener::append_fanuc_value(const Position& p, char letter, std::size_t at, double value,
                                   std::string& out) const {
  // Distances, angles and the feed take a point; the other addresses (G M
  // T H D S P L N ...) a whole number, which a point would make an alarm.
  if (std::strchr("xyzabcijkrquvwf", letter)) {
    append_fanuc_number(out, value);
    return;
  }
  const double whole = std::round(value);
  const double tenths = std::round(value * 10);
  if ((letter == 'g' || letter == 'm') && std::abs(value * 10 - tenths) < 1e-9 && whole != value) {
    out += fmt::format("{:.1f}", value);  // G05.1, G54.1 ...
    return;
  }
  if (std::abs(value - whole) > 1e-9 || std::abs(whole) > 1e9)
    fail(p, at,
         fmt::format("{} takes a whole number on a Fanuc control, and the value here is {}",
                     static_cast<char>(letter - 'a' + 'A'), value));
  out += fmt::format("{}", static_cast<long long>(whole));
}

void Flattener::only_comment_from(const Position& p, std::size_t i) const {
  const std::string& t = norm_.text;
  if (i < t.size() && t[i] == ';')
    fanuc_end_of_block(p, i);
  else if (i < t.size() && t[i] != '(')
    fail(p, i,
         "more after a macro statement: a Fanuc block holds one; put the rest on a line "
         "of its own");
}

void Flattener::fanuc_end_of_block(const Position& p, std::size_t i) const {
  // ';' is a Fanuc block's end (EOB), not a comment: text after it would
  // be another block on the control.
  if (norm_.text.find_first_not_of(';', i) != std::string::npos)
    fail(p, i, kFanucTextAfterEndOfBlock);
}

bool Flattener::fanuc_condition(const ValueReader& r, std::size_t& i) const {
  const std::size_t at = i;
  const double c = r.expression(i);
  if (c != 0.0 && c != 1.0)
    throw ValueError{
        "the condition is not a comparison (EQ NE GT GE LT LE, combined with AND "
        "OR XOR): [#1 GT 0]",
        at};
  return c == 1.0;
}

int Flattener::fanuc_loop_id(const Position& p, std::size_t& i) const {
  const std::string& t = norm_.text;
  const std::size_t at = i;
  int m = 0;
  while (i < t.size() && digit(t[i]) && m < 1000) m = m * 10 + (t[i++] - '0');
  if (i == at || m < 1 || m > 3) fail(p, at, "a loop's number after DO and END is 1, 2 or 3");
  only_comment_from(p, i);
  return m;
}

void Flattener::fanuc_assignment(const Position& p, const ValueReader& r, std::size_t i) {
  const std::string& t = norm_.text;
  const std::size_t at = i++;  // '#'
  if (i < t.size() && t[i] == '<')
    throw ValueError{"named parameters #<...> are LinuxCNC's, not Fanuc's", at};
  const int n = r.integer_value(i);
  if (i >= t.size() || t[i] != '=')
    throw ValueError{"a variable outside an address: #i = value", at};
  ++i;
  // `#2 = #1` copies a vacant #1 as vacant; any other expression of one
  // is refused by the reader or is arithmetic (vacant as 0).
  std::size_t k = i + 1;
  while (k < t.size() && digit(t[k])) ++k;
  const bool copy =
      i < t.size() && t[i] == '#' && k > i + 1 && (k == t.size() || t[k] == '(' || t[k] == ';');
  const std::size_t value_at = i;
  const double v = r.statement_value(i);
  if (is_vacant(v) && !copy)
    throw ValueError{"a bracketed vacant variable (never set): write #i = #j to copy it", value_at};
  only_comment_from(p, i);
  try {
    fanuc_->set(n, is_vacant(v) ? std::nullopt : std::optional<double>(v));
  } catch (ValueError& e) {
    e.at = at;
    throw;
  }
}

Flattener::Position Flattener::fanuc_find_end(const Position& from, int m) const {
  const Source& s = *sources_[from.source];
  const std::string end = "end" + std::to_string(m);
  NormalizedLine n;
  for (std::size_t k = from.line + 1; k < s.size(); ++k) {
    const std::string_view raw = s.line(k);
    if (raw.find_first_of("eE") == std::string_view::npos) continue;
    normalize(without_cr(raw), n);
    const std::size_t i = skip_sequence_number(n.text, 0);
    if (starts_with(n.text, i, end) &&
        (i + end.size() >= n.text.size() || !digit(n.text[i + end.size()])))
      return {from.source, k};
    std::string label;
    if (program_label(raw, label)) break;
  }
  fail(from, static_cast<std::size_t>(-1),
       fmt::format("DO{} without END{} after it in this program", m, m));
}

Flattener::Position Flattener::fanuc_goto(const Position& p, long n, std::size_t at) {
  const Source& s = *sources_[p.source];
  // The current program: between program number lines (or '%').
  auto bound = [&](std::size_t k) {
    const std::string_view raw = s.line(k);
    std::string label;
    const std::size_t first = raw.find_first_not_of(" \t");
    return program_label(raw, label) || (first != std::string_view::npos && raw[first] == '%');
  };
  std::size_t begin = p.line, end = p.line + 1;
  while (begin > 0 && !bound(begin - 1)) --begin;
  while (end < s.size() && !bound(end)) ++end;
  const std::string want = std::to_string(n);
  NormalizedLine nl;
  auto numbered = [&](std::size_t k) {
    const std::string_view raw = s.line(k);
    if (raw.find_first_of("nN") == std::string_view::npos) return false;
    normalize(without_cr(raw), nl);
    std::size_t i = nl.text.size() && nl.text[0] == '/' ? 1 : 0;
    if (i >= nl.text.size() || nl.text[i] != 'n') return false;
    std::size_t j = ++i;
    while (j < nl.text.size() && digit(nl.text[j])) ++j;
    if (j == i) return false;
    std::size_t z = i;
    while (z + 1 < j && nl.text[z] == '0') ++z;
    return nl.text.compare(z, j - z, want) == 0 && (j - z) == want.size();
  };
  std::size_t target = end;
  for (std::size_t k = p.line + 1; k < end && target == end; ++k)
    if (numbered(k)) target = k;
  for (std::size_t k = begin; k <= p.line && target == end; ++k)
    if (numbered(k)) target = k;
  if (target == end) {
    const std::string where =
        p.source == 0 && begin == 0 && s.first_line > 1 && !whole_program_
            ? fmt::format(
                  " from line {} on (volmap reads the lines before line {} once, as they "
                  "come: a jump back before the first macro statement is not followed)",
                  s.first_line, s.first_line)
            : std::string();
    fail(p, at, fmt::format("GOTO {}: no block N{} in this program{}", n, n, where));
  }
  // Loops the jump leaves end; a jump into one is found at its END.
  while (!frames_.empty() && frames_.back().kind == Frame::kFanucLoop) {
    const Frame& f = frames_.back();
    const Position e = fanuc_find_end(f.start, std::stoi(f.label));
    if (f.start.source == p.source && target >= f.start.line && target <= e.line) break;
    frames_.pop_back();
  }
  return {p.source, target};
}

bool Flattener::fanuc_evaluate(const Position& p) {
  const std::string_view raw = sources_[p.source]->line(p.line);
  const std::string_view text = without_cr(raw);
  normalize(text, norm_);
  const std::string& t = norm_.text;
  const auto& col = norm_.column;
  tokens_.clear();
  line_.clear();
  if (!t.empty() && t[0] == '%') return false;
  bool any = false;
  std::size_t i = 0;
  if (!t.empty() && t[0] == '/') tokens_.push_back({0, 1}), i = 1;
  std::vector<bool> omitted;
  try {
    ValueReader r(t, params_, fanuc_, true);
    while (i < t.size()) {
      const char c = t[i];
      if (c == '(') {
        const std::size_t close = t.find(')', i);
        const std::size_t e = close == std::string::npos ? t.size() : close + 1;
        tokens_.push_back({i, e});
        i = e;
      } else if (c == ';') {
        fanuc_end_of_block(p, i);
        i = t.size();
      } else if (c == '#') {
        throw ValueError{
            "a macro statement beside NC words: a Fanuc block holds one or the "
            "other; put it on a line of its own",
            i};
      } else if (c >= 'a' && c <= 'z') {
        const std::size_t begin = i++;
        const std::size_t value_begin = i;
        const double v = r.real_value(i);
        Token tok{begin, i, c, false, v};
        const std::string_view value_text =
            std::string_view(t).substr(value_begin, i - value_begin);
        if (!ValueReader::is_literal(value_text)) {
          tok.evaluated = true;
          any = true;
          if (is_vacant(v)) {
            // `X#24` with #24 vacant: the address is left out. Anything
            // else of a vacant variable here is refused.
            if (value_text.find_first_not_of("#0123456789") != std::string_view::npos ||
                value_text.rfind('#') != 0)
              throw ValueError{"a vacant variable (never set) inside an address's expression",
                               value_begin};
            tok.letter = '\x01';  // left out
          }
        }
        tokens_.push_back(tok);
      } else {
        throw ValueError{fmt::format("unexpected character '{}'; not a G-code word", c), i};
      }
    }
  } catch (const ValueError& e) {
    fail(p, e.at, e.message);
  }
  if (!any) return false;
  for (std::size_t k = 0; k < tokens_.size(); ++k) {
    const Token& tok = tokens_[k];
    if (tok.letter == '\x01') continue;
    const std::size_t from = col[tok.begin];
    std::size_t gap = from;
    while (gap > 0 && (text[gap - 1] == ' ' || text[gap - 1] == '\t')) --gap;
    if (!line_.empty() || gap == 0) line_.append(text.substr(gap, from - gap));
    if (tok.evaluated) {
      line_ += text[from];
      append_fanuc_value(p, tok.letter, tok.begin, tok.value, line_);
    } else {
      line_.append(text.substr(from, col[tok.end - 1] + 1 - from));
    }
  }
  // (The tokens of left-out addresses stay out of fanuc_call's and
  // fanuc_g65's reading too.)
  std::erase_if(tokens_, [](const Token& tok) { return tok.letter == '\x01'; });
  if (!line_.empty() && raw.size() != text.size()) line_ += '\r';
  return true;
}

}  // namespace volmap::nc::flatten
