// How explain reports fitted numbers: rounded to 6 significant digits in
// JSON (null when not finite), standard errors by the delta method, a
// (sin, cos) pair as amplitude and phase.
#pragma once

#include <Eigen/Core>
#include <nlohmann/json.hpp>
#include <optional>
#include <string>
#include <utility>
#include <vector>

namespace volmap::explanation {

/// v rounded to `digits` significant digits (0 and non-finite values unchanged).
double round_significant(double v, int digits = 6);
/// v rounded to 6 significant digits; null when not finite.
nlohmann::json json_number(double v);
/// The same for an optional value; null when absent.
nlohmann::json json_number(const std::optional<double>& v);
/// sqrt(g^T cov g) for a function with gradient g.
double delta_se(const Eigen::VectorXd& g, const Eigen::MatrixXd& cov);
/// Amplitude hypot(a, b) of beta[i_sin] sin + beta[i_cos] cos, its standard
/// error and the phase atan2(b, a) in degrees.
void amplitude_phase(const Eigen::VectorXd& beta, const Eigen::MatrixXd& cov, int i_sin, int i_cos,
                     double& amp, double& amp_se, double& phase_deg);

/// A finding's parameters as a reader wants them: the unit out of the name
/// and after the number, each value with its standard error in sensible
/// digits ("value 2.05 ± 0.23 µm, tau 988 ± 150 s"); an array parameter
/// (setup_shift's per_run_um) element by element with the errors of
/// "name/i".
std::string parameters_text(const std::vector<std::pair<std::string, nlohmann::json>>& parameters,
                            const std::vector<std::pair<std::string, double>>& std_errors);

/// A unit as a key writes it ("um_per_m_min") for a reader ("µm per m/min").
std::string unit_text(const std::string& unit);

/// A plot's regressor (a recordings column, "run", "feed_mm_min * dir_x")
/// as an axis label: its meaning, a comma, its unit ("X position, mm",
/// "time since start, s").
std::string regressor_label(const std::string& regressor);

}  // namespace volmap::explanation
