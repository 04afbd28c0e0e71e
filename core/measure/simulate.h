// The real machine in software (`volmap simulate`, docs/simulate.md): the
// recordings an instrument would produce when running a plan on a machine
// with the given geometric errors and effects.
//
// Per planned point (core/measure/plan.h), in the recording frame (workpiece, or
// machine base for plans with "frame": "machine"), micrometres:
//   deviation = ErrorModel::exact(u, dir).dP            (geometric errors, exact HTM)
//             + effects_deviation_w_mm(...)             (core/measure/effects.h)
//             + noise_um * N(0, 1)                      (per recorded value)
// projected on the beam direction for the projection form.
// Positions are quantised to the recordings writer's decimals before the
// model is evaluated, so the file is self-consistent to the last digit.
// Noise: std::mt19937_64 seeded with the plan's seed and Box-Muller (one
// normal per two raw draws), independent of the standard library's
// distribution implementations: the same plan gives the same bytes.
#pragma once

#include <cstdint>
#include <map>
#include <random>
#include <string>

#include "core/measure/effects.h"
#include "core/measure/plan.h"
#include "core/measure/recordings.h"
#include "core/model/error_model.h"

namespace volmap {

/// Standard normal numbers from std::mt19937_64 by the Box-Muller transform.
class NormalSource {
 public:
  explicit NormalSource(std::uint64_t seed) : engine_(seed) {}
  double next();
  /// A uniform number in (0, 1]: 53 random bits.
  double uniform();

 private:
  std::mt19937_64 engine_;
};

/// Runs the plan on the model. `effects` may be null. `metadata` is copied
/// into the recordings (machine, errors, plan, ... file names).
Recordings simulate(const ErrorModel& model, const Plan& plan, const EffectSet* effects,
                    const std::map<std::string, std::string>& metadata = {});

}  // namespace volmap
