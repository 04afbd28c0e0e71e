// AptReader: CIRCLE (arcs and helices about any axis) and CYCLE (drilling
// holes written out as moves). docs/post-five-axis.md "APT / CLDATA" gives
// the sources of each convention.
#include <fmt/format.h>

#include <algorithm>
#include <cmath>

#include "core/common/input_error.h"
#include "gcode/nc_path.h"
#include "postproc/five_axis/apt_reader.h"
#include "postproc/five_axis/five_axis_post.h"

namespace volmap::post {
namespace {

// LinuxCNC's G83 clearance above the depth of the last peck (0.010 inch).
constexpr double kPeckClearanceMm = 0.254;
// Bounds on what one record may expand to.
constexpr int kMaxChords = 100000, kMaxPecks = 10000;

// v turned about the unit axis n by angle a (right hand).
Eigen::Vector3d rotate(const Eigen::Vector3d& v, const Eigen::Vector3d& n, double a) {
  return v * std::cos(a) + n.cross(v) * std::sin(a) + n * n.dot(v) * (1.0 - std::cos(a));
}

bool has_word(const AptRecord& r, const char* word) {
  return std::find(r.args.begin(), r.args.end(), word) != r.args.end();
}

}  // namespace

void AptReader::circle_record(const AptRecord& r) {
  if (cycle_) fail("CIRCLE/ inside a CYCLE/; end the cycle with CYCLE/OFF first");
  if (circle_) fail("two CIRCLE/ records without the GOTO/ of the first");
  // NX: x,y,z,i,j,k,r,tolerance,ratio,tool diameter,corner radius
  // [,TIMES,n]; SOLIDWORKS CAM: x,y,z,i,j,k; Creo: x,y,z,i,j,k,r.
  for (const std::string& a : r.args)
    if (a == "TIMES")
      fail(
          "CIRCLE/ with TIMES (several turns of a helix) is not supported; output the helix "
          "one turn per CIRCLE/ or as GOTO points");
  const std::vector<double> v = numbers(r);
  Circle c;
  c.line = line_;
  bool clockwise_about_axis = false;
  if (v.size() == 11) {
    if (dialect_ == AptDialect::kSolidworks || dialect_ == AptDialect::kCreo)
      fail(fmt::format("CIRCLE/ with 11 values (NX's form) in a file from {}",
                       apt_dialect_name(dialect_)));
    // NX: "circle or helix axis vector ... assuming a clockwise direction".
    clockwise_about_axis = true;
    c.radius_mm = v[6] * unit_mm_;
  } else if (v.size() == 6 || v.size() == 7) {
    if (dialect_ == AptDialect::kNx)
      fail(fmt::format("CIRCLE/ with {} values in a file from NX (which writes 11)", v.size()));
    if (v.size() == 7) c.radius_mm = v[6] * unit_mm_;
  } else {
    fail(
        fmt::format("CIRCLE/ with {} values: volmap reads x,y,z,i,j,k (SOLIDWORKS CAM), "
                    "x,y,z,i,j,k,r (Creo) and NX's 11 values; the axis i,j,k is needed",
                    v.size()));
  }
  const Eigen::Vector3d n(v[3], v[4], v[5]);
  if (n.norm() < 1e-9) fail("CIRCLE/: the axis i,j,k is zero");
  c.centre_mm = Eigen::Vector3d(v[0], v[1], v[2]) * unit_mm_;
  c.axis = (clockwise_about_axis ? -n : n).normalized();
  circle_ = c;
}

void AptReader::arc_to(const Eigen::Vector3d& end_mm, const Eigen::Vector3d& axis,
                       std::deque<FiveAxisLine>& out) {
  if (goto_rapid_) fail("RAPID before the GOTO/ of a CIRCLE/: an arc is a feed move");
  const Circle& c = *circle_;
  const Eigen::Vector3d& n = c.axis;
  const Eigen::Vector3d s = tip_mm_;
  Eigen::Vector3d e = end_mm;
  if ((e - s).norm() < 1e-9) e = s;  // a full circle
  const Eigen::Vector3d rs = (s - c.centre_mm) - (s - c.centre_mm).dot(n) * n;
  const Eigen::Vector3d re = (e - c.centre_mm) - (e - c.centre_mm).dot(n) * n;
  const double r0 = rs.norm(), r1 = re.norm();
  if (r0 < 1e-6) fail("the arc of CIRCLE/ starts on its axis");
  // The same circle as LinuxCNC judges an arc's two radii.
  if (!nc::linuxcnc_accepts_radii(r0, r1, false))
    fail(
        fmt::format("the GOTO/ after CIRCLE/ (line {}) is not on the circle: {:.4f} mm from "
                    "its axis, the arc starts {:.4f} mm from it",
                    c.line, r1, r0));
  if (c.radius_mm > 0 && !nc::linuxcnc_accepts_radii(r0, c.radius_mm, false))
    fail(
        fmt::format("the arc of CIRCLE/ (line {}) starts {:.4f} mm from its axis; its radius "
                    "is {:.4f} mm",
                    c.line, r0, c.radius_mm));
  double sweep = 2 * M_PI;
  if (e != s) {
    sweep = std::atan2(n.dot(rs.cross(re)), rs.dot(re));
    if (sweep <= 1e-12) sweep += 2 * M_PI;
  }
  const Eigen::Vector3d a0 = axis_, a1 = axis.normalized();
  // About X, Y or Z: an arc of the interpreter's planes, exact.
  for (int k = 0; k < 3; ++k) {
    if (std::abs(std::abs(n[k]) - 1.0) > 1e-12) continue;
    static constexpr int kPlane[3] = {2, 1, 0};  // normal X: YZ (G19), Y: ZX (G18), Z: XY (G17)
    add_move(e, a1, false, feed_, out);
    nc::Motion& m = out.back().move.tip;
    m.kind = nc::MotionKind::kArc;
    m.plane = kPlane[k];
    m.clockwise = n[k] < 0;
    m.center_mm = c.centre_mm;
    m.center_mm[k] = s[k];
    return;
  }
  // About a tilted axis: chords within chord_mm_ of the arc.
  const double r = std::max(r0, r1);
  const double step = r > chord_mm_ ? 2.0 * std::acos(1.0 - chord_mm_ / r) : M_PI / 2;
  const double chords = std::ceil(sweep / step);
  if (!(chords <= kMaxChords))
    fail(
        fmt::format("the arc of CIRCLE/ (line {}), {:.4g} mm about a tilted axis, would take more "
                    "than {} chords within {:g} µm; output it as GOTO points",
                    c.line, r, kMaxChords, chord_mm_ * 1e3));
  const int count = std::max(2, static_cast<int>(chords));
  const Eigen::Vector3d base = c.centre_mm + (s - c.centre_mm).dot(n) * n;
  const double rise = (e - s).dot(n);
  for (int i = 1; i <= count; ++i) {
    const double t = static_cast<double>(i) / count;
    const Eigen::Vector3d p =
        i == count ? e
                   : base + rotate(rs, n, t * sweep) * ((r0 + t * (r1 - r0)) / r0) + n * rise * t;
    add_move(p, slerp_axis(a0, a1, t), false, feed_, out);
  }
}

double AptReader::cycle_depth(double fedto) const {
  // SOLIDWORKS CAM: FEDTO is the depth below the GOTO point (positive;
  // checked on its files). NX: an offset along the tool axis from the
  // point (its posts add mom_cycle_feed_to * axis), so negative below it.
  if (fedto == 0) return 0;
  if (dialect_ == AptDialect::kSolidworks && fedto > 0) return fedto;
  if (dialect_ == AptDialect::kNx && fedto < 0) return -fedto;
  if (dialect_ == AptDialect::kSolidworks || dialect_ == AptDialect::kNx)
    fail(fmt::format("CYCLE/ FEDTO {} from {}: the hole would end above its point", fedto,
                     apt_dialect_name(dialect_)));
  fail(
      "CYCLE/ with FEDTO in a file whose CAM system volmap cannot tell (NX writes it as an "
      "offset, SOLIDWORKS CAM as a depth): output the holes as GOTO moves");
}

void AptReader::cycle_record(const AptRecord& r, std::deque<FiveAxisLine>& out) {
  const std::string first = r.args.empty() ? "" : r.args[0];
  add_comment(r, out);
  if (first == "OFF") {
    cycle_.reset();
    return;
  }
  if (first == "INIT" || first == "CLEAR") return;  // SOLIDWORKS CAM's brackets: no values
  if (first == "ON") {
    if (!last_cycle_) fail("CYCLE/ON before any cycle was defined");
    cycle_ = last_cycle_;
    return;
  }
  if (dialect_ == AptDialect::kCreo || has_word(r, "DEPTH") || has_word(r, "CLEAR"))
    fail(
        "Creo's CYCLE/ (DEPTH, CLEAR): whether its GOTO points are the hole tops or the "
        "clearance points is not established; output the holes as GOTO moves");
  Cycle cy;
  size_t k = 0;
  std::string type, sub;
  while (k < r.args.size() && (r.args[k] == "DRILL" || r.args[k] == "DEEP" ||
                               r.args[k] == "DEEP2" || r.args[k] == "BRKCHP" ||
                               r.args[k] == "REAM" || r.args[k] == "TAP" || r.args[k] == "BORE"))
    (type.empty() ? type : sub) = r.args[k++];
  if (!sub.empty() && type == "DRILL") type = sub, sub.clear();
  if (type.empty() || !sub.empty())
    fail(fmt::format("CYCLE/{}: not a cycle volmap writes out (DRILL, DEEP, DEEP2, BRKCHP, REAM)",
                     apt_shown(first)));
  if (type == "TAP" || type == "BORE")
    fail(
        fmt::format("CYCLE/{}: the spindle must {} in the hole, which plain moves cannot say; "
                    "post this operation with a three-axis program and the controller's cycle",
                    type, type == "TAP" ? "reverse in step with the feed" : "stop and orient"));
  cy.type = type;
  std::optional<double> fedto, rapto, rtrcto;
  double feed = 0;
  for (; k < r.args.size(); k += 2) {
    const std::string& w = r.args[k];
    double x = 0;
    if (apt_number(w, x))
      fail(
          "CYCLE/ in the positional form (a number where a word such as FEDTO belongs): where "
          "its GOTO stands differs between CAM systems; output the couplet form or GOTO moves");
    if (k + 1 >= r.args.size() || !apt_number(r.args[k + 1], x))
      fail(fmt::format("CYCLE/: {} needs a number after it", apt_shown(w)));
    if (w == "FEDTO")
      fedto = x;
    else if (w == "RAPTO")
      rapto = x;
    else if (w == "RTRCTO")
      rtrcto = x;
    else if (w == "DWELL")
      cy.dwell_s = x;
    else if (w == "INCR" || w == "STEP")
      cy.first_peck_mm = cy.peck_mm = x * unit_mm_;
    else if (w == "1STPECK")
      cy.first_peck_mm = x * unit_mm_;
    else if (w == "SUBPECK")
      cy.peck_mm = x * unit_mm_;
    else if (w == "MMPM" || w == "IPM")
      feed = x;
    else if (w == "MMPR" || w == "IPR")
      fail("CYCLE/ feed per revolution is not supported; output MMPM or IPM");
    else
      fail(fmt::format("CYCLE/: '{}' is not understood", apt_shown(w)));
  }
  if (!fedto || !rapto) fail("CYCLE/ needs FEDTO (the depth) and RAPTO (the R level)");
  if (!(feed > 0)) fail("CYCLE/ needs a feed (MMPM or IPM)");
  const bool pecks = type != "DRILL" && type != "REAM";
  if (pecks && !(cy.first_peck_mm > 0 && cy.peck_mm > 0))
    fail(fmt::format("CYCLE/{} needs its peck depths (INCR, or 1STPECK and SUBPECK)", type));
  if (!pecks) cy.first_peck_mm = cy.peck_mm = 0;
  if (pecks && !(std::abs(*fedto) * unit_mm_ / std::min(cy.first_peck_mm, cy.peck_mm) <= kMaxPecks))
    fail(fmt::format("CYCLE/{}: more than {} pecks per hole", type, kMaxPecks));
  cy.depth_mm = cycle_depth(*fedto) * unit_mm_;
  cy.rapto_mm = *rapto * unit_mm_;
  cy.retract_mm = rtrcto ? *rtrcto * unit_mm_ : cy.rapto_mm;
  cy.feed_mm_per_min = feed * unit_mm_;
  if (cy.rapto_mm < -cy.depth_mm) fail("CYCLE/: RAPTO is below the hole's bottom");
  if (cy.retract_mm < cy.rapto_mm) fail("CYCLE/: RTRCTO is below RAPTO");
  if (cy.dwell_s < 0) fail("CYCLE/: a negative DWELL");
  cycle_ = cy;
  last_cycle_ = cy;
}

// One hole at `top` along the tool axis: rapid to the R level (LinuxCNC's
// order: up to R first when below it, then across), feed to the bottom in
// pecks (each back to R, down again rapid to 0.254 mm above the last depth),
// dwell, back to the retract level.
void AptReader::hole(const Eigen::Vector3d& top, std::deque<FiveAxisLine>& out) {
  const Cycle& cy = *cycle_;
  const Eigen::Vector3d a = axis_;
  auto at = [&](double h) -> Eigen::Vector3d { return top + h * a; };
  auto rapid_to = [&](const Eigen::Vector3d& p) {
    if ((p - tip_mm_).norm() > 1e-9) add_move(p, a, true, 0, out);
  };
  auto feed_to = [&](const Eigen::Vector3d& p) { add_move(p, a, false, cy.feed_mm_per_min, out); };
  double h = (tip_mm_ - top).dot(a);
  if (h < cy.rapto_mm) {
    rapid_to(tip_mm_ + (cy.rapto_mm - h) * a);
    h = cy.rapto_mm;
  }
  rapid_to(at(h));
  rapid_to(at(cy.rapto_mm));
  if (cy.first_peck_mm > 0) {
    double reached = std::min(cy.depth_mm, cy.first_peck_mm);
    feed_to(at(-reached));
    while (reached < cy.depth_mm - 1e-9) {
      rapid_to(at(cy.rapto_mm));
      const double again = -reached + kPeckClearanceMm;
      if (again < cy.rapto_mm) rapid_to(at(again));
      reached = std::min(cy.depth_mm, reached + cy.peck_mm);
      feed_to(at(-reached));
    }
  } else {
    feed_to(at(-cy.depth_mm));
  }
  if (cy.dwell_s > 0) add_text(fmt::format("G4 P{}", cy.dwell_s), out);
  if (cy.type == "REAM") feed_to(at(cy.rapto_mm));
  rapid_to(at(cy.retract_mm));
}

}  // namespace volmap::post
