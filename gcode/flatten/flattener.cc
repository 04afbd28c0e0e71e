#include "gcode/flatten/flattener.h"

#include <fmt/format.h>

#include <charconv>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <sstream>

#include "core/common/input_error.h"

namespace volmap::nc::flatten {

std::string_view Source::line(std::size_t k) const {
  std::size_t b = begins[k], e = begins[k + 1];
  if (newline[k]) --e;  // the '\n'
  return std::string_view(data).substr(b, e - b);
}

std::unique_ptr<Source> make_source(std::string file, std::string data, int first_line) {
  auto s = std::make_unique<Source>();
  s->file = std::move(file);
  s->data = std::move(data);
  s->first_line = first_line;
  std::size_t b = 0;
  const std::string& d = s->data;
  while (b < d.size()) {
    s->begins.push_back(b);
    const std::size_t nl = d.find('\n', b);
    if (nl == std::string::npos) {
      s->newline.push_back(false);
      b = d.size();
    } else {
      s->newline.push_back(true);
      b = nl + 1;
    }
  }
  s->begins.push_back(d.size());
  return s;
}

namespace {

bool is_word_letter(char c) { return (c >= 'a' && c <= 'z') || c == '@' || c == '^'; }

// A value as a literal: the shortest decimal that reads back to the same
// double, in fixed notation (G-code has no exponents).
void append_number(std::string& out, double v) {
  if (v == 0.0) v = 0.0;  // no "-0"
  char buf[400];
  const auto r = std::to_chars(buf, buf + sizeof buf, v, std::chars_format::fixed);
  out.append(buf, r.ptr);
}

}  // namespace

Flattener::Flattener(Parameters& parameters, std::vector<std::string> subroutine_path)
    : params_(parameters), path_(std::move(subroutine_path)) {}

void Flattener::start(std::unique_ptr<Source> main) {
  sources_.clear();
  sources_.push_back(std::move(main));
  pc_ = {};
}

void Flattener::fail(const Position& p, std::size_t norm_at, const std::string& msg) const {
  const Source& s = *sources_[p.source];
  int column = 0;
  if (norm_at < norm_.column.size()) column = static_cast<int>(norm_.column[norm_at]) + 1;
  throw InputError(s.file, s.first_line + static_cast<int>(p.line), column, msg);
}

bool Flattener::evaluate(const Position& p) {
  const std::string_view raw = sources_[p.source]->line(p.line);
  const std::string_view text = without_cr(raw);
  normalize(text, norm_);
  const std::string& t = norm_.text;
  const auto& col = norm_.column;
  std::vector<Token>& tokens = tokens_;
  tokens.clear();
  bool any = false;
  std::size_t i = 0;
  if (!t.empty() && t[0] == '%') return false;
  if (!t.empty() && t[0] == '/') tokens.push_back({0, 1}), i = 1;
  try {
    ValueReader r(t, params_);
    while (i < t.size()) {
      const char c = t[i];
      if (c == '(') {
        const std::size_t close = t.find(')', i);
        const std::size_t end = close == std::string::npos ? t.size() : close + 1;
        tokens.push_back({i, end});
        i = end;
      } else if (c == ';') {
        tokens.push_back({i, t.size()});
        i = t.size();
      } else if (c == '#') {
        const std::size_t at = i;
        ParameterTarget target = r.target(i);
        if (i >= t.size() || t[i] != '=')
          throw ValueError{"a parameter outside a word is an assignment: #1 = value", at};
        ++i;
        const double v = r.real_value(i);
        try {
          if (target.number)
            params_.queue(target.number, v);
          else
            params_.queue(std::move(target.name), v);
        } catch (ValueError& e) {
          e.at = at;
          throw;
        }
        any = true;
      } else if (is_word_letter(c)) {
        const std::size_t begin = i++;
        const std::size_t value_begin = i;
        const double v = r.real_value(i);
        Token tok{begin, i, c, false, v};
        if (!ValueReader::is_literal(std::string_view(t).substr(value_begin, i - value_begin))) {
          tok.evaluated = true;
          any = true;
        }
        tokens.push_back(tok);
      } else {
        throw ValueError{fmt::format("unexpected character '{}'; not a G-code word", c), i};
      }
    }
  } catch (const ValueError& e) {
    fail(p, e.at, e.message);
  }
  params_.commit();
  if (!any) return false;
  line_.clear();
  if (tokens.empty() || (tokens.size() == 1 && t[0] == '/')) return true;  // assignments only
  // The evaluated line: each word as written where it was a literal, its
  // value where it was computed; assignments dropped; comments kept; the
  // spaces before each kept token as they were.
  for (std::size_t k = 0; k < tokens.size(); ++k) {
    const Token& tok = tokens[k];
    const std::size_t from = col[tok.begin];
    std::size_t gap = from;
    while (gap > 0 && (text[gap - 1] == ' ' || text[gap - 1] == '\t')) --gap;
    if (k > 0 || gap == 0) line_.append(text.substr(gap, from - gap));
    if (tok.evaluated) {
      line_ += text[from];
      append_number(line_, tok.value);
    } else {
      line_.append(text.substr(from, col[tok.end - 1] + 1 - from));
    }
  }
  if (raw.size() != text.size()) line_ += '\r';
  return true;
}

bool Flattener::next(FlatLine& out, bool ended) {
  for (;;) {
    if (ended) return false;
    if (pc_.line >= sources_[pc_.source]->size()) {
      if (pc_.source == 0 && frames_.empty()) return false;
      // (A subroutine file's lines run only inside its sub, which ends it.)
      const Frame& f = frames_.back();
      if (f.kind == Frame::kFanucLoop)
        fail(f.start, static_cast<std::size_t>(-1),
             fmt::format("DO{} without END{}: the file ends inside the loop; add END{}", f.label,
                         f.label, f.label));
      static constexpr const char* kEnd[] = {"endsub", "endwhile", "while", "endrepeat",
                                             "endif",  "M99",      "END",   "M99"};
      fail(f.start, static_cast<std::size_t>(-1),
           fmt::format("O{} is not closed: the file ends before its {}; add it", f.label,
                       kEnd[f.kind]));
    }
    if (++executed_ > max_executed_) {
      fail(pc_, static_cast<std::size_t>(-1),
           fmt::format("the program runs more than {} lines; an endless loop? (volmap flattens "
                       "loops before posting)",
                       max_executed_));
    }
    const Position p = pc_;
    ++pc_.line;
    if (fanuc_) {
      if (!fanuc_line(p, out)) continue;
      ++emitted_;
      return true;
    }
    const Source& s = *sources_[p.source];
    const std::string_view raw = s.line(p.line);
    OWord o;
    const bool label = raw.find_first_of("oO") != std::string_view::npos && read_oword(p, o);
    if (label && !o.keyword.empty()) {
      execute_oword(p, o);
      continue;
    }
    // (A bare O<n> reached in the flow: a program number, written as it is.)
    const bool rewritten = !label && evaluate(p);
    if (!label && fanuc_call(p)) continue;
    if (rewritten && line_.empty()) continue;  // assignments only
    out.text = rewritten ? std::string_view(line_) : raw;
    out.file = &s.file;
    out.line = s.first_line + static_cast<int>(p.line);
    // (Only the program's last line can lack a line ending; run again by a
    // loop or a call, a line always gets one.)
    out.newline = s.newline[p.line] || p.source != 0 || !frames_.empty();
    out.rewritten = rewritten;
    out.verbatim = label;
    ++emitted_;
    return true;
  }
}

}  // namespace volmap::nc::flatten
