// Physics beyond the rigid-body geometric model, injected by `volmap
// simulate` (format "volmap-effects/1", docs/simulate.md). The effect names
// and parameter names are those of shared/spec/explain.md, so `volmap
// explain` reports what a simulation injected under the same names.
//
// Translational effects (reversal, thermal_drift, cyclic, servo_lag, sag,
// setup_shift) displace the tool relative to the workpiece by delta along
// the machine's +X, +Y or +Z direction (the effect's "axis"): in the
// recording frame that is R_w_b * delta * e_axis (nominal R_w_b at the
// observation; identity for machines without rotary axes). With q_K the
// axis position (mm), s_K its approach direction, t the time (s):
//   reversal            delta = s_K value_um / 2   (B = mean(+) - mean(-) = value_um);
//                       kind "spike": -s_K value_um exp(-d_K / length_mm), d_K the
//                       distance K moved since it reversed (the axis sticks, then
//                       catches up); kind "lateral": s_J value_um / 2, J = input_axis
//                       (K shifts when J reverses: play across J's guideway)
//   thermal_drift       delta = f(t) * (1, or (q_K - origin_mm) / reference_length_mm
//                       for kind "scale"), f(t) = amplitude_um (1 - exp(-t / tau_s)),
//                       or rate_um_per_h t / 3600, or um_per_k (T(t) - reference_c)
//   cyclic              delta = amplitude_um sin(2 pi q_K / period_mm + phase)
//   servo_lag           delta = -um_per_m_min (feed_mm_min / 1000) m_K, m the unit
//                       direction of the last linear move (the axis lags behind)
//   sag                 delta = coefficient (q_in - origin)^power, q_in the position
//                       of input_axis in mm or degrees; coefficient in um per unit^power
//   setup_shift         delta = per_run_um[run - 1] (a number along axis, or [x, y, z])
// Rotary effects act as component errors of a rotary axis K at angle theta,
// propagated by the first-order gains (core/model/gain_evaluator.h):
//   rotary_wobble       tilts about the two axes perpendicular to K (for C: EAC, EBC)
//                       amplitude_urad (cos, sin)(order theta + phase)
//   rotary_positioning  angular positioning error (for C: ECC)
//                       amplitude_urad sin(order theta + phase)
#pragma once

#include <Eigen/Core>
#include <iosfwd>
#include <string>
#include <vector>

#include "core/model/error_model.h"
#include "core/model/gain_evaluator.h"
#include "core/model/machine.h"

namespace volmap {

enum class EffectKind : std::uint8_t {
  kReversal,
  kThermalDrift,
  kCyclic,
  kServoLag,
  kSag,
  kSetupShift,
  kRotaryWobble,
  kRotaryPositioning
};

/// The form of a lost motion (reversal): a step, a spike that decays along
/// the travel after the reversal, or a step of another axis (lateral play).
enum class LostMotion : std::uint8_t { kStep, kSpike, kLateral };

/// Thermal drift against time or temperature.
enum class DriftLaw : std::uint8_t { kSettling, kRate, kTemperature };

struct Effect {
  EffectKind kind = EffectKind::kReversal;
  std::string path;  ///< JSON path in the effects file, for messages
  AxisName axis = AxisName::X;
  double value_um = 0.0;  // reversal
  LostMotion lost_motion = LostMotion::kStep;
  double length_mm = 0.0;  ///< reversal spike: decay length along the travel
  bool scale = false;      // thermal_drift kind "scale"
  DriftLaw law = DriftLaw::kSettling;
  double amplitude_um = 0.0, tau_s = 0.0, rate_um_per_h = 0.0, um_per_k = 0.0;
  double reference_c = 20.0;
  std::string sensor;  ///< temperature sensor (temp_<sensor>_c)
  double origin_mm = 0.0, reference_length_mm = 1000.0;
  double period_mm = 0.0, phase_rad = 0.0;  // cyclic, rotary
  double um_per_m_min = 0.0;                // servo_lag
  AxisName input_axis = AxisName::X;        // sag
  double coefficient = 0.0, origin = 0.0;
  int power = 2;
  std::vector<Eigen::Vector3d> per_run_um;  ///< setup_shift, machine directions
  int order = 1;                            // rotary
  double amplitude_urad = 0.0;
  int gain_index[2] = {-1, -1};  ///< rotary: error names in GainEvaluator
};

struct EffectSet {
  std::string file;
  std::vector<Effect> effects;
};

/// The state of the machine at one observation.
struct EffectContext {
  AxisVector u;  ///< internal units
  ApproachDirections dir{};
  double t_s = 0.0;
  double feed_mm_min = 0.0;  ///< 0: not known / static
  Eigen::Vector3d move_direction = Eigen::Vector3d::Zero();
  /// Distance each linear axis (X, Y, Z) moved since it last reversed, mm.
  Eigen::Vector3d since_reversal_mm = Eigen::Vector3d::Constant(INFINITY);
  int run = 0;                 ///< 1-based
  double temperature_c = 0.0;  ///< of the plan's sensor (NaN when none)
};

/// Reads an effects file for machine m (axes must exist; rotary effects need
/// a rotary axis). Throws InputError with the JSON path.
EffectSet read_effects_json(std::istream& in, const std::string& file, const Machine& m,
                            const GainEvaluator& gains);
EffectSet load_effects_json(const std::string& path, const Machine& m, const GainEvaluator& gains);

/// Sum of all effects at one observation: the deviation of the tool relative
/// to the workpiece in workpiece coordinates, mm. `gains` must be at ctx.u.
Eigen::Vector3d effects_deviation_w_mm(const EffectSet& effects, const Machine& m,
                                       const GainEvaluator& gains, const EffectContext& ctx);

/// The name of an effect kind as in explain.md ("thermal_drift").
const char* effect_name(EffectKind k);

}  // namespace volmap
