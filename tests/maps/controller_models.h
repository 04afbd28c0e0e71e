// Controller models for the export tests: small interpreters, written from
// the controllers' documentation and source (docs/exports.md cites each
// rule), that read an exported file the way the controller reads it and
// say which axis positions the controller commands for a wanted position.
// The export tests then move a simulated real machine (the direct error
// model) to those positions and check that the tool tip lands where it was
// wanted. None of this shares code with maps/exports: a sign, unit or index
// the exporter gets wrong shows as a residual of the size of the error.
#pragma once

#include <Eigen/Dense>
#include <algorithm>
#include <array>
#include <cmath>
#include <functional>
#include <map>
#include <sstream>
#include <stdexcept>
#include <string>
#include <vector>

#include "core/model/error_model.h"

namespace volmap::maps::controller_models {

// ---- the simulated real machine ----

/// Where the tool tip of the three-axis test machines goes (axis frame, mm)
/// when the axes stand at c, X approached in direction x_dir: c + e(c), the
/// direct model's exact tip error. Positions are held inside the travel of
/// the errors (a correction may step a micrometre past a travel end).
inline Eigen::Vector3d actual_tip(const ErrorModel& m, const Eigen::Vector3d& c, int x_dir) {
  const std::array<double, 3> hi = {200.0, 100.0, 100.0};
  AxisVector u(3);
  for (int d = 0; d < 3; ++d) u[d] = std::clamp(c[d], 0.0, hi[static_cast<size_t>(d)]);
  const ApproachDirections dir = {static_cast<signed char>(x_dir), 0, 0, 0, 0, 0};
  return c + m.exact(u, dir).dP_mm;
}

/// The exact correction at P: the axis positions c with actual_tip(c) = P,
/// by fixed-point iteration (the error's slope is ~1e-4, so it converges
/// to rounding in a few steps).
inline Eigen::Vector3d exact_command(const ErrorModel& m, const Eigen::Vector3d& p, int x_dir) {
  Eigen::Vector3d c = p;
  for (int it = 0; it < 30; ++it) c += p - actual_tip(m, c, x_dir);
  return c;
}

// ---- shared reading helpers ----

/// Linear interpolation in a table of strictly increasing positions,
/// holding the end values outside (as every table here is read).
inline double interpolate(const std::vector<double>& pos, const std::vector<double>& val,
                          double x) {
  if (pos.empty()) return 0.0;
  if (x <= pos.front()) return val.front();
  if (x >= pos.back()) return val.back();
  const size_t k = static_cast<size_t>(std::upper_bound(pos.begin(), pos.end(), x) - pos.begin());
  const double f = (x - pos[k - 1]) / (pos[k] - pos[k - 1]);
  return val[k - 1] + f * (val[k] - val[k - 1]);
}

inline std::vector<std::string> lines_of(const std::string& text) {
  std::vector<std::string> out;
  std::istringstream in(text);
  std::string line;
  while (std::getline(in, line)) {
    if (!line.empty() && line.back() == '\r') line.pop_back();
    out.push_back(line);
  }
  return out;
}

/// strtod that must consume the whole (trimmed) field.
inline double number(const std::string& field, const std::string& where) {
  size_t b = field.find_first_not_of(' '), e = field.find_last_not_of(' ');
  if (b == std::string::npos) throw std::runtime_error(where + ": empty field");
  const std::string s = field.substr(b, e - b + 1);
  char* end = nullptr;
  const double v = std::strtod(s.c_str(), &end);
  if (end != s.c_str() + s.size()) throw std::runtime_error(where + ": not a number: " + s);
  return v;
}

// ---- LinuxCNC joint compensation (COMP_FILE, COMP_FILE_TYPE 0) ----
//
// LinuxCNC 2.9, src/emc/motion/usrmotintf.cc usrmotLoadComp: each line is
// read with sscanf("%lf %lf %lf"), reading stops at the first line that is
// not three numbers; type 0 stores fwd_trim = nominal - forward, rev_trim =
// nominal - reverse. command.c EMCMOT_SET_JOINT_COMP refuses a nominal not
// above the previous one and more than EMCMOT_COMP_SIZE (256) entries.
// control.c compute_screw_comp: the trim is interpolated linearly at the
// commanded joint position (pos_cmd), with the forward trims when the joint
// moves up and the reverse trims when it moves down, held constant outside
// the table; it is added to the command (motor_pos_cmd = pos_cmd +
// backlash_filt + motor_offset).
struct LinuxCncJoint {
  std::vector<double> nominal, fwd_trim, rev_trim;
  double trim(double pos_cmd, int vel_sign) const {
    return interpolate(nominal, vel_sign < 0 ? rev_trim : fwd_trim, pos_cmd);
  }
};

inline LinuxCncJoint read_linuxcnc_comp(const std::string& text) {
  LinuxCncJoint j;
  for (const std::string& line : lines_of(text)) {
    double nom, fwd, rev;
    if (std::sscanf(line.c_str(), "%lf %lf %lf", &nom, &fwd, &rev) != 3) break;
    if (!j.nominal.empty() && nom <= j.nominal.back())
      throw std::runtime_error("compensation values must increase");
    if (j.nominal.size() >= 256) throw std::runtime_error("too many compensation entries");
    j.nominal.push_back(nom);
    j.fwd_trim.push_back(nom - fwd);
    j.rev_trim.push_back(nom - rev);
  }
  return j;
}

// ---- SINUMERIK .ini part programs (LEC %_N_AX_EEC_INI, CEC %_N_NC_CEC_INI) ----
//
// The lines a SINUMERIK reads from these files: the program name line
// ("%_N_<name>_INI"), CHANDATA(n), comments after ';', system variable
// assignments "$NAME[i,j,...]=value" and the end M17. Anything else is an
// error here (the control would raise an alarm on it). Values are kept as
// text by name and index list, e.g. values["$AA_ENC_COMP"]["0,3,AX1"].
struct SiemensIni {
  std::string program;
  std::map<std::string, std::map<std::string, std::string>> values;
  const std::string& at(const std::string& name, const std::string& index) const {
    auto n = values.find(name);
    if (n == values.end() || n->second.count(index) == 0)
      throw std::runtime_error("no " + name + "[" + index + "]");
    return n->second.at(index);
  }
  double number_at(const std::string& name, const std::string& index) const {
    return number(at(name, index), name + "[" + index + "]");
  }
};

inline SiemensIni read_siemens_ini(const std::string& text) {
  SiemensIni ini;
  bool ended = false;
  for (const std::string& raw : lines_of(text)) {
    std::string line = raw.substr(0, raw.find(';'));
    while (!line.empty() && line.back() == ' ') line.pop_back();
    if (line.empty()) continue;
    if (ended) throw std::runtime_error("text after M17: " + line);
    if (ini.program.empty()) {
      if (line.rfind("%_N_", 0) != 0 || line.size() < 9 || line.substr(line.size() - 4) != "_INI")
        throw std::runtime_error("first line is not %_N_<name>_INI: " + line);
      ini.program = line;
      continue;
    }
    if (line.rfind("CHANDATA(", 0) == 0) continue;
    if (line == "M17") {
      ended = true;
      continue;
    }
    const size_t open = line.find('['), close = line.find(']'), eq = line.find('=');
    if (line[0] != '$' || open == std::string::npos || close < open || eq != close + 1)
      throw std::runtime_error("not an assignment: " + line);
    ini.values[line.substr(0, open)][line.substr(open + 1, close - open - 1)] = line.substr(eq + 1);
  }
  if (!ended) throw std::runtime_error("no M17");
  return ini;
}

// AXn -> n - 1 (the general machine axis names the exports use).
inline int siemens_axis(std::string name) {
  if (name.size() > 2 && name.front() == '(' && name.back() == ')')
    name = name.substr(1, name.size() - 2);
  if (name.size() != 3 || name.rfind("AX", 0) != 0 || name[2] < '1' || name[2] > '3')
    throw std::runtime_error("not AX1..AX3: " + name);
  return name[2] - '1';
}

/// The points of an equidistant SINUMERIK table: positions MIN + N STEP for
/// N = 0 .. (MAX - MIN) / STEP, values read by `value_of(N)` (each must be
/// there). Modulo tables are not used by the exports and refused here.
inline void siemens_points(double min, double max, double step,
                           const std::function<double(int)>& value_of, std::vector<double>& pos,
                           std::vector<double>& val) {
  const double n = (max - min) / step;
  if (!(step > 0) || std::abs(n - std::round(n)) > 1e-9) throw std::runtime_error("bad STEP");
  for (int k = 0; k <= static_cast<int>(std::lround(n)); ++k) {
    pos.push_back(min + k * step);
    val.push_back(value_of(k));
  }
}

// LEC (K3 4.4.2, MSEC): the actual value of the axis's measuring system is
// modified by the table value at the axis's position, linearly interpolated,
// the end values held outside MIN..MAX; "a positive compensation value
// causes the corresponding machine axis to move in the negative
// direction". The position loop drives the modified actual value m + v(m)
// to the setpoint s, so the encoder (the axis) stands at m = s - v(m).
struct SiemensLec {
  std::array<std::vector<double>, 3> pos, val;
  double axis_position(int axis, double setpoint) const {
    double m = setpoint;
    for (int it = 0; it < 5; ++it)
      m = setpoint - interpolate(pos[static_cast<size_t>(axis)], val[static_cast<size_t>(axis)], m);
    return m;
  }
};

inline SiemensLec read_siemens_lec(const SiemensIni& ini) {
  if (ini.program != "%_N_AX_EEC_INI") throw std::runtime_error("not %_N_AX_EEC_INI");
  SiemensLec lec;
  for (const auto& entry : ini.values.at("$AA_ENC_COMP_STEP")) {
    const std::string& index = entry.first;
    const std::string& text = entry.second;
    const std::string ax = index.substr(index.find(',') + 1);
    const int a = siemens_axis(ax);
    if (ini.number_at("$AA_ENC_COMP_IS_MODULO", index) != 0) throw std::runtime_error("modulo");
    siemens_points(
        ini.number_at("$AA_ENC_COMP_MIN", index), ini.number_at("$AA_ENC_COMP_MAX", index),
        number(text, "STEP"),
        [&](int k) { return ini.number_at("$AA_ENC_COMP", "0," + std::to_string(k) + "," + ax); },
        lec.pos[static_cast<size_t>(a)], lec.val[static_cast<size_t>(a)]);
  }
  return lec;
}

// CEC (K3 4.4.3): table t is read at the setpoint of its input axis
// (linear interpolation, end values held), for both directions of travel
// of the input axis (DIRECTION 0) or only the positive (1) / negative (-1)
// one, and its output is added to the setpoint of its output axis; tables
// of one axis add up. A table acts only while SD41300
// $SN_CEC_TABLE_ENABLE[t] = 1 (not set: 0).
struct SiemensCec {
  struct Table {
    int input = 0, output = 0, direction = 0;
    bool enabled = false;
    std::vector<double> pos, val;
  };
  std::vector<Table> tables;
  Eigen::Vector3d added(const Eigen::Vector3d& setpoint, const std::array<int, 3>& moving) const {
    Eigen::Vector3d add = Eigen::Vector3d::Zero();
    for (const Table& t : tables) {
      const int m = moving[static_cast<size_t>(t.input)];
      if (!t.enabled || (t.direction != 0 && t.direction != m)) continue;
      add[t.output] += interpolate(t.pos, t.val, setpoint[t.input]);
    }
    return add;
  }
};

inline SiemensCec read_siemens_cec(const SiemensIni& ini) {
  if (ini.program != "%_N_NC_CEC_INI") throw std::runtime_error("not %_N_NC_CEC_INI");
  SiemensCec cec;
  for (const auto& entry : ini.values.at("$AN_CEC_INPUT_AXIS")) {
    const std::string& index = entry.first;
    const std::string& text = entry.second;
    SiemensCec::Table t;
    t.input = siemens_axis(text);
    t.output = siemens_axis(ini.at("$AN_CEC_OUTPUT_AXIS", index));
    t.direction = static_cast<int>(ini.number_at("$AN_CEC_DIRECTION", index));
    if (ini.number_at("$AN_CEC_MULT_BY_TABLE", index) != 0 ||
        ini.number_at("$AN_CEC_IS_MODULO", index) != 0)
      throw std::runtime_error("multiplied or modulo table");
    auto enable = ini.values.find("$SN_CEC_TABLE_ENABLE");
    t.enabled = enable != ini.values.end() && enable->second.count(index) != 0 &&
                number(enable->second.at(index), "SD41300") == 1;
    siemens_points(
        ini.number_at("$AN_CEC_MIN", index), ini.number_at("$AN_CEC_MAX", index),
        ini.number_at("$AN_CEC_STEP", index),
        [&](int k) { return ini.number_at("$AN_CEC", index + "," + std::to_string(k)); }, t.pos,
        t.val);
    cec.tables.push_back(std::move(t));
  }
  return cec;
}

// ---- HEIDENHAIN TNC tables (.COM, .CMA) ----
//
// Read as the TNC and pyLSV2's table reader (pyLSV2/table_reader.py,
// NCTable.parse_table) read them: line 1 "BEGIN <name>[ MM|INCH]", line 2
// the column names, each followed by blanks; a column starts where its name
// starts and ends where the next name starts (the last one at the end of
// the header line); every row is sliced at those positions and the slice
// stripped of blanks; "[END]" ends the table. Nothing is split at blanks,
// so a value that is not inside its column's slice is read wrong or not
// at all, as on the control.
struct TncTable {
  std::string begin;  ///< the BEGIN line's text after "BEGIN "
  std::vector<std::string> columns;
  std::vector<std::map<std::string, std::string>> rows;
  double number_at(size_t row, const std::string& column) const {
    return number(rows.at(row).at(column), begin + " row " + std::to_string(row) + " " + column);
  }
};

inline TncTable read_tnc_table(const std::string& text) {
  const std::vector<std::string> lines = lines_of(text);
  if (lines.size() < 3 || lines[0].rfind("BEGIN ", 0) != 0)
    throw std::runtime_error("not a TNC table");
  TncTable t;
  t.begin = lines[0].substr(6);
  const std::string& header = lines[1];
  std::vector<size_t> start;
  for (size_t i = 0; i < header.size();) {
    if (header[i] == ' ') {
      ++i;
      continue;
    }
    const size_t end = header.find(' ', i);
    if (end == std::string::npos) throw std::runtime_error("column name without a blank after it");
    start.push_back(i);
    t.columns.push_back(header.substr(i, end - i));
    i = end;
  }
  start.push_back(header.size());
  bool ended = false;
  for (size_t l = 2; l < lines.size(); ++l) {
    if (lines[l].rfind("[END]", 0) == 0) {
      ended = true;
      break;
    }
    std::map<std::string, std::string> row;
    for (size_t c = 0; c < t.columns.size(); ++c) {
      std::string cell =
          start[c] < lines[l].size() ? lines[l].substr(start[c], start[c + 1] - start[c]) : "";
      const size_t b = cell.find_first_not_of(' '), e = cell.find_last_not_of(' ');
      row[t.columns[c]] = b == std::string::npos ? "" : cell.substr(b, e - b + 1);
    }
    t.rows.push_back(std::move(row));
  }
  if (!ended) throw std::runtime_error("no [END]");
  return t;
}

}  // namespace volmap::maps::controller_models
