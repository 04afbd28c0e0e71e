#include "core/measure/simulate.h"

#include <fmt/format.h>

#include <cmath>
#include <numbers>

#include "core/common/input_error.h"
#include "core/common/units.h"
#include "core/model/gain_evaluator.h"

namespace volmap {

double NormalSource::uniform() {
  // 53 bits -> (0, 1]: never 0, so log() below is finite.
  return (static_cast<double>(engine_() >> 11) + 1.0) * 0x1.0p-53;
}

double NormalSource::next() {
  const double u1 = uniform();
  const double u2 = uniform();
  return std::sqrt(-2.0 * std::log(u1)) * std::cos(2.0 * std::numbers::pi * u2);
}

Recordings simulate(const ErrorModel& model, const Plan& plan, const EffectSet* effects,
                    const std::map<std::string, std::string>& metadata) {
  const Machine& m = model.machine();
  GainEvaluator gains(m, model.options().formulation, model.errors().convention);
  if (effects != nullptr) {
    for (const Effect& e : effects->effects) {
      if (e.kind != EffectKind::kThermalDrift || e.law != DriftLaw::kTemperature) continue;
      if (!plan.temperature)
        throw InputError::at_json_path(
            effects->file, e.path + "/um_per_k",
            "a thermal drift against temperature needs a temperature the plan "
            "records; add \"temperature\": {\"sensor\": ...} to the plan");
      if (!e.sensor.empty() && e.sensor != plan.temperature->sensor)
        throw InputError::at_json_path(
            effects->file, e.path + "/sensor",
            fmt::format("sensor \"{}\" is not the plan's (\"{}\"); name the "
                        "plan's sensor",
                        e.sensor, plan.temperature->sensor));
    }
  }

  Recordings r;
  r.metadata = metadata;
  r.metadata["seed"] = std::to_string(plan.seed);
  r.metadata["noise_um"] = fmt::format("{}", plan.noise_um);
  r.frame = plan.frame;
  const std::size_t n = plan.points.size();
  r.line.assign(n, 0);
  for (AxisName a : m.axis_order) {
    r.position[static_cast<int>(a)].reserve(n);
    r.dir[static_cast<int>(a)].reserve(n);
  }
  for (int c = 0; c < 3; ++c)
    if (plan.record_union & (1u << c)) r.e_um[static_cast<std::size_t>(c)].reserve(n);
  NamedColumn* temperature = nullptr;
  if (plan.temperature) {
    r.temperature_c.push_back({"temp_" + plan.temperature->sensor + "_c", {}});
    temperature = &r.temperature_c.back();
  }

  NormalSource noise(plan.seed);
  for (const PlannedPoint& p : plan.points) {
    const PoseError dv = model.exact(p.u, p.dir);
    Eigen::Vector3d d_w_mm = dv.dP_mm;
    EffectContext ctx;
    if (effects != nullptr && !effects->effects.empty()) {
      gains.at(p.u);
      ctx.u = p.u;
      ctx.dir = p.dir;
      ctx.t_s = p.t_s;
      ctx.feed_mm_min = p.feed_mm_min;
      ctx.move_direction = p.move_direction;
      ctx.since_reversal_mm = p.since_reversal_mm;
      ctx.run = p.run;
      ctx.temperature_c = plan.temperature ? plan.temperature->at(p.t_s) : std::nan("");
      d_w_mm += effects_deviation_w_mm(*effects, m, gains, ctx);
    }
    Eigen::Vector3d d_um = d_w_mm * units::kUmPerMm;
    if (plan.frame == RecordingFrame::kMachine)
      d_um = nominal_base_to_workpiece(m, p.u).linear() * d_um;

    for (int i = 0; i < m.axis_count(); ++i) {
      const int a = static_cast<int>(m.axis_order[static_cast<std::size_t>(i)]);
      r.position[static_cast<std::size_t>(a)].push_back(p.u[i]);
      r.dir[static_cast<std::size_t>(a)].push_back(p.dir[static_cast<std::size_t>(i)]);
    }
    r.run.push_back(r.run_index(std::to_string(p.run)));
    r.t_s.push_back(p.t_s);
    if (plan.any_feed) r.feed_mm_min.push_back(p.feed_mm_min > 0 ? p.feed_mm_min : std::nan(""));
    if (temperature) temperature->values.push_back(plan.temperature->at(p.t_s));
    for (int c = 0; c < 3; ++c) {
      if (!(plan.record_union & (1u << c))) continue;
      double v = std::nan("");
      if (!p.projection && (p.record_mask & (1u << c))) {
        const double z = noise.next();
        v = d_um[c] + plan.noise_um * z;
      }
      r.e_um[static_cast<std::size_t>(c)].push_back(v);
    }
    if (plan.any_projection) {
      double v = std::nan("");
      Eigen::Vector3d beam = Eigen::Vector3d::Constant(std::nan(""));
      if (p.projection) {
        const double z = noise.next();
        v = p.beam.dot(d_um) + plan.noise_um * z;
        beam = p.beam;
      }
      for (std::size_t c = 0; c < 3; ++c) r.n[c].push_back(beam[static_cast<int>(c)]);
      r.e_along_n_um.push_back(v);
    }
  }
  r.check_consistent();
  return r;
}

}  // namespace volmap
