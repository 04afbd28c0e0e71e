// A measurement plan given as JSON text (named "plan.json" in messages).
#pragma once

#include <sstream>
#include <string>

#include "core/measure/plan.h"

namespace volmap::test {

inline Plan plan_from_text(const std::string& json, const Machine& m) {
  std::istringstream in(json);
  return read_plan_json(in, "plan.json", m);
}

}  // namespace volmap::test
