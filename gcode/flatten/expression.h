// Values of RS274NGC words as LinuxCNC reads them (its interp_read.cc and
// the manual's "Expressions" chapter): a number, a parameter #n, #<name>,
// ##n or #[expr], a bracketed expression, a unary function, and a sign
// before any of them.
//
// The text is a normalized line (normalize()): lower case, without the
// spaces and tabs LinuxCNC drops before it reads a line. Binary operators
// by precedence, all left-associative:
//   **  >  * / MOD  >  + -  >  EQ NE GT GE LT LE  >  AND OR XOR
// EQ and NE compare within 0.0001 (LinuxCNC's TOLERANCE_EQUAL); trig
// functions take and give degrees; MOD's result has the sign of neither
// operand but lies in [0, |b|); ROUND rounds half away from zero.
#pragma once

#include <cstddef>
#include <cstdint>
#include <string>
#include <string_view>
#include <vector>

#include "gcode/flatten/fanuc_variables.h"
#include "gcode/flatten/parameters.h"

namespace volmap::nc::flatten {

/// A line as LinuxCNC reads it: letters folded to lower case, spaces and
/// tabs dropped, comments kept as written; `column[k]` is where character
/// k came from in the original line (0-based).
struct NormalizedLine {
  std::string text;
  std::vector<std::uint32_t> column;
};
void normalize(std::string_view line, NormalizedLine& out);

/// Where an assignment puts its value.
struct ParameterTarget {
  int number = 0;    ///< numbered parameter, or 0 for a named one
  std::string name;  ///< named parameter (lower case, no spaces)
};

enum class Op;

class ValueReader {
 public:
  ValueReader(std::string_view text, const Parameters& parameters) : t_(text), p_(parameters) {}
  /// Fanuc Custom Macro B (docs/post.md, "Dialects"): variables from `v`
  /// (a vacant one reads as NaN: EQ and NE tell it from 0, arithmetic
  /// and order comparisons take it as 0, as the manual's tables say;
  /// elsewhere it is refused); AND OR XOR bind like * and + there, so a
  /// bracket level that mixes them with other operators is refused, and so
  /// are the functions whose result depends on a parameter of the control
  /// (ATAN, ASIN below 0), ROUND in an NC address (rounded to the least
  /// input increment there), ** and EXISTS (LinuxCNC's). FIX and FUP cut
  /// toward and away from zero (LinuxCNC: floor and ceiling).
  ValueReader(std::string_view text, const Parameters& parameters, const FanucVariables* v,
              bool in_address)
      : t_(text), p_(parameters), fanuc_(v), in_address_(in_address) {}

  /// LinuxCNC's read_real_value at `i`; `i` moves past it.
  double real_value(std::size_t& i) const;
  /// A value that must be an integer (within 0.0001, then rounded).
  int integer_value(std::size_t& i) const;
  /// A bracketed expression at `i` ('[').
  double expression(std::size_t& i) const;
  /// An expression without brackets around it, up to the end of the line
  /// or a comment: the right side of a Fanuc assignment (`#3 = #1 * 90.`).
  double statement_value(std::size_t& i) const;
  /// The parameter an assignment at `i` ('#') sets.
  ParameterTarget target(std::size_t& i) const;
  /// Was the word value read at [begin, end) a plain number (no parameter,
  /// expression or function)? Then it is written as it was.
  static bool is_literal(std::string_view text);

 private:
  [[noreturn]] void fail(std::size_t at, std::string message) const;
  double parameter(std::size_t& i) const;
  std::string name(std::size_t& i) const;
  double unary(std::size_t& i) const;
  double number(std::size_t& i) const;
  /// The binary operator (or the closing ']') at i, past it.
  Op read_operator(std::size_t& i, std::size_t open) const;
  char at(std::size_t i) const { return i < t_.size() ? t_[i] : '\0'; }

  /// Operands and operators from i up to the ']' (or, `to_end`, the
  /// line's end or a comment); `open`: where errors say it began.
  double operations(std::size_t& i, std::size_t open, bool to_end) const;
  /// A letter at i that begins no operator (a word after a statement).
  bool word_after(std::size_t i) const;
  double fanuc_function(std::string_view fn, std::size_t begin, std::size_t& i) const;

  std::string_view t_;
  const Parameters& p_;
  const FanucVariables* fanuc_ = nullptr;
  bool in_address_ = false;
};

/// Is `v` a vacant Fanuc variable's value (NaN)?
bool is_vacant(double v);
/// ABS ACOS ASIN ATAN COS EXP FIX FUP LN ROUND SIN SQRT TAN (lower case):
/// the unary functions LinuxCNC and Fanuc share (their meanings differ
/// in places: fanuc_functions.cc).
bool is_shared_function(std::string_view fn);

}  // namespace volmap::nc::flatten
