// Identification of geometric errors from recordings (`volmap identify`,
// docs/identify.md): weighted least squares of the location (link) errors
// of the rotary block and the squareness errors of the linear axes (Lei &
// Hsu 2003, section 3: "the unknown link errors can be identified by using
// the least square estimation method"; the probe-ball data of their refs.
// [11], [12]), optionally polynomial (linear axes, limited rotary axes) or
// Fourier (continuous rotary axes) component errors, and per-run setup
// offsets.
//
// Model: the recorded value of an observation is p^T R_rec_w dv(u, dir; e),
// dv the exact HTM pose error (ErrorModel::exact) with the known errors and
// the current estimates e, p the recorded component or the projection
// direction, R_rec_w the workpiece->recording rotation (identity, or R_b_w
// for "# frame: machine"). Gauss-Newton on this exact model with the
// first-order Jacobian J (error gains, core/model/gain_evaluator.h) held fixed:
// the iteration converges to the exact least-squares solution; noise-free
// data is recovered to far below 1e-6 um.
//
// Identifiability: SVD (eigen-decomposition of J_s^T J_s) of the weighted,
// column-scaled Jacobian J_s. Singular values below rank_tolerance * the
// largest span the parameter combinations the recording cannot separate;
// one parameter per combination is fixed at 0 and flagged, never reported
// as an estimate. Standard errors: sigma^2 (J^T W J)^-1 over the estimated
// parameters, sigma^2 from the weighted residuals.
#pragma once

#include <Eigen/Core>
#include <cmath>
#include <functional>
#include <iosfwd>
#include <nlohmann/json.hpp>
#include <stdexcept>
#include <string>
#include <vector>

#include "core/measure/recordings.h"
#include "core/model/error_model.h"

namespace volmap {

/// A component error fitted as a curve: degree of the polynomial (linear
/// axes, rotary axes with limited travel: sum c_k s^k, k = 1..degree, s the
/// position scaled to [-1, 1] over travel) or order of the Fourier series
/// (continuous rotary axes: c_k cos k theta + s_k sin k theta).
struct ComponentFit {
  std::string name;  ///< "EXX", "ECC"
  int degree = 3;
};

/// A ComponentFit the machine or the options cannot take. what() reads
/// "component <detail>"; detail() names the fit as given and the problem
/// ("EXX:9: the degree (order) is 1..8", "EXX given twice"), so a caller
/// can name the fit in its own terms (the CLI: "--component <detail>").
class ComponentFitError : public std::invalid_argument {
 public:
  explicit ComponentFitError(const std::string& detail);
  const std::string& detail() const { return detail_; }

 private:
  std::string detail_;
};

struct IdentifyOptions {
  Formulation formulation = Formulation::kIndependent;
  /// What the fitted (and the known) location errors mean.
  LocationConvention convention = LocationConvention::kIso230;
  /// Location errors to fit; empty: every location error of the model
  /// (model_error_names) that `known` does not give.
  std::vector<std::string> parameters;
  std::vector<ComponentFit> components;
  bool setup_offsets = false;       ///< a constant offset (x, y, z) per run
  const ErrorSet* known = nullptr;  ///< errors held fixed (may be null)
  int max_iterations = 30;
  double step_tolerance = 1e-10;  ///< um or urad: Gauss-Newton stops below
  double rank_tolerance = 1e-7;   ///< relative singular value of J_s
  double strong_correlation = 0.9;
  /// Told each stage ("computing the sensitivities") and each Gauss-Newton
  /// iteration (done, max_iterations; total 0 for a stage). May be empty.
  std::function<void(const std::string& stage, std::size_t done, std::size_t total)> progress;
};

enum class ParameterKind : std::uint8_t { kLocation, kComponent, kSetupOffset };

struct IdentifiedParameter {
  std::string name;  ///< "EX0C", "EXX.p2", "ECC.c1", "offset_x.run3"
  std::string unit;  ///< "um" or "urad"
  ParameterKind kind = ParameterKind::kLocation;
  bool identifiable = true;
  double estimate = 0.0;   ///< unit; 0 when not identifiable (fixed)
  double std_error = 0.0;  ///< unit; NaN when not identifiable or no redundancy
  /// Variance inflation: the standard error over the one the parameter would
  /// have if its column were uncorrelated with the others' (sqrt of the VIF);
  /// NaN when not estimated.
  double inflation = std::nan("");
};

/// A combination of parameters the recording cannot separate: changing
/// terms[0] by +1 (its unit) together with terms[k] by their coefficients
/// leaves every observation unchanged (to first order).
struct UnidentifiableCombination {
  std::vector<std::pair<std::string, double>> terms;  ///< fixed parameter first, coefficient 1
  std::string fixed;                                  ///< the parameter fixed at 0
  std::string text;                                   ///< "EY0A - 1 EY0C"
  std::string explanation;                            ///< why (documented rule, docs/identify.md)
  std::string remedy;                                 ///< the measurement that would separate them
};

/// A fitted component curve, for the errors CSV.
struct FittedCurve {
  AxisName axis = AxisName::X;
  Component component = Component::EX;
  bool periodic = false;
  std::vector<double> knots;   ///< internal units (mm, rad)
  std::vector<double> values;  ///< internal units (mm, rad)
};

struct IdentifyResult {
  std::vector<IdentifiedParameter> parameters;
  std::size_t rows_used = 0;
  std::size_t equations = 0;  ///< scalar observations (ex, ey, ez, e_um cells)
  int rank = 0;
  std::vector<double> singular_values;  ///< of J_s, descending
  double condition_number = 0.0;        ///< of the estimated parameters (J_s restricted)
  std::vector<UnidentifiableCombination> unidentifiable;
  std::vector<std::string> correlation_names;  ///< estimated parameters
  Eigen::MatrixXd correlation;
  struct Pair {
    std::string a, b;
    double rho;
  };
  std::vector<Pair> strong_correlations;
  double rms_before_um = 0.0, rms_after_um = 0.0;  ///< weighted RMS residual
  double sigma_um = 0.0;                           ///< residual standard deviation (unit weight)
  int iterations = 0;
  bool converged = false;
  std::vector<FittedCurve> curves;
  std::vector<std::pair<std::string, double>> location_estimates;  ///< identifiable, mm / rad
  /// The noise the recording states ("# noise_um:" metadata, as volmap
  /// simulate writes it), NaN when it states none.
  double stated_noise_um = std::nan("");
  /// What makes the estimates doubtful, one sentence each (docs/identify.md,
  /// "Fit quality"): a residual sigma well above the stated noise, a fit
  /// that removes little, parameters barely identifiable.
  std::vector<std::string> warnings;
};

/// Identifies the errors. Throws InputError (recordings file:line) for an
/// observation the model cannot evaluate, std::invalid_argument for bad
/// options (unknown names; ComponentFitError for a component on an axis
/// that `known` tabulates).
IdentifyResult identify(const Machine& m, const Recordings& rec, const IdentifyOptions& options);

/// Errors CSV (shared/spec/errors.md) of the result: the blocks of
/// `known_text` (the known errors file, verbatim, may be empty), the fitted
/// curves tabulated (positions 6 decimals, values um/urad 6 decimals), and
/// the identifiable location errors. Non-identifiable ones are not written
/// (a comment names them). Deterministic.
void write_identified_errors_csv(std::ostream& out, const IdentifyResult& result,
                                 const std::map<std::string, std::string>& metadata,
                                 const std::string& known_text);

namespace identification {
/// IdentifyResult::warnings for a finished fit with `dof` degrees of
/// freedom (docs/identify.md, "Fit quality").
std::vector<std::string> fit_warnings(const IdentifyResult& r, int dof);
}  // namespace identification

/// The report as JSON (format "volmap-identify/1", docs/identify.md) and text.
nlohmann::ordered_json identify_report_json(const IdentifyResult& result);
std::string identify_report_text(const IdentifyResult& result);

}  // namespace volmap
