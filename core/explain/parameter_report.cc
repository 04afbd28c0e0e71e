#include "core/explain/parameter_report.h"

#include <fmt/format.h>

#include <algorithm>
#include <cmath>
#include <string>

#include "core/common/units.h"

namespace volmap::explanation {

double round_significant(double v, int digits) {
  if (!std::isfinite(v) || v == 0) return v == 0 ? 0.0 : v;
  return std::stod(fmt::format("{:.{}g}", v, digits));
}

nlohmann::json json_number(double v) {
  if (!std::isfinite(v)) return nullptr;
  return round_significant(v);
}

nlohmann::json json_number(const std::optional<double>& v) {
  return v ? json_number(*v) : nlohmann::json(nullptr);
}

double delta_se(const Eigen::VectorXd& g, const Eigen::MatrixXd& cov) {
  return std::sqrt(std::max(0.0, g.dot(cov * g)));
}

void amplitude_phase(const Eigen::VectorXd& beta, const Eigen::MatrixXd& cov, int i_sin, int i_cos,
                     double& amp, double& amp_se, double& phase_deg) {
  const double a = beta[i_sin], b = beta[i_cos];
  amp = std::hypot(a, b);
  Eigen::VectorXd g = Eigen::VectorXd::Zero(beta.size());
  if (amp > 0) {
    g[i_sin] = a / amp;
    g[i_cos] = b / amp;
  }
  amp_se = delta_se(g, cov);
  phase_deg = std::atan2(b, a) * units::kDegPerRad;
}

}  // namespace volmap::explanation
