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

  /// LinuxCNC's read_real_value at `i`; `i` moves past it.
  double real_value(std::size_t& i) const;
  /// A value that must be an integer (within 0.0001, then rounded).
  int integer_value(std::size_t& i) const;
  /// A bracketed expression at `i` ('[').
  double expression(std::size_t& i) const;
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

  std::string_view t_;
  const Parameters& p_;
};

}  // namespace volmap::nc::flatten
