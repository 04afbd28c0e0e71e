// Per-node uncertainty of a table: the standard uncertainty of the tool-tip
// error dP at every node, propagated from the repeatability of the measured
// errors (docs/maps.md, "Uncertainty").
//
// Every error the errors file gives (each present component error of each
// axis, each location error) is taken as independent with standard
// uncertainty sigma: sigma_mm for translational errors, sigma_rad for
// angular ones. First-order propagation through the error gains g_k(u)
// (Hsu Table II, core/gain_evaluator.h) gives the covariance of dP,
// sum_k sigma_k^2 g_k g_k^T; the channel "u" holds the square root of its
// trace, sqrt(sum_k sigma_k^2 |g_k(u)|^2) (mm): the 3-D standard uncertainty
// of the tool-tip position error. It does not depend on the approach
// direction, so every layer holds the same values.
#pragma once

#include <Eigen/Core>
#include <nlohmann/json.hpp>
#include <optional>
#include <string>
#include <vector>

#include "core/model/error_model.h"
#include "maps/tables/volumetric_table.h"

namespace volmap::maps {

struct Repeatability {
  double translational_mm = 0.0;  ///< standard uncertainty of EXX, EX0C, ... (mm)
  double angular_rad = 0.0;       ///< standard uncertainty of EAX, EC0X, ... (rad)
};

/// Covariance of identified location errors (volmap identify --json,
/// docs/identify.md): Sigma_ij = rho_ij sigma_i sigma_j over the estimated
/// parameters, internal units (mm, rad) squared, indexed by the error gains
/// of GainEvaluator (names()).
struct ParameterCovariance {
  std::vector<std::string> names;  ///< canonical error names ("EY0A")
  std::vector<int> gain_index;     ///< into GainEvaluator::names()
  Eigen::MatrixXd covariance;      ///< (mm|rad)^2
};

/// From an identify report ("volmap-identify/1": parameters[].std_error,
/// correlation{names, matrix}). Location errors only: a component-curve
/// parameter ("EXX.p2") is refused (its gain needs the curve's basis, not
/// propagated yet); setup offsets belong to the recording, not the
/// machine, and are left out. Throws std::invalid_argument naming the file
/// and JSON path.
ParameterCovariance covariance_from_identify(const nlohmann::json& report, const Machine& m,
                                             Formulation f, const std::string& file);

/// From the errors file's metadata "# repeatability_um: R" and
/// "# repeatability_urad: R" (standard uncertainties, 1 sigma; a missing
/// key is 0). Nothing when neither is given. Throws std::invalid_argument
/// naming the key when a value is not a non-negative number.
std::optional<Repeatability> repeatability_from(const ErrorSet& errors);

/// Appends the channel "u" to a freshly laid-out table (values reallocated,
/// zero). No-op when it is there.
void add_uncertainty_channel(VolumetricTable& table);

/// Fills channel "u" of every node and layer (threads: 0 = all cores).
/// The same bytes for any thread count.
/// With `covariance` (may be null) too: u^2 = sum_k sigma_k^2 |g_k|^2 over
/// the errors the covariance does not name (repeatability) + sum_ij
/// Sigma_ij g_i . g_j over those it names (trace of G Sigma G^T).
void fill_uncertainty(const ErrorModel& model, VolumetricTable& table, const Repeatability& r,
                      int threads = 0, const ParameterCovariance* covariance = nullptr);

}  // namespace volmap::maps
