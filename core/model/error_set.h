// The geometric errors of a machine as loaded from an errors CSV
// (spec: shared/spec/errors.md), in internal units: lengths in mm, angles in
// rad, for both axis positions and error values.
//
// Interpolation between tabulated positions: piecewise cubic Hermite with
// Fritsch–Carlson monotone slopes (PCHIP, Fritsch & Carlson 1980; end slopes
// by the one-sided three-point formula, as MATLAB's pchip). Why: it is C1
// (no kinks in the error field, so corrected tool paths stay smooth), local
// (one bad reading disturbs two intervals, not the whole axis as a natural
// spline would) and it never overshoots the measured values (a spline can
// invent an error larger than any the laser saw). Two rows: linear. One row:
// constant.
//
// Outside the table: OutsidePolicy::kError (default) refuses with the axis,
// position, table range and the file:line of the block; kClamp holds the end
// value and counts the clamped evaluations. A rotary axis whose table spans
// exactly 360 degrees is periodic: positions wrap, nothing is outside.
//
// Bidirectional tables (dir column): evaluation takes the approach direction
// (+1, -1); direction 0 (unknown, or the axis stands still) gives the mean of
// the two directions. A block with rows of one direction only serves both.
#pragma once

#include <algorithm>
#include <array>
#include <cassert>
#include <cmath>
#include <cstdint>
#include <map>
#include <optional>
#include <string>
#include <string_view>
#include <vector>

#include "core/common/axis_name.h"

namespace volmap {

enum class OutsidePolicy : std::uint8_t { kError, kClamp };

/// What the location errors of a file mean (docs/model.md, "Location
/// errors"):
///  - kIso230: ISO 230-1, the contract's meaning (shared/spec/errors.md) and
///    the default: a rotary axis turns about its actual average line, placed
///    by its location errors, so at its zero position it moves nothing; a
///    squareness turns the direction of a linear axis's motion, not what the
///    axis carries.
///  - kLink: Lei & Hsu's link errors (their eqs. 7-15, the paper's
///    identification): a rigid offset or tilt of each axis frame relative to
///    the frame that carries it. A file says so with `# convention: link`.
enum class LocationConvention : std::uint8_t { kIso230, kLink };
/// The metadata value: "iso230-1" or "link".
const char* location_convention_name(LocationConvention c);
/// "iso230-1" (also "iso", "ISO 230-1") or "link"; nullopt otherwise.
std::optional<LocationConvention> parse_location_convention(std::string_view text);

/// The six component errors of one axis in one approach direction, on one
/// knot vector (the union of the knots of every component's own table; a
/// cubic Hermite with exact values and slopes at inserted knots reproduces
/// each component's own interpolant exactly, so merging costs no accuracy and
/// saves five of six searches per evaluation).
struct AxisErrorTable {
  std::vector<double> position;  ///< knots, mm or rad, strictly increasing
  /// value[i][c], slope[i][c]: component c at knot i (mm or rad; per mm/rad).
  std::vector<std::array<double, kComponentCount>> value;
  std::vector<std::array<double, kComponentCount>> slope;
  bool periodic = false;  ///< rotary table spanning exactly 2*pi
  std::string source;     ///< "file:line" of the (first) block, for messages
  /// The axis the table belongs to: names it in messages and says whether
  /// positions print as mm or degrees. (Added by the reader; default X.)
  AxisName axis = AxisName::X;
  /// Lookup accelerator set by prepare_lookup(): 1/step when the knots are
  /// equally spaced (to 1e-12 relative), so the interval is found by one
  /// multiplication; 0 means binary search. Derived, never read from a file.
  double uniform_inv_step = 0.0;

  bool empty() const { return position.empty(); }
  double min_position() const { return position.front(); }
  double max_position() const { return position.back(); }
};

/// All component errors of one axis: one table per approach direction.
struct AxisErrors {
  AxisName axis = AxisName::X;
  AxisErrorTable plus;                          ///< dir = +1 (or the only table)
  AxisErrorTable minus;                         ///< dir = -1; empty when not bidirectional
  std::array<bool, kComponentCount> present{};  ///< given in the file
  bool bidirectional() const { return !minus.empty(); }
};

/// The contents of one errors CSV.
struct ErrorSet {
  std::string file;                                            ///< as named on input
  std::map<std::string, std::string> metadata;                 ///< "# key: value" lines
  std::map<std::string, int> metadata_line;                    ///< their line numbers
  std::array<std::optional<AxisErrors>, kAxisNameCount> axis;  ///< by AxisName
  /// Location errors by canonical name ("EC0X"), mm or rad.
  std::map<std::string, double> location;
  /// What `location` means (metadata `# convention:`; ISO 230-1 without it).
  LocationConvention convention = LocationConvention::kIso230;

  const AxisErrors* errors_of(AxisName a) const {
    const auto& e = axis[static_cast<int>(a)];
    return e ? &*e : nullptr;
  }
  double location_error(const std::string& canonical_name) const {
    auto it = location.find(canonical_name);
    return it == location.end() ? 0.0 : it->second;
  }
};

/// Whether the errors are zero everywhere: no location error other than 0
/// and no table value other than 0 (no entries at all, or a file of
/// zeros). Such a machine is where its axes say; the post-processors then
/// give a program back as it is.
bool errors_all_zero(const ErrorSet& errors);

/// Sets the derived lookup fields of a table (uniform_inv_step). Call after
/// filling position; evaluation is correct without it, only slower.
void prepare_lookup(AxisErrorTable& table);
void prepare_lookup(ErrorSet& errors);

/// PCHIP slopes (Fritsch–Carlson) for values y at strictly increasing knots x.
std::vector<double> pchip_slopes(const std::vector<double>& x, const std::vector<double>& y);

/// PCHIP slopes for a periodic table (y.front() == y.back(), the span
/// x.back() - x.front() is one period): every knot, the two ends included,
/// takes the interior Fritsch–Carlson slope with its neighbours across the
/// wrap, so the interpolant is C1 through the wrap as well. Both ends get the
/// same slope. Fewer than three knots: all slopes zero (a closed table of two
/// knots is constant).
std::vector<double> pchip_slopes_periodic(const std::vector<double>& x,
                                          const std::vector<double>& y);

// ---- inline evaluation: on the hot path of every model evaluation ----

namespace detail {
[[noreturn, gnu::cold, gnu::noinline]] void throw_outside(const AxisErrorTable& table, double q);
inline constexpr double kTwoPi = 2.0 * 3.14159265358979323846;
/// How far outside its table a position may lie and still be at the end
/// (mm or rad): check_within_travel's slack.
inline constexpr double kEndSlack = 1e-9;
}  // namespace detail

/// Evaluates a table at position q (mm or rad): the six component errors
/// (mm, rad). Throws std::out_of_range with a user message when q is outside
/// and policy is kError; with kClamp holds the end value and increments
/// *clamped (when given).
inline void evaluate_table(const AxisErrorTable& table, double q, OutsidePolicy policy,
                           std::array<double, kComponentCount>& out,
                           std::uint64_t* clamped = nullptr) {
  assert(!table.empty());
  assert(table.value.size() == table.position.size());
  assert(table.slope.size() == table.position.size());
  const std::vector<double>& x = table.position;
  const std::size_t n = x.size();
  const double x_first = x.front();
  const double x_last = x.back();

  if (!(q >= x_first && q <= x_last)) {  // outside, or NaN
    if (table.periodic && std::isfinite(q)) {
      // Wrap into [x_first, x_first + 2 pi); rounding may leave q a hair
      // outside the knots, where the closed table has its end value anyway.
      q = x_first + std::fmod(q - x_first, detail::kTwoPi);
      if (q < x_first) q += detail::kTwoPi;
      q = std::clamp(q, x_first, x_last);
    } else if (q >= x_first - detail::kEndSlack && q <= x_last + detail::kEndSlack) {
      // A position equal to an end up to rounding (a backward
      // transformation's A = 30.000000000000004 deg on a table ending at
      // 30) is at that end, not outside; the slack is the travel check's.
      out = table.value[q < x_first ? 0 : n - 1];
      return;
    } else {
      if (policy == OutsidePolicy::kError || std::isnan(q)) detail::throw_outside(table, q);
      if (clamped != nullptr) ++*clamped;
      out = table.value[q < x_first ? 0 : n - 1];
      return;
    }
  }
  if (n == 1) {
    out = table.value[0];
    return;
  }

  // Interval i with x[i] <= q <= x[i+1], i in [0, n-2].
  std::size_t i;
  if (table.uniform_inv_step > 0.0) {
    // q >= x_first here, so truncation is floor (and needs no SSE4.1 roundsd).
    i = static_cast<std::size_t>((q - x_first) * table.uniform_inv_step);
    if (i > n - 2) i = n - 2;
    // Rounding at a knot may pick the neighbour interval: both are exact there.
    if (q < x[i] && i > 0) --i;
    if (q > x[i + 1] && i + 2 < n) ++i;
  } else {
    const auto after = std::upper_bound(x.begin() + 1, x.end() - 1, q);
    i = static_cast<std::size_t>(after - x.begin()) - 1;
  }
  const double h = x[i + 1] - x[i];
  const double s = (q - x[i]) / h;
  const double one_minus_s = 1.0 - s;
  const double h00 = (1.0 + 2.0 * s) * one_minus_s * one_minus_s;
  const double h10 = s * one_minus_s * one_minus_s * h;
  const double h01 = s * s * (3.0 - 2.0 * s);
  const double h11 = s * s * (s - 1.0) * h;
  const std::array<double, kComponentCount>& y0 = table.value[i];
  const std::array<double, kComponentCount>& y1 = table.value[i + 1];
  const std::array<double, kComponentCount>& m0 = table.slope[i];
  const std::array<double, kComponentCount>& m1 = table.slope[i + 1];
  for (int c = 0; c < kComponentCount; ++c)
    out[c] = h00 * y0[c] + h10 * m0[c] + h01 * y1[c] + h11 * m1[c];
}

/// Evaluates an axis's errors for approach direction dir (+1, -1, 0).
inline void evaluate_axis(const AxisErrors& errors, double q, int dir, OutsidePolicy policy,
                          std::array<double, kComponentCount>& out,
                          std::uint64_t* clamped = nullptr) {
  if (!errors.bidirectional() || dir > 0) {
    evaluate_table(errors.plus, q, policy, out, clamped);
    return;
  }
  if (dir < 0) {
    evaluate_table(errors.minus, q, policy, out, clamped);
    return;
  }
  // Direction unknown: the mean of both directions. One clamped evaluation
  // of the axis counts once, even when both tables clamp.
  std::uint64_t clamped_here = 0;
  std::array<double, kComponentCount> minus_out;
  evaluate_table(errors.plus, q, policy, out, &clamped_here);
  evaluate_table(errors.minus, q, policy, minus_out, &clamped_here);
  for (int c = 0; c < kComponentCount; ++c) out[c] = 0.5 * (out[c] + minus_out[c]);
  if (clamped != nullptr && clamped_here > 0) ++*clamped;
}

}  // namespace volmap
