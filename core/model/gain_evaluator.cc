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

// The algebra of error_gains (core/sensitivity.cc): JointLever::gain.
Eigen::Vector3d GainEvaluator::dP(int k) const {
  const Entry& e = entries_[static_cast<std::size_t>(k)];
  Eigen::Vector3d gP, gQ;
  levers_[static_cast<std::size_t>(e.lever)].gain(e.component, e.location, gP, gQ);
  return gP;
}

Eigen::Vector3d GainEvaluator::dQ(int k) const {
  const Entry& e = entries_[static_cast<std::size_t>(k)];
  Eigen::Vector3d gP, gQ;
  levers_[static_cast<std::size_t>(e.lever)].gain(e.component, e.location, gP, gQ);
  return gQ;
}

}  // namespace volmap
