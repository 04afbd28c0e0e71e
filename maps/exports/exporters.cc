#include "maps/exports/exporters.h"

#include <fmt/format.h>

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <memory>

#include "maps/tables/output_wording.h"

namespace volmap::maps {

const std::vector<std::string>& export_formats() {
  static const std::vector<std::string> f = {"csv",         "json",       "linuxcnc", "siemens-lec",
                                             "siemens-cec", "heidenhain", "fanuc",    "isg-csv"};
  return f;
}

std::vector<ExportFile> export_table(const VolumetricTable& table, const std::string& format,
                                     const ExportOptions& options) {
  if (format == "csv") return exporters::csv(table, options);
  if (format == "json") return exporters::json(table, options);
  if (format == "linuxcnc") return exporters::linuxcnc(table, options);
  if (format == "siemens-lec") return exporters::siemens_lec(table, options);
  if (format == "siemens-cec") return exporters::siemens_cec(table, options);
  if (format == "heidenhain") return exporters::heidenhain(table, options);
  if (format == "fanuc") return exporters::fanuc(table, options);
  if (format == "isg-csv") return exporters::isg_csv(table, options);
  std::string known;
  for (const std::string& f : export_formats()) known += (known.empty() ? "" : ", ") + f;
  throw ExportError(fmt::format("`format` {}: unknown format; expected one of {}", format, known));
}

void write_export(const std::string& dir, const std::vector<ExportFile>& files) {
  namespace fs = std::filesystem;
  std::error_code ec;
  fs::create_directories(dir, ec);
  if (ec || !fs::is_directory(dir))
    throw std::runtime_error(fmt::format("{}: cannot create the folder ({}); check the path", dir,
                                         ec ? ec.message() : "not a folder"));
  std::vector<std::unique_ptr<AtomicOutput>> out;
  for (const ExportFile& f : files) {
    out.push_back(std::make_unique<AtomicOutput>((fs::path(dir) / f.name).string(),
                                                 std::vector<std::string>{}, kOutputWording));
    out.back()->stream() << f.text;
    if (!out.back()->stream())
      throw std::runtime_error(fmt::format("{}: write error (disk full?)", out.back()->path()));
  }
  for (auto& o : out) o->commit();
}

namespace exporters {

std::vector<std::int64_t> home_line_nodes(const VolumetricTable& t, const ExportOptions& o) {
  std::vector<std::int64_t> idx;
  for (int d = 0; d < t.axis_count(); ++d) {
    const GridAxis& g = t.grid[static_cast<size_t>(d)];
    const double h =
        static_cast<size_t>(d) < o.home.size() ? o.home[static_cast<size_t>(d)] : g.start;
    std::int64_t best = 0;
    for (std::int64_t k = 1; k < g.count; ++k)
      if (std::abs(g.node(k) - h) < std::abs(g.node(best) - h)) best = k;
    idx.push_back(best);
  }
  return idx;
}

std::vector<double> along_axis(const VolumetricTable& t, const std::vector<std::int64_t>& home,
                               int axis, int channel, int dir) {
  const GridAxis& g = t.grid[static_cast<size_t>(axis)];
  std::vector<double> out(static_cast<size_t>(g.count), 0.0);
  std::int64_t stride = 1, base = 0;
  // Storage order: first axis fastest.
  std::int64_t s = 1;
  for (int d = 0; d < t.axis_count(); ++d) {
    if (d == axis)
      stride = s;
    else
      base += home[static_cast<size_t>(d)] * s;
    s *= t.grid[static_cast<size_t>(d)].count;
  }
  int used = 0;
  for (int layer = 0; layer < t.layer_count(); ++layer) {
    const ApproachDirections ld = t.layer_directions(layer);
    if (dir != 0 && ld[static_cast<size_t>(axis)] != 0 && ld[static_cast<size_t>(axis)] != dir)
      continue;
    ++used;
    for (std::int64_t k = 0; k < g.count; ++k)
      out[static_cast<size_t>(k)] += t.at(layer, base + k * stride)[channel];
  }
  for (double& v : out) v /= used;
  return out;
}

double interpolate_nodes(const GridAxis& g, const std::vector<double>& values, double pos) {
  std::int64_t i = 0;
  double s = 0.0;
  g.locate(std::clamp(pos, g.start, g.end), i, s);  // the grid's own cell search
  return (1 - s) * values[static_cast<size_t>(i)] + s * values[static_cast<size_t>(i + 1)];
}

const ErrorSet& require_errors(const ExportOptions& o, const std::string& format) {
  if (o.errors == nullptr)
    throw ExportError(fmt::format(
        "`format` {}: needs the component errors the table was built from; give them with "
        "`errors` E.csv (volmap, ISG CSV or Etalon format)",
        format));
  return *o.errors;
}

int du_channel(const VolumetricTable& t, int axis) {
  return *t.channel(std::string("u") + static_cast<char>('x' + axis));
}

bool is_bidirectional(const VolumetricTable& t, int axis) {
  for (int a : t.bidirectional_axes)
    if (a == axis) return true;
  return false;
}

std::string fixed(double v, int decimals) {
  std::string s = fmt::format("{:.{}f}", v, decimals);
  if (s[0] == '-' && s.find_first_not_of("-0.") == std::string::npos) s.erase(0, 1);
  return s;
}

double display_position(AxisName a, double v) { return is_rotary(a) ? v * 180.0 / M_PI : v; }

void require_uniform(const VolumetricTable& t, int axis, const std::string& format) {
  const GridAxis& g = t.grid[static_cast<size_t>(axis)];
  if (!g.uniform())
    throw ExportError(fmt::format(
        "`format` {}: axis {}: the spacing {:g} does not divide the travel {:g}..{:g} (the last "
        "cell is shorter), but the controller needs equidistant points; build the table with a "
        "spacing that divides the travel",
        format, axis_char(g.axis), g.spacing, g.start, g.end));
}

void require_three_axis(const VolumetricTable& t, const std::string& format) {
  if (!t.three_axis_correction()) {
    std::string axes;
    for (const GridAxis& g : t.grid) axes += axis_char(g.axis);
    throw ExportError(fmt::format(
        "`format` {}: the controller takes three-axis tables (linear X, Y, Z with the correction "
        "du) only, this table has {} axes ({}); export it as csv or json{}",
        format, t.axis_count(), axes,
        format == "heidenhain" ? ", or give `errors` for the KinematicsComp tables" : ""));
  }
}

}  // namespace exporters
}  // namespace volmap::maps
