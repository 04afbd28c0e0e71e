// Runs the parameters, expressions and O-word control flow of an RS274NGC
// program as LinuxCNC does (its manual's "O Codes" chapter) and hands out
// the flat program: one line per block the controller would execute, with
// literal numbers. A line without parameters or expressions comes out as
// written (each time a loop or a call runs it); O-word lines and lines
// that only set parameters come out as nothing (their comments stay).
//
// The flattener evaluates a line just before the interpreter runs it, so
// the system parameters it reads (#5420.., #5220, ...) are those of the
// interpreter's state at that point, as on the controller.
//
// O-words: sub/endsub/call (numbered and named, arguments #1-#30, return
// values in #<_value>), while/endwhile, do/while, repeat/endrepeat,
// if/elseif/else/endif, break, continue, return; a subroutine not in the
// program is read from NAME.ngc on the subroutine path (LinuxCNC's
// SUBROUTINE_PATH). An O-word with a label that does not match, a call to
// a subroutine nowhere to be found, an endless loop (more than
// kMaxExecutedLines lines) are refused with file:line.
//
// Fanuc-style subprograms as LinuxCNC 2.9 runs them by default: M98 P<n>
// [L<count>] runs the lines after a bare O<n> up to M99, sharing #1-#30
// with the caller (no arguments, no return value). A bare O<n> reached in
// the main program is a label (a Fanuc program number): written as it is.
// M99 in the main program is refused (rs274 ends the program there, a
// controller may loop).
#pragma once

#include <cstddef>
#include <map>
#include <memory>
#include <optional>
#include <string>
#include <string_view>
#include <vector>

#include "gcode/flatten/expression.h"
#include "gcode/flatten/parameters.h"

namespace volmap::nc::flatten {

/// Lines a flattened program may execute (loops and calls counted): a
/// guard against an endless loop.
inline constexpr long kMaxExecutedLines = 20'000'000;
/// Nested subroutine calls: rs274 runs 9 and refuses the 10th ("Too many
/// subroutine levels").
inline constexpr int kMaxCallDepth = 9;

/// One file's lines in memory.
struct Source {
  std::string file;
  std::string data;
  int first_line = 1;               ///< the number of data's first line in the file
  std::vector<std::size_t> begins;  ///< each line's start in data; one more: the end
  std::vector<bool> newline;        ///< the line ended with '\n'
  std::size_t size() const { return newline.size(); }
  std::string_view line(std::size_t k) const;
};
/// Splits `data` into lines (a '\r' before '\n' stays with its line).
std::unique_ptr<Source> make_source(std::string file, std::string data, int first_line);

/// A line without the '\r' of a CRLF ending.
inline std::string_view without_cr(std::string_view t) {
  return !t.empty() && t.back() == '\r' ? t.substr(0, t.size() - 1) : t;
}

struct FlatLine {
  std::string_view text;  ///< valid until the next call
  const std::string* file = nullptr;
  int line = 0;
  bool newline = true;
  bool rewritten = false;  ///< evaluated: differs from the program's line
  bool verbatim = false;   ///< a bare O<n> label: written as it is, not interpreted
};

class Flattener {
 public:
  Flattener(Parameters& parameters, std::vector<std::string> subroutine_path);

  /// The program from the line where flattening begins to its end.
  void start(std::unique_ptr<Source> main);
  /// The next line the controller executes; false at the end (the end of
  /// the main program, or the program has ended: `ended`).
  bool next(FlatLine& out, bool ended);

  long executed_lines() const { return executed_; }
  /// The endless-loop guard (kMaxExecutedLines by default).
  void set_max_executed_lines(long n) { max_executed_ = n; }
  long emitted_lines() const { return emitted_; }
  /// Reads the program as Fanuc Custom Macro B (fanuc_macro.cc) instead of
  /// LinuxCNC's O-words; `variables` outlives the flattener. `whole`: the
  /// main program is flattened from its first block (every GOTO target is
  /// in it).
  void set_fanuc(FanucVariables* variables, bool whole) {
    fanuc_ = variables;
    whole_program_ = whole;
  }

 private:
  struct Position {
    std::size_t source = 0, line = 0;
  };
  struct OWord {
    std::string label;     ///< "100" or "<name>"
    std::string keyword;   ///< sub, call, while, ...
    std::size_t rest = 0;  ///< in the normalized line, after the keyword
    std::size_t at = 0;    ///< where the O-word begins
  };

  struct Frame {
    enum Kind {
      kCall,
      kWhile,
      kDo,
      kRepeat,
      kIf,
      kFanucCall,
      kFanucLoop,
      kFanucMacro
    } kind = kCall;
    std::string label;  ///< Fanuc loops: the m of DO m
    Position start;     ///< call: where to return; loops: their first line; if: the `if` line
    Position target;    ///< M98, G65: the program number's line
    long remaining = 0;
    bool taken = false;  ///< if: a branch ran; Fanuc loops: DO m without WHILE
  };

  [[noreturn]] void fail(const Position& p, std::size_t norm_at, const std::string& msg) const;
  /// Reads line p's O-word, if it has one.
  bool read_oword(const Position& p, OWord& o) const;
  /// The next O-word line after `from` in its source with `label` and one
  /// of `keywords`; fails at `from`, naming the last keyword, when there is
  /// none.
  Position find(const Position& from, const std::string& label,
                std::initializer_list<std::string_view> keywords) const;
  /// The line after q.
  static Position after(const Position& q) { return {q.source, q.line + 1}; }
  void execute_oword(const Position& p, const OWord& o);
  void sub_oword(const Position& p, const OWord& o);   ///< sub call endsub return
  void loop_oword(const Position& p, const OWord& o);  ///< do while endwhile repeat endrepeat
  void if_oword(const Position& p, const OWord& o);    ///< if elseif else endif
  void jump_oword(const Position& p, const OWord& o);  ///< break continue
  bool top_is(Frame::Kind k, const std::string& label) const;
  /// Refuses anything but a comment at i, after O-word o.
  void only_comment_after(const Position& p, const OWord& o, std::size_t i) const;
  void call(const Position& p, const OWord& o);
  Position find_sub(const Position& p, const std::string& label);
  /// A line of words: evaluated into line_ (true) or left as written (false).
  bool evaluate(const Position& p);
  /// M98 / M99 in the line evaluate() read: true when it was one (done).
  bool fanuc_call(const Position& p);
  double condition(const Position& p, const OWord& o) const;
  /// The line of program number O<label> (or :<label>) in the program and
  /// the files read; fails at `at` naming `what` (M98, G65).
  Position find_program(const Position& p, const std::string& label, std::size_t at,
                        const char* what);
  std::optional<Position> locate_program(const std::string& label) const;
  /// Fanuc: program O<label> from its own file on the subroutine path.
  std::optional<Position> load_program_file(const std::string& label);

  // fanuc_macro.cc
  /// Is `raw` a program number line (O1234, :1234)? `label`: its number.
  bool program_label(std::string_view raw, std::string& label) const;
  /// Runs line p as Fanuc Custom Macro B: true and `out` set when the
  /// control executes it as a block, false when it was a statement.
  bool fanuc_line(const Position& p, FlatLine& out);
  bool fanuc_statement(const Position& p);
  bool fanuc_condition(const ValueReader& r, std::size_t& i) const;
  int fanuc_loop_id(const Position& p, std::size_t& i) const;
  void fanuc_assignment(const Position& p, const ValueReader& r, std::size_t i);
  void only_comment_from(const Position& p, std::size_t i) const;
  /// A ';' at i: the block's end; text after it refused.
  void fanuc_end_of_block(const Position& p, std::size_t i) const;
  void push_fanuc_loop(const Position& p, int m, bool do_only);
  Position fanuc_find_end(const Position& from, int m) const;
  Position fanuc_goto(const Position& p, long n, std::size_t at);
  bool fanuc_evaluate(const Position& p);
  /// An evaluated address's value as a Fanuc control reads it.
  void append_fanuc_value(const Position& p, char letter, std::size_t at, double value,
                          std::string& out) const;
  bool fanuc_g65(const Position& p);

  Parameters& params_;
  std::vector<std::string> path_;
  std::vector<std::unique_ptr<Source>> sources_;
  std::map<std::string, Position> subs_;  ///< label -> its `sub` line
  std::vector<Frame> frames_;
  Position pc_;
  mutable NormalizedLine norm_;  ///< the line last read (read_oword() reads into it)
  std::string line_;
  struct Token {
    std::size_t begin = 0, end = 0;  ///< in the normalized line
    char letter = 0;                 ///< a word's (lower case), or 0
    bool evaluated = false;
    double value = 0.0;
  };
  std::vector<Token> tokens_;  ///< evaluate()'s
  long executed_ = 0, emitted_ = 0;
  long max_executed_ = kMaxExecutedLines;
  bool break_leaked_ = false, continue_leaked_ = false;  ///< execute_oword()'s LinuxCNC bugs
  FanucVariables* fanuc_ = nullptr;
  bool whole_program_ = false;
  std::vector<FanucLocals> macro_arguments_;  ///< each G65 frame's, for each of its L calls
};

}  // namespace volmap::nc::flatten
