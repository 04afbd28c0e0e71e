#include "core/measure/effects.h"

#include <fmt/format.h>

#include <cmath>
#include <fstream>
#include <iostream>
#include <numbers>

#include "core/common/input_error.h"
#include "core/common/json_input.h"
#include "core/common/units.h"

namespace volmap {
namespace {

struct KindName {
  EffectKind kind;
  const char* name;
};
constexpr KindName kKinds[] = {
    {EffectKind::kReversal, "reversal"},
    {EffectKind::kThermalDrift, "thermal_drift"},
    {EffectKind::kCyclic, "cyclic"},
    {EffectKind::kServoLag, "servo_lag"},
    {EffectKind::kSag, "sag"},
    {EffectKind::kSetupShift, "setup_shift"},
    {EffectKind::kRotaryWobble, "rotary_wobble"},
    {EffectKind::kRotaryPositioning, "rotary_positioning"},
};

/// The kind named by "effect"; fails naming every kind for another name.
EffectKind effect_kind(const JsonObject& o) {
  const std::string name = o.string("effect");
  for (const KindName& k : kKinds)
    if (name == k.name) return k.kind;
  std::string list;
  for (const KindName& k : kKinds) list += std::string(list.empty() ? "" : ", ") + k.name;
  o.fail("effect", fmt::format("unknown effect \"{}\"; expected one of: {} (geometric errors "
                               "come from the errors CSV)",
                               name, list));
}

AxisName linear_axis(const JsonObject& o, const Machine& m, const std::string& key) {
  const AxisName a = o.axis(key);
  if (is_rotary(a) || !m.index_of(a))
    o.fail(key, "expected a linear axis of this machine (X, Y or Z)");
  return a;
}

AxisName rotary_axis(const JsonObject& o, const Machine& m, const std::string& key) {
  const AxisName a = o.axis(key);
  if (!is_rotary(a) || !m.index_of(a)) o.fail(key, "expected a rotary axis of this machine");
  return a;
}

void read_thermal_drift(const JsonObject& o, const Machine& m, Effect& e) {
  o.allow_only({"effect", "description", "axis", "kind", "amplitude_um", "tau_s", "rate_um_per_h",
                "um_per_k", "sensor", "reference_c", "origin_mm", "reference_length_mm"});
  e.axis = linear_axis(o, m, "axis");
  const std::string kind = o.string_or("kind", "offset");
  if (kind != "offset" && kind != "scale") o.fail("kind", "expected \"offset\" or \"scale\"");
  e.scale = kind == "scale";
  const int laws = (o.has("amplitude_um") ? 1 : 0) + (o.has("rate_um_per_h") ? 1 : 0) +
                   (o.has("um_per_k") ? 1 : 0);
  if (laws != 1)
    o.fail("", "give exactly one of amplitude_um (with tau_s), rate_um_per_h, um_per_k");
  if (o.has("amplitude_um")) {
    e.law = DriftLaw::kSettling;
    e.amplitude_um = o.number("amplitude_um");
    e.tau_s = o.number("tau_s");
    if (!(e.tau_s > 0)) o.fail("tau_s", "expected a time constant > 0 (s)");
  } else if (o.has("rate_um_per_h")) {
    e.law = DriftLaw::kRate;
    e.rate_um_per_h = o.number("rate_um_per_h");
  } else {
    e.law = DriftLaw::kTemperature;
    e.um_per_k = o.number("um_per_k");
    e.sensor = o.string_or("sensor", "");
    e.reference_c = o.number_or("reference_c", 20.0);
  }
  e.origin_mm = o.number_or("origin_mm", 0.0);
  e.reference_length_mm = o.number_or("reference_length_mm", 1000.0);
  if (!(e.reference_length_mm > 0)) o.fail("reference_length_mm", "expected a length > 0 (mm)");
}

void read_sag(const JsonObject& o, const Machine& m, Effect& e) {
  o.allow_only({"effect", "description", "axis", "input_axis", "coefficient", "power", "origin"});
  e.axis = linear_axis(o, m, "axis");
  e.input_axis = o.axis("input_axis");
  if (!m.index_of(e.input_axis)) o.fail("input_axis", "expected an axis of this machine");
  e.coefficient = o.number("coefficient");
  const double p = o.number_or("power", 2.0);
  if (p < 1 || p > 8 || p != std::floor(p)) o.fail("power", "expected a whole number 1..8");
  e.power = static_cast<int>(p);
  e.origin = o.number_or("origin", 0.0);
}

void read_setup_shift(const JsonObject& o, const Machine& m, Effect& e) {
  o.allow_only({"effect", "description", "axis", "per_run_um"});
  const nlohmann::json& v = o.at("per_run_um");
  if (!v.is_array()) o.fail("per_run_um", "expected an array, one entry per run");
  const bool along_axis = o.has("axis");
  if (along_axis) e.axis = linear_axis(o, m, "axis");
  for (std::size_t k = 0; k < v.size(); ++k) {
    const std::string p = "per_run_um/" + std::to_string(k);
    Eigen::Vector3d d = Eigen::Vector3d::Zero();
    if (v[k].is_number() && along_axis) {
      d[static_cast<int>(e.axis)] = v[k].get<double>();
    } else if (v[k].is_array() && v[k].size() == 3 && v[k][0].is_number() && v[k][1].is_number() &&
               v[k][2].is_number()) {
      d = {v[k][0].get<double>(), v[k][1].get<double>(), v[k][2].get<double>()};
    } else {
      o.fail(p, along_axis ? "expected a number (µm along axis) or [x, y, z] (µm)"
                           : "expected [x, y, z] in µm (or give \"axis\" and numbers)");
    }
    if (!d.allFinite()) o.fail(p, "expected finite numbers");
    e.per_run_um.push_back(d);
  }
}

/// rotary_wobble and rotary_positioning: the component errors of the axis
/// they act as (GainEvaluator indices).
void read_rotary(const JsonObject& o, const Machine& m, const GainEvaluator& gains, Effect& e) {
  o.allow_only({"effect", "description", "axis", "order", "amplitude_urad", "phase_deg"});
  e.axis = rotary_axis(o, m, "axis");
  const double order = o.number_or("order", 1.0);
  if (order < 0 || order != std::floor(order) || order > 360)
    o.fail("order", "expected a whole number 0..360");
  e.order = static_cast<int>(order);
  e.amplitude_urad = o.number("amplitude_urad");
  e.phase_rad = o.number_or("phase_deg", 0.0) * units::kRadPerDeg;
  const int own = static_cast<int>(e.axis) - 3;
  if (e.kind == EffectKind::kRotaryPositioning) {
    e.gain_index[0] = gains.index_of(component_error_name(static_cast<Component>(own + 3), e.axis));
  } else {
    int k = 0;
    for (int c = 0; c < 3; ++c)
      if (c != own)
        e.gain_index[k++] =
            gains.index_of(component_error_name(static_cast<Component>(c + 3), e.axis));
  }
}

void read_reversal(const JsonObject& o, const Machine& m, Effect& e) {
  o.allow_only({"effect", "description", "axis", "value_um", "kind", "length_mm", "input_axis"});
  e.axis = linear_axis(o, m, "axis");
  e.value_um = o.number("value_um");
  const std::string kind = o.string_or("kind", "step");
  if (kind == "spike") {
    e.lost_motion = LostMotion::kSpike;
    e.length_mm = o.number("length_mm");
    if (!(e.length_mm > 0)) o.fail("length_mm", "expected a decay length > 0 (mm)");
  } else if (kind == "lateral") {
    e.lost_motion = LostMotion::kLateral;
    e.input_axis = linear_axis(o, m, "input_axis");
    if (e.input_axis == e.axis) o.fail("input_axis", "expected an axis other than \"axis\"");
  } else if (kind != "step") {
    o.fail("kind", "expected \"step\", \"spike\" or \"lateral\"");
  }
  for (const char* k : {"length_mm", "input_axis"})
    if (o.has(k) && !(kind == (std::string(k) == "length_mm" ? "spike" : "lateral")))
      o.fail(k, fmt::format("not a parameter of a reversal of kind \"{}\"", kind));
}

Effect read_effect(const JsonObject& o, const Machine& m, const GainEvaluator& gains) {
  Effect e;
  e.path = o.path();
  e.kind = effect_kind(o);
  switch (e.kind) {
    case EffectKind::kReversal:
      read_reversal(o, m, e);
      break;
    case EffectKind::kThermalDrift:
      read_thermal_drift(o, m, e);
      break;
    case EffectKind::kCyclic:
      o.allow_only({"effect", "description", "axis", "period_mm", "amplitude_um", "phase_deg"});
      e.axis = linear_axis(o, m, "axis");
      e.period_mm = o.number("period_mm");
      if (!(e.period_mm > 0)) o.fail("period_mm", "expected a period > 0 (mm)");
      e.amplitude_um = o.number("amplitude_um");
      e.phase_rad = o.number_or("phase_deg", 0.0) * units::kRadPerDeg;
      break;
    case EffectKind::kServoLag:
      o.allow_only({"effect", "description", "axis", "um_per_m_min"});
      e.axis = linear_axis(o, m, "axis");
      e.um_per_m_min = o.number("um_per_m_min");
      break;
    case EffectKind::kSag:
      read_sag(o, m, e);
      break;
    case EffectKind::kSetupShift:
      read_setup_shift(o, m, e);
      break;
    case EffectKind::kRotaryWobble:
    case EffectKind::kRotaryPositioning:
      read_rotary(o, m, gains, e);
      break;
  }
  return e;
}

double axis_value(const Machine& m, const AxisVector& u, AxisName a) {
  const double q = u[*m.index_of(a)];
  return is_rotary(a) ? q / units::kRadPerDeg : q;
}

}  // namespace

const char* effect_name(EffectKind k) {
  for (const KindName& n : kKinds)
    if (n.kind == k) return n.name;
  return "?";
}

EffectSet read_effects_json(std::istream& in, const std::string& file, const Machine& m,
                            const GainEvaluator& gains) {
  const nlohmann::json doc = parse_json_document(in, file);
  const JsonObject root(file, doc, "");
  root.allow_only({"format", "description", "effects"});
  if (root.has("format") && root.string("format") != "volmap-effects/1")
    root.fail("format", "expected \"volmap-effects/1\"");
  EffectSet set;
  set.file = file;
  for (const JsonObject& o : root.objects("effects"))
    set.effects.push_back(read_effect(o, m, gains));
  return set;
}

EffectSet load_effects_json(const std::string& path, const Machine& m, const GainEvaluator& gains) {
  if (path == "-") return read_effects_json(std::cin, "<stdin>", m, gains);
  std::ifstream in(path, std::ios::binary);
  if (!in)
    throw InputError(path, 0, "cannot open the effects file; check the path and the permissions");
  return read_effects_json(in, path, m, gains);
}

Eigen::Vector3d effects_deviation_w_mm(const EffectSet& effects, const Machine& m,
                                       const GainEvaluator& gains, const EffectContext& ctx) {
  Eigen::Vector3d d_b_um = Eigen::Vector3d::Zero();  // translational, machine directions
  Eigen::Vector3d d_w_mm = Eigen::Vector3d::Zero();  // rotary, workpiece frame
  for (const Effect& e : effects.effects) {
    const int k = static_cast<int>(e.axis);
    switch (e.kind) {
      case EffectKind::kReversal: {
        const int s = ctx.dir[static_cast<std::size_t>(*m.index_of(e.axis))];
        if (e.lost_motion == LostMotion::kStep) {
          d_b_um[k] += 0.5 * e.value_um * s;
        } else if (e.lost_motion == LostMotion::kSpike) {
          d_b_um[k] -= s * e.value_um * std::exp(-ctx.since_reversal_mm[k] / e.length_mm);
        } else {
          d_b_um[k] +=
              0.5 * e.value_um * ctx.dir[static_cast<std::size_t>(*m.index_of(e.input_axis))];
        }
        break;
      }
      case EffectKind::kThermalDrift: {
        double f = 0.0;
        switch (e.law) {
          case DriftLaw::kSettling:
            f = e.amplitude_um * (1.0 - std::exp(-ctx.t_s / e.tau_s));
            break;
          case DriftLaw::kRate:
            f = e.rate_um_per_h * ctx.t_s / 3600.0;
            break;
          case DriftLaw::kTemperature:
            f = e.um_per_k * (ctx.temperature_c - e.reference_c);
            break;
        }
        if (e.scale) f *= (axis_value(m, ctx.u, e.axis) - e.origin_mm) / e.reference_length_mm;
        d_b_um[k] += f;
        break;
      }
      case EffectKind::kCyclic:
        d_b_um[k] += e.amplitude_um *
                     std::sin(2.0 * std::numbers::pi * axis_value(m, ctx.u, e.axis) / e.period_mm +
                              e.phase_rad);
        break;
      case EffectKind::kServoLag:
        d_b_um[k] -= e.um_per_m_min * (ctx.feed_mm_min / 1000.0) * ctx.move_direction[k];
        break;
      case EffectKind::kSag:
        d_b_um[k] +=
            e.coefficient * std::pow(axis_value(m, ctx.u, e.input_axis) - e.origin, e.power);
        break;
      case EffectKind::kSetupShift:
        if (ctx.run >= 1 && static_cast<std::size_t>(ctx.run) <= e.per_run_um.size())
          d_b_um += e.per_run_um[static_cast<std::size_t>(ctx.run - 1)];
        break;
      case EffectKind::kRotaryWobble: {
        const double theta = ctx.u[*m.index_of(e.axis)];
        const double arg = e.order * theta + e.phase_rad;
        d_w_mm += gains.dP(e.gain_index[0]) * (e.amplitude_urad * 1e-6 * std::cos(arg));
        d_w_mm += gains.dP(e.gain_index[1]) * (e.amplitude_urad * 1e-6 * std::sin(arg));
        break;
      }
      case EffectKind::kRotaryPositioning: {
        const double theta = ctx.u[*m.index_of(e.axis)];
        d_w_mm += gains.dP(e.gain_index[0]) *
                  (e.amplitude_urad * 1e-6 * std::sin(e.order * theta + e.phase_rad));
        break;
      }
    }
  }
  const Eigen::Matrix3d R_w_b = nominal_base_to_workpiece(m, ctx.u).linear().transpose();
  return d_w_mm + R_w_b * (d_b_um * 1e-3);
}

}  // namespace volmap
