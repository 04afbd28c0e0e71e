// The flattener's calls of programs in the file (flattener.h): Fanuc-style
// M98/M99 subprograms (LinuxCNC runs them too) and, in the Fanuc dialect,
// G65 macro calls (Fanuc's Series 0i-MF operator's manual, B-64604EN,
// "Custom macro"):
// - G65 P<program> L<times> <arguments>: a macro call with its own local
//   variables, the arguments by argument specification I (A=#1 B=#2 C=#3
//   I=#4 J=#5 K=#6 D=#7 E=#8 F=#9 H=#11 M=#13 Q=#17 R=#18 S=#19 T=#20
//   U=#21 V=#22 W=#23 X=#24 Y=#25 Z=#26); M99 returns;
// - M98 P<program> L<times>, or (Fanuc) P with the times in the digits
//   before the last four (0i: P30010 runs O0010 three times), shares the
//   caller's variables; M99 returns.
#include <fmt/format.h>

#include <cmath>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <optional>
#include <sstream>

#include "core/common/input_error.h"
#include "gcode/flatten/flattener.h"

namespace volmap::nc::flatten {
namespace {

// The argument letters of G65 (specification I) and their variables.
int argument_variable(char letter) {
  switch (letter) {
    case 'a':
      return 1;
    case 'b':
      return 2;
    case 'c':
      return 3;
    case 'i':
      return 4;
    case 'j':
      return 5;
    case 'k':
      return 6;
    case 'd':
      return 7;
    case 'e':
      return 8;
    case 'f':
      return 9;
    case 'h':
      return 11;
    case 'm':
      return 13;
    case 'q':
      return 17;
    case 'r':
      return 18;
    case 's':
      return 19;
    case 't':
      return 20;
    case 'u':
      return 21;
    case 'v':
      return 22;
    case 'w':
      return 23;
    case 'x':
      return 24;
    case 'y':
      return 25;
    case 'z':
      return 26;
    default:
      return 0;
  }
}

}  // namespace

std::optional<Flattener::Position> Flattener::locate_program(const std::string& label) const {
  // A bare O<n> line of the program (Fanuc: or :<n>).
  std::string found;
  OWord o;
  for (std::size_t k = 0; k < sources_.size(); ++k) {
    const Source& s = *sources_[k];
    for (Position q{k, 0}; q.line < s.size(); ++q.line) {
      const std::string_view raw = s.line(q.line);
      if (raw.find_first_of(fanuc_ ? "oO:" : "oO") == std::string_view::npos) continue;
      if (fanuc_ ? program_label(raw, found) && found == label
                 : read_oword(q, o) && o.keyword.empty() && o.label == label)
        return q;
    }
  }
  return std::nullopt;
}

std::optional<Flattener::Position> Flattener::load_program_file(const std::string& label) {
  // A Fanuc control keeps its macros and subprograms as programs of their
  // own (O9810 ...): a file on the subroutine path named after the number,
  // O9810, O9810.nc or 9810.nc (the number with at least 4 digits, or as
  // written), holding that program.
  const std::string padded = std::string(label.size() < 4 ? 4 - label.size() : 0, '0') + label;
  for (const std::string& dir : path_)
    for (const std::string& name :
         {"O" + padded, "O" + padded + ".nc", padded + ".nc", "O" + label + ".nc", label + ".nc"}) {
      const std::filesystem::path f = std::filesystem::path(dir) / name;
      std::ifstream in(f, std::ios::binary);
      if (!in) continue;
      std::ostringstream data;
      data << in.rdbuf();
      sources_.push_back(make_source(f.string(), std::move(data).str(), 1));
      if (const std::optional<Position> q = locate_program(label)) return q;
      sources_.pop_back();  // not the program it is named after
    }
  return std::nullopt;
}

Flattener::Position Flattener::find_program(const Position& p, const std::string& label,
                                            std::size_t at, const char* what) {
  if (const std::optional<Position> q = locate_program(label)) return *q;
  if (fanuc_)
    if (const std::optional<Position> q = load_program_file(label)) return *q;
  fail(p, at,
       fmt::format("{} P{}: the program has no O{} line{}; add the {} (O{} ... M99) after the "
                   "main program's M30",
                   what, label, label,
                   fanuc_ ? fmt::format(" and no file O{} or O{}.nc is on the subroutine path "
                                        "(--subroutine-path, default the program's folder)",
                                        label, label)
                          : "",
                   std::string_view(what) == "G65" ? "macro" : "subprogram", label));
}

bool Flattener::fanuc_call(const Position& p) {
  const Token *m98 = nullptr, *m99 = nullptr, *pw = nullptr, *lw = nullptr;
  for (const Token& tok : tokens_) {
    if (tok.letter == 'm' && tok.value == 98.0) m98 = &tok;
    if (tok.letter == 'm' && tok.value == 99.0) m99 = &tok;
    if (tok.letter == 'p') pw = &tok;
    if (tok.letter == 'l') lw = &tok;
  }
  if (!m98 && !m99) return false;
  const Token* code = m98 ? m98 : m99;
  for (const Token& tok : tokens_)
    if (tok.letter != 0 && tok.letter != 'n' && &tok != code && &tok != pw && &tok != lw)
      fail(p, tok.begin,
           fmt::format("M{} with other words in one block; put it on a line of its own",
                       m98 ? 98 : 99));
  if (m98 && m99) fail(p, m99->begin, "M98 and M99 in one block");
  if (m99) {
    if (pw) fail(p, pw->begin, "M99 P (a jump to a sequence number) is not supported");
    while (!frames_.empty() && frames_.back().kind != Frame::kCall &&
           frames_.back().kind != Frame::kFanucCall && frames_.back().kind != Frame::kFanucMacro)
      frames_.pop_back();
    if (frames_.empty() || frames_.back().kind == Frame::kCall)
      fail(p, m99->begin,
           "M99 outside an M98 subprogram: rs274 ends the program here, other controllers run it "
           "again from the start; end it with M30 (or M2)");
    Frame& f = frames_.back();
    if (f.kind == Frame::kFanucMacro) {
      fanuc_->pop_call();  // G65's locals end; another call gets fresh ones
      if (--f.remaining > 0) fanuc_->push_call(macro_arguments_.back());
    }
    if (f.remaining > 0 && f.kind == Frame::kFanucMacro) {
      pc_ = after(f.target);
    } else if (f.kind == Frame::kFanucMacro) {
      pc_ = f.start;
      frames_.pop_back();
      macro_arguments_.pop_back();
    } else if (--f.remaining > 0) {
      pc_ = after(f.target);
    } else {
      pc_ = f.start;
      frames_.pop_back();
    }
    return true;
  }
  auto integer = [&](const Token* tok, const char* what) {
    const double v = tok->value;
    if (v != std::floor(v) || v < 0 || v > 99999)
      fail(p, tok->begin, fmt::format("M98's {} must be a whole number from 0 to 99999", what));
    return static_cast<long>(v);
  };
  if (!pw) fail(p, m98->begin, "M98 without P: give the subprogram's number (M98 P100)");
  std::string label = std::to_string(integer(pw, "P"));
  long count = lw ? integer(lw, "L") : 1;
  if (fanuc_ && pw->value > 9999) {
    // Fanuc 0i: the digits before the last four count the calls (P30010:
    // O0010 three times); Haas and 8-digit program numbers: P is the
    // number. Whichever program the file has decides; both: refused.
    const std::string short_label = std::to_string(static_cast<long>(pw->value) % 10000);
    // (Programs stored on their own count too: load_program_file.)
    const bool whole = locate_program(label).has_value() || load_program_file(label).has_value();
    const bool split =
        locate_program(short_label).has_value() || load_program_file(short_label).has_value();
    if (whole && split)
      fail(p, pw->begin,
           fmt::format("M98 P{}: the file has O{} and O{}, and which one runs "
                       "depends on the control (4-digit program numbers with the "
                       "count before them, or 8-digit ones); renumber one",
                       label, label, short_label));
    if (split) {
      if (lw) fail(p, lw->begin, "M98 with both L and a count in P's leading digits");
      count = static_cast<long>(pw->value) / 10000;
      label = short_label;
    }
  }
  if (count == 0) return true;  // L0 calls nothing
  int depth = 0;
  for (const Frame& f : frames_) depth += f.kind == Frame::kCall || f.kind == Frame::kFanucCall;
  if (depth >= kMaxCallDepth)
    fail(p, m98->begin,
         fmt::format("subprogram calls nested deeper than {} (LinuxCNC's limit)", kMaxCallDepth));
  Frame f;
  f.kind = Frame::kFanucCall;
  f.label = label;
  f.start = after(p);
  f.target = find_program(p, label, pw->begin, "M98");
  f.remaining = count;
  frames_.push_back(f);
  pc_ = after(f.target);
  return true;
}

bool Flattener::fanuc_g65(const Position& p) {
  const Token* g65 = nullptr;
  for (const Token& tok : tokens_)
    if (tok.letter == 'g' &&
        (tok.value == 65.0 || tok.value == 66.0 || tok.value == 67.0 || tok.value == 66.1)) {
      if (tok.value != 65.0)
        fail(p, tok.begin,
             fmt::format("G{:g}: modal macro calls are not read; call the macro "
                         "with G65 at each point",
                         tok.value));
      g65 = &tok;
    }
  if (!g65) return false;
  const std::string& t = norm_.text;
  FanucLocals args{};
  const Token *pw = nullptr, *lw = nullptr;
  int last_ijk = 0;
  for (const Token& tok : tokens_) {
    if (tok.letter == 0 || &tok == g65 || tok.letter == 'n') continue;
    if (&tok < g65)
      fail(p, tok.begin, "a word before G65: the manual puts G65 before its arguments; move it");
    if (const int ijk = tok.letter == 'i' ? 1 : tok.letter == 'j' ? 2 : tok.letter == 'k' ? 3 : 0) {
      if (ijk < last_ijk)
        fail(p, tok.begin,
             "I J K out of order: a control may read them as argument "
             "specification II (a new set); write them in the order I J K");
      last_ijk = ijk;
    }
    if (tok.letter == 'p') {
      pw = &tok;
      continue;
    }
    if (tok.letter == 'l') {
      lw = &tok;
      continue;
    }
    const int v = argument_variable(tok.letter);
    if (v == 0)
      fail(p, tok.begin,
           fmt::format("{} is not an argument of G65 (specification I)",
                       static_cast<char>(tok.letter - 'a' + 'A')));
    if (args[static_cast<std::size_t>(v)])
      fail(p, tok.begin, "an argument given twice (argument specification II) is not read");
    if (!tok.evaluated && std::strchr("xyzabcijkrquvw", tok.letter) && tok.value != 0.0 &&
        t.find('.', tok.begin) >= tok.end)
      fail(p, tok.begin,
           fmt::format("the argument {} has no decimal point: a Fanuc control "
                       "reads it in least input increments unless parameter "
                       "3401#0 says otherwise; write it with the point",
                       static_cast<char>(tok.letter - 'a' + 'A')));
    args[static_cast<std::size_t>(v)] = tok.value;
  }
  if (!pw) fail(p, g65->begin, "G65 without P: give the macro's program number (G65 P9010)");
  if (pw->value != std::floor(pw->value) || pw->value < 1 || pw->value > 99999999)
    fail(p, pw->begin, "G65's P is a program number");
  const double times = lw ? lw->value : 1.0;
  if (times != std::floor(times) || times < 1 || times > 9999)
    fail(p, lw->begin, "G65's L is the number of calls, 1 to 9999");
  int depth = 0;
  for (const Frame& f : frames_)
    depth += f.kind == Frame::kCall || f.kind == Frame::kFanucCall || f.kind == Frame::kFanucMacro;
  if (depth >= kMaxCallDepth)
    fail(p, g65->begin, fmt::format("calls nested deeper than {}", kMaxCallDepth));
  const std::string label = fmt::format("{}", static_cast<long>(pw->value));
  Frame f;
  f.kind = Frame::kFanucMacro;
  f.label = label;
  f.start = after(p);
  f.target = find_program(p, label, pw->begin, "G65");
  f.remaining = static_cast<long>(times);
  frames_.push_back(f);
  macro_arguments_.push_back(args);
  fanuc_->push_call(args);
  pc_ = after(f.target);
  return true;
}

}  // namespace volmap::nc::flatten
