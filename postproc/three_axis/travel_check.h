// The travel check of volmap post: every commanded position, corrected,
// must lie within the machine's travel (issue 23), whichever path of
// ProgramPost writes the line.
#pragma once

#include <Eigen/Core>
#include <string>

#include "core/model/machine.h"
#include "gcode/nc_interpreter.h"
#include "postproc/three_axis/corrector.h"

namespace volmap::post {

/// Throws InputError (file:line) when the motion m takes an axis outside the
/// machine's travel: its end point, the extremes of an arc's sweep, a canned
/// cycle's R plane and clearance level, each as the axes reach it with tool
/// length compensation (Corrector::axis_position). The message names the
/// likely cause: no work offset (origin_mm at the machine's zero), or a
/// program that lies outside the travel at its origin. Under cutter
/// compensation the tool centre is off the programmed path by up to
/// xy_margin_mm in X and Y: each point is checked that far either side.
void check_travel(const Machine& machine, const nc::Motion& m, const Corrector& c,
                  const Eigen::Vector3d& origin_mm, const std::string& file, int line,
                  double xy_margin_mm = 0.0);

}  // namespace volmap::post
