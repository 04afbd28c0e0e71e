// The circular tests (ISO 230-4) in explain's outputs: the readings G and H
// in the JSON and the summary, and the polar plots of the report.
#pragma once

#include <nlohmann/json.hpp>
#include <string>
#include <vector>

#include "core/explain/explain.h"

namespace volmap::explanation {

nlohmann::ordered_json circular_json(const std::vector<CircularTest>& tests);
std::string circular_text(const std::vector<CircularTest>& tests);
/// A section per test: its readings and two polar plots of the radial
/// deviation, magnified about the nominal circle: as recorded with the
/// findings' fit dashed, and what the findings leave.
std::string circular_html(const std::vector<CircularTest>& tests);

}  // namespace volmap::explanation
