// First-order error gains (Hsu Tables I/II, core/sensitivity.h) at many axis
// positions without re-binding a model per position: the identification
// Jacobian and the simulator's effects need them at every observation.
//
// gain(k) equals error_gains(machine, formulation, u)[k] for the position
// last passed to at(u); names() is model_error_names(machine).
// Units: dP in mm per mm (translational errors) or mm per rad (angular),
// dQ in rad per rad; workpiece coordinates.
#pragma once

#include <string>
#include <vector>

#include "core/model/error_model.h"
#include "core/model/sensitivity.h"

namespace volmap {

class GainEvaluator {
 public:
  /// convention: what the location errors mean (the errors file's).
  GainEvaluator(const Machine& m, Formulation f,
                LocationConvention convention = LocationConvention::kIso230);

  const std::vector<std::string>& names() const { return names_; }
  /// Index of an error name in names() (canonical or with letter O), or -1.
  int index_of(const std::string& name) const;

  /// Sets the position; the levers are computed once here.
  void at(const AxisVector& u);
  /// Position gain dP of error k at the last position (workpiece frame).
  Eigen::Vector3d dP(int k) const;
  /// Orientation gain dQ of error k at the last position.
  Eigen::Vector3d dQ(int k) const;
  bool angular(int k) const { return entries_[static_cast<std::size_t>(k)].component >= 3; }

 private:
  struct Entry {
    int lever = 0;      ///< index into levers_
    int component = 0;  ///< 0..5: EX EY EZ EA EB EC
    bool location = false;
  };
  ErrorModel model_;
  std::vector<std::string> names_;
  std::vector<Entry> entries_;
  std::vector<ErrorModel::JointLever> levers_;
};

}  // namespace volmap
