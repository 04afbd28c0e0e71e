// What `volmap post` did, for the person who runs it: a few lines for
// stderr, and a self-contained HTML page (--report: no script, no network)
// with the summary, the canned cycles whose feed leaves the tolerance, and
// the lines that changed, as read and as written.
#pragma once

#include <string>

#include "postproc/three_axis/post_program.h"

namespace volmap::post {

struct PostSummaryInfo {
  std::string program;  ///< the input as given
  std::string output;   ///< the output as given ("-": standard output)
  std::string machine;  ///< the machine's name
  std::string errors;   ///< the errors file or table as given
  double tolerance_um = 1.0;
};

/// The summary: lines in and out, changed and added, arcs kept, cut and
/// linearised, the largest correction and the largest predicted deviation
/// between points; then one warning per canned cycle whose feed into the
/// hole leaves the tolerance (the first 20, and how many more). Each line
/// ends with '\n'.
std::string post_summary_text(const PostSummaryInfo& info, const PostReport& r);

/// The --report page.
std::string post_report_html(const PostSummaryInfo& info, const PostReport& r);

}  // namespace volmap::post
