#include "core/model/sensitivity.h"

#include <stdexcept>

namespace volmap {

std::vector<std::string> model_error_names(const Machine& m) {
  std::vector<std::string> names;
  std::vector<AxisName> chain_order;
  for (const Joint& j : m.workpiece_chain) chain_order.push_back(j.axis);
  for (const Joint& j : m.tool_chain) chain_order.push_back(j.axis);
  for (AxisName a : chain_order)
    for (int c = 0; c < kComponentCount; ++c)
      names.push_back(component_error_name(static_cast<Component>(c), a));
  auto has = [&](AxisName a) { return m.index_of(a).has_value(); };
  if (has(AxisName::X) && has(AxisName::Y)) names.push_back("EC0X");
  if (has(AxisName::Z) && has(AxisName::X)) names.push_back("EB0Z");
  if (has(AxisName::Z) && has(AxisName::Y)) names.push_back("EA0Z");
  for (AxisName a : chain_order) {
    if (!is_rotary(a)) continue;
    const int own = static_cast<int>(a) - 3;  // direction index of its line
    for (int c = 0; c < 3; ++c)               // offsets perpendicular to the line
      if (c != own) names.push_back(error_name_string({static_cast<Component>(c), a, true}));
    for (int c = 0; c < 3; ++c)  // tilts
      if (c != own) names.push_back(error_name_string({static_cast<Component>(c + 3), a, true}));
    names.push_back(error_name_string({static_cast<Component>(own + 3), a, true}));
  }
  return names;
}

std::vector<ErrorGain> error_gains(const Machine& m, Formulation f, const AxisVector& u,
                                   LocationConvention convention) {
  ErrorSet none;
  none.file = "<no errors>";
  none.convention = convention;
  const ErrorModel model(m, none, ModelOptions{f, OutsidePolicy::kError});
  std::vector<ErrorModel::JointLever> levers;
  model.levers(u, levers);
  std::vector<ErrorGain> gains;
  for (const std::string& name : model_error_names(m)) {
    const ErrorName n = *parse_error_name(name);
    const ErrorModel::JointLever* L = nullptr;
    for (const auto& l : levers)
      if (l.axis == n.axis) L = &l;
    if (!L) throw std::logic_error("no joint for " + name);
    const int c = static_cast<int>(n.component);
    ErrorGain g{name, c >= 3, Eigen::Vector3d::Zero(), Eigen::Vector3d::Zero()};
    L->gain(c, n.location, g.dP, g.dQ);
    gains.push_back(g);
  }
  return gains;
}

std::vector<double> error_values(const Machine& m, const ErrorSet& errors, const AxisVector& u,
                                 OutsidePolicy outside) {
  std::vector<double> values;
  for (const std::string& name : model_error_names(m)) {
    const ErrorName n = *parse_error_name(name);
    if (n.location) {
      values.push_back(errors.location_error(name));
      continue;
    }
    const AxisErrors* ax = errors.errors_of(n.axis);
    if (!ax) {
      values.push_back(0.0);
      continue;
    }
    std::array<double, kComponentCount> v;
    evaluate_axis(*ax, u[*m.index_of(n.axis)], 0, outside, v);
    values.push_back(v[static_cast<size_t>(n.component)]);
  }
  return values;
}

}  // namespace volmap
