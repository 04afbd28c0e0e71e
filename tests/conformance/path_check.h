// The engine's measure of a posted program: rs274's moves of the output,
// moved by the machine's error (lost motion as play, the error of each
// tool's length), against rs274's moves of the input, both ways:
//  - actual to nominal: every point of the output's feeds (sampled between
//    the points too) and every cut start (the end of a traverse that a feed
//    follows), moved by the error, from the nearest nominal feed;
//  - nominal to actual: every point of the input's feeds (sampled) from the
//    output's actual feed path (the commanded point that the error moves
//    there, c = n - e(n), from the output's commanded moves).
#pragma once

#include <Eigen/Core>
#include <map>
#include <memory>
#include <string>
#include <vector>

#include "core/model/error_set.h"
#include "core/model/machine.h"
#include "postproc/three_axis/corrector.h"
#include "tests/conformance/canon.h"

namespace volmap::conformance {

/// The error model of one errors file, with a Corrector per tool length.
class ErrorField {
 public:
  ErrorField(const Machine& machine, ErrorSet errors);
  const post::Corrector& corrector(double tool_offset_mm) const;

 private:
  Machine machine_;
  ErrorSet errors_;
  mutable std::map<long long, std::unique_ptr<post::Corrector>> by_length_;
};

struct PathDeviation {
  double actual_to_nominal_um = 0.0, nominal_to_actual_um = 0.0;
  /// How much each may be: the tolerance, a quarter more, and the rounding
  /// of rs274's printed numbers (4 decimals in the program's unit) on both
  /// readings, at the worst point.
  double actual_limit_um = 0.0, nominal_limit_um = 0.0;
  Eigen::Vector3d actual_at = Eigen::Vector3d::Zero(), nominal_at = Eigen::Vector3d::Zero();
  /// Where the worst point lies: "a cut start", "a line", "an arc" (of the
  /// output, or of the input for nominal_where).
  std::string actual_where, nominal_where;
  bool actual_fails() const { return actual_to_nominal_um > actual_limit_um; }
  bool nominal_fails() const { return nominal_to_actual_um > nominal_limit_um; }
  bool nominal_empty = false, output_empty = false;
};

/// `stands_at`: machine positions of the axes where the controller stands
/// uncorrected whatever the post writes (where rs274 starts, the G28/G30
/// homes): a feed that starts there is measured at its end only (its start
/// is off by the error there, which no block of the program moves).
PathDeviation compare_paths(const std::vector<CanonMove>& nominal,
                            const std::vector<CanonMove>& output, const ErrorField& field,
                            double tolerance_um, const std::vector<Eigen::Vector3d>& stands_at);

}  // namespace volmap::conformance
