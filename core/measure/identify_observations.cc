#include "core/measure/identify_observations.h"

#include <algorithm>
#include <cmath>

#include "core/common/input_error.h"
#include "core/model/machine.h"

namespace volmap::identification {
namespace {

/// R_rec_w: the workpiece->recording rotation at u (R_b_w in the machine
/// frame, else the identity).
Eigen::Matrix3d recording_rotation(const Machine& m, const AxisVector& u, bool machine_frame) {
  return machine_frame ? Eigen::Matrix3d(nominal_base_to_workpiece(m, u).linear())
                       : Eigen::Matrix3d::Identity();
}

}  // namespace

Observations gather_observations(const Machine& m, const Recordings& rec) {
  Observations obs;
  std::vector<Equation>& eqs = obs.equations;
  const std::size_t n_rows = rec.size();
  obs.machine_frame = rec.frame == RecordingFrame::kMachine && m.has_rotary_axes();
  for (std::size_t i = 0; i < n_rows; ++i) {
    const double w = rec.weight.empty() ? 1.0 : rec.weight[i];
    if (w <= 0) continue;
    AxisVector u = m.home;
    ApproachDirections d{};
    for (int k = 0; k < m.axis_count(); ++k) {
      const auto a = static_cast<std::size_t>(m.axis_order[static_cast<std::size_t>(k)]);
      if (!rec.position[a].empty()) u[k] = rec.position[a][i];
      if (!rec.dir[a].empty()) d[static_cast<std::size_t>(k)] = rec.dir[a][i];
    }
    const Eigen::Matrix3d R = recording_rotation(m, u, obs.machine_frame);
    const int row = static_cast<int>(obs.u.size());
    bool any = false;
    for (int c = 0; c < 3; ++c) {
      if (!rec.has_component(c)) continue;
      const double y = rec.e_um[static_cast<std::size_t>(c)][i];
      if (std::isnan(y)) continue;
      eqs.push_back({row, R.transpose() * Eigen::Vector3d::Unit(c), y, std::sqrt(w)});
      any = true;
    }
    if (rec.has_projection() && !std::isnan(rec.e_along_n_um[i])) {
      const Eigen::Vector3d n(rec.n[0][i], rec.n[1][i], rec.n[2][i]);
      eqs.push_back({row, R.transpose() * n, rec.e_along_n_um[i], std::sqrt(w)});
      any = true;
    }
    if (!any) continue;
    obs.u.push_back(u);
    obs.dir.push_back(d);
    obs.run.push_back(rec.has_run() ? rec.run[i] : -1);
    obs.line.push_back(rec.line[i]);
  }
  if (eqs.empty())
    throw InputError(
        rec.file, 0,
        "no recorded deviation to fit (every deviation cell is empty or has weight 0)");
  return obs;
}

std::vector<bool> moved_axes(const Machine& m, const std::vector<AxisVector>& us) {
  std::vector<bool> moved(static_cast<std::size_t>(m.axis_count()), false);
  for (int k = 0; k < m.axis_count(); ++k) {
    double lo = 1e300, hi = -1e300;
    for (const AxisVector& u : us) {
      lo = std::min(lo, u[k]);
      hi = std::max(hi, u[k]);
    }
    moved[static_cast<std::size_t>(k)] = hi - lo > 1e-9;
  }
  return moved;
}

Eigen::MatrixXd weighted_jacobian(const Machine& m, GainEvaluator& gains, const Observations& obs,
                                  const std::vector<ParameterColumn>& cols) {
  const std::vector<Equation>& eqs = obs.equations;
  const int P = static_cast<int>(cols.size());
  Eigen::MatrixXd J(static_cast<Eigen::Index>(eqs.size()), P);
  std::size_t e = 0;
  for (std::size_t row = 0; row < obs.u.size(); ++row) {
    gains.at(obs.u[row]);
    const std::size_t e_begin = e;
    while (e < eqs.size() && eqs[e].row == static_cast<int>(row)) ++e;
    for (int j = 0; j < P; ++j) {
      const ParameterColumn& c = cols[static_cast<std::size_t>(j)];
      Eigen::Vector3d g_w;  // workpiece frame, um per parameter unit
      if (c.p.kind == ParameterKind::kSetupOffset) {
        // offsets live in the recording frame: p_rec . e_c = (R p_w) . e_c
        const Eigen::Matrix3d R = recording_rotation(m, obs.u[row], obs.machine_frame);
        g_w = obs.run[row] == c.run ? Eigen::Vector3d(R.row(c.coordinate).transpose())
                                    : Eigen::Vector3d::Zero();
      } else {
        g_w = physical_gain_w_um(c, gains, obs.u[row]);
      }
      for (std::size_t k = e_begin; k < e; ++k)
        J(static_cast<Eigen::Index>(k), j) = eqs[k].sqrt_w * eqs[k].p_w.dot(g_w);
    }
  }
  return J;
}

}  // namespace volmap::identification
