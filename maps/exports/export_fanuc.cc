// FANUC exports (docs/exports.md, "fanuc"):
//
//  * fanuc_pitch.txt: stored pitch error compensation as a parameter tape
//    record ("%", parameter blocks N<no>A<axis>P<value>, pitch data blocks
//    N1<point>P<value>, "%"). Compensation point p of an axis covers the
//    section from node k-1 to node k (p = base + k); its value is the
//    increment of the correction over that section, in detection units x
//    magnification (parameter 3623), at most +-7 per point. The correction
//    at the reference position (home node, parameter 3620) is zero by
//    definition: values are relative to it. Increments come from the
//    rounded absolute correction (error feedback), so re-summing them gives
//    the absolute correction within half a unit at every point, with no
//    drift along the axis.
//    Bidirectional axis: bidirectional pitch error compensation (3605#0 = 1),
//    the negative-direction points follow the positive ones (3626), and
//    3627 holds the absolute compensation at the reference position for
//    the negative direction.
//  * fanuc_3d.csv: the three-dimensional error compensation lattice, the
//    correction vector (Cx, Cy, Cz) in detection units at every grid
//    vertex (mean of the direction layers), which the control interpolates
//    trilinearly in each cell.
//  * FANUC.txt: the parameters, signs and units in words.
#include <fmt/format.h>

#include <algorithm>
#include <cmath>

#include "maps/exports/exporters.h"

namespace volmap::maps::exporters {

namespace {

constexpr std::int64_t kMaxPitchPoints = 1024;  // data numbers 0..1023, all axes together
constexpr int kMaxPerPoint = 7;                 // per point, x magnification
constexpr int kMaxMagnification = 100;          // parameter 3623

struct AxisPitch {
  std::int64_t base = 0;                ///< data number of node 0's section
  std::vector<std::int64_t> plus;       ///< increments, positive direction (node 0: 0)
  std::vector<std::int64_t> minus;      ///< same, negative direction (bidirectional only)
  std::int64_t minus_at_reference = 0;  ///< 3627, detection units
  int magnification = 1;                ///< 3623
};

// Absolute correction relative to the reference node, quantized to units of
// `unit_mm`, then differenced: increments whose partial sums are the rounded
// absolute values.
std::vector<std::int64_t> increments(const std::vector<double>& correction, std::int64_t reference,
                                     double unit_mm) {
  std::vector<std::int64_t> inc(correction.size(), 0);
  std::int64_t previous = 0;
  for (size_t k = 0; k < correction.size(); ++k) {
    const std::int64_t q =
        std::llround((correction[k] - correction[static_cast<size_t>(reference)]) / unit_mm);
    if (k > 0) inc[k] = q - previous;
    previous = q;
  }
  return inc;
}

std::int64_t max_abs(const std::vector<std::int64_t>& v) {
  std::int64_t m = 0;
  for (std::int64_t x : v) m = std::max(m, x < 0 ? -x : x);
  return m;
}

// Axis j's pitch error compensation: its points from data number `base`,
// the magnification that keeps every point within +-7, the increments.
AxisPitch axis_pitch(const VolumetricTable& t, const std::vector<std::int64_t>& home, int j,
                     double unit, std::int64_t base) {
  const GridAxis& g = t.grid[static_cast<size_t>(j)];
  const char k = axis_char(g.axis);
  require_uniform(t, j, "fanuc");
  const double interval_units = g.spacing / unit;
  if (std::abs(interval_units - std::round(interval_units)) > 1e-6)
    throw ExportError(fmt::format(
        "`format` fanuc: axis {}: the spacing {:g} mm is not a whole number of detection units "
        "({:g} mm; parameter 3624 is an integer): build the table with a spacing that is",
        k, g.spacing, unit));
  AxisPitch p;
  p.base = base;
  const std::int64_t h = home[static_cast<size_t>(j)];
  const int c = du_channel(t, j);
  const bool bidir = is_bidirectional(t, j);
  const std::vector<double> plus = along_axis(t, home, j, c, bidir ? +1 : 0);
  const std::vector<double> minus = bidir ? along_axis(t, home, j, c, -1) : std::vector<double>{};
  int m = 1;
  for (; m <= kMaxMagnification; ++m) {
    p.plus = increments(plus, h, unit * m);
    std::int64_t worst = max_abs(p.plus);
    if (bidir) {
      p.minus = increments(minus, h, unit * m);
      worst = std::max(worst, max_abs(p.minus));
    }
    if (worst <= kMaxPerPoint) break;
  }
  if (m > kMaxMagnification) {
    double step = 0.0;
    for (size_t n = 1; n < plus.size(); ++n) step = std::max(step, std::abs(plus[n] - plus[n - 1]));
    throw ExportError(
        fmt::format("`format` fanuc: axis {}: the correction changes by up to {:.3f} um over one "
                    "{:g} mm interval; "
                    "a pitch compensation point takes at most +-{} x magnification {} detection "
                    "units ({:g} mm): "
                    "build the table with a finer spacing",
                    k, step * 1e3, g.spacing, kMaxPerPoint, kMaxMagnification, unit));
  }
  p.magnification = m;
  if (bidir)
    p.minus_at_reference =
        std::llround((minus[static_cast<size_t>(h)] - plus[static_cast<size_t>(h)]) / unit);
  return p;
}

// fanuc_pitch.txt: the parameters, then the pitch data of every axis.
std::string pitch_tape(const VolumetricTable& t, const std::vector<std::int64_t>& home,
                       const std::vector<AxisPitch>& axes, double unit) {
  auto param = [&](int number, auto value_of) {
    std::string s = fmt::format("N{:05d}", number);
    for (int j = 0; j < 3; ++j) s += fmt::format("A{}P{}", j + 1, value_of(j));
    return s + "\n";
  };
  std::string tape = "%\n";
  tape += param(3605, [&](int j) { return is_bidirectional(t, j) ? "00000001" : "00000000"; });
  tape += param(3620, [&](int j) {
    return axes[static_cast<size_t>(j)].base + home[static_cast<size_t>(j)];
  });
  tape += param(3621, [&](int j) { return axes[static_cast<size_t>(j)].base; });
  tape += param(3622, [&](int j) {
    return axes[static_cast<size_t>(j)].base + t.grid[static_cast<size_t>(j)].count - 1;
  });
  tape += param(3623, [&](int j) { return axes[static_cast<size_t>(j)].magnification; });
  tape += param(3624,
                [&](int j) { return std::llround(t.grid[static_cast<size_t>(j)].spacing / unit); });
  tape += param(3626, [&](int j) {
    const AxisPitch& p = axes[static_cast<size_t>(j)];
    return p.minus.empty() ? std::int64_t{0} : p.base + t.grid[static_cast<size_t>(j)].count;
  });
  tape += param(3627, [&](int j) { return axes[static_cast<size_t>(j)].minus_at_reference; });
  for (int j = 0; j < 3; ++j) {
    const AxisPitch& p = axes[static_cast<size_t>(j)];
    std::int64_t n = p.base;
    for (std::int64_t v : p.plus) tape += fmt::format("N{}P{}\n", 10000 + n++, v);
    for (std::int64_t v : p.minus) tape += fmt::format("N{}P{}\n", 10000 + n++, v);
  }
  tape += "%\n";

  return tape;
}

// fanuc_3d.csv: the correction vector at every grid vertex (mean of the
// direction layers), detection units.
std::string lattice_csv(const VolumetricTable& t, double unit) {
  std::string lattice = fmt::format(
      "# volmap FANUC three-dimensional error compensation lattice: machine {}, errors {}\n"
      "# c*: correction added to the axis (commanded minus nominal), detection units of {:g} mm\n",
      t.machine_name, t.errors_source, unit);
  lattice += "i,j,k,x_mm,y_mm,z_mm,cx,cy,cz\n";
  std::vector<std::int64_t> idx(3);
  for (std::int64_t n = 0; n < t.node_count(); ++n) {
    t.node_index(n, idx.data());
    lattice += fmt::format("{},{},{}", idx[0], idx[1], idx[2]);
    for (int d = 0; d < 3; ++d)
      lattice += "," + fixed(t.grid[static_cast<size_t>(d)].node(idx[static_cast<size_t>(d)]), 4);
    for (int d = 0; d < 3; ++d) {
      double sum = 0.0;
      for (int layer = 0; layer < t.layer_count(); ++layer) sum += t.at(layer, n)[du_channel(t, d)];
      lattice += fmt::format(",{}", std::llround(sum / t.layer_count() / unit));
    }
    lattice += "\n";
  }

  return lattice;
}

// FANUC.txt: the parameters, signs and units in words.
std::string fanuc_notes(const VolumetricTable& t, const std::vector<std::int64_t>& home,
                        const std::vector<AxisPitch>& axes, double unit) {
  std::string notes = fmt::format(
      "volmap export for FANUC: machine {}, errors {}\n"
      "Detection unit {:g} mm. Axis numbers A1 A2 A3 = X Y Z (renumber to the control's axes).\n\n"
      "fanuc_pitch.txt (stored pitch error compensation, parameter tape format):\n"
      "  3605#0 bidirectional pitch error compensation (1 for a bidirectional axis)\n"
      "  3620 compensation point number of the reference position (the home node)\n"
      "  3621 / 3622 most negative / most positive point number (positive direction)\n"
      "  3623 magnification (values x magnification x detection unit)\n"
      "  3624 interval between compensation points (detection units)\n"
      "  3626 most negative point number for the negative direction (bidirectional)\n"
      "  3627 absolute compensation at the reference position, negative direction (detection "
      "units)\n"
      "  N1pppp = value of compensation point pppp: the increment of the correction over the\n"
      "  section that ends at that point (correction = commanded minus nominal position, about\n"
      "  minus the error), relative to the reference position, at most +-7 per point.\n",
      t.machine_name, t.errors_source, unit);
  for (int j = 0; j < 3; ++j) {
    const GridAxis& g = t.grid[static_cast<size_t>(j)];
    const AxisPitch& p = axes[static_cast<size_t>(j)];
    const std::vector<double> plus =
        along_axis(t, home, j, du_channel(t, j), is_bidirectional(t, j) ? +1 : 0);
    notes += fmt::format(
        "  {}: points {}..{}{}, reference {} at {:g} mm, magnification {}; the correction at the "
        "reference position, {} um, is not in the table (reference position / grid shift)\n",
        axis_char(g.axis), p.base, p.base + g.count - 1,
        p.minus.empty() ? std::string("")
                        : fmt::format(" (negative direction {}..{})", p.base + g.count,
                                      p.base + 2 * g.count - 1),
        p.base + home[static_cast<size_t>(j)], g.node(home[static_cast<size_t>(j)]),
        p.magnification, fixed(plus[static_cast<size_t>(home[static_cast<size_t>(j)])] * 1e3, 3));
  }
  notes +=
      "\nfanuc_3d.csv (three-dimensional error compensation): the correction vector at every\n"
      "grid vertex, detection units, interpolated trilinearly by the control; enter the\n"
      "lattice origin, intervals and point counts of the grid in the 3D compensation parameters\n"
      "and the vectors as its compensation data (mean of the approach directions).\n";
  return notes;
}

}  // namespace

std::vector<ExportFile> fanuc(const VolumetricTable& t, const ExportOptions& o) {
  require_three_axis(t, "fanuc");
  const double unit = o.detection_unit_mm;
  if (!(unit > 0.0) || !std::isfinite(unit))
    throw ExportError("`format` fanuc: the detection unit must be a positive number of mm");
  const std::vector<std::int64_t> home = home_line_nodes(t, o);

  // ---- pitch error compensation ----
  std::vector<AxisPitch> axes;
  std::int64_t next = 0;
  for (int j = 0; j < 3; ++j) {
    axes.push_back(axis_pitch(t, home, j, unit, next));
    next += t.grid[static_cast<size_t>(j)].count * (is_bidirectional(t, j) ? 2 : 1);
  }
  if (next > kMaxPitchPoints)
    throw ExportError(
        fmt::format("`format` fanuc: {} pitch error compensation points needed, the control has {} "
                    "(data numbers "
                    "0..{}) for all axes together: build the table with a coarser spacing",
                    next, kMaxPitchPoints, kMaxPitchPoints - 1));
  return {{"fanuc_pitch.txt", pitch_tape(t, home, axes, unit)},
          {"fanuc_3d.csv", lattice_csv(t, unit)},
          {"FANUC.txt", fanuc_notes(t, home, axes, unit)}};
}

}  // namespace volmap::maps::exporters
