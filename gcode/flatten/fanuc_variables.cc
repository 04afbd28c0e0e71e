#include "gcode/flatten/fanuc_variables.h"

#include <fmt/format.h>

#include "gcode/flatten/parameters.h"

namespace volmap::nc::flatten {
namespace {

[[noreturn]] void refuse(int n) {
  if (n >= 1000)
    throw ValueError{fmt::format(
        "#{} is a Fanuc system variable: the control's own (modal state, offsets, positions, "
        "clocks, alarms), known only on the machine; volmap does not read or set system "
        "variables",
        n)};
  throw ValueError{fmt::format(
      "#{} is not a Fanuc macro variable (local #1-#33, common #100-#199 and #500-#999)", n)};
}

}  // namespace

void FanucVariables::load(int n, double value) {
  if (n >= 100 && n <= 199) common_[static_cast<std::size_t>(n - 100)] = value;
  if (n >= 500 && n <= 999) kept_[static_cast<std::size_t>(n - 500)] = value;
}

std::optional<double> FanucVariables::get(int n) const {
  if (n == 0) return std::nullopt;
  if (n >= 1 && n <= 33) return locals_.back()[static_cast<std::size_t>(n)];
  if (n >= 100 && n <= 199) return common_[static_cast<std::size_t>(n - 100)];
  if (n >= 500 && n <= 999) {
    const auto& v = kept_[static_cast<std::size_t>(n - 500)];
    if (!v)
      throw ValueError{fmt::format(
          "#{} is read before the program sets it: #500-#999 keep their values on the control "
          "between runs, which volmap cannot know; set it in the program first, or give its "
          "value in a parameter file (--var-file, a line `{} value`)",
          n, n)};
    return v;
  }
  refuse(n);
}

void FanucVariables::set(int n, std::optional<double> value) {
  if (n == 0) throw ValueError{"#0 is always vacant and cannot be set"};
  if (n >= 1 && n <= 33) {
    locals_.back()[static_cast<std::size_t>(n)] = value;
  } else if (n >= 100 && n <= 199) {
    common_[static_cast<std::size_t>(n - 100)] = value;
  } else if (n >= 500 && n <= 999) {
    kept_[static_cast<std::size_t>(n - 500)] = value;
  } else if (n == 3000) {
    throw ValueError{fmt::format(
        "#3000 = {}: the program raises a macro alarm here and the control stops; volmap posts "
        "programs that run to their end (check the condition that led here)",
        value ? fmt::format("{:g}", *value) : std::string("<vacant>"))};
  } else if (n == 3006) {
    throw ValueError{
        "#3006: the program stops here with a message for the operator; a post cannot know "
        "what the operator does next: remove the stop, or post the parts before and after it "
        "separately"};
  } else {
    refuse(n);
  }
}

}  // namespace volmap::nc::flatten
