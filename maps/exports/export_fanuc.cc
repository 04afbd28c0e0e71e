// FANUC exports (docs/exports.md, "fanuc", which cites the source of each
// rule and lists what no source settles):
//
//  * fanuc_pitch.txt: stored pitch error compensation as a parameter tape
//    record ("%", parameter records, pitch data records, "%"). Point n of an
//    axis holds the increment of the compensation over the section from
//    point n-1 to point n (FANUC's rotary example: the value of the
//    reference point 3620 is that of the section ending at the reference
//    position), in detection units x magnification (3623); 3621 =
//    3620 - (travel on the negative side / interval) + 1 (the first point
//    whose section lies inside the travel). The compensation is zero at the
//    reference position (for the reference return direction, 1006#5 ZMI);
//    a bidirectional axis (3605#0 BDP) has its negative-direction points at
//    3000 + the positive ones (FOCAS numbering), 3626 their first, and 3627
//    the other direction's absolute compensation at the reference position.
//    Increments come from the rounded absolute compensation (error
//    feedback), so re-summing them gives it within half a unit everywhere.
//  * fanuc_3d_transcription.csv (30i series only): the correction vectors
//    at the grid vertices for the three-dimensional error compensation
//    data screen (trilinear in each cell); a sheet to transcribe, not a
//    file any FANUC control loads.
//  * FANUC.txt: the parameters, signs, units and what to check, in words.
#include <fmt/format.h>

#include <algorithm>
#include <cmath>

#include "maps/exports/exporters.h"

namespace volmap::maps {

FanucOptions::Series parse_fanuc_series(const std::string& name) {
  std::string n;
  for (char ch : name) n += static_cast<char>(std::tolower(static_cast<unsigned char>(ch)));
  for (const char* a : {"16i", "18i", "21i", "0i-a", "0i-b", "0i-c", "0i-d"})
    if (n == a) return FanucOptions::Series::k16i;
  for (const char* a : {"30i", "31i", "32i", "0i-f"})
    if (n == a) return FanucOptions::Series::k30i;
  throw std::invalid_argument(fmt::format(
      "FANUC series {:?} is not one volmap knows: give 16i (also 18i, 21i, 0i-A..0i-D) or 30i "
      "(also 31i, 32i, 0i-F){}",
      name, n == "0i" ? "; 0i-D and 0i-F differ in their pitch error compensation limits" : ""));
}

namespace exporters {

namespace {

using Series = FanucOptions::Series;

struct SeriesRules {
  const char* name;
  std::int64_t points;  ///< pitch error compensation points 0 .. points-1
  int min_value, max_value;
  const char* q;  ///< "Q1" in the records of the 30i series
};

SeriesRules rules_of(Series s) {
  return s == Series::k16i ? SeriesRules{"16i", 1024, -7, 7, ""}
                           : SeriesRules{"30i", 1536, -128, 127, "Q1"};
}

constexpr int kMaxMagnification = 100;         // 3623
constexpr std::int64_t kNegativeTable = 3000;  // bidirectional: 3000 + point

struct AxisPitch {
  std::int64_t reference = 0, first = 0, last = 0;  ///< 3620, 3621, 3622
  std::vector<std::int64_t> plus, minus;            ///< values of points first..last
  std::int64_t other_at_reference = 0;              ///< 3627, detection units
  int magnification = 1;                            ///< 3623
  double dropped_mm = 0.0;  ///< compensation at the reference position, left out
};

// Values of points first..last for node corrections c (mm), home node h, in
// units q: the increments of round((c(k) - c(h)) / q) over each section;
// with h = 0 the reference point's own section (outside the travel) is 0.
std::vector<std::int64_t> point_values(const std::vector<double>& c, std::int64_t h, double q) {
  std::vector<std::int64_t> v;
  if (h == 0) v.push_back(0);
  auto rounded = [&](size_t k) { return std::llround((c[k] - c[static_cast<size_t>(h)]) / q); };
  for (size_t k = 1; k < c.size(); ++k) v.push_back(rounded(k) - rounded(k - 1));
  return v;
}

bool within(const std::vector<std::int64_t>& v, const SeriesRules& r) {
  return std::all_of(v.begin(), v.end(),
                     [&](std::int64_t x) { return x >= r.min_value && x <= r.max_value; });
}

AxisPitch axis_pitch(const VolumetricTable& t, const std::vector<std::int64_t>& home, int j,
                     const ExportOptions& o, std::int64_t first) {
  const GridAxis& g = t.grid[static_cast<size_t>(j)];
  const char k = axis_char(g.axis);
  const SeriesRules rules = rules_of(o.fanuc.series);
  const double unit = o.detection_unit_mm;
  require_uniform(t, j, "fanuc");
  const std::int64_t h = home[static_cast<size_t>(j)];
  const double reference =
      static_cast<size_t>(j) < o.home.size() ? o.home[static_cast<size_t>(j)] : g.start;
  if (std::abs(reference - g.node(h)) > 1e-9 * std::max(1.0, std::abs(reference)))
    throw ExportError(fmt::format(
        "`format` fanuc: axis {}: the reference position {:g} mm is not a node of the grid "
        "(every {:g} mm from {:g}); FANUC's compensation points lie at the reference position "
        "plus multiples of the interval: build the table with a spacing that puts a node there",
        k, reference, g.spacing, g.start));
  const double interval =
      g.spacing / (o.fanuc.series == Series::k16i ? o.fanuc.input_increment_mm : unit);
  if (std::abs(interval - std::round(interval)) > 1e-6)
    throw ExportError(fmt::format(
        "`format` fanuc: axis {}: the spacing {:g} mm is not a whole number of {} ({:g} mm): "
        "build the table with a spacing that is",
        k, g.spacing,
        o.fanuc.series == Series::k16i ? "least input increments (3624)" : "detection units",
        o.fanuc.series == Series::k16i ? o.fanuc.input_increment_mm : unit));
  AxisPitch p;
  p.first = first;
  p.reference = h == 0 ? first : first + h - 1;
  p.last = p.reference + (g.count - 1 - h);
  const int c = du_channel(t, j);
  const bool bidir = is_bidirectional(t, j);
  const std::vector<double> plus = along_axis(t, home, j, c, bidir ? +1 : 0);
  const std::vector<double> minus = bidir ? along_axis(t, home, j, c, -1) : std::vector<double>{};
  for (p.magnification = 1; p.magnification <= kMaxMagnification; ++p.magnification) {
    const double q = unit * p.magnification;
    p.plus = point_values(plus, h, q);
    if (bidir) p.minus = point_values(minus, h, q);
    if (within(p.plus, rules) && within(p.minus, rules)) break;
  }
  if (p.magnification > kMaxMagnification) {
    double step = 0.0;
    for (size_t n = 1; n < plus.size(); ++n) step = std::max(step, std::abs(plus[n] - plus[n - 1]));
    throw ExportError(fmt::format(
        "`format` fanuc: axis {}: the correction changes by up to {:.3f} µm over one {:g} mm "
        "interval; a pitch error compensation point of the {} series takes {}..{} x magnification "
        "{} detection units ({:g} mm): build the table with a finer spacing",
        k, step * 1e3, g.spacing, rules.name, rules.min_value, rules.max_value, kMaxMagnification,
        unit));
  }
  const std::vector<double>& by_reference = bidir && o.fanuc.reference_direction < 0 ? minus : plus;
  const std::vector<double>& other = bidir && o.fanuc.reference_direction < 0 ? plus : minus;
  p.dropped_mm = by_reference[static_cast<size_t>(h)];
  if (bidir)
    p.other_at_reference =
        std::llround((other[static_cast<size_t>(h)] - by_reference[static_cast<size_t>(h)]) / unit);
  return p;
}

// 3605 of axis j: the machine's byte with bit 0 (the right-most digit) set
// for a bidirectional axis and cleared otherwise.
std::string param_3605(const std::vector<std::string>& current, int j, bool bidir) {
  const std::string& byte = current.size() == 1 ? current[0] : current[static_cast<size_t>(j)];
  return byte.substr(0, 7) + (bidir ? "1" : "0");
}

std::string pitch_tape(const VolumetricTable& t, const std::vector<AxisPitch>& axes,
                       const ExportOptions& o) {
  const SeriesRules rules = rules_of(o.fanuc.series);
  auto param = [&](int number, auto value_of) {
    std::string s = fmt::format("N{:05d}{}", number, rules.q);
    for (int j = 0; j < 3; ++j) s += fmt::format("A{}P{}", j + 1, value_of(j));
    return s + "\n";
  };
  auto axis = [&](int j) -> const AxisPitch& { return axes[static_cast<size_t>(j)]; };
  std::string tape = "%\n";
  if (!o.fanuc.param_3605.empty())
    tape += param(3605,
                  [&](int j) { return param_3605(o.fanuc.param_3605, j, is_bidirectional(t, j)); });
  tape += param(3620, [&](int j) { return axis(j).reference; });
  tape += param(3621, [&](int j) { return axis(j).first; });
  tape += param(3622, [&](int j) { return axis(j).last; });
  tape += param(3623, [&](int j) { return axis(j).magnification; });
  tape += param(3624, [&](int j) {
    const double spacing = t.grid[static_cast<size_t>(j)].spacing;
    return o.fanuc.series == Series::k16i
               ? fmt::format("{}", std::llround(spacing / o.fanuc.input_increment_mm))
               : fixed(spacing, 4);
  });
  tape += param(3626, [&](int j) {
    return axis(j).minus.empty() ? std::int64_t{0} : kNegativeTable + axis(j).first;
  });
  tape += param(3627, [&](int j) { return axis(j).other_at_reference; });
  // In the order of their numbers: every axis's positive direction, then
  // the negative directions (3000 + point).
  for (const AxisPitch& p : axes) {
    std::int64_t n = p.first;
    for (std::int64_t v : p.plus) tape += fmt::format("N{}{}P{}\n", 10000 + n++, rules.q, v);
  }
  for (const AxisPitch& p : axes) {
    std::int64_t n = kNegativeTable + p.first;
    for (std::int64_t v : p.minus) tape += fmt::format("N{}{}P{}\n", 10000 + n++, rules.q, v);
  }
  return tape + "%\n";
}

// fanuc_3d_transcription.csv: the correction vector at every grid vertex
// (mean of the direction layers), detection units; how many lie outside
// the data range -128..127 in *outside.
std::string transcription_sheet(const VolumetricTable& t, double unit, std::int64_t* outside) {
  std::string body;
  std::vector<std::int64_t> idx(3);
  *outside = 0;
  for (std::int64_t n = 0; n < t.node_count(); ++n) {
    t.node_index(n, idx.data());
    body += fmt::format("{},{},{}", idx[0], idx[1], idx[2]);
    for (int d = 0; d < 3; ++d)
      body += "," + fixed(t.grid[static_cast<size_t>(d)].node(idx[static_cast<size_t>(d)]), 4);
    for (int d = 0; d < 3; ++d) {
      double sum = 0.0;
      for (int layer = 0; layer < t.layer_count(); ++layer) sum += t.at(layer, n)[du_channel(t, d)];
      const std::int64_t v = std::llround(sum / t.layer_count() / unit);
      if (v < -128 || v > 127) ++*outside;
      body += fmt::format(",{}", v);
    }
    body += "\n";
  }
  return fmt::format(
             "# volmap transcription sheet for FANUC three-dimensional error compensation (30i "
             "series): machine {}, errors {}\n"
             "# Not a file a FANUC control loads: enter the values on the 3-D error compensation "
             "data screen (or with FOCAS cnc_wrvolc) in the control's point order.\n"
             "# c*: correction added to the axis (commanded minus nominal), detection units of "
             "{:g} mm; data range -128..127 ({} values outside it)\n"
             "# Not confirmed by a FANUC source, check on the control: the parameters that set "
             "the lattice (origin, intervals, point counts) and its point numbering (FOCAS: "
             "1..15625)\n"
             "i,j,k,x_mm,y_mm,z_mm,cx,cy,cz\n",
             t.machine_name, t.errors_source, unit, *outside) +
         body;
}

}  // namespace

std::vector<ExportFile> fanuc(const VolumetricTable& t, const ExportOptions& o) {
  require_three_axis(t, "fanuc");
  const double unit = o.detection_unit_mm;
  if (!(unit > 0.0) || !std::isfinite(unit))
    throw ExportError("`format` fanuc: the detection unit must be a positive number of mm");
  for (const std::string& byte : o.fanuc.param_3605)
    if (byte.size() != 8 || byte.find_first_not_of("01") != std::string::npos)
      throw ExportError(fmt::format(
          "`format` fanuc: parameter 3605 {:?} is not 8 binary digits (bit 7 first, as the "
          "control shows it)",
          byte));
  if (!o.fanuc.param_3605.empty() && o.fanuc.param_3605.size() != 1 &&
      o.fanuc.param_3605.size() != 3)
    throw ExportError("`format` fanuc: give parameter 3605 once (every axis) or once per axis");
  const SeriesRules rules = rules_of(o.fanuc.series);
  const std::vector<std::int64_t> home = home_line_nodes(t, o);
  std::vector<AxisPitch> axes;
  std::int64_t next = 0;
  for (int j = 0; j < 3; ++j) {
    axes.push_back(axis_pitch(t, home, j, o, next));
    next = axes.back().last + 1;
  }
  if (next > rules.points)
    throw ExportError(fmt::format(
        "`format` fanuc: {} pitch error compensation points needed, the {} series has {} (0..{}) "
        "for all axes together: build the table with a coarser spacing",
        next, rules.name, rules.points, rules.points - 1));
  std::vector<AxisPitchSummary> summary;
  for (int j = 0; j < 3; ++j) {
    const AxisPitch& p = axes[static_cast<size_t>(j)];
    summary.push_back({p.reference, p.first, p.last, !p.minus.empty(), p.magnification,
                       p.other_at_reference, p.dropped_mm});
  }
  std::vector<ExportFile> files = {{"fanuc_pitch.txt", pitch_tape(t, axes, o)}};
  std::int64_t outside = 0;
  if (o.fanuc.series == Series::k30i)
    files.push_back({"fanuc_3d_transcription.csv", transcription_sheet(t, unit, &outside)});
  files.push_back({"FANUC.txt", fanuc_notes(t, home, summary, o, outside)});
  return files;
}

}  // namespace exporters
}  // namespace volmap::maps
