// `volmap explain` (shared/spec/explain.md, docs/explain.md): where a model
// and a recording disagree, which physics the model left out, its fitted
// parameters, and how much the fit improves on the recording and on runs
// held out of the fit.
//
// Observations: every recorded scalar (ex_um, ey_um, ez_um cell, or e_um of
// the projection form) is one equation y = p_rec^T d_rec(u), p_rec the unit
// component or beam direction. In the workpiece frame p_w = R_rec_w^T p_rec
// (R_rec_w = I, or R_b_w for "# frame: machine"); in machine directions
// p_b = R_b_w p_w. Everything below is linear least squares in micrometres:
//
//   baseline  fixed:  y - p_w . ErrorModel::exact(u, dir).dP      (--baseline)
//                     plus one constant per recorded component (instrument zero)
//             fitted: constant per component + every location error + every
//                     component error of the linear axes as a polynomial
//                     s^1..s^degree (s scaled over the travel), through the
//                     first-order gains of core/gain_evaluator.h (the
//                     linearised model `volmap identify` iterates on)
//   candidates (effect names of explain.md; effects.h gives the same physics
//              to `volmap simulate`), one column per linear parameter:
//     reversal K            p_b[K] s_K / 2                        value_um
//     thermal_drift K       p_b[K] f(t) (offset) or p_b[K] f(t) q_K / 1000 (scale),
//                           f = 1 - exp(-t/tau_s) (tau_s by scan + golden section),
//                           t / 3600 (rate) or T_sensor - 20 degC (um_per_k)
//     cyclic K              p_b[K] (sin, cos)(2 pi q_K / period_mm)  (period by scan + refine)
//     servo_lag K           -p_b[K] (F / 1000) s_K                 um_per_m_min
//     sag K from J          p_b[K] (q_J - c)^2, p_b[K] (q_J - c)   coefficient, origin
//     setup_shift K         p_b[K] [run == r], every run           per_run_um
//     rotary_wobble R       tilts perpendicular to R, (cos, sin)(n theta)  (order n = 1..4)
//     rotary_positioning R  own angular error, (sin, cos)(n theta)          (order n = 1..4)
//     fixed baseline only:  scale / squareness / straightness / angular of each linear axis
//
// Selection: forward, one effect per step; a step must lower BIC by more than
// 10 and, when the recording has two runs or more, lower the leave-one-run-out
// RMS by more than 5 %. Candidates whose columns the current model already
// spans are not estimable here; candidates that explain the same structure as
// the best one (fitted values correlated > 0.98, a BIC within the selection
// margin) are reported as `confounded`, not as a finding. A recording whose
// time rises with an axis position in every run (one-direction sweeps)
// confounds thermal drift with scale by design; that is reported whatever the
// residuals show.
#pragma once

#include <Eigen/Core>
#include <functional>
#include <map>
#include <nlohmann/json.hpp>
#include <optional>
#include <string>
#include <vector>

#include "core/measure/recordings.h"
#include "core/model/error_set.h"
#include "core/model/machine.h"

namespace volmap {

struct ExplainOptions {
  const ErrorSet* baseline = nullptr;  ///< fixed baseline (--baseline); null: fitted rigid body
  std::string baseline_file;           ///< for the description
  /// Polynomial degree of the fitted component errors of the linear axes;
  /// 0: automatic (a value per target for an axis with at most 12 targets,
  /// as ISO 230-2 evaluates positioning; cubic for denser sampling).
  int degree = 0;
  int max_findings = 6;
  /// The nonlinear parameter a candidate's detectable size is quoted at, by
  /// candidate key ("cyclic/X/" -> period_mm, "thermal_drift/X/offset/settling"
  /// -> tau_s, "rotary_wobble/C/" -> order); otherwise at its fitted value.
  /// For planning a test: how small a 16 mm pitch error would show.
  std::map<std::string, double> detectable_at;
  bool machine_assumed = false;  ///< the machine is cartesian_machine_for(rec) (no --machine)
  /// Told each stage of the work ("fitting the baseline"), and the
  /// candidates of each selection step as they are fitted (done, total;
  /// total 0 for a stage). May be empty.
  std::function<void(const std::string& stage, std::size_t done, std::size_t total)> progress;
};

/// Where the baseline residuals have structure: strength is the adjusted
/// correlation ratio (share of the residual variance the regressor's bins or
/// levels explain, 0..1).
struct Mismatch {
  std::string component;  ///< "ex", "ey", "ez" or "e" (projection)
  std::string regressor;  ///< "dir_x", "t_s", "x_mm", "run", "temp_air_c", ...
  std::string where;
  double strength = 0.0;
};

/// A plot series: the regressor and the residuals before / after a finding.
struct ExplainPlot {
  std::string regressor;  ///< axis label
  std::vector<double> x, before_um, after_um;
  std::vector<int> group;  ///< colour class (approach direction, run), may be empty
};

struct Finding {
  std::string effect;  ///< explain.md name
  std::optional<AxisName> axis;
  std::vector<std::pair<std::string, nlohmann::json>> parameters;  ///< ordered
  std::vector<std::pair<std::string, double>> std_errors;
  double rms_before_um = 0.0, rms_after_um = 0.0;
  std::optional<double> heldout_rms_before_um, heldout_rms_after_um;
  double delta_bic = 0.0;
  std::string explanation;
  ExplainPlot plot;
};

struct Confounded {
  std::vector<std::string> effects;
  std::optional<AxisName> axis;
  std::string explanation, remedy;
};

/// How one candidate was tested (docs/explain.md, "Detection"): its
/// statistic, its p-value corrected for the scan and the family, and the
/// smallest amplitude the recording's design lets the test see with 95 %
/// power (none when the design cannot reveal it at all).
struct CandidateResult {
  std::string effect;
  std::optional<AxisName> axis;
  std::string variant;
  std::string status;  ///< "finding", "confounded", "not significant", "did not hold up"
  /// The likelihood-ratio statistic, its critical value and corrected
  /// p-value; none for a candidate that was not estimable.
  std::optional<double> chi2, critical_chi2, p_value;
  std::string detectable_unit;                       ///< the key is detectable_<unit>
  std::optional<double> detectable;                  ///< in that unit
  std::optional<std::pair<std::string, double>> at;  ///< the nonlinear parameter it was quoted at
};

/// A circular test (ISO 230-4, the ballbar) found in the recording: one
/// circle at one feed, its counter-clockwise and clockwise runs. Deviations
/// are radial, after the least-squares circle (centre offset and radius
/// error removed, as ISO 230-4 evaluates): `deviation_um` as recorded (less
/// a fixed baseline's prediction), `fitted_um` the part the findings explain.
struct CircularTest {
  std::string plane;  ///< "XY", "YZ", "ZX"
  Eigen::Vector3d centre_mm = Eigen::Vector3d::Zero();
  double radius_mm = 0, feed_mm_min = 0;
  struct Path {
    std::string run;        ///< as the recording names it
    std::string direction;  ///< "ccw" (angle rising from the first plane axis) or "cw"
    std::vector<double> angle_deg, deviation_um, fitted_um;
    double g_um = 0;        ///< circular deviation G of the recording
    double g_after_um = 0;  ///< G of what the findings leave
  };
  std::vector<Path> paths;
  std::optional<double> h_um, h_after_um;  ///< circular hysteresis H (both directions)
};

struct ExplainResult {
  std::string recordings_file;
  std::size_t observations = 0;  ///< scalar equations
  std::size_t runs = 0;
  std::string baseline_description;
  double baseline_rms_um = 0.0;
  std::optional<double> baseline_heldout_rms_um;
  std::vector<Mismatch> mismatch;
  std::vector<Finding> findings;
  std::vector<Confounded> confounded;
  std::vector<CandidateResult> candidates;   ///< every candidate tested, in a fixed order
  std::vector<CircularTest> circular_tests;  ///< ISO 230-4 readings, when the recording has any
  double final_rms_um = 0.0;
  std::optional<double> final_heldout_rms_um;
  std::vector<std::string> notes;  ///< candidates not estimable on this recording, etc.
};

/// A machine for a recording without --machine: Cartesian, the axes that the
/// recording names, travel over the recorded positions, all in the tool chain.
Machine cartesian_machine_for(const Recordings& rec);

/// Runs the analysis. Throws InputError (recordings file:line) for rows the
/// model cannot use, std::invalid_argument for bad options.
ExplainResult explain(const Machine& m, const Recordings& rec, const ExplainOptions& options);

/// The JSON result (format "volmap-explain/1"): deterministic, numbers rounded
/// to fixed decimals.
nlohmann::ordered_json explain_json(const ExplainResult& r);
/// The short human summary printed on stdout.
std::string explain_text(const ExplainResult& r);
/// The self-contained HTML report (inline SVG, no script, no network).
std::string explain_html(const ExplainResult& r);

}  // namespace volmap
