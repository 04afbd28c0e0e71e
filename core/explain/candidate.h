// The candidate physics of `volmap explain`: every effect name of
// shared/spec/explain.md as columns in um per parameter unit (the formulas
// of core/measure/effects.h, which `volmap simulate` injects), with the
// report of its fitted parameters. Table: docs/explain.md.
#pragma once

#include <Eigen/Core>
#include <functional>
#include <optional>
#include <string>
#include <vector>

#include "core/explain/axis_labels.h"
#include "core/explain/explain.h"
#include "core/explain/observations.h"

namespace volmap::explanation {

/// One candidate effect: build(theta) gives its columns (n x kc, um per
/// parameter unit, unweighted) for the nonlinear parameter theta (ignored
/// when grid is empty); report() turns the fitted coefficients into the
/// parameters of explain.md.
struct Candidate {  // an aggregate: build one with designated initializers
  std::string effect{};
  std::optional<AxisName> axis{};
  std::string variant{};  ///< "offset", "scale", sensor, error name, ...
  // column builder: theta -> physical columns (n x kc)
  std::function<Eigen::MatrixXd(double)> build{};
  std::vector<double> grid{};  ///< theta values to scan; empty: no nonlinear parameter
  bool refine = false;         ///< golden-section refinement between grid neighbours
  bool log_refine = false;
  bool per_run = false;
  int nonlinear = 0;
  // reporting
  std::function<void(const Eigen::VectorXd& beta, const Eigen::MatrixXd& cov, double theta,
                     double theta_se, Finding& f)>
      report{};
  std::function<double(int row)> plot_x{};  ///< the regressor that gives it away
  std::string plot_label{};
  std::function<int(int row)> plot_group{};
  // detection (detection.h): which coefficients make the amplitude the
  // detectable size is quoted for, and its unit (JSON key detectable_<unit>)
  enum class Amplitude {
    kFirst,      ///< coefficient 0 (the others at zero)
    kPair,       ///< hypot of coefficients 0 and 1 at the least visible phase
    kEachColumn  ///< any one coefficient alone (one run shifted), the least visible
  };
  Amplitude amplitude = Amplitude::kFirst;
  std::string amplitude_unit = "um";
  /// The look-elsewhere path length of the scan in closed form (detection.h),
  /// where the numerical walk would cost a column build per small step
  /// (a period scan over 100 000 readings); empty: walked numerically.
  std::function<double()> path_length{};
  std::string key() const {
    return effect + "/" + (axis ? axis_letter(*axis) : "-") + "/" + variant;
  }
};

/// What the recording holds, which decides the candidates it can support.
struct CandidateContext {
  const Observations& obs;
  const ExplainOptions& options;
  std::vector<AxisName> linear_axes, rotary_axes;  ///< machine axes with varying recorded positions
  std::vector<AxisName> bidirectional_axes;        ///< linear axes approached from both sides
  bool has_time = false, has_feed = false;
  double duration_s = 0.0;
};

/// One column (n x 1): value_of(e) for every equation e.
template <typename ValueOf>
Eigen::MatrixXd one_column(const Observations& obs, ValueOf value_of) {
  const Eigen::Index n = static_cast<Eigen::Index>(obs.count);
  Eigen::MatrixXd C(n, 1);
  for (Eigen::Index e = 0; e < n; ++e) C(e, 0) = value_of(e);
  return C;
}

/// Reports a candidate of one coefficient: the parameter `name` with its
/// standard error.
void report_one_parameter(const std::string& name, const Eigen::VectorXd& beta,
                          const Eigen::MatrixXd& cov, Finding& f);

/// Plots the candidate against the position of axis a (mm or degrees).
void plot_against_position(Candidate& cand, const Observations& obs, AxisName a);

/// What the recording holds (axes that move, directions, time, feed).
CandidateContext candidate_context(const Observations& obs, const ExplainOptions& options);

/// Every candidate the recording can support (docs/explain.md, table), in
/// a fixed order.
std::vector<Candidate> make_candidates(const CandidateContext& c);

// One function per effect family (candidates_<family>.cc), each appending
// its candidates for the deflecting axis K to `out`; along_k is p_b[K] per
// equation.
void add_cyclic_candidate(const CandidateContext& c, AxisName k, const Eigen::VectorXd& along_k,
                          std::vector<Candidate>& out);
void add_lost_motion_candidates(const CandidateContext& c, AxisName k,
                                const Eigen::VectorXd& along_k, std::vector<Candidate>& out);
void add_thermal_drift_candidates(const CandidateContext& c, AxisName k, bool k_moves,
                                  const Eigen::VectorXd& along_k, std::vector<Candidate>& out);
void add_setup_shift_candidate(const CandidateContext& c, AxisName k,
                               const Eigen::VectorXd& along_k, std::vector<Candidate>& out);
/// K deflects with the position of each other recorded axis J.
void add_sag_candidates(const CandidateContext& c, AxisName k, const Eigen::VectorXd& along_k,
                        std::vector<Candidate>& out);
/// Wobble and positioning of every rotary axis the recording turns.
void add_rotary_candidates(const CandidateContext& c, std::vector<Candidate>& out);
/// With a fixed baseline: the geometric errors it lacks.
void add_geometric_candidates(const CandidateContext& c, std::vector<Candidate>& out);

}  // namespace volmap::explanation
