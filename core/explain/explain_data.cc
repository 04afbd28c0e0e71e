// The recording as equations (core/explain_internal.h) and the Cartesian
// machine explain assumes without --machine.
#include <fmt/format.h>

#include <algorithm>
#include <cmath>
#include <map>
#include <memory>
#include <sstream>

#include "core/common/input_error.h"
#include "core/explain/explain_internal.h"
#include "core/model/error_model.h"
#include "core/model/gain_evaluator.h"
#include "core/model/machine_json.h"

namespace volmap {
namespace explain_detail {

Data build_data(const Machine& m, const Recordings& rec, const ExplainOptions& opt) {
  Data d(m, rec);
  for (int a = 0; a < kAxisNameCount; ++a) {
    const AxisName ax = static_cast<AxisName>(a);
    if (rec.has_axis(ax) && !m.index_of(ax))
      throw InputError(rec.file, 0,
                       fmt::format("the recording has a {} column but the machine has no {} axis; "
                                   "give the machine that made the recording (--machine)",
                                   position_column_name(ax), axis_str(ax)));
  }
  const std::size_t rows = rec.size();
  d.runs = rec.has_run() ? std::max<int>(1, static_cast<int>(rec.run_names.size())) : 1;
  // The tool of each row (recordings.md: the tool_mm column, else the
  // "# tool_mm:" metadata, else the machine's): the tool tip, and with it
  // the Abbe levers of the angular errors, moves with the tool. One gain
  // evaluator and baseline model per tool length; the errors stay as
  // measured (the measurement tool is the machine file's).
  double default_tool_mm = m.tool_length_mm;
  if (const auto it = rec.metadata.find("tool_mm"); it != rec.metadata.end()) {
    char* end = nullptr;
    const double v = std::strtod(it->second.c_str(), &end);
    if (end != it->second.c_str() && std::isfinite(v) && v >= 0) default_tool_mm = v;
  }
  struct ToolModels {
    GainEvaluator gains;
    std::optional<ErrorModel> model;
  };
  std::map<double, std::unique_ptr<ToolModels>> by_tool;
  auto models_for = [&](double tool_mm) -> ToolModels& {
    auto it = by_tool.find(tool_mm);
    if (it == by_tool.end()) {
      Machine mt = m;
      if (std::isnan(mt.measurement_tool_length_mm))
        mt.measurement_tool_length_mm = m.tool_length_mm;
      mt.tool_length_mm = tool_mm;
      auto tm = std::make_unique<ToolModels>(
          ToolModels{GainEvaluator(mt, Formulation::kIndependent), std::nullopt});
      if (opt.baseline) tm->model.emplace(mt, *opt.baseline);
      it = by_tool.emplace(tool_mm, std::move(tm)).first;
    }
    return *it->second;
  };
  d.names = models_for(default_tool_mm).gains.names();

  std::vector<Eigen::Vector3d> pw, pb;
  std::vector<double> y, w;
  std::vector<std::vector<double>> gp_rows;
  const std::size_t nn = d.names.size();
  std::vector<double> gp_flat;
  gp_flat.reserve(rows * 2 * nn);
  AxisVector u(m.axis_count());
  for (std::size_t i = 0; i < rows; ++i) {
    const int ii = static_cast<int>(i);
    for (int k = 0; k < m.axis_count(); ++k)
      u[k] = d.q(m.axis_order[static_cast<std::size_t>(k)], ii);
    const Eigen::Matrix3d R_b_w = nominal_base_to_workpiece(m, u).linear();
    const Eigen::Matrix3d R_rec_w =
        rec.frame == RecordingFrame::kMachine ? R_b_w : Eigen::Matrix3d::Identity();
    const double weight = rec.weight.empty() ? 1.0 : rec.weight[i];
    if (!(weight >= 0) || !std::isfinite(weight))
      throw InputError(rec.file, rec.line[i], "weight must be a finite number >= 0");
    const double tool_mm =
        i < rec.tool_mm.size() && std::isfinite(rec.tool_mm[i]) ? rec.tool_mm[i] : default_tool_mm;
    ToolModels& tm = models_for(tool_mm);
    GainEvaluator& gains = tm.gains;
    std::optional<ErrorModel>& model = tm.model;
    bool gains_ready = false;
    Eigen::Vector3d pred_w_um = Eigen::Vector3d::Zero();
    bool pred_ready = false;
    auto add = [&](const Eigen::Vector3d& p_rec, double value, int group) {
      if (!std::isfinite(value) || weight == 0) return;
      if (!gains_ready) {
        gains.at(u);
        gains_ready = true;
      }
      if (model && !pred_ready) {
        ApproachDirections dir{};
        for (int k = 0; k < m.axis_count(); ++k)
          dir[static_cast<std::size_t>(k)] =
              static_cast<std::int8_t>(d.s(m.axis_order[static_cast<std::size_t>(k)], ii));
        try {
          pred_w_um = model->exact(u, dir).dP_mm * 1e3;
        } catch (const std::exception& e) {
          throw InputError(rec.file, rec.line[i],
                           fmt::format("the baseline cannot be evaluated here: {}", e.what()));
        }
        pred_ready = true;
      }
      const Eigen::Vector3d p_w = R_rec_w.transpose() * p_rec;
      pw.push_back(p_w);
      pb.push_back(R_b_w * p_w);
      y.push_back(value - p_w.dot(pred_w_um));
      w.push_back(weight);
      d.row.push_back(ii);
      d.group.push_back(group);
      d.run.push_back(rec.has_run() && rec.run[i] >= 0 ? rec.run[i] : 0);
      d.has_groups[group] = true;
      for (std::size_t k = 0; k < nn; ++k)
        gp_flat.push_back(p_w.dot(gains.dP(static_cast<int>(k))));
    };
    for (int c = 0; c < 3; ++c)
      if (rec.has_component(c))
        add(Eigen::Vector3d::Unit(c), rec.e_um[static_cast<std::size_t>(c)][i], c);
    if (rec.has_projection()) {
      const Eigen::Vector3d nv(rec.n[0][i], rec.n[1][i], rec.n[2][i]);
      if (nv.allFinite()) add(nv, rec.e_along_n_um[i], 3);
    }
  }
  d.n = y.size();
  if (d.n < 4)
    throw InputError(rec.file, 0,
                     fmt::format("{} usable observations; explain needs at least 4", d.n));
  d.y = Eigen::Map<const Eigen::VectorXd>(y.data(), static_cast<Eigen::Index>(d.n));
  d.sw.resize(static_cast<Eigen::Index>(d.n));
  d.p_w.resize(3, static_cast<Eigen::Index>(d.n));
  d.p_b.resize(3, static_cast<Eigen::Index>(d.n));
  for (std::size_t e = 0; e < d.n; ++e) {
    d.sw[static_cast<Eigen::Index>(e)] = std::sqrt(w[e]);
    d.p_w.col(static_cast<Eigen::Index>(e)) = pw[e];
    d.p_b.col(static_cast<Eigen::Index>(e)) = pb[e];
  }
  d.gp = Eigen::Map<const Eigen::Matrix<double, Eigen::Dynamic, Eigen::Dynamic, Eigen::RowMajor>>(
      gp_flat.data(), static_cast<Eigen::Index>(d.n), static_cast<Eigen::Index>(nn));
  d.run_eq.assign(static_cast<std::size_t>(d.runs), {});
  for (std::size_t e = 0; e < d.n; ++e)
    d.run_eq[static_cast<std::size_t>(d.run[e])].push_back(static_cast<int>(e));
  // Runs without equations do not count.
  std::vector<std::vector<int>> nonempty;
  std::vector<int> remap(static_cast<std::size_t>(d.runs), -1);
  for (int r = 0; r < d.runs; ++r)
    if (!d.run_eq[static_cast<std::size_t>(r)].empty()) {
      remap[static_cast<std::size_t>(r)] = static_cast<int>(nonempty.size());
      nonempty.push_back(d.run_eq[static_cast<std::size_t>(r)]);
    }
  for (int& r : d.run) r = remap[static_cast<std::size_t>(r)];
  d.run_eq = nonempty;
  d.runs = static_cast<int>(nonempty.size());
  return d;
}

}  // namespace explain_detail

using explain_detail::axis_str;
using explain_detail::kRadToDeg;

Machine cartesian_machine_for(const Recordings& rec) {
  nlohmann::ordered_json doc;
  doc["format"] = "volmap-machine/1";
  doc["name"] = "cartesian";
  doc["description"] = "Cartesian machine with the axes of the recording (explain, no --machine)";
  nlohmann::ordered_json axes = nlohmann::ordered_json::object();
  nlohmann::ordered_json tool = nlohmann::ordered_json::array();
  nlohmann::ordered_json work = nlohmann::ordered_json::array();
  for (int a = 0; a < kAxisNameCount; ++a) {
    const AxisName ax = static_cast<AxisName>(a);
    if (!rec.has_axis(ax)) continue;
    double lo = INFINITY, hi = -INFINITY;
    for (double v : rec.position[static_cast<std::size_t>(a)])
      if (std::isfinite(v)) {
        lo = std::min(lo, v);
        hi = std::max(hi, v);
      }
    if (!std::isfinite(lo)) lo = hi = 0;
    const double k = is_rotary(ax) ? kRadToDeg : 1.0;
    lo *= k;
    hi *= k;
    if (hi <= lo) hi = lo + 1;
    nlohmann::ordered_json dirv = {a % 3 == 0 ? 1 : 0, a % 3 == 1 ? 1 : 0, a % 3 == 2 ? 1 : 0};
    nlohmann::ordered_json ad;
    ad["type"] = is_rotary(ax) ? "rotary" : "linear";
    ad["direction"] = dirv;
    ad[is_rotary(ax) ? "travel_deg" : "travel_mm"] = {lo, hi};
    ad[is_rotary(ax) ? "home_deg" : "home_mm"] = std::clamp(0.0, lo, hi);
    axes[axis_str(ax)] = ad;
    nlohmann::ordered_json joint;
    joint["axis"] = axis_str(ax);
    joint["offset_mm"] = {0, 0, 0};
    (is_rotary(ax) ? work : tool).push_back(joint);
  }
  doc["axes"] = axes;
  doc["workpiece_chain"] = work;
  doc["tool_chain"] = tool;
  doc["spindle_offset_mm"] = {0, 0, 0};
  doc["tool"] = {{"length_mm", 0}, {"axis", {0, 0, 1}}};
  doc["workpiece_origin_mm"] = {0, 0, 0};
  std::istringstream in(doc.dump());
  return read_machine_json(in, rec.file + " (Cartesian machine of its axes)");
}

}  // namespace volmap
