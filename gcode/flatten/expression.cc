#include "gcode/flatten/expression.h"

#include <fmt/format.h>

#include <charconv>
#include <cmath>
#include <limits>
#include <numbers>

namespace volmap::nc::flatten {
namespace {

constexpr double kRadPerDeg = std::numbers::pi / 180.0;
constexpr double kDegPerRad = 180.0 / std::numbers::pi;
/// LinuxCNC's TOLERANCE_EQUAL: EQ and NE, and how close to an integer an
/// integer value must be.
constexpr double kToleranceEqual = 0.0001;

}  // namespace

// (Declared in the header, for read_operator().)
enum class Op {
  kPower,
  kTimes,
  kDivide,
  kMod,
  kPlus,
  kMinus,
  kEq,
  kNe,
  kGt,
  kGe,
  kLt,
  kLe,
  kAnd,
  kOr,
  kXor,
  kClose
};

namespace {

int precedence(Op op) {
  switch (op) {
    case Op::kPower:
      return 6;
    case Op::kTimes:
    case Op::kDivide:
    case Op::kMod:
      return 5;
    case Op::kPlus:
    case Op::kMinus:
      return 4;
    case Op::kEq:
    case Op::kNe:
    case Op::kGt:
    case Op::kGe:
    case Op::kLt:
    case Op::kLe:
      return 3;
    case Op::kAnd:
    case Op::kOr:
    case Op::kXor:
      return 2;
    case Op::kClose:
      return 1;
  }
  return 1;
}

bool is_letter(char c) { return c >= 'a' && c <= 'z'; }

bool is_logic(Op op) { return op == Op::kAnd || op == Op::kOr || op == Op::kXor; }
bool is_comparison(Op op) { return op >= Op::kEq && op <= Op::kLe; }

// Fanuc's rules before the operation (ValueReader's Fanuc constructor):
// vacant operands, comparisons too close to call, bitwise AND OR XOR on
// other values than 0 and 1, MOD of negative or fractional values. Sets
// `a` and returns true when it decided the operation itself.
bool fanuc_operands(Op op, double& a, double& b, const char*& why) {
  const bool va = std::isnan(a), vb = std::isnan(b);
  if ((op == Op::kEq || op == Op::kNe) && (va || vb)) {
    // The manual's table: #1 EQ #0 holds for a vacant #1, #1 NE 0 too.
    a = ((va && vb) == (op == Op::kEq)) ? 1.0 : 0.0;
    return true;
  }
  if (va) a = 0.0;  // "<vacant> is 0 in operations and in GE GT LE LT"
  if (vb) b = 0.0;
  if (is_comparison(op)) {
    const double d = std::abs(a - b), scale = std::max({1.0, std::abs(a), std::abs(b)});
    if (d > 1e-9 * scale && d < kToleranceEqual)
      why =
          "a comparison of values closer than 0.0001 but not equal: whether a Fanuc control "
          "counts them equal depends on its arithmetic; round them first (ROUND, FIX)";
    else if (d <= 1e-9 * scale)
      b = a;  // equal to the last bits of a double: equal on the control too
  }
  if (is_logic(op) && ((a != 0.0 && a != 1.0) || (b != 0.0 && b != 1.0)))
    why =
        "AND, OR or XOR of values other than 0 and 1: a Fanuc control combines the bits of "
        "the binary integers, LinuxCNC their truth; compare first ([#1 EQ 1] AND ...)";
  if (op == Op::kMod && (a < 0 || b <= 0 || a != std::floor(a) || b != std::floor(b)))
    why = "MOD of a negative or fractional value: its result differs between Fanuc controls";
  if (op == Op::kPower) why = "** is LinuxCNC's power operator, not Fanuc's";
  return false;
}

// a = a op b, as LinuxCNC's execute_binary (Fanuc's rules first when
// `fanuc`); the reason it is refused, or nullptr.
const char* apply(Op op, double& a, double b, bool fanuc) {
  if (fanuc) {
    const char* why = nullptr;
    if (fanuc_operands(op, a, b, why)) return nullptr;
    if (why) return why;
  }
  switch (op) {
    case Op::kPower:
      if (a < 0.0 && std::floor(b) != b) return "a negative number to a non-integer power";
      a = std::pow(a, b);
      break;
    case Op::kTimes:
      a *= b;
      break;
    case Op::kDivide:
      if (b == 0.0) return "division by zero";
      a /= b;
      break;
    case Op::kMod:
      if (b == 0.0) return "MOD by zero";
      a = std::fmod(a, b);
      if (a < 0.0) a += std::abs(b);
      break;
    case Op::kPlus:
      a += b;
      break;
    case Op::kMinus:
      a -= b;
      break;
    case Op::kEq:
      a = std::abs(a - b) < kToleranceEqual ? 1.0 : 0.0;
      break;
    case Op::kNe:
      a = std::abs(a - b) >= kToleranceEqual ? 1.0 : 0.0;
      break;
    case Op::kGt:
      a = a > b ? 1.0 : 0.0;
      break;
    case Op::kGe:
      a = a >= b ? 1.0 : 0.0;
      break;
    case Op::kLt:
      a = a < b ? 1.0 : 0.0;
      break;
    case Op::kLe:
      a = a <= b ? 1.0 : 0.0;
      break;
    case Op::kAnd:
      a = (a != 0.0 && b != 0.0) ? 1.0 : 0.0;
      break;
    case Op::kOr:
      a = (a != 0.0 || b != 0.0) ? 1.0 : 0.0;
      break;
    case Op::kXor:
      a = ((a != 0.0) != (b != 0.0)) ? 1.0 : 0.0;
      break;
    case Op::kClose:
      break;
  }
  return std::isfinite(a) ? nullptr : "the expression's value is not a finite number";
}
bool is_digit(char c) { return c >= '0' && c <= '9'; }

}  // namespace

bool is_vacant(double v) { return std::isnan(v); }

bool is_shared_function(std::string_view fn) {
  static constexpr std::string_view kFunctions[] = {"abs", "acos", "asin", "atan", "cos",
                                                    "exp", "fix",  "fup",  "ln",   "round",
                                                    "sin", "sqrt", "tan"};
  for (std::string_view f : kFunctions)
    if (f == fn) return true;
  return false;
}

void normalize(std::string_view line, NormalizedLine& out) {
  out.text.clear();
  out.column.clear();
  char comment_end = 0;  // ')' inside ( ), '\n' after ';'
  for (std::size_t k = 0; k < line.size(); ++k) {
    char c = line[k];
    if (comment_end == 0) {
      if (c == ' ' || c == '\t') continue;
      if (c == '(') comment_end = ')';
      if (c == ';') comment_end = '\n';
      if (c >= 'A' && c <= 'Z') c = static_cast<char>(c - 'A' + 'a');
    } else if (c == comment_end) {
      comment_end = 0;
    }
    out.text += c;
    out.column.push_back(static_cast<std::uint32_t>(k));
  }
}

void ValueReader::fail(std::size_t at, std::string message) const {
  throw ValueError{std::move(message), at};
}

bool ValueReader::is_literal(std::string_view text) {
  std::size_t k = 0;
  if (k < text.size() && (text[k] == '+' || text[k] == '-')) ++k;
  bool digits = false;
  for (; k < text.size(); ++k) {
    if (is_digit(text[k]))
      digits = true;
    else if (text[k] != '.')
      return false;
  }
  return digits;
}

double ValueReader::number(std::size_t& i) const {
  const std::size_t begin = i;
  if (at(i) == '+' || at(i) == '-') ++i;
  bool point = false, digits = false;
  for (;; ++i) {
    const char c = at(i);
    if (is_digit(c)) {
      digits = true;
    } else if (c == '.' && !point) {
      point = true;
    } else {
      break;
    }
  }
  if (!digits)
    fail(begin, begin < t_.size() ? fmt::format("'{}' is not a number, a parameter or an "
                                                "expression",
                                                t_[begin])
                                  : std::string("a value is missing at the end of the line"));
  double v = 0;
  const char* first = t_.data() + begin + (t_[begin] == '+' ? 1 : 0);
  const auto r = std::from_chars(first, t_.data() + i, v);
  if (r.ec != std::errc() || !std::isfinite(v)) fail(begin, "bad number");
  return v;
}

double ValueReader::real_value(std::size_t& i) const {
  const char c = at(i), c1 = at(i + 1);
  if (c == '[') return expression(i);
  if (c == '#') return parameter(i);
  if ((c == '+' || c == '-') && c1 != '\0' && !is_digit(c1) && c1 != '.') {
    ++i;
    const std::size_t at_value = i;
    const double v = real_value(i);
    if (std::isnan(v)) fail(at_value, "a sign before a vacant variable (never set)");
    return c == '-' ? -v : v;
  }
  if (is_letter(c)) return unary(i);
  return number(i);
}

int ValueReader::integer_value(std::size_t& i) const {
  const std::size_t begin = i;
  const double v = real_value(i);
  if (std::isnan(v)) fail(begin, "a vacant variable (never set) where a number is needed");
  const double r = std::floor(v + 0.5);
  if (std::abs(v - r) > kToleranceEqual)
    fail(begin, fmt::format("{} is not an integer, and an integer is needed here", v));
  if (std::abs(r) > 1e9) fail(begin, "integer out of range");
  return static_cast<int>(r);
}

std::string ValueReader::name(std::size_t& i) const {
  // At '<': up to '>'. (normalize() dropped the spaces and folded the case,
  // as LinuxCNC does with names.)
  const std::size_t begin = i++;
  const std::size_t close = t_.find('>', i);
  if (close == std::string_view::npos) fail(begin, "named parameter '<' is not closed; add '>'");
  std::string n(t_.substr(i, close - i));
  if (n.empty()) fail(begin, "named parameter without a name");
  i = close + 1;
  return n;
}

double ValueReader::parameter(std::size_t& i) const {
  const std::size_t begin = i++;  // '#'
  try {
    if (fanuc_) {
      if (at(i) == '<') fail(begin, "named parameters #<...> are LinuxCNC's, not Fanuc's");
      const std::optional<double> v = fanuc_->get(integer_value(i));
      return v ? *v : std::numeric_limits<double>::quiet_NaN();
    }
    if (at(i) == '<') {
      const std::string n = name(i);
      return p_.get(n);
    }
    const int n = integer_value(i);
    return p_.get(n);
  } catch (ValueError& e) {
    if (e.at == static_cast<std::size_t>(-1)) e.at = begin;
    throw;
  }
}

ParameterTarget ValueReader::target(std::size_t& i) const {
  ++i;  // '#'
  ParameterTarget t;
  if (at(i) == '<') {
    t.name = name(i);
  } else {
    const std::size_t begin = i;
    t.number = integer_value(i);
    if (t.number < 1 || t.number >= kParameterCount)
      fail(begin, fmt::format("parameter number {} is out of range (1 to {})", t.number,
                              kParameterCount - 1));
  }
  return t;
}

double ValueReader::unary(std::size_t& i) const {
  const std::size_t begin = i;
  std::size_t e = i;
  while (is_letter(at(e))) ++e;
  const std::string_view fn = t_.substr(i, e - i);
  i = e;
  if (fanuc_) return fanuc_function(fn, begin, i);
  if (fn == "exists") {
    if (at(i) != '[' || at(i + 1) != '#') fail(begin, "EXISTS takes a parameter: EXISTS[#<name>]");
    i += 2;
    bool exists = true;  // a numbered parameter always exists (rs274)
    if (at(i) == '<') {
      exists = p_.exists(name(i));
    } else {
      const std::size_t number_at = i;
      const int n = integer_value(i);
      if (n < 1 || n >= kParameterCount)
        fail(number_at,
             fmt::format("parameter number {} is out of range (1 to {})", n, kParameterCount - 1));
    }
    if (at(i) != ']') fail(i, "EXISTS[#...] is not closed; add ']'");
    ++i;
    return exists ? 1.0 : 0.0;
  }
  if (!is_shared_function(fn))
    fail(begin, fmt::format("unknown function or operator '{}'; LinuxCNC's are ABS ACOS ASIN "
                            "ATAN COS EXP FIX FUP LN ROUND SIN SQRT TAN EXISTS",
                            fn));
  if (at(i) != '[') fail(i, fmt::format("{} needs its argument in [ ]", fn));
  const double x = expression(i);
  if (fn == "atan") {
    if (at(i) != '/' || at(i + 1) != '[') fail(i, "ATAN takes two arguments: ATAN[y]/[x]");
    ++i;
    const double x2 = expression(i);
    return std::atan2(x, x2) * kDegPerRad;
  }
  if (fn == "abs") return std::abs(x);
  if (fn == "acos" || fn == "asin") {
    if (x < -1.0 || x > 1.0)
      fail(begin, fmt::format("argument to {} out of range (-1 to 1): {}", fn, x));
    return (fn == "acos" ? std::acos(x) : std::asin(x)) * kDegPerRad;
  }
  if (fn == "cos") return std::cos(x * kRadPerDeg);
  if (fn == "sin") return std::sin(x * kRadPerDeg);
  if (fn == "tan") return std::tan(x * kRadPerDeg);
  if (fn == "exp") return std::exp(x);
  if (fn == "fix") return std::floor(x);
  if (fn == "fup") return std::ceil(x);
  if (fn == "ln") {
    if (x <= 0.0) fail(begin, fmt::format("zero or negative argument to LN: {}", x));
    return std::log(x);
  }
  if (fn == "round") return std::trunc(x + (x < 0.0 ? -0.5 : 0.5));
  // sqrt
  if (x < 0.0) fail(begin, fmt::format("negative argument to SQRT: {}", x));
  return std::sqrt(x);
}

double ValueReader::expression(std::size_t& i) const {
  const std::size_t open = i++;
  return operations(i, open, false);
}

double ValueReader::statement_value(std::size_t& i) const { return operations(i, i, true); }

double ValueReader::operations(std::size_t& i, std::size_t open, bool to_end) const {
  // LinuxCNC's read_real_expression: operands and operators on two stacks,
  // an operator reduced while the next one does not bind tighter.
  std::vector<double> values;
  std::vector<std::pair<Op, std::size_t>> ops;
  bool logic = false, other = false;  // the operators of this bracket level
  for (;;) {
    values.push_back(real_value(i));
    const std::size_t where = i;
    Op op = Op::kClose;
    // (A statement's value ends at the line's end or a comment; another
    // statement or a word after it is the caller's to refuse.)
    if (!to_end ||
        (at(i) != '\0' && at(i) != '(' && at(i) != ';' && at(i) != '#' && !word_after(i))) {
      op = read_operator(i, open);
      if (to_end && op == Op::kClose) fail(where, "a ']' without its '['");
    }
    if (op != Op::kClose) (is_logic(op) ? logic : other) = true;
    if (fanuc_ && logic && other)
      fail(where,
           "AND, OR or XOR beside other operators in one bracket: Fanuc binds them like * and "
           "+, LinuxCNC after the comparisons; bracket each operand ([#1 EQ 1] AND [#2 EQ 2])");
    while (!ops.empty() && precedence(op) <= precedence(ops.back().first)) {
      const double b = values.back();
      values.pop_back();
      if (const char* why = apply(ops.back().first, values.back(), b, fanuc_ != nullptr))
        fail(ops.back().second, why);
      ops.pop_back();
    }
    if (op == Op::kClose) break;
    ops.emplace_back(op, where);
  }
  return values.back();
}

bool ValueReader::word_after(std::size_t i) const {
  if (!is_letter(at(i))) return false;
  for (std::string_view op : {"mod", "and", "xor", "or", "eq", "ne", "gt", "ge", "lt", "le"})
    if (t_.substr(i, op.size()) == op) return false;
  return true;
}

Op ValueReader::read_operator(std::size_t& i, std::size_t open) const {
  // Longest first where one is the start of another (** before *).
  static constexpr std::pair<std::string_view, Op> kOperators[] = {
      {"]", Op::kClose}, {"**", Op::kPower}, {"*", Op::kTimes}, {"/", Op::kDivide},
      {"+", Op::kPlus},  {"-", Op::kMinus},  {"mod", Op::kMod}, {"and", Op::kAnd},
      {"xor", Op::kXor}, {"or", Op::kOr},    {"eq", Op::kEq},   {"ne", Op::kNe},
      {"gt", Op::kGt},   {"ge", Op::kGe},    {"lt", Op::kLt},   {"le", Op::kLe}};
  for (const auto& [text, op] : kOperators)
    if (t_.substr(i, text.size()) == text) {
      i += text.size();
      return op;
    }
  const char c = at(i);
  if (c == '\0' || c == '(' || c == ';') fail(open, "expression '[' is not closed; add ']'");
  if (is_letter(c)) {
    std::size_t e = i;
    while (is_letter(at(e))) ++e;
    fail(i,
         fmt::format("'{}' is not an operator; is a ']' missing before it?", t_.substr(i, e - i)));
  }
  fail(i, fmt::format("unknown operator '{}' in an expression", c));
}

}  // namespace volmap::nc::flatten
