// The parameters of an RS274NGC program as LinuxCNC keeps them (its
// manual's "Numbered/Named Parameters" chapter): numbered #1-#5602, named
// local #<x> (one scope per subroutine call) and global #<_x>, and the
// system parameters an offline post knows, read from the interpreter's state
// when the program asks (work offsets, the current position, the tool).
//
// Values known only on the machine at run time (probe results, HAL pins,
// M66 inputs) are refused when read, naming the parameter.
#pragma once

#include <array>
#include <cstddef>
#include <map>
#include <optional>
#include <set>
#include <string>
#include <string_view>
#include <vector>

namespace volmap::nc {
class Interpreter;
}

namespace volmap::nc::flatten {

/// LinuxCNC's RS274NGC_MAX_PARAMETERS: numbered parameters are #1-#5601.
inline constexpr int kParameterCount = 5602;
/// #1-#30: a subroutine's arguments, local to each call.
inline constexpr int kArgumentCount = 30;

/// Thrown by a parameter or expression that cannot be read; the caller
/// adds file, line and column.
struct ValueError {
  std::string message;
  /// Where in the (normalized) line, when known.
  std::size_t at = static_cast<std::size_t>(-1);
};

class Parameters {
 public:
  /// `interp` answers the system parameters (its state when asked: the
  /// flattener evaluates a line just before the interpreter runs it).
  explicit Parameters(const Interpreter& interp);

  /// Initial values of numbered parameters (a LinuxCNC .var file): the
  /// ones the interpreter does not derive from its own state.
  void load(int number, double value);

  double get(int number) const;
  /// Throws ValueError for a named parameter never set ("not defined", as
  /// LinuxCNC) and for run-time values. `name`: lower case, no spaces.
  double get(std::string_view name) const;
  bool exists(std::string_view name) const;

  /// Assignments take effect after the line (LinuxCNC): queue them, then
  /// commit().
  void queue(int number, double value);
  void queue(std::string name, double value);
  void commit();

  /// A subroutine call: new locals, #1-#30 from the arguments.
  void push_call(const std::vector<double>& args);
  void pop_call();
  int call_level() const { return static_cast<int>(frames_.size()) - 1; }
  /// The value a subroutine returned (#<_value>, #<_value_returned>).
  void set_return(std::optional<double> value);

 private:
  struct Frame {
    std::array<double, kArgumentCount> args{};  ///< the caller's #1-#30, restored at return
    std::map<std::string, double, std::less<>> named;
  };
  std::optional<double> system(int number) const;
  std::optional<double> predefined(std::string_view name) const;

  const Interpreter& interp_;
  std::vector<double> numbered_;
  std::set<int> written_;  ///< system parameters (#5000 on) the program has set
  std::map<std::string, double, std::less<>> global_;
  std::vector<Frame> frames_;
  std::vector<std::pair<int, double>> queued_numbered_;
  std::vector<std::pair<std::string, double>> queued_named_;
  double value_ = 0.0;
  bool value_returned_ = false;
};

}  // namespace volmap::nc::flatten
