// The factorized form of a volumetric table (docs/maps.md, "Factorized
// form"): instead of dv on a grid over all axes, per-axis 1-D tables of the
// six component errors (EX..EC of each axis, per approach direction, as
// cubic Hermite data: knots, values, slopes) plus the location errors,
// evaluated through the HTM chain of the machine (core/error_model.h:
// T = Trans(offset) L E(q) Trans(q d) / Rot(d, q), Hsu eqs. 1-6, Lei & Hsu
// eqs. 10-17). For the rigid-body model this is exact, not an
// approximation: the tool pose error of any axis position u is the product
// of the per-axis transforms, so the table size grows with the sum of the
// axes' knots, not their product (X'Y'ZA'C': 13 + 11 + 11 + 14 + 25 knots).
//
// File: one JSON document, "volmap-factorized/1", internal units (mm, rad)
// with doubles written so that they read back bit-exact; the machine
// definition embedded, so the file evaluates on its own.
#pragma once

#include <iosfwd>
#include <nlohmann/json.hpp>
#include <string>

#include "core/model/error_model.h"

namespace volmap::maps {

struct FactorizedTable {
  nlohmann::ordered_json machine_definition;  ///< docs/machine-format.md, as read
  std::string machine_name;
  std::string errors_source;
  Formulation formulation = Formulation::kIndependent;
  ErrorSet errors;  ///< the 1-D tables (knots, values, slopes) and location errors
};

/// The factorized form of a model; machine_definition is the machine file's
/// JSON (the model's machine was read from it).
FactorizedTable make_factorized(const nlohmann::ordered_json& machine_definition,
                                const ErrorModel& model);

/// The model that evaluates a factorized table through the HTM chain
/// (outside the travel: an error, as the direct model).
ErrorModel factorized_model(const FactorizedTable& t);

/// JSON text of the file (deterministic).
std::string factorized_json(const FactorizedTable& t);
void save_factorized(const std::string& path, const FactorizedTable& t);
/// Throws InputError (file, JSON path, what) for a document that is not a
/// volmap-factorized/1 table.
FactorizedTable read_factorized(std::istream& in, const std::string& file);

/// Knots of all 1-D tables (both directions), and bytes of the file's
/// numbers (8 per value, slope and knot): the table's size.
std::size_t factorized_values(const FactorizedTable& t);

}  // namespace volmap::maps
