// volmap verify --report: a self-contained HTML page (inline SVG, no script,
// no network) that shows the deviation of the actual tool path from the
// nominal one along the whole program, before and after compensation: the
// summary table, the deviation profile along the path (largest deviation
// per stretch of path, logarithmic axis, so that microns and tenths of a
// micron show on one plot), the tool-axis deviation for five axes, and the
// program lines where the deviation is largest.
#pragma once

#include <cstdint>
#include <string>

#include "postproc/verify/deviation_profile.h"

namespace volmap::post {

struct VerifyReportRun {
  std::string label;    ///< "before", "after"
  std::string program;  ///< file name as given
  double max_um = 0, rms_um = 0;
  double max_urad = 0, rms_urad = 0;  ///< five axes
  std::uint64_t samples = 0;
  int worst_line = 0;
  const DeviationProfile* profile = nullptr;
};

struct VerifyReportInfo {
  std::string machine;  ///< machine name
  std::string errors;   ///< errors file as given
  bool five_axis = false;
};

std::string verify_report_html(const VerifyReportInfo& info, const VerifyReportRun& before,
                               const VerifyReportRun& after);

}  // namespace volmap::post
