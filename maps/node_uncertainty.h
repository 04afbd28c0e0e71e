// Per-node uncertainty of a table: the standard uncertainty of the tool-tip
// error dP at every node, propagated from the repeatability of the measured
// errors (docs/maps.md, "Uncertainty").
//
// Every error the errors file gives (each present component error of each
// axis, each location error) is taken as independent with standard
// uncertainty sigma: sigma_mm for translational errors, sigma_rad for
// angular ones. First-order propagation through the error gains g_k(u)
// (Hsu Table II, core/gain_evaluator.h) gives the covariance of dP,
// sum_k sigma_k^2 g_k g_k^T; the channel "u" holds the square root of its
// trace, sqrt(sum_k sigma_k^2 |g_k(u)|^2) (mm): the 3-D standard uncertainty
// of the tool-tip position error. It does not depend on the approach
// direction, so every layer holds the same values.
#pragma once

#include <optional>
#include <string>

#include "core/error_model.h"
#include "maps/volumetric_table.h"

namespace volmap::maps {

struct Repeatability {
  double translational_mm = 0.0;  ///< standard uncertainty of EXX, EX0C, ... (mm)
  double angular_rad = 0.0;       ///< standard uncertainty of EAX, EC0X, ... (rad)
};

/// From the errors file's metadata "# repeatability_um: R" and
/// "# repeatability_urad: R" (standard uncertainties, 1 sigma; a missing
/// key is 0). Nothing when neither is given. Throws std::invalid_argument
/// naming the key when a value is not a non-negative number.
std::optional<Repeatability> repeatability_from(const ErrorSet& errors);

/// Appends the channel "u" to a freshly laid-out table (values reallocated,
/// zero). No-op when it is there.
void add_uncertainty_channel(VolumetricTable& table);

/// Fills channel "u" of every node and layer (threads: 0 = all cores).
/// The same bytes for any thread count.
void fill_uncertainty(const ErrorModel& model, VolumetricTable& table, const Repeatability& r,
                      int threads = 0);

}  // namespace volmap::maps
