// Axis letters and ISO 230-1 error names.
//
// ISO 230-1 names an error E<dir><axis>: EXX is the X-direction
// (positioning) error of the X axis, EAY the angular error of the Y axis about
// X (roll is EAX for X, pitch/yaw the other two). Location errors carry a zero:
// EC0X is the squareness of X (rotation of its line about Z), EX0C the X offset
// of the C axis line.
#pragma once

#include <array>
#include <cstdint>
#include <optional>
#include <string>
#include <string_view>

namespace volmap {

/// A machine axis letter. Linear: X Y Z; rotary: A B C (about X Y Z).
enum class AxisName : std::uint8_t { X = 0, Y = 1, Z = 2, A = 3, B = 4, C = 5 };
inline constexpr int kAxisNameCount = 6;

/// The six component errors of one axis, in ISO 230-1 order:
/// three translational (along X, Y, Z) then three angular (about X, Y, Z).
enum class Component : std::uint8_t { EX = 0, EY = 1, EZ = 2, EA = 3, EB = 4, EC = 5 };
inline constexpr int kComponentCount = 6;

inline bool is_rotary(AxisName a) { return static_cast<int>(a) >= 3; }
inline bool is_angular(Component c) { return static_cast<int>(c) >= 3; }
char axis_char(AxisName a);
std::optional<AxisName> axis_from_char(char c);

/// "EXX", "EAY", ... for component c of axis a.
std::string component_error_name(Component c, AxisName a);

/// A parsed ISO 230-1 error name.
struct ErrorName {
  Component component;  ///< the direction letter (EX..EC)
  AxisName axis;        ///< the axis the error belongs to
  bool location;        ///< true for location errors (E?0?), constants
};

/// Parses "EXX", "EC0X", "ECOX" (letter O accepted for the zero). Returns
/// nothing for strings that are not of the ISO form at all. Does not judge
/// whether a location error is meaningful: see is_known_location_error().
std::optional<ErrorName> parse_error_name(std::string_view name);

/// Canonical spelling: "EC0X" (zero, never the letter O).
std::string error_name_string(const ErrorName& n);

/// Location errors volmap models. Linear axis K: the two tilts of its line
/// (EA0K, EB0K, EC0K except rotation about K itself). Rotary axis K: the two
/// offsets of its line perpendicular to it, the two tilts, and its zero
/// position error (EC0C for C). Returns an explanation when not known.
std::optional<std::string> location_error_problem(const ErrorName& n);

}  // namespace volmap
