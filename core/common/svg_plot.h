// What the reports' plots share (explain, map, verify): round tick values,
// labelled axes, a legend outside the plotting area, a value with its
// standard error in sensible digits. Inline SVG, deterministic text.
//
// The classes written are what tests/support/layout_probe.h measures in
// headless Chromium: `plot` on each <svg>, `frame` on the plotting area,
// `x-label`/`y-label` on axis labels, `x-tick`/`y-tick` on tick labels,
// `legend` on the legend group, `data` on marks that must stay inside the
// frame.
#pragma once

#include <string>
#include <utility>
#include <vector>

namespace volmap::svg {

/// Tick values over [lo, hi]: a step of 1, 2 or 5 times a power of ten that
/// gives about `target` ticks, every tick within [lo, hi] (to rounding),
/// each written with the decimals its step needs.
struct Ticks {
  std::vector<double> values;
  double step = 1.0;
  int decimals = 0;  ///< digits after the point in tick_text
  std::string text(double v) const;
};
Ticks nice_ticks(double lo, double hi, int target = 5);

/// [lo, hi] widened to the nearest multiples of a nice step, so that the
/// outer ticks are the ends of the axis.
std::pair<double, double> nice_range(double lo, double hi, int target = 5);

/// "2.05 ± 0.23": the standard error to two significant digits, the value
/// to the same decimal place, its integer part never rounded ("988 ± 150");
/// without a finite error, the value to four significant digits.
std::string value_with_error(double value, double std_error);

/// The plotting area of a plot, px.
struct Frame {
  double left, top, width, height;
  double right() const { return left + width; }
  double bottom() const { return top + height; }
};

/// A linear map of [lo, hi] onto [px_lo, px_hi].
struct Scale {
  double lo, hi, px_lo, px_hi;
  double operator()(double v) const { return px_lo + (v - lo) / (hi - lo) * (px_hi - px_lo); }
};

/// <svg class="plot"> of the given size; `log_y` adds the class `log-y`
/// (a logarithmic vertical axis: its ticks are decades).
std::string open_plot(double width, double height, const std::string& title = {},
                      bool log_y = false);

/// The frame's rectangle (class `frame`).
std::string frame_rect(const Frame& f, const char* fill = "#fff");

/// Ticks and their labels under the frame, and the axis label below them.
std::string x_axis(const Frame& f, const Scale& x, const Ticks& t, const std::string& label);

/// Ticks and labels left of the frame, the label turned along the axis at
/// `label_x` px from the left edge of the plot.
std::string y_axis(const Frame& f, const Scale& y, const Ticks& t, const std::string& label,
                   double label_x = 12);

/// A label turned along a vertical axis (reading upwards), centred at
/// (x, y) px, of class `cls` (`y-label`, a colour bar's `c-label`).
std::string vertical_label(const char* cls, double x, double y, const std::string& label);

/// A legend in one row starting at (x, y) px: a swatch and a name per entry
/// (colour, name), in a group of class `legend`.
std::string legend_row(double x, double y,
                       const std::vector<std::pair<std::string, std::string>>& entries);

}  // namespace volmap::svg
