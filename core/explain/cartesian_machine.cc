// The Cartesian machine explain assumes without a machine definition.
#include <algorithm>
#include <cmath>
#include <sstream>

#include "core/common/units.h"
#include "core/explain/axis_labels.h"
#include "core/explain/explain.h"
#include "core/model/machine_json.h"

namespace volmap {

using explanation::axis_letter;

Machine cartesian_machine_for(const Recordings& rec) {
  nlohmann::ordered_json doc;
  doc["format"] = "volmap-machine/1";
  doc["name"] = "cartesian";
  doc["description"] =
      "Cartesian machine with the axes of the recording (explain without a machine file)";
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
    const double k = is_rotary(ax) ? units::kDegPerRad : 1.0;
    lo *= k;
    hi *= k;
    if (hi <= lo) hi = lo + 1;
    nlohmann::ordered_json dirv = {a % 3 == 0 ? 1 : 0, a % 3 == 1 ? 1 : 0, a % 3 == 2 ? 1 : 0};
    nlohmann::ordered_json ad;
    ad["type"] = is_rotary(ax) ? "rotary" : "linear";
    ad["direction"] = dirv;
    ad[is_rotary(ax) ? "travel_deg" : "travel_mm"] = {lo, hi};
    ad[is_rotary(ax) ? "home_deg" : "home_mm"] = std::clamp(0.0, lo, hi);
    axes[axis_letter(ax)] = ad;
    nlohmann::ordered_json joint;
    joint["axis"] = axis_letter(ax);
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
