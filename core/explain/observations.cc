// The recording as equations (observations.h).
#include "core/explain/observations.h"

#include <fmt/format.h>

#include <algorithm>
#include <cmath>
#include <map>
#include <memory>

#include "core/common/input_error.h"
#include "core/common/internal_error.h"
#include "core/explain/axis_labels.h"
#include "core/model/error_model.h"
#include "core/model/gain_evaluator.h"

namespace volmap::explanation {
namespace {

void check_recorded_axes_exist(const Machine& m, const Recordings& rec) {
  for (int a = 0; a < kAxisNameCount; ++a) {
    const AxisName ax = static_cast<AxisName>(a);
    if (rec.has_axis(ax) && !m.index_of(ax))
      throw InputError(rec.file, 0,
                       fmt::format("the recording has a {} column but the machine has no {} axis; "
                                   "give the machine that made the recording (`machine`)",
                                   position_column_name(ax), axis_letter(ax)));
  }
}

/// The tool of a row without a tool_mm cell: the "# tool_mm:" metadata,
/// else the machine's.
double default_tool_length_mm(const Machine& m, const Recordings& rec) {
  double default_tool_mm = m.tool_length_mm;
  if (const auto it = rec.metadata.find("tool_mm"); it != rec.metadata.end()) {
    char* end = nullptr;
    const double v = std::strtod(it->second.c_str(), &end);
    if (end != it->second.c_str() && std::isfinite(v) && v >= 0) default_tool_mm = v;
  }
  return default_tool_mm;
}

// The tool of each row (recordings.md: the tool_mm column, else the
// "# tool_mm:" metadata, else the machine's): the tool tip, and with it
// the Abbe levers of the angular errors, moves with the tool. One gain
// evaluator and baseline model per tool length; the errors stay as
// measured (the measurement tool is the machine file's).
class ModelsByTool {
 public:
  struct Models {
    GainEvaluator gains;
    std::optional<ErrorModel> baseline;
  };

  ModelsByTool(const Machine& m, const ErrorSet* baseline) : machine_(m), baseline_(baseline) {}

  Models& for_tool(double tool_mm) {
    auto it = by_tool_.find(tool_mm);
    if (it == by_tool_.end()) {
      Machine mt = machine_;
      if (std::isnan(mt.measurement_tool_length_mm))
        mt.measurement_tool_length_mm = machine_.tool_length_mm;
      mt.tool_length_mm = tool_mm;
      auto models = std::make_unique<Models>(
          Models{GainEvaluator(mt, Formulation::kIndependent,
                               baseline_ ? baseline_->convention : LocationConvention::kIso230),
                 std::nullopt});
      if (baseline_) models->baseline.emplace(mt, *baseline_);
      it = by_tool_.emplace(tool_mm, std::move(models)).first;
    }
    return *it->second;
  }

 private:
  const Machine& machine_;
  const ErrorSet* baseline_;
  std::map<double, std::unique_ptr<Models>> by_tool_;
};

/// The equations collected row by row, before they are packed into Eigen.
struct EquationList {
  std::vector<Eigen::Vector3d> direction_wp, direction_base;
  std::vector<double> deviation_um, weight;
  std::vector<double> gain_flat;  ///< row-major, one row of error gains per equation
};

/// Adds the equations of recording row i: one per recorded component and
/// one for the projection form. The gains (and the fixed baseline's
/// prediction) are evaluated at the row's first usable value.
void add_row_equations(Observations& obs, EquationList& eqs, ModelsByTool& models_by_tool,
                       double default_tool_mm, std::size_t i, AxisVector& u) {
  const Machine& m = obs.machine;
  const Recordings& rec = obs.recordings;
  const std::size_t error_count = obs.error_names.size();
  const int ii = static_cast<int>(i);
  for (int k = 0; k < m.axis_count(); ++k)
    u[k] = obs.position(m.axis_order[static_cast<std::size_t>(k)], ii);
  const Eigen::Matrix3d R_b_w = nominal_base_to_workpiece(m, u).linear();
  const Eigen::Matrix3d R_rec_w =
      rec.frame == RecordingFrame::kMachine ? R_b_w : Eigen::Matrix3d::Identity();
  const double weight = rec.weight.empty() ? 1.0 : rec.weight[i];
  if (!(weight >= 0) || !std::isfinite(weight))
    throw InputError(rec.file, rec.line[i], "weight must be a finite number >= 0");
  const double tool_mm =
      i < rec.tool_mm.size() && std::isfinite(rec.tool_mm[i]) ? rec.tool_mm[i] : default_tool_mm;
  ModelsByTool::Models& models = models_by_tool.for_tool(tool_mm);
  GainEvaluator& gains = models.gains;
  std::optional<ErrorModel>& baseline = models.baseline;
  bool gains_ready = false;
  Eigen::Vector3d predicted_wp_um = Eigen::Vector3d::Zero();
  bool prediction_ready = false;
  auto add = [&](const Eigen::Vector3d& p_rec, double value, int component) {
    if (!std::isfinite(value) || weight == 0) return;
    if (!gains_ready) {
      gains.at(u);
      gains_ready = true;
    }
    if (baseline && !prediction_ready) {
      ApproachDirections dir{};
      for (int k = 0; k < m.axis_count(); ++k)
        dir[static_cast<std::size_t>(k)] =
            static_cast<std::int8_t>(obs.approach(m.axis_order[static_cast<std::size_t>(k)], ii));
      try {
        predicted_wp_um = baseline->exact(u, dir).dP_mm * 1e3;
      } catch (const std::exception& e) {
        throw_if_unexpected(e, rec.file, rec.line[i]);  // a bug is said to be one
        throw InputError(rec.file, rec.line[i],
                         fmt::format("the baseline cannot be evaluated here: {}", e.what()));
      }
      prediction_ready = true;
    }
    const Eigen::Vector3d p_w = R_rec_w.transpose() * p_rec;
    eqs.direction_wp.push_back(p_w);
    eqs.direction_base.push_back(R_b_w * p_w);
    eqs.deviation_um.push_back(value - p_w.dot(predicted_wp_um));
    eqs.weight.push_back(weight);
    obs.recording_row.push_back(ii);
    obs.component.push_back(component);
    obs.run.push_back(rec.has_run() && rec.run[i] >= 0 ? rec.run[i] : 0);
    obs.has_component[component] = true;
    for (std::size_t k = 0; k < error_count; ++k)
      eqs.gain_flat.push_back(p_w.dot(gains.dP(static_cast<int>(k))));
  };
  for (int c = 0; c < 3; ++c)
    if (rec.has_component(c))
      add(Eigen::Vector3d::Unit(c), rec.e_um[static_cast<std::size_t>(c)][i], c);
  if (rec.has_projection()) {
    const Eigen::Vector3d nv(rec.n[0][i], rec.n[1][i], rec.n[2][i]);
    if (nv.allFinite()) add(nv, rec.e_along_n_um[i], kProjection);
  }
}

void pack_equations(Observations& obs, const EquationList& eqs) {
  const Eigen::Index n = static_cast<Eigen::Index>(obs.count);
  obs.deviation_um = Eigen::Map<const Eigen::VectorXd>(eqs.deviation_um.data(), n);
  obs.sqrt_weight.resize(n);
  obs.direction_wp.resize(3, n);
  obs.direction_base.resize(3, n);
  for (std::size_t e = 0; e < obs.count; ++e) {
    obs.sqrt_weight[static_cast<Eigen::Index>(e)] = std::sqrt(eqs.weight[e]);
    obs.direction_wp.col(static_cast<Eigen::Index>(e)) = eqs.direction_wp[e];
    obs.direction_base.col(static_cast<Eigen::Index>(e)) = eqs.direction_base[e];
  }
  obs.error_gain =
      Eigen::Map<const Eigen::Matrix<double, Eigen::Dynamic, Eigen::Dynamic, Eigen::RowMajor>>(
          eqs.gain_flat.data(), n, static_cast<Eigen::Index>(obs.error_names.size()));
}

/// The equations of each run; runs without equations do not count.
/// The direction of motion to each row (Observations::move_direction).
void find_move_directions(Observations& obs) {
  const Recordings& rec = obs.recordings;
  const int rows = static_cast<int>(rec.size());
  obs.move_direction = Eigen::Matrix3Xd::Zero(3, rows);
  auto at = [&](int i) {
    Eigen::Vector3d p;
    for (int k = 0; k < 3; ++k) p[k] = obs.position(static_cast<AxisName>(k), i);
    return p;
  };
  auto same_run = [&](int a, int b) { return !rec.has_run() || rec.run[a] == rec.run[b]; };
  constexpr double kMoved_mm = 1e-9;
  for (int i = 0; i < rows; ++i) {
    Eigen::Vector3d d = Eigen::Vector3d::Zero();
    if (i > 0 && same_run(i - 1, i)) d = at(i) - at(i - 1);
    if (d.norm() < kMoved_mm && i + 1 < rows && same_run(i, i + 1)) d = at(i + 1) - at(i);
    if (d.norm() < kMoved_mm)
      for (int k = 0; k < 3; ++k) d[k] = obs.approach(static_cast<AxisName>(k), i);
    if (d.norm() > 0) obs.move_direction.col(i) = d.normalized();
  }
  obs.since_reversal_mm = Eigen::Matrix3Xd::Constant(3, rows, INFINITY);
  Eigen::Vector3d reversed_at = Eigen::Vector3d::Constant(NAN);
  for (int i = 0; i < rows; ++i) {
    if (i == 0 || !same_run(i - 1, i)) reversed_at.setConstant(NAN);
    for (int k = 0; k < 3; ++k) {
      const AxisName a = static_cast<AxisName>(k);
      if (i > 0 && same_run(i - 1, i) && obs.approach(a, i - 1) != 0 &&
          obs.approach(a, i) != obs.approach(a, i - 1))
        reversed_at[k] = obs.position(a, i - 1);
      if (!std::isnan(reversed_at[k]))
        obs.since_reversal_mm(k, i) = std::abs(obs.position(a, i) - reversed_at[k]);
    }
  }
}

void group_runs(Observations& obs) {
  obs.equations_of_run.assign(static_cast<std::size_t>(obs.run_count), {});
  for (std::size_t e = 0; e < obs.count; ++e)
    obs.equations_of_run[static_cast<std::size_t>(obs.run[e])].push_back(static_cast<int>(e));
  std::vector<std::vector<int>> nonempty;
  std::vector<int> remap(static_cast<std::size_t>(obs.run_count), -1);
  for (int r = 0; r < obs.run_count; ++r)
    if (!obs.equations_of_run[static_cast<std::size_t>(r)].empty()) {
      remap[static_cast<std::size_t>(r)] = static_cast<int>(nonempty.size());
      nonempty.push_back(obs.equations_of_run[static_cast<std::size_t>(r)]);
    }
  for (int& r : obs.run) r = remap[static_cast<std::size_t>(r)];
  obs.equations_of_run = nonempty;
  obs.run_count = static_cast<int>(nonempty.size());
}

}  // namespace

Observations build_observations(const Machine& m, const Recordings& rec,
                                const ExplainOptions& opt) {
  Observations obs(m, rec);
  check_recorded_axes_exist(m, rec);
  const std::size_t rows = rec.size();
  obs.run_count = rec.has_run() ? std::max<int>(1, static_cast<int>(rec.run_names.size())) : 1;
  const double default_tool_mm = default_tool_length_mm(m, rec);
  ModelsByTool models_by_tool(m, opt.baseline);
  obs.error_names = models_by_tool.for_tool(default_tool_mm).gains.names();

  EquationList eqs;
  eqs.gain_flat.reserve(rows * 2 * obs.error_names.size());
  AxisVector u(m.axis_count());
  for (std::size_t i = 0; i < rows; ++i)
    add_row_equations(obs, eqs, models_by_tool, default_tool_mm, i, u);
  obs.count = eqs.deviation_um.size();
  if (obs.count < 4)
    throw InputError(rec.file, 0,
                     fmt::format("{} usable observations; explain needs at least 4", obs.count));
  pack_equations(obs, eqs);
  group_runs(obs);
  find_move_directions(obs);
  return obs;
}

}  // namespace volmap::explanation
