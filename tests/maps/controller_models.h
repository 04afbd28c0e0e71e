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

}  // namespace volmap::maps::controller_models
