// AptReader: the motion records: GOTO and its kin, CIRCLE (arcs), CYCLE
// (holes written out as moves). docs/post-five-axis.md "APT / CLDATA".
#include <fmt/format.h>

#include <algorithm>
#include <cmath>

#include "core/common/input_error.h"
#include "postproc/five_axis/apt_reader.h"

namespace volmap::post {

double AptReader::feed_of(const AptRecord& r, size_t from, bool& per_rev) const {
  for (const std::string& a : r.args)
    if (((a == "IPM" || a == "IPR") && unit_mm_ != 25.4) ||
        ((a == "MMPM" || a == "MMPR") && unit_mm_ != 1.0))
      fail(
          fmt::format("a feed in {} while the lengths are read in {}: the CL file's units "
                      "disagree; add UNITS/{} before its first record",
                      a, unit_mm_ == 1.0 ? "mm" : "inches", unit_mm_ == 1.0 ? "INCHES" : "MM"));
  // FEDRAT/f[,unit] or FEDRAT/unit,f in any order (NX writes the unit
  // first, SOLIDWORKS CAM and Creo after); without a unit, per minute.
  double f = -1;
  per_rev = false;
  for (size_t k = from; k < r.args.size(); ++k) {
    const std::string& a = r.args[k];
    double v = 0;
    if (a == "MMPM" || a == "IPM")
      continue;
    else if (a == "MMPR" || a == "IPR")
      per_rev = true;
    else if (apt_number(a, v) && f < 0)
      f = v;
    else
      fail(fmt::format("FEDRAT/: '{}' is not understood (a feed and MMPM or IPM)", apt_shown(a)));
  }
  return f;
}

void AptReader::motion_record(const AptRecord& r, std::deque<FiveAxisLine>& out) {
  const std::string& k = r.key;
  if (k == "GOTO") {
    if (cycle_ && rapid_next_)
      fail("RAPID before a hole of a CYCLE/: the hole's moves are the cycle's");
    if (circle_goto_) circle_.reset(), circle_goto_ = false;  // the arc's GOTO was the last
    goto_rapid_ = rapid_next_;
    rapid_next_ = false;
    goto_open_ = true;
    goto_point(numbers(r), out);
    return;
  }
  if (k == "RAPID") {
    rapid_next_ = true;
    add_text("(APT: RAPID)", out);
    return;
  }
  if (k == "FEDRAT") {
    bool per_rev = false;
    const double f = feed_of(r, 0, per_rev);
    if (!r.args.empty() && r.args[0] == "INVERS")
      fail("FEDRAT/INVERS (inverse time) is not supported; output feeds per minute");
    if (per_rev) fail("FEDRAT/ per revolution (MMPR, IPR) is not supported; output MMPM or IPM");
    if (!(f > 0)) fail("FEDRAT/ needs a positive feed");
    feed_ = f * unit_mm_;
    add_comment(r, out);
    return;
  }
  if (k == "UNITS" || k == "UNIT") {
    const std::string a = r.args.empty() ? "" : r.args[0];
    if (a == "INCHES" || a == "INCH")
      unit_mm_ = 25.4;
    else if (a == "MM")
      unit_mm_ = 1.0;
    else
      fail(fmt::format("{}/ takes MM or INCHES", k));
    add_comment(r, out);
    return;
  }
  if (k == "MULTAX") {
    // GOTO with i,j,k is read whatever MULTAX says; with three values the
    // tool axis stays as it was (MULTAX/OFF's meaning).
    if (!r.args.empty() && r.args[0] != "ON" && r.args[0] != "OFF") fail("MULTAX takes ON or OFF");
    add_comment(r, out);
    return;
  }
  if (k == "TLAXIS") {
    const std::vector<double> v = numbers(r);
    if (v.size() != 3 || Eigen::Vector3d(v[0], v[1], v[2]).norm() < 1e-9)
      fail("TLAXIS/ takes a tool axis i,j,k");
    axis_ = Eigen::Vector3d(v[0], v[1], v[2]).normalized();
    add_comment(r, out);
    return;
  }
  if (position_record(r, out)) return;
  if (k == "CIRCLE") {
    circle_record(r);
    add_comment(r, out);
    return;
  }
  if (k == "CYCLE") {
    cycle_record(r, out);
    return;
  }
  if (k == "NURBS" || k == "KNOT" || k == "CNTRL")
    fail(
        "NURBS/ spline output is not supported; set the operation's motion output to linear "
        "(NX: Machine Control, Motion Output Type Linear)");
  if (k == "MOVARC" || k == "INDIRV" || k.rfind("TLON", 0) == 0 || k.rfind("GOFWD", 0) == 0)
    fail(
        fmt::format("{}: this form of circular motion is not supported; output arcs as "
                    "CIRCLE/ records or as GOTO points",
                    k));
  fail(
      fmt::format("'{}' is not an APT record volmap knows; it may move the tool, so it is "
                  "refused: remove it if it moves nothing, or output the CL file without it",
                  apt_shown(r.text)));
}

// FROM, GODLTA, GOHOME. True when `r` was one.
bool AptReader::position_record(const AptRecord& r, std::deque<FiveAxisLine>& out) {
  const std::string& k = r.key;
  if (k == "FROM") {
    const std::vector<double> v = numbers(r);
    if (v.size() != 3 && v.size() != 6) fail("FROM/ takes x,y,z or x,y,z,i,j,k");
    const Eigen::Vector3d p = Eigen::Vector3d(v[0], v[1], v[2]) * unit_mm_;
    if (moved_ && (p - tip_mm_).norm() > 1e-6)
      fail("FROM/ after motion, away from where the tool is: a FROM moves nothing");
    tip_mm_ = p;
    if (v.size() == 6) axis_ = Eigen::Vector3d(v[3], v[4], v[5]).normalized();
    add_comment(r, out);
    return true;
  }
  if (k == "GODLTA") {
    const std::vector<double> v = numbers(r);
    Eigen::Vector3d d;
    if (v.size() == 1) {
      if (std::abs(axis_.z() - 1.0) > 1e-9)
        fail(
            "GODLTA/ with one value while the tool axis is not +Z: CAM systems differ on "
            "whether it moves along Z or the tool axis; write GODLTA/dx,dy,dz");
      d = Eigen::Vector3d(0, 0, v[0]);
    } else if (v.size() == 3 || v.size() == 6) {
      d = Eigen::Vector3d(v[0], v[1], v[2]);
    } else {
      fail("GODLTA/ takes dz, dx,dy,dz or dx,dy,dz,i,j,k");
    }
    const bool rapid = rapid_next_;
    rapid_next_ = false;
    Eigen::Vector3d a = axis_;
    if (v.size() == 6) a = Eigen::Vector3d(v[3], v[4], v[5]);
    if (cycle_) fail("GODLTA/ inside a CYCLE/: holes are GOTO points");
    add_move(tip_mm_ + d * unit_mm_, a, rapid, feed_, out);
    return true;
  }
  if (k == "GOHOME") {
    // NX: the return point; NX's posts write it as a rapid move
    // (MOM_gohome_move calls MOM_rapid_move).
    const std::vector<double> v = numbers(r);
    if (v.size() != 3 && v.size() != 6) fail("GOHOME/ takes x,y,z or x,y,z,i,j,k");
    if (cycle_) fail("GOHOME/ inside a CYCLE/; end the cycle with CYCLE/OFF first");
    rapid_next_ = false;
    const Eigen::Vector3d a = v.size() == 6 ? Eigen::Vector3d(v[3], v[4], v[5]) : axis_;
    add_move(Eigen::Vector3d(v[0], v[1], v[2]) * unit_mm_, a, true, feed_, out);
    return true;
  }
  return false;
}

bool AptReader::more_points(const std::string& text, int line, std::deque<FiveAxisLine>& out) {
  if (!goto_open_) return false;
  line_ = line;
  const AptRecord r = parse_apt_record("GOTO/" + text);
  goto_point(numbers(r), out);
  return true;
}

void AptReader::goto_point(const std::vector<double>& v, std::deque<FiveAxisLine>& out) {
  if (v.size() != 3 && v.size() != 6) fail("GOTO/ takes x,y,z or x,y,z,i,j,k");
  Eigen::Vector3d a = axis_;
  if (v.size() == 6) {
    a = Eigen::Vector3d(v[3], v[4], v[5]);
    if (a.norm() < 1e-9) fail("GOTO/: the tool axis i,j,k is zero");
    a.normalize();
  }
  if (csys_axis_) {
    // SOLIDWORKS CAM: the setup's tool axis is CSYS's third column; a GOTO
    // that disagrees means the points are not in the part frame.
    if (csys_axis_->norm() < 1e-9 || (csys_axis_->normalized() - a).norm() > 1e-3)
      fail(
          "the tool axis differs from the third column of the CSYS/ before it: the frame of "
          "the GOTO points is not the one volmap reads (the part frame); output the CL data "
          "without CSYS");
    csys_axis_.reset();
  }
  const Eigen::Vector3d p = Eigen::Vector3d(v[0], v[1], v[2]) * unit_mm_;
  if (cycle_) {
    axis_ = a;
    hole(p, out);
  } else if (circle_) {
    circle_goto_ = true;
    arc_to(p, a, out);
  } else {
    add_move(p, a, goto_rapid_, feed_, out);
  }
}

void AptReader::add_move(const Eigen::Vector3d& end_mm, const Eigen::Vector3d& axis, bool rapid,
                         double feed, std::deque<FiveAxisLine>& out) {
  if (!rapid && !(feed > 0)) fail("a feed move before any FEDRAT/; add FEDRAT/");
  FiveAxisLine l;
  l.line = line_;
  l.synthetic = true;
  l.has_move = true;
  FiveAxisMove& m = l.move;
  m.rapid = rapid;
  m.by_angles = false;
  m.tip.kind = nc::MotionKind::kLinear;
  m.tip.start_mm = tip_mm_;
  m.tip.end_mm = end_mm;
  m.a0 = axis_;
  m.a1 = axis.normalized();
  m.q0 = m.q1 = q_;
  m.feed_mode = nc::kG94UnitsPerMinute;
  m.feed = feed;
  tip_mm_ = end_mm;
  axis_ = m.a1;
  moved_ = true;
  out.push_back(std::move(l));
}

}  // namespace volmap::post
