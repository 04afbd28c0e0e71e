// The O-words of the flattener (flattener.h): reading them, finding the
// lines they jump to, and running each kind (subroutines, loops,
// conditionals, Fanuc-style M98/M99 subprograms).
#include <fmt/format.h>

#include <charconv>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <optional>
#include <sstream>

#include "core/common/input_error.h"
#include "gcode/flatten/flattener.h"

namespace volmap::nc::flatten {

bool Flattener::read_oword(const Position& p, OWord& o) const {
  NormalizedLine& norm = norm_;
  normalize(without_cr(sources_[p.source]->line(p.line)), norm);
  const std::string& t = norm.text;
  std::size_t i = 0;
  if (i < t.size() && t[i] == '/') ++i;
  if (i < t.size() && t[i] == 'n') {
    ++i;
    while (i < t.size() && ((t[i] >= '0' && t[i] <= '9') || t[i] == '.')) ++i;
  }
  if (i >= t.size() || t[i] != 'o') return false;
  o.at = i++;
  if (t[0] == '/') fail(p, 0, "block delete '/' on an O-word line is not supported; remove it");
  // The label: O100, O0100, O<name>, O<100> (= O100), or computed: O[expr],
  // O#7 (rs274 reads them all; SEMANTICS.md in tests/data/flatten).
  auto all_digits = [](std::string_view d) {
    return !d.empty() && d.find_first_not_of("0123456789") == std::string_view::npos;
  };
  auto number_label = [&](std::string_view d) {
    long v = 0;
    const auto r = std::from_chars(d.data(), d.data() + d.size(), v);
    if (r.ec != std::errc()) fail(p, o.at, "O-word number out of range");
    return std::to_string(v);
  };
  if (i < t.size() && t[i] == '<') {
    const std::size_t close = t.find('>', i);
    if (close == std::string::npos) fail(p, i, "O-word name '<' is not closed; add '>'");
    const std::string_view name = std::string_view(t).substr(i + 1, close - i - 1);
    o.label = all_digits(name) ? number_label(name) : t.substr(i, close - i + 1);
    i = close + 1;
  } else if (i < t.size() && (t[i] == '[' || t[i] == '#')) {
    try {
      const int v = ValueReader(t, params_).integer_value(i);
      if (v < 0) fail(p, o.at, "a negative O-word number");
      o.label = std::to_string(v);
    } catch (const ValueError& e) {
      fail(p, e.at, e.message);
    }
  } else {
    const std::size_t b = i;
    while (i < t.size() && t[i] >= '0' && t[i] <= '9') ++i;
    if (i == b) fail(p, o.at, "an O-word needs a number or a <name> (O100, O<name>)");
    o.label = number_label(std::string_view(t).substr(b, i - b));
  }
  const std::size_t k = i;
  while (i < t.size() && t[i] >= 'a' && t[i] <= 'z') ++i;
  o.keyword = t.substr(k, i - k);
  o.rest = i;
  static constexpr std::string_view kKeywords[] = {
      "sub",  "endsub", "call",   "do",        "while", "endwhile", "if",    "elseif",
      "else", "endif",  "repeat", "endrepeat", "break", "continue", "return"};
  bool known = false;
  for (std::string_view kw : kKeywords) known = known || kw == o.keyword;
  if (o.keyword.empty() && (i >= t.size() || t[i] == '(' || t[i] == ';')) {
    if (o.label.front() == '<')
      fail(
          p, o.at,
          fmt::format("O{} without a keyword; a named O-word needs one (sub, call, ...)", o.label));
    return true;  // a bare O<n>: a Fanuc program number or M98 label
  }
  if (!known) {
    fail(p, k,
         fmt::format("unknown O-word keyword '{}'; LinuxCNC's are sub endsub call do while "
                     "endwhile if elseif else endif repeat endrepeat break continue return",
                     o.keyword));
  }
  return true;
}

Flattener::Position Flattener::find(const Position& from, const std::string& label,
                                    std::initializer_list<std::string_view> keywords) const {
  const Source& s = *sources_[from.source];
  OWord o;
  for (Position p = after(from); p.line < s.size(); ++p.line) {
    // A cheap look first: most lines are not O-words.
    const std::string_view l = s.line(p.line);
    if (l.find_first_of("oO") == std::string_view::npos) continue;
    if (!read_oword(p, o) || o.label != label) continue;
    for (std::string_view kw : keywords)
      if (o.keyword == kw) return p;
  }
  read_oword(from, o);
  fail(from, o.at,
       fmt::format("no {} for O{} in {}; add it", *(keywords.end() - 1), label, s.file));
}

double Flattener::condition(const Position& p, const OWord& o) const {
  std::size_t i = o.rest;
  const std::string& t = norm_.text;
  if (i >= t.size() || t[i] != '[')
    fail(p, i, fmt::format("O{} {} needs a condition in [ ]", o.label, o.keyword));
  double v = 0.0;
  try {
    v = ValueReader(t, params_).expression(i);
  } catch (const ValueError& e) {
    fail(p, e.at, e.message);
  }
  if (i < t.size() && t[i] != '(' && t[i] != ';')
    fail(p, i,
         fmt::format("only a comment may follow O{} {} [...]; put the rest on a line of its "
                     "own",
                     o.label, o.keyword));
  return v;
}

Flattener::Position Flattener::find_sub(const Position& p, const std::string& label) {
  if (const auto it = subs_.find(label); it != subs_.end()) return it->second;
  // Defined further on in the program.
  OWord o;
  const Source& main = *sources_[0];
  for (Position q{0, 0}; q.line < main.size(); ++q.line) {
    if (main.line(q.line).find_first_of("oO") == std::string_view::npos) continue;
    if (read_oword(q, o) && o.label == label && o.keyword == "sub") return subs_[label] = q;
  }
  // A file of its own on the subroutine path: NAME.ngc (LinuxCNC: 123.ngc
  // for O123).
  {
    const std::string name = label.front() == '<' ? label.substr(1, label.size() - 2) : label;
    for (const std::string& dir : path_) {
      const std::filesystem::path f = std::filesystem::path(dir) / (name + ".ngc");
      std::ifstream in(f, std::ios::binary);
      if (!in) continue;
      std::ostringstream data;
      data << in.rdbuf();
      sources_.push_back(make_source(f.string(), std::move(data).str(), 1));
      const std::size_t index = sources_.size() - 1;
      const Source& s = *sources_.back();
      for (Position q{index, 0}; q.line < s.size(); ++q.line) {
        if (s.line(q.line).find_first_of("oO") == std::string_view::npos) continue;
        if (read_oword(q, o) && o.label == label && o.keyword == "sub") return subs_[label] = q;
      }
      read_oword(p, o);
      fail(p, o.at,
           fmt::format("{} has no `o{} sub`; a subroutine file defines the subroutine "
                       "it is named after",
                       f.string(), label));
    }
  }
  read_oword(p, o);
  std::string where;
  for (const std::string& dir : path_) where += (where.empty() ? "" : ":") + dir;
  fail(p, o.at,
       fmt::format("subroutine O{} is not defined in the program, and {}.ngc is not on the "
                   "subroutine path ({}); give `--subroutine-path`",
                   label, label.front() == '<' ? label.substr(1, label.size() - 2) : label, where));
}

void Flattener::call(const Position& p, const OWord& o) {
  std::vector<double> args;
  std::size_t i = o.rest;
  const std::string t = norm_.text;  // (find_sub reads other lines into norm_)
  try {
    ValueReader r(t, params_);
    while (i < t.size() && t[i] == '[') args.push_back(r.expression(i));
  } catch (const ValueError& e) {
    fail(p, e.at, e.message);
  }
  if (i < t.size() && t[i] != '(' && t[i] != ';')
    fail(p, i, "a call's arguments are values in [ ]: o100 call [1] [2.5]");
  if (args.size() > static_cast<std::size_t>(kArgumentCount))
    fail(p, o.at, fmt::format("more than {} arguments", kArgumentCount));
  int depth = 0;
  for (const Frame& f : frames_) depth += f.kind == Frame::kCall || f.kind == Frame::kFanucCall;
  if (depth >= kMaxCallDepth)
    fail(p, o.at,
         fmt::format("subroutine calls nested deeper than {} (LinuxCNC's limit); an "
                     "endless recursion?",
                     kMaxCallDepth));
  const Position sub = find_sub(p, o.label);
  Frame f;
  f.kind = Frame::kCall;
  f.label = o.label;
  f.start = after(p);
  frames_.push_back(f);
  params_.push_call(args);
  pc_ = after(sub);
}

void Flattener::execute_oword(const Position& p, const OWord& o) {
  const std::string& kw = o.keyword;
  if (kw.empty()) return;  // a bare label run through (next() writes it)
  if (kw == "sub" || kw == "call" || kw == "endsub" || kw == "return") return sub_oword(p, o);
  if (kw == "if" || kw == "elseif" || kw == "else" || kw == "endif") return if_oword(p, o);
  if (kw == "break" || kw == "continue") return jump_oword(p, o);
  loop_oword(p, o);
}

bool Flattener::top_is(Frame::Kind k, const std::string& label) const {
  return !frames_.empty() && frames_.back().kind == k && frames_.back().label == label;
}

void Flattener::only_comment_after(const Position& p, const OWord& o, std::size_t i) const {
  const std::string& t = norm_.text;
  if (i < t.size() && t[i] != '(' && t[i] != ';')
    fail(p, i, fmt::format("unexpected text after O{} {}", o.label, o.keyword));
}

void Flattener::sub_oword(const Position& p, const OWord& o) {
  const std::string& kw = o.keyword;
  if (kw == "sub") {
    if (const auto it = subs_.find(o.label);
        it != subs_.end() && (it->second.source != p.source || it->second.line != p.line))
      fail(p, o.at, fmt::format("subroutine O{} is defined twice", o.label));
    subs_[o.label] = p;
    pc_ = after(find(p, o.label, {"endsub"}));
    return;
  }
  if (kw == "call") return call(p, o);
  if (kw == "endsub" || kw == "return") {
    std::optional<double> value;
    std::size_t i = o.rest;
    if (i < norm_.text.size() && norm_.text[i] == '[') {
      try {
        value = ValueReader(norm_.text, params_).expression(i);
      } catch (const ValueError& e) {
        fail(p, e.at, e.message);
      }
    }
    only_comment_after(p, o, i);
    while (!frames_.empty() && frames_.back().kind != Frame::kCall) frames_.pop_back();
    if (frames_.empty() || frames_.back().label != o.label)
      fail(p, o.at,
           frames_.empty() ? fmt::format("O{} {} outside a call of O{}", o.label, kw, o.label)
                           : fmt::format("O{} {} inside O{}; the labels must match", o.label, kw,
                                         frames_.back().label));
    params_.set_return(value);
    params_.pop_call();
    pc_ = frames_.back().start;
    frames_.pop_back();
    return;
  }
}

void Flattener::loop_oword(const Position& p, const OWord& o) {
  const std::string& kw = o.keyword;
  if (kw == "do") {
    only_comment_after(p, o, o.rest);
    frames_.push_back({Frame::kDo, o.label, p, {}, 0, false});
    return;
  }
  if (kw == "while") {
    const double c = condition(p, o);
    if (top_is(Frame::kDo, o.label)) {  // the end of a do loop
      if (c != 0.0 && break_leaked_)
        fail(p, o.at,
             "a do loop after a break out of a while loop: LinuxCNC 2.9 runs it only "
             "once (a known interpreter bug); restructure the loops");
      if (c != 0.0)
        pc_ = after(frames_.back().start);
      else
        frames_.pop_back();
      return;
    }
    if (c != 0.0) {
      frames_.push_back({Frame::kWhile, o.label, p, {}, 0, false});
    } else {
      pc_ = after(find(p, o.label, {"endwhile"}));
    }
    return;
  }
  if (kw == "endwhile") {
    only_comment_after(p, o, o.rest);
    if (!top_is(Frame::kWhile, o.label))
      fail(p, o.at, fmt::format("O{} endwhile without its O{} while", o.label, o.label));
    pc_ = frames_.back().start;  // the condition again
    frames_.pop_back();
    return;
  }
  if (kw == "repeat") {
    const double n = condition(p, o);
    const double rounded = std::nearbyint(n);  // half to even, as LinuxCNC
    if (rounded > 1e9) fail(p, o.rest, "a repeat count above 10^9");
    const long count = static_cast<long>(rounded);
    if (count > 0) {
      frames_.push_back({Frame::kRepeat, o.label, p, {}, count, false});
    } else {
      pc_ = after(find(p, o.label, {"endrepeat"}));
    }
    return;
  }
  if (kw == "endrepeat") {
    only_comment_after(p, o, o.rest);
    if (!top_is(Frame::kRepeat, o.label))
      fail(p, o.at, fmt::format("O{} endrepeat without its O{} repeat", o.label, o.label));
    Frame& f = frames_.back();
    if (--f.remaining > 0)
      pc_ = after(f.start);
    else
      frames_.pop_back();
    return;
  }
}

void Flattener::if_oword(const Position& p, const OWord& o) {
  const std::string& kw = o.keyword;
  if (kw == "if") {
    const double c = condition(p, o);
    frames_.push_back({Frame::kIf, o.label, p, {}, 0, c != 0.0});
    if (c == 0.0) pc_ = find(p, o.label, {"elseif", "else", "endif"});
    return;
  }
  if (kw == "elseif" || kw == "else") {
    if (!top_is(Frame::kIf, o.label))
      fail(p, o.at, fmt::format("O{} {} without its O{} if", o.label, kw, o.label));
    Frame& f = frames_.back();
    if (f.taken) {
      pc_ = find(p, o.label, {"endif"});
      return;
    }
    if (kw == "else") {
      only_comment_after(p, o, o.rest);
      f.taken = true;
      return;
    }
    const double c = condition(p, o);
    if (c != 0.0)
      frames_.back().taken = true;
    else
      pc_ = find(p, o.label, {"elseif", "else", "endif"});
    return;
  }
  if (kw == "endif") {
    only_comment_after(p, o, o.rest);
    if (!top_is(Frame::kIf, o.label))
      fail(p, o.at, fmt::format("O{} endif without its O{} if", o.label, o.label));
    frames_.pop_back();
    return;
  }
}

void Flattener::jump_oword(const Position& p, const OWord& o) {
  const std::string& kw = o.keyword;
  // break, continue: the innermost loop of this label, leaving the ifs and
  // loops inside it (not a call).
  only_comment_after(p, o, o.rest);
  std::size_t k = frames_.size();
  while (k > 0 && frames_[k - 1].label != o.label && frames_[k - 1].kind != Frame::kCall &&
         frames_[k - 1].kind != Frame::kFanucCall)
    --k;
  if (k == 0 || frames_[k - 1].label != o.label || frames_[k - 1].kind == Frame::kCall ||
      frames_[k - 1].kind == Frame::kFanucCall || frames_[k - 1].kind == Frame::kIf)
    fail(p, o.at, fmt::format("O{} {} outside a loop of label O{}", o.label, kw, o.label));
  if (frames_[k - 1].kind == Frame::kRepeat)
    fail(p, o.at,
         fmt::format("O{} {} inside a repeat loop: LinuxCNC allows it in while and do "
                     "loops only; use a while loop",
                     o.label, kw));
  frames_.resize(k);
  const Frame f = frames_.back();
  // LinuxCNC 2.9's interpreter leaks these two (SEMANTICS.md in
  // tests/data/flatten): a break out of a while loop makes the next do loop
  // stop after one pass; a continue in a do loop makes a later break loop
  // once more. Where that would change what runs, volmap refuses.
  if (kw == "break" && continue_leaked_)
    fail(p, o.at,
         "a break after a continue in a do loop: LinuxCNC 2.9 runs such a loop once "
         "more than written (a known interpreter bug); restructure the loops");
  if (kw == "break" && f.kind == Frame::kWhile) break_leaked_ = true;
  if (kw == "continue" && f.kind == Frame::kDo) continue_leaked_ = true;
  if (kw == "break") {
    frames_.pop_back();
    const char* end = f.kind == Frame::kWhile ? "endwhile"
                      : f.kind == Frame::kDo  ? "while"
                                              : "endrepeat";
    pc_ = after(find(p, o.label, {end}));
    return;
  }
  // continue
  if (f.kind == Frame::kWhile) {
    pc_ = f.start;
    frames_.pop_back();
  } else {
    const char* end = f.kind == Frame::kDo ? "while" : "endrepeat";
    pc_ = find(p, o.label, {end});
  }
}

}  // namespace volmap::nc::flatten
