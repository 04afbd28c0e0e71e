#include "core/model/gain_evaluator.h"

#include <stdexcept>

namespace volmap {
namespace {
ErrorSet no_errors(LocationConvention convention) {
  ErrorSet none;
  none.file = "<no errors>";
  none.convention = convention;
  return none;
}
}  // namespace

GainEvaluator::GainEvaluator(const Machine& m, Formulation f, LocationConvention convention)
    : model_(m, no_errors(convention), ModelOptions{f, OutsidePolicy::kError}),
      names_(model_error_names(m)) {
  AxisVector home = m.home;
  model_.levers(home, levers_);
  for (const std::string& name : names_) {
    const ErrorName n = *parse_error_name(name);
    int lever = -1;
    for (std::size_t k = 0; k < levers_.size(); ++k)
      if (levers_[k].axis == n.axis) lever = static_cast<int>(k);
    if (lever < 0) throw std::logic_error("no joint for " + name);
    entries_.push_back({lever, static_cast<int>(n.component), n.location});
  }
}

int GainEvaluator::index_of(const std::string& name) const {
  const std::optional<ErrorName> n = parse_error_name(name);
  if (!n) return -1;
  const std::string canonical = error_name_string(*n);
  for (std::size_t k = 0; k < names_.size(); ++k)
    if (names_[k] == canonical) return static_cast<int>(k);
  return -1;
}

void GainEvaluator::at(const AxisVector& u) { model_.levers(u, levers_); }

// Same algebra as error_gains (core/sensitivity.cc), component errors:
//   translational c:  dP = sign R_w_L e_c
//   angular c:        dP = sign R_w_L (e_c x lever),  dQ = sign R_w_L (e_c x axis_L)
// Location errors: JointLever::location_gain.
Eigen::Vector3d GainEvaluator::dP(int k) const {
  const Entry& e = entries_[static_cast<std::size_t>(k)];
  const ErrorModel::JointLever& L = levers_[static_cast<std::size_t>(e.lever)];
  if (e.location) {
    Eigen::Vector3d gP, gQ;
    L.location_gain(e.component, gP, gQ);
    return gP;
  }
  if (e.component < 3) return L.sign * L.R_w_L.col(e.component);
  const Eigen::Vector3d unit = Eigen::Vector3d::Unit(e.component - 3);
  return L.sign * (L.R_w_L * unit.cross(L.lever_component_mm));
}

Eigen::Vector3d GainEvaluator::dQ(int k) const {
  const Entry& e = entries_[static_cast<std::size_t>(k)];
  const ErrorModel::JointLever& L = levers_[static_cast<std::size_t>(e.lever)];
  if (e.location) {
    Eigen::Vector3d gP, gQ;
    L.location_gain(e.component, gP, gQ);
    return gQ;
  }
  if (e.component < 3) return Eigen::Vector3d::Zero();
  const Eigen::Vector3d unit = Eigen::Vector3d::Unit(e.component - 3);
  return L.sign * (L.R_w_L * unit.cross(L.axis_L));
}

}  // namespace volmap
