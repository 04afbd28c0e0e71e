// Location errors between ISO 230-1 and link meaning (contract:
// core/model/location_convention.h; derivation: docs/model.md, "Location
// errors").
#include "core/model/location_convention.h"

#include <fmt/format.h>

#include <algorithm>
#include <cmath>
#include <optional>
#include <stdexcept>
#include <vector>

#include "core/common/units.h"

namespace volmap {
namespace {

using Iso = Eigen::Isometry3d;

// The largest location errors convert takes: 10 mm, 10 mrad.
constexpr double kLargestShiftMm = 10.0;
constexpr double kLargestAngleRad = 1e-2;

Iso make(const Eigen::Matrix3d& R, const Eigen::Vector3d& t) {
  Iso T = Iso::Identity();
  T.linear() = R;
  T.translation() = t;
  return T;
}

Eigen::Vector3d vee_skew(const Eigen::Matrix3d& D) {
  return 0.5 * Eigen::Vector3d(D(2, 1) - D(1, 2), D(0, 2) - D(2, 0), D(1, 0) - D(0, 1));
}

/// R(x) = Rz(x2) Ry(x1) Rx(x0); with own >= 0, R(x, own angle 0) * Rot(w, x_own).
Eigen::Matrix3d form_rotation(const Eigen::Vector3d& x, int own, const Eigen::Vector3d& w) {
  if (own < 0) return small_rotation_exact(x);
  Eigen::Vector3d line = x;
  line[own] = 0.0;
  return small_rotation_exact(line) * axis_rotation(w, x[own]);
}

/// The angles x with form_rotation(x, own, w) = R, for a rotation near the
/// identity: fixed-point steps on the body-frame residual, each shrinking it
/// by a factor of the angles' size. Throws std::invalid_argument when the
/// rotation is no small error (the steps do not converge).
Eigen::Vector3d decompose(const Eigen::Matrix3d& R, int own, const Eigen::Vector3d& w) {
  Eigen::Vector3d x = vee_skew(R);
  for (int it = 0; it < 50; ++it) {
    const Eigen::Vector3d r = vee_skew(form_rotation(x, own, w).transpose() * R);
    x += r;
    if (r.norm() < 1e-18) return x;
  }
  if (x.allFinite() && (form_rotation(x, own, w) - R).norm() < 1e-15) return x;
  throw std::invalid_argument(fmt::format(
      "location errors of {:.3g} rad do not convert: the conversion is for small errors (a few "
      "mrad at most); check the file's units (µm and µrad)",
      vee_skew(R).norm()));
}

/// One joint's location errors: translation (mm) and angles (rad).
struct Values {
  Eigen::Vector3d t = Eigen::Vector3d::Zero();
  Eigen::Vector3d x = Eigen::Vector3d::Zero();
};

struct JointShape {
  const Joint* joint = nullptr;
  int own = 0;                                      ///< index of the axis letter's direction
  Eigen::Vector3d pivot = Eigen::Vector3d::Zero();  ///< linear squareness pivot
};

/// The location transform L of a joint (ErrorModel's construction).
Iso location_of(const JointShape& s, const Values& v, LocationConvention c) {
  if (s.joint->rotary) {
    const bool iso = c == LocationConvention::kIso230;
    return make(form_rotation(v.x, iso ? s.own : -1, Eigen::Vector3d::Unit(s.own)), v.t);
  }
  const Eigen::Matrix3d R = small_rotation_exact(v.x);
  return make(R, -(R - Eigen::Matrix3d::Identity()) * s.pivot);
}

/// ISO 230-1's placement P of a joint (L without a rotary axis's zero error).
Iso placement_of(const JointShape& s, const Values& v) {
  if (!s.joint->rotary) return location_of(s, v, LocationConvention::kIso230);
  Eigen::Vector3d line = v.x;
  line[s.own] = 0.0;
  return make(small_rotation_exact(line), v.t);
}

/// Splits G = L N: L in convention c, N a transform that commutes with the
/// joint's motion (a shift along a rotary line; a shift and a turn about
/// its own line for a linear axis).
Values split(const JointShape& s, const Iso& G, LocationConvention c, Iso& N) {
  Values v;
  const Eigen::Vector3d& d = s.joint->direction_parent;
  if (s.joint->rotary) {
    const bool iso = c == LocationConvention::kIso230;
    v.x = decompose(G.linear(), iso ? s.own : -1, Eigen::Vector3d::Unit(s.own));
    const Eigen::Matrix3d R_L = location_of(s, v, c).linear();
    const Eigen::Vector3d Rd = R_L * d;
    const double shift = G.translation()[s.own] / Rd[s.own];
    v.t = G.translation() - shift * Rd;
    v.t[s.own] = 0.0;
    N = make(Eigen::Matrix3d::Identity(), shift * d);
    return v;
  }
  // The turn about the axis's own line (about +e_own, whatever the sign of
  // d: it commutes with Trans(q d) either way) goes to N.
  const Eigen::Vector3d e_own = Eigen::Vector3d::Unit(s.own);
  v.x = decompose(G.linear(), s.own, e_own);
  const double roll = v.x[s.own];
  v.x[s.own] = 0.0;
  const Iso L = location_of(s, v, c);
  N = make(axis_rotation(e_own, roll),
           L.linear().transpose() * (G.translation() - L.translation()));
  return v;
}

Values values_of(const ErrorSet& e, AxisName a) {
  Values v;
  for (int c = 0; c < kComponentCount; ++c) {
    const double value = e.location_error(error_name_string({static_cast<Component>(c), a, true}));
    (c < 3 ? v.t : v.x)[c % 3] = value;
  }
  return v;
}

void store(ErrorSet& e, AxisName a, const Values& v) {
  for (int c = 0; c < kComponentCount; ++c) {
    const ErrorName n{static_cast<Component>(c), a, true};
    const std::string name = error_name_string(n);
    e.location.erase(name);
    if (location_error_problem(n)) continue;
    const double value = c < 3 ? v.t[c] : v.x[c - 3];
    // Written with 1e-6 um / urad: what rounds to zero there is left out.
    if (std::abs(value) >= 5e-13) e.location[name] = value;
  }
}

/// Walks one chain; returns its set-up part K (link = ISO K).
Iso convert_chain(const std::vector<Joint>& chain, const ErrorModel& model, const ErrorSet& in,
                  LocationConvention target, ErrorSet& out) {
  Iso K = Iso::Identity();
  const bool to_iso = target == LocationConvention::kIso230;
  for (const Joint& j : chain) {
    const JointShape s{&j, static_cast<int>(j.axis) % 3, model.location_pivot_mm(j.axis)};
    const Values given = values_of(in, j.axis);
    const Iso A = make(Eigen::Matrix3d::Identity(), j.offset_parent_mm);
    const Iso G =
        A.inverse() * (to_iso ? K : K.inverse()) * A * location_of(s, given, in.convention);
    Iso N;
    const Values converted = split(s, G, target, N);
    store(out, j.axis, converted);
    // split gives G = L N: the joint holds L = G N^-1, so
    // K = P N (to ISO 230-1, P the new placement) or P N^-1 (to link, P the
    // given ISO placement); derivation in docs/model.md.
    K = to_iso ? placement_of(s, converted) * N : placement_of(s, given) * N.inverse();
  }
  return K;
}

/// The largest difference between the link model and the ISO model with
/// the set-up parts, over a grid of poses (three per axis).
void check(const Machine& m, const ErrorSet& link, const ErrorSet& iso, Formulation f,
           ConventionConversion& r) {
  Machine shifted = m;
  shifted.spindle_offset_mm = r.tool_setup * m.spindle_offset_mm;
  shifted.tool_axis = r.tool_setup.linear() * m.tool_axis;
  const ModelOptions opt{f, OutsidePolicy::kClamp};
  const ErrorModel link_model(m, link, opt), iso_model(shifted, iso, opt);
  const Iso W = r.workpiece_setup.inverse();
  const int n = m.axis_count();
  int poses = 1;
  for (int i = 0; i < n; ++i) poses *= 3;
  AxisVector u(n);
  for (int p = 0; p < poses; ++p) {
    for (int i = 0, rest = p; i < n; ++i, rest /= 3) {
      const AxisLimits& L = m.limits[static_cast<size_t>(i)];
      const double lo = L.unlimited ? 0.0 : L.min, hi = L.unlimited ? 4 * M_PI / 3 : L.max;
      u[i] = lo + (hi - lo) * (rest % 3) / 2.0;
    }
    const ToolPose a = link_model.actual(u);
    const ToolPose b = iso_model.actual(u);
    const Eigen::Vector3d tip = W * (b.tip_mm + m.workpiece_origin_mm) - m.workpiece_origin_mm;
    r.check_tip_mm = std::max(r.check_tip_mm, (tip - a.tip_mm).norm());
    r.check_axis_rad = std::max(r.check_axis_rad, (W.linear() * b.axis - a.axis).norm());
  }
  r.check_poses = poses;
}

}  // namespace

ConventionConversion convert_location_convention(const Machine& m, const ErrorSet& errors,
                                                 LocationConvention target,
                                                 Formulation formulation) {
  ConventionConversion r;
  r.errors = errors;
  r.errors.convention = target;
  if (errors.convention == target) return r;
  // Small errors only: the decomposition and the set-up part assume them.
  for (const auto& [name, value] : errors.location) {
    const std::optional<ErrorName> n = parse_error_name(name);
    const bool angular = n && is_angular(n->component);
    if (std::abs(value) > (angular ? kLargestAngleRad : kLargestShiftMm))
      throw std::invalid_argument(fmt::format(
          "{}: {} = {:g} {} is no small location error; the conversion takes at most {:g} {}: "
          "check the file's units (µm, µrad)",
          errors.file, name, value * (angular ? units::kUradPerRad : units::kUmPerMm),
          angular ? "µrad" : "µm",
          (angular ? kLargestAngleRad * units::kUradPerRad : kLargestShiftMm * units::kUmPerMm),
          angular ? "µrad" : "µm"));
  }
  // Binds the errors (refuses an axis the machine lacks) and gives the pivots.
  const ErrorModel model(m, errors, ModelOptions{formulation, OutsidePolicy::kClamp});
  r.workpiece_setup = convert_chain(m.workpiece_chain, model, errors, target, r.errors);
  r.tool_setup = convert_chain(m.tool_chain, model, errors, target, r.errors);
  const bool to_iso = target == LocationConvention::kIso230;
  check(m, to_iso ? errors : r.errors, to_iso ? r.errors : errors, formulation, r);
  return r;
}

void small_transform_parts(const Eigen::Isometry3d& T, Eigen::Vector3d& t_um,
                           Eigen::Vector3d& angles_urad) {
  t_um = T.translation() * units::kUmPerMm;
  angles_urad = decompose(T.linear(), -1, Eigen::Vector3d::UnitZ()) * units::kUradPerRad;
}

}  // namespace volmap
