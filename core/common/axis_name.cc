#include "core/common/axis_name.h"

namespace volmap {

char axis_char(AxisName a) { return "XYZABC"[static_cast<int>(a)]; }

std::optional<AxisName> axis_from_char(char c) {
  switch (c) {
    case 'X':
      return AxisName::X;
    case 'Y':
      return AxisName::Y;
    case 'Z':
      return AxisName::Z;
    case 'A':
      return AxisName::A;
    case 'B':
      return AxisName::B;
    case 'C':
      return AxisName::C;
    default:
      return std::nullopt;
  }
}

std::string component_error_name(Component c, AxisName a) {
  std::string s = "E";
  s += "XYZABC"[static_cast<int>(c)];
  s += axis_char(a);
  return s;
}

std::optional<ErrorName> parse_error_name(std::string_view name) {
  if (name.size() < 3 || name[0] != 'E') return std::nullopt;
  std::optional<AxisName> dir = axis_from_char(name[1]);
  if (!dir) return std::nullopt;
  const auto component = static_cast<Component>(static_cast<int>(*dir));
  if (name.size() == 3) {
    std::optional<AxisName> axis = axis_from_char(name[2]);
    if (!axis) return std::nullopt;
    return ErrorName{component, *axis, false};
  }
  if (name.size() == 4 && (name[2] == '0' || name[2] == 'O')) {
    std::optional<AxisName> axis = axis_from_char(name[3]);
    if (!axis) return std::nullopt;
    return ErrorName{component, *axis, true};
  }
  return std::nullopt;
}

std::string error_name_string(const ErrorName& n) {
  std::string s = "E";
  s += "XYZABC"[static_cast<int>(n.component)];
  if (n.location) s += '0';
  s += axis_char(n.axis);
  return s;
}

std::optional<std::string> location_error_problem(const ErrorName& n) {
  const int c = static_cast<int>(n.component);
  const int a = static_cast<int>(n.axis);
  if (!n.location) return std::nullopt;
  if (!is_rotary(n.axis)) {
    if (!is_angular(n.component))
      return "a linear axis has no translational location error (an offset of "
             "its line is absorbed by the workpiece origin)";
    if (c - 3 == a) return "a rotation of a linear axis line about itself has no effect";
    return std::nullopt;
  }
  // Rotary axis about direction a-3.
  if (!is_angular(n.component) && c == a - 3)
    return "an offset of a rotary axis along its own line has no effect";
  return std::nullopt;
}

}  // namespace volmap
