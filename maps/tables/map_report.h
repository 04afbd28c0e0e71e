// The map report (volmap map --report map.html): one self-contained HTML
// page, inline SVG only (no scripts, no styles or fonts from the network),
// that shows the error field of a table as colour maps per component on
// three slices through the middle of the travel, and the in-plane error
// vectors of each slice. Every tag is closed (XHTML-style), so the page is
// also well-formed XML. Deterministic: the same table gives the same bytes.
#pragma once

#include <string>

#include "maps/tables/volumetric_table.h"

namespace volmap::maps {

struct ReportInfo {
  std::string model;                   ///< "independent" / "dependent"
  double max_interpolation_um = -1.0;  ///< < 0: not checked
  std::string interpolation;           ///< "linear" / "cubic"
  double build_seconds = 0.0;
};

/// The page. Slices: for every pair of the first three axes, the plane
/// through the middle node of the remaining axes; layer `layer` (0: the
/// first direction layer). Panels per slice: ex, ey, ez, |e| (um), the
/// correction ux uy uz or the tool-axis error (urad) when present, the
/// uncertainty u when present, and the in-plane error vectors. At most 48
/// nodes per axis are drawn (every k-th node).
std::string map_report_html(const VolumetricTable& table, const ReportInfo& info, int layer = 0);

}  // namespace volmap::maps
