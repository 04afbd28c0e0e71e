// An NC program's lines as the controller runs them, for the interpreter
// and the post-processors: read in large pieces (a program of any size
// streams through in constant memory), the tape's frame set aside (a UTF-8
// byte-order mark, a Fanuc tape's leader text before the first '%', and
// what follows the closing '%': handed out verbatim, not read; LinuxCNC's
// '%' rules refused where rs274 refuses them), and, from the first line that uses parameters,
// expressions or O-word control flow on, the program flattened (flatten/flattener.h).
//
// Every line of the file comes out once, in order, until flattening
// begins; each is either a block to interpret or verbatim text to write
// as it is (not run by the controller, not interpreted). A flat program
// never pays for what it does not use: one look per line for '#', '[' and
// an O-word.
#pragma once

#include <istream>
#include <memory>
#include <string>
#include <string_view>
#include <vector>

#include "gcode/dialect.h"
#include "gcode/flatten/flattener.h"
#include "gcode/flatten/parameters.h"
#include "gcode/nc_block.h"

namespace volmap::nc {

class Interpreter;

struct ProgramLine {
  std::string_view text;  ///< without its line ending ('\r' of CRLF kept); valid until next()
  const std::string* file = nullptr;
  int line = 0;            ///< 1-based, in `file`
  bool newline = true;     ///< a '\n' followed it
  bool verbatim = false;   ///< not run by the controller: write it as it is, do not interpret
  bool rewritten = false;  ///< evaluated by the flattener
  /// From the flattened part of the program (ProgramReader::original_rest()
  /// holds what it was flattened from), its trailer included.
  bool flattened = false;
  /// A line of axis words X Y Z only (nc::lex_plain_axis_words), read
  /// already: `words` holds them. Most lines of a CAM program are such.
  bool plain = false;
  PlainAxisWords words;
};

struct ReadReport {
  bool byte_order_mark = false;
  int leader_lines = 0;        ///< lines before the first '%' (tape leader)
  int trailer_lines = 0;       ///< lines after the closing '%'
  int flattened_from = 0;      ///< the line where flattening began, 0 if it did not
  long flat_blocks = 0;        ///< lines the flattened part came out as
  long flat_source_lines = 0;  ///< lines of the program it was flattened from
  DialectChoice dialect;       ///< the dialect read, and why (auto: what decided)
};

class ProgramReader {
 public:
  /// `interp`: the interpreter the lines go to (the system parameters are
  /// its state; the dialect of its setup, `auto` resolved from the
  /// program's head before the first line, is set in it).
  /// `subroutine_path`: where O<name> call finds NAME.ngc.
  ProgramReader(std::istream& in, std::string file, Interpreter& interp,
                std::vector<std::string> subroutine_path);
  ~ProgramReader();

  bool next(ProgramLine& out);
  /// The flattener's endless-loop guard (flatten::kMaxExecutedLines).
  void set_max_executed_lines(long n) { max_executed_ = n; }
  const ReadReport& report() const { return report_; }
  const std::string& file() const { return file_; }
  /// Lines of the program file read so far (a last line without '\n'
  /// counted): all of them once next() returned false.
  long input_lines() const { return number_ + flattened_extra_lines_; }
  /// The program's text from the line where flattening began to its end,
  /// as read (empty if it did not begin): what a post that changed none
  /// of the flattened lines writes back instead of them.
  const std::string& original_rest() const { return original_rest_; }

 private:
  /// The next physical line from the stream; false at its end.
  bool physical(std::string_view& text, bool& newline);
  void fill();
  void find_leader();
  /// The dialect, `auto` resolved (report_.dialect), set in the interpreter.
  void choose_dialect();
  void start_flattening(std::string_view first, bool newline);
  /// LinuxCNC's rules for a '%' line (refused where rs274 refuses it).
  void linuxcnc_percent_line(std::string_view text, int line) const;
  /// LinuxCNC: a program opened by '%' that neither closes nor ends.
  void linuxcnc_end_of_file() const;

  std::istream& in_;
  std::string file_;
  Interpreter& interp_;
  bool fanuc_ = false;  ///< the dialect (known after the first next())
  /// Fanuc: the head has macro statements, so the program is flattened
  /// from its first block (a GOTO may jump back to any block).
  bool flatten_from_start_ = false;
  std::unique_ptr<flatten::FanucVariables> fanuc_variables_;
  std::vector<std::string> path_;
  std::vector<char> buf_;
  std::size_t begin_ = 0, end_ = 0;
  bool eof_ = false;
  int number_ = 0;
  bool started_ = false;
  int leader_left_ = 0;
  bool opened_ = false, closed_ = false;  ///< '%' seen: the first, the closing one
  bool content_seen_ = false;             ///< LinuxCNC: a line that is not blank was read
  std::unique_ptr<flatten::Parameters> params_;
  std::unique_ptr<flatten::Flattener> flat_;
  std::unique_ptr<flatten::Source> trailer_;  ///< after the closing '%' of a flattened program
  std::size_t trailer_next_ = 0;
  ReadReport report_;
  std::string original_rest_;
  long flattened_extra_lines_ = 0;  ///< lines read in for flattening beyond its first
  long max_executed_ = flatten::kMaxExecutedLines;
};

/// Does this line use parameters, expressions or an O-word (outside its
/// comments)? Then it and all that follow are flattened.
bool needs_flattening(std::string_view text);
/// The same for a Fanuc program: also a macro statement (IF, WHILE, DO,
/// END, GOTO at the block's start) or a macro call (G65, G66).
bool fanuc_needs_flattening(std::string_view text);

}  // namespace volmap::nc
