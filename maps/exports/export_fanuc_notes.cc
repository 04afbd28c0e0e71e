// FANUC.txt: what the FANUC export wrote, in words: the parameters and
// their values per axis, signs and units, the series rules applied, and
// what no public source settles (to check on the control before use).
// Sources: docs/exports.md, "fanuc".
#include <fmt/format.h>

#include "maps/exports/exporters.h"

namespace volmap::maps::exporters {

namespace {

std::string axis_lines(const VolumetricTable& t, const std::vector<std::int64_t>& home,
                       const std::vector<AxisPitchSummary>& axes, const ExportOptions& o) {
  std::string s;
  for (int j = 0; j < 3; ++j) {
    const GridAxis& g = t.grid[static_cast<size_t>(j)];
    const AxisPitchSummary& p = axes[static_cast<size_t>(j)];
    s += fmt::format(
        "  A{} = {}: 3620 = {} (reference position {:g} mm), points {}..{}{}, magnification {}; "
        "the compensation at the reference position, {} µm, is not in the table (the "
        "reference position / grid shift takes it){}\n",
        j + 1, axis_char(g.axis), p.reference, g.node(home[static_cast<size_t>(j)]), p.first,
        p.last,
        p.bidirectional
            ? fmt::format(" and {}..{} (negative direction)", 3000 + p.first, 3000 + p.last)
            : std::string(""),
        p.magnification, fixed(p.dropped_mm * 1e3, 3),
        p.bidirectional ? fmt::format("; 3627 = {} detection units", p.other_at_reference)
                        : std::string(""));
  }
  if (o.fanuc.param_3605.empty()) {
    std::string bidir;
    for (int j = 0; j < 3; ++j)
      bidir += fmt::format("{}A{} {}", j == 0 ? "" : ", ", j + 1,
                           axes[static_cast<size_t>(j)].bidirectional ? 1 : 0);
    s += fmt::format(
        "  3605 is NOT on the tape (a tape record rewrites all eight bits of a bit parameter):\n"
        "  set bit 0 (BDPx) by hand to {} and keep the other bits, or export again with\n"
        "  --fanuc-param-3605 giving the control's current value.\n",
        bidir);
  }
  return s;
}

}  // namespace

std::string fanuc_notes(const VolumetricTable& t, const std::vector<std::int64_t>& home,
                        const std::vector<AxisPitchSummary>& axes, const ExportOptions& o,
                        std::int64_t outside) {
  const bool s16 = o.fanuc.series == FanucOptions::Series::k16i;
  std::string notes = fmt::format(
      "volmap export for FANUC: machine {}, errors {}\n"
      "Series {}\n  ({}).\n"
      "Detection unit {:g} mm. Axis numbers A1 A2 A3 = X Y Z (renumber to the control's axes).\n"
      "Reference position return direction {} (1006#5 ZMI = {}).\n\n",
      t.machine_name, t.errors_source, s16 ? "16i" : "30i",
      s16 ? "16i/18i/21i, 0i-A..0i-D: points 0..1023, values -7..7, 3624 in least input "
            "increments"
          : "30i/31i/32i, 0i-F: points 0..1535, values -128..127, 3624 in mm, Q1 records",
      o.detection_unit_mm, o.fanuc.reference_direction > 0 ? "positive" : "negative",
      o.fanuc.reference_direction > 0 ? 0 : 1);
  notes += fmt::format(
      "fanuc_pitch.txt (stored pitch error compensation, parameter tape record; input it in\n"
      "emergency stop with parameter write enabled):\n"
      "  3605#0 bidirectional pitch error compensation (BDPx){}\n"
      "  3620 point of the reference position; 3621 / 3622 first / last point (positive\n"
      "  direction); 3621 = 3620 - (travel below the reference / interval) + 1, except with\n"
      "  the reference at the travel start: 3621 = 3620 (the reference point's own zero\n"
      "  section, as in FANUC's rotary example)\n"
      "  3623 magnification; 3624 interval ({}); 3626 first point of the negative direction\n"
      "  (3000 + 3621); 3627 absolute compensation at the reference position when it is\n"
      "  approached against the reference return direction (detection units)\n"
      "  N1pppp: point pppp holds the increment of the compensation over the section from\n"
      "  point pppp-1 to pppp (compensation = commanded minus nominal position, about minus\n"
      "  the error), detection units x magnification; zero at the reference position.\n",
      o.fanuc.param_3605.empty() ? ": not written, see below"
                                 : ": the given value with bit 0 set from the table",
      s16 ? fmt::format("least input increments of {:g} mm", o.fanuc.input_increment_mm)
          : std::string("mm"));
  notes += axis_lines(t, home, axes, o);
  if (!s16)
    notes += fmt::format(
        "\nfanuc_3d_transcription.csv: the correction vector at every grid vertex (mean of the\n"
        "approach directions), detection units, for the three-dimensional error compensation\n"
        "data screen; the control interpolates it trilinearly in each cell. A sheet to\n"
        "transcribe, not a file the control loads.{}\n"
        "Not confirmed by a FANUC source: the parameters that set the lattice (origin,\n"
        "intervals, point counts) and the control's point numbering (FOCAS numbers them\n"
        "1..15625); check them in the control's 3-D error compensation documentation.\n",
        outside > 0 ? fmt::format(" {} values lie outside -128..127 and cannot be entered as "
                                  "they are.",
                                  outside)
                    : std::string(""));
  notes +=
      "\nNot confirmed by a FANUC source, check on the control before use: the pitch data\n"
      "record (N10000 + point, Q1 on the 30i series), 3624's unit, 3627's unit and sign, the\n"
      "magnification range 1..100, the sign of the compensation (commanded minus nominal),\n"
      "and the load procedure (emergency stop, parameter write enabled, input from the memory\n"
      "card or RS-232 on the parameter screen): follow the machine's manual.\n"
      "Run the axis to a few points with a laser after loading.\n";
  return notes;
}

}  // namespace volmap::maps::exporters
