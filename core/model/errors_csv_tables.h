// The tables of the errors CSV reader (errors_csv.cc): each component's own
// table in one direction, as read, and the merge of an axis's components onto
// one knot vector (AxisErrorTable). Internal to the reader.
//
// Merging policy (the spec asks for "a stated policy" outside a table): the
// merged table of an axis spans the union of its components' ranges. A
// component whose own table is shorter takes, at every merged knot beyond its
// own ends, its end value with slope zero: it is held at its end value, and
// only in the first merged interval past its end does the cubic blend from
// its own end slope to zero (the Hermite form keeps one slope per knot, so
// the blend keeps the table C1). Inside its own range every component is
// reproduced exactly: at an inserted knot its value and slope are those of
// its own PCHIP interpolant. The blend departs from the end value y_e by at
// most (4/27) h |m_e| (h the blend interval, m_e the component's own end
// slope); when every component covers the same range, there is no blend.
//
// Periodic tables: a rotary-axis table spanning exactly 360 degrees is one
// full turn; its ends must hold the same values, and its slopes are the
// periodic PCHIP slopes (C1 through the wrap). All components of a rotary
// axis in one direction must then cover the same full turn.
#pragma once

#include <array>
#include <optional>
#include <string>
#include <vector>

#include "core/common/axis_name.h"
#include "core/model/error_set.h"

namespace volmap::errors_csv_tables {

/// The rows of one direction of a component-error block, in file units.
struct ComponentRows {
  std::vector<double> position_file;  ///< mm or degrees
  std::vector<int> line;
  std::vector<std::array<double, kComponentCount>> value_file;  ///< um, urad
};

/// One component's own table in one direction, internal units.
struct ComponentTable {
  std::vector<double> position;  ///< mm or rad, strictly increasing
  std::vector<double> value;     ///< mm or rad
  std::vector<double> slope;     ///< PCHIP slopes
  bool periodic = false;
  int line = 0;  ///< header line of its block
};

/// One component of an axis: one table serving both directions, or two.
struct ComponentData {
  ComponentTable plus;                  ///< dir +1, or both directions
  std::optional<ComponentTable> minus;  ///< dir -1 when bidirectional
};

struct AxisDraft {
  int first_line = 0;  ///< header line of the axis's first block
  std::array<std::optional<ComponentData>, kComponentCount> component;
};

/// Component `c`'s own table from its rows (file units converted to mm /
/// rad) with its PCHIP slopes; a table spanning 360 degrees of a rotary axis
/// is periodic and must close (InputError in `file` otherwise).
ComponentTable make_component_table(const ComponentRows& rows, AxisName axis, Component c,
                                    int header_line, const std::string& file);

/// The components of `draft` (their dir=-1 tables when `minus`) merged onto
/// the union of their knots, by the policy above; components over different
/// full turns are an InputError in `file`.
AxisErrorTable merge_component_tables(const AxisDraft& draft, AxisName axis, bool minus,
                                      const std::string& file);

}  // namespace volmap::errors_csv_tables
