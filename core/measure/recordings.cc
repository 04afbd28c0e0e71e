// Recordings: the table's own checks, and the writer of the recordings CSV
// (contract: core/measure/recordings.h, spec: shared/spec/recordings.md).
// The reader is recordings_reader.cc.
#include "core/measure/recordings.h"

#include <fmt/format.h>

#include <cmath>
#include <cstdlib>
#include <functional>
#include <ostream>
#include <stdexcept>
#include <string>
#include <vector>

#include "core/common/csv.h"
#include "core/common/input_error.h"
#include "core/common/units.h"
#include "core/measure/recordings_columns.h"

namespace volmap {
namespace {

using namespace recordings_columns;

std::string fixed(double v, int decimals) {
  if (std::isnan(v)) return std::string();
  std::string s = fmt::format("{:.{}f}", v, decimals);
  if (s.front() == '-' && s.find_first_not_of("-0.") == std::string::npos) s.erase(0, 1);
  return s;
}

}  // namespace

std::int32_t Recordings::run_index(const std::string& name) {
  for (std::size_t k = 0; k < run_names.size(); ++k)
    if (run_names[k] == name) return static_cast<std::int32_t>(k);
  run_names.push_back(name);
  return static_cast<std::int32_t>(run_names.size() - 1);
}

void Recordings::check_consistent() const {
  const std::size_t n_rows = size();
  auto check = [&](std::size_t s, const std::string& what) {
    if (s != 0 && s != n_rows)
      throw std::logic_error(
          fmt::format("recordings column {} has {} rows, expected {}", what, s, n_rows));
  };
  for (int a = 0; a < kAxisNameCount; ++a) {
    check(position[static_cast<std::size_t>(a)].size(),
          kPositionColumns[static_cast<std::size_t>(a)]);
    check(dir[static_cast<std::size_t>(a)].size(), kDirColumns[static_cast<std::size_t>(a)]);
  }
  for (std::size_t c = 0; c < 3; ++c) {
    check(e_um[c].size(), kDeviationColumns[c]);
    check(n[c].size(), kNormalColumns[c]);
    if (n[c].size() != e_along_n_um.size())
      throw std::logic_error("recordings: nx, ny, nz and e_um must come together");
  }
  check(e_along_n_um.size(), "e_um");
  check(run.size(), "run");
  check(t_s.size(), "t_s");
  check(feed_mm_min.size(), "feed_mm_min");
  check(tool_mm.size(), "tool_mm");
  check(weight.size(), "weight");
  for (const NamedColumn& c : temperature_c)
    if (c.values.size() != n_rows)
      throw std::logic_error(fmt::format("recordings column {} has {} rows, expected {}", c.name,
                                         c.values.size(), n_rows));
  for (const ExtraColumn& c : extra)
    if (c.text.size() != n_rows || c.value.size() != n_rows)
      throw std::logic_error(fmt::format("recordings column {} has {} rows, expected {}", c.name,
                                         c.text.size(), n_rows));
}

std::string position_column_name(AxisName a) {
  return kPositionColumns[static_cast<std::size_t>(a)];
}
std::string dir_column_name(AxisName a) { return kDirColumns[static_cast<std::size_t>(a)]; }

double quantize_recorded_position(AxisName a, double position) {
  const bool rotary = is_rotary(a);
  const std::string s = fixed(rotary ? position / units::kRadPerDeg : position,
                              rotary ? RecordingDecimals::kDegree : RecordingDecimals::kMillimetre);
  const double v = *csv::parse_number(s);
  return rotary ? v * units::kRadPerDeg : v;
}

void write_recordings_csv(std::ostream& out, const Recordings& r) {
  r.check_consistent();
  using D = RecordingDecimals;
  struct Out {
    std::string name;
    std::function<std::string(std::size_t)> cell;
  };
  std::vector<Out> cols;
  if (r.has_run())
    cols.push_back({"run", [&](std::size_t i) {
                      const std::int32_t k = r.run[i];
                      return k < 0 ? std::string() : r.run_names[static_cast<std::size_t>(k)];
                    }});
  if (!r.t_s.empty())
    cols.push_back({"t_s", [&](std::size_t i) { return fixed(r.t_s[i], D::kSecond); }});
  for (int a = 0; a < kAxisNameCount; ++a) {
    const auto& v = r.position[static_cast<std::size_t>(a)];
    if (v.empty()) continue;
    const bool rotary = is_rotary(static_cast<AxisName>(a));
    cols.push_back({kPositionColumns[static_cast<std::size_t>(a)], [&v, rotary](std::size_t i) {
                      return rotary ? fixed(v[i] / units::kRadPerDeg, D::kDegree)
                                    : fixed(v[i], D::kMillimetre);
                    }});
  }
  for (int a = 0; a < kAxisNameCount; ++a) {
    const auto& v = r.dir[static_cast<std::size_t>(a)];
    if (v.empty()) continue;
    cols.push_back(
        {kDirColumns[static_cast<std::size_t>(a)], [&v](std::size_t i) {
           return v[i] > 0 ? std::string("+1") : v[i] < 0 ? std::string("-1") : std::string("0");
         }});
  }
  if (!r.feed_mm_min.empty())
    cols.push_back(
        {"feed_mm_min", [&](std::size_t i) { return fixed(r.feed_mm_min[i], D::kFeed); }});
  if (!r.tool_mm.empty())
    cols.push_back({"tool_mm", [&](std::size_t i) { return fixed(r.tool_mm[i], D::kMillimetre); }});
  for (const NamedColumn& c : r.temperature_c)
    cols.push_back({c.name, [&c](std::size_t i) { return fixed(c.values[i], D::kCelsius); }});
  if (!r.weight.empty())
    cols.push_back({"weight", [&](std::size_t i) { return fixed(r.weight[i], D::kWeight); }});
  for (std::size_t c = 0; c < 3; ++c) {
    const auto& v = r.e_um[c];
    if (v.empty()) continue;
    cols.push_back(
        {kDeviationColumns[c], [&v](std::size_t i) { return fixed(v[i], D::kMicrometre); }});
  }
  if (r.has_projection()) {
    for (std::size_t c = 0; c < 3; ++c) {
      const auto& v = r.n[c];
      cols.push_back(
          {kNormalColumns[c], [&v](std::size_t i) { return fixed(v[i], D::kDirection); }});
    }
    cols.push_back(
        {"e_um", [&](std::size_t i) { return fixed(r.e_along_n_um[i], D::kMicrometre); }});
  }
  for (const ExtraColumn& c : r.extra)
    cols.push_back({c.name, [&c](std::size_t i) { return c.text[i]; }});

  std::string text = "# volmap recordings v1\n";
  std::map<std::string, std::string> meta = r.metadata;
  meta.erase("frame");
  bool any_rotary = false;
  for (int a = 3; a < kAxisNameCount; ++a)
    any_rotary = any_rotary || !r.position[static_cast<std::size_t>(a)].empty();
  if (r.frame == RecordingFrame::kMachine || any_rotary)
    meta["frame"] = r.frame == RecordingFrame::kMachine ? "machine" : "workpiece";
  for (const auto& [k, v] : meta) text += "# " + k + ": " + v + "\n";
  for (std::size_t j = 0; j < cols.size(); ++j) {
    if (j > 0) text += ',';
    text += cols[j].name;
  }
  text += '\n';
  out << text;
  for (std::size_t i = 0; i < r.size(); ++i) {
    text.clear();
    for (std::size_t j = 0; j < cols.size(); ++j) {
      if (j > 0) text += ',';
      text += cols[j].cell(i);
    }
    text += '\n';
    out << text;
  }
}

void require_machine_tool_length(const Recordings& r, double machine_tool_mm,
                                 const std::string& machine_name) {
  constexpr double kTolMm = 1e-3;
  auto refuse = [&](int line, double tool_mm) {
    throw InputError(
        r.file, line,
        fmt::format(
            "tool length {:g} mm, machine \"{}\" has {:g} mm; the fit predicts with the machine's "
            "tool: set tool_length_mm in the machine file to the tool of the recording, or split "
            "the recording by tool",
            tool_mm, machine_name, machine_tool_mm));
  };
  for (std::size_t i = 0; i < r.tool_mm.size(); ++i)
    if (std::isfinite(r.tool_mm[i]) && std::abs(r.tool_mm[i] - machine_tool_mm) > kTolMm)
      refuse(i < r.line.size() ? r.line[i] : 0, r.tool_mm[i]);
  const auto it = r.metadata.find("tool_mm");
  if (it != r.metadata.end() && r.tool_mm.empty()) {
    char* end = nullptr;
    const double v = std::strtod(it->second.c_str(), &end);
    if (end != it->second.c_str() && std::isfinite(v) && std::abs(v - machine_tool_mm) > kTolMm)
      refuse(0, v);
  }
}

}  // namespace volmap
