// A model of a FANUC control reading the pitch error compensation tape and
// the 3-D error compensation data (tests/maps/controller_models.h says what
// these models are for). The rules, from the sources docs/exports.md cites:
//  * tape: "%", records "N<number>[Q1]A<axis>P<value>..." (parameters,
//    30i series with Q1) and "N<10000 + point>[Q1]P<value>" (pitch data),
//    "%" (FANUC parameter manuals, "Inputting and outputting parameters").
//  * point n holds the increment of the compensation over the section from
//    point n-1 to point n, times the magnification 3623, in detection
//    units; the compensation is zero at the reference position (3620) for
//    the reference return direction; compensation positions are the
//    reference position plus (n - 3620) x 3624 (FANUC's examples: the
//    reference point's value is that of the section ending there).
//  * bidirectional (3605#0): negative-direction points 3000 + n from 3626,
//    starting from 3627 (absolute, detection units) at the reference.
//  * between points the compensation is taken linearly (the interpolated
//    variant; classic pitch compensation outputs each increment within its
//    section, which differs from this by less than one point's value).
#pragma once

#include <array>
#include <map>
#include <stdexcept>
#include <string>
#include <vector>

#include "tests/maps/controller_models.h"

namespace volmap::maps::controller_models {

struct FanucTape {
  bool q1 = false;                                      ///< records with Q1 (30i series)
  std::map<int, std::array<std::string, 3>> parameter;  ///< number -> value of A1..A3
  std::map<long, long> pitch;                           ///< point -> value
  long param(int number, int axis) const {
    return std::stol(parameter.at(number).at(static_cast<size_t>(axis)));
  }
};

inline FanucTape read_fanuc_tape(const std::string& text) {
  const std::vector<std::string> lines = lines_of(text);
  if (lines.size() < 2 || lines.front() != "%" || lines.back() != "%")
    throw std::runtime_error("a tape record starts and ends with %");
  FanucTape tape;
  for (size_t l = 1; l + 1 < lines.size(); ++l) {
    const std::string& r = lines[l];
    size_t i = 1;
    if (r.empty() || r[0] != 'N') throw std::runtime_error("not an N record: " + r);
    while (i < r.size() && std::isdigit(static_cast<unsigned char>(r[i]))) ++i;
    const long number = std::stol(r.substr(1, i - 1));
    const bool q1 = r.compare(i, 2, "Q1") == 0;
    if (l == 1) tape.q1 = q1;
    if (q1 != tape.q1) throw std::runtime_error("Q1 on some records only: " + r);
    if (q1) i += 2;
    if (number >= 10000) {
      if (r[i] != 'P') throw std::runtime_error("pitch record without P: " + r);
      tape.pitch[number - 10000] = std::stol(r.substr(i + 1));
      continue;
    }
    std::array<std::string, 3> v;
    for (int a = 0; a < 3; ++a) {
      const std::string key = "A" + std::to_string(a + 1) + "P";
      if (r.compare(i, key.size(), key) != 0)
        throw std::runtime_error("expected " + key + ": " + r);
      i += key.size();
      const size_t end = r.find('A', i);
      v[static_cast<size_t>(a)] = r.substr(i, end == std::string::npos ? end : end - i);
      i = end;
    }
    tape.parameter[static_cast<int>(number)] = v;
  }
  return tape;
}

/// The compensation (mm) of axis `axis` at machine position x, moving in
/// direction dir, for a control whose reference position is ref_mm,
/// reference return direction ref_dir, detection unit unit_mm and (16i)
/// least input increment input_mm.
inline double fanuc_pitch_compensation(const FanucTape& tape, int axis, double x, int dir,
                                       double ref_mm, int ref_dir, double unit_mm,
                                       double input_mm) {
  const long ref = tape.param(3620, axis), first = tape.param(3621, axis),
             last = tape.param(3622, axis), mag = tape.param(3623, axis);
  const double interval = tape.q1
                              ? number(tape.parameter.at(3624)[static_cast<size_t>(axis)], "3624")
                              : static_cast<double>(tape.param(3624, axis)) * input_mm;
  const bool bidir = tape.parameter.count(3605) != 0
                         ? tape.parameter.at(3605)[static_cast<size_t>(axis)].back() == '1'
                         : tape.param(3626, axis) != 0;
  const bool other = bidir && dir != 0 && dir != ref_dir;
  const bool negative_table = bidir && dir < 0;
  const long offset = negative_table ? tape.param(3626, axis) - first : 0;
  const double start = other ? static_cast<double>(tape.param(3627, axis)) : 0.0;
  // Absolute compensation at the positions of points first-1 .. last.
  std::map<long, double> at;
  at[ref] = start;
  for (long p = ref + 1; p <= last; ++p) at[p] = at[p - 1] + tape.pitch.at(p + offset) * mag;
  for (long p = ref; p >= first; --p) at[p - 1] = at[p] - tape.pitch.at(p + offset) * mag;
  std::vector<double> pos, val;
  for (const auto& [p, v] : at) {
    pos.push_back(ref_mm + static_cast<double>(p - ref) * interval);
    val.push_back(v * unit_mm);
  }
  return interpolate(pos, val, x);
}

}  // namespace volmap::maps::controller_models
