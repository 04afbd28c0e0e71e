// ISO 230-1 location errors, docs/model.md: volmap's error model against an
// independent reference model written here with explicit 4x4 products.
//
// ISO 230-1 meaning: the location errors of an axis say where its line is
// (a rotary axis's offsets and tilts, a linear axis's squareness); they do
// not displace the frames after it. So with no component errors an axis at
// q = 0 moves nothing, and a rotary axis's zero error is a rotation about its
// actual line. Per joint, parent <- joint (o offset, d direction, q position,
// E(q) the component errors, C(q) = Trans(q d) E(q) or E(q) Rot(d, q)):
//   T = Trans(o) · L · C(q) · P^-1
//   linear:  L = P = [R(a, b, c) | 0]   (Trans(r) R Trans(-r) independent)
//   rotary:  P = [R(a, b, c without the own angle) | t],  L = P · Rot(e_k, z)
// The old "link" convention, T = Trans(o) · L · C(q) with L = [R(a, b, c) | t],
// is the second reference model. The kinematic-parameter-independent
// formulation (Hsu Table II) pivots linear joints' errors at the tool tip of
// the measurement pose r: E' = [R_e | delta_e - (R_e - I) r_c].
//
// The reference uses volmap only for the machine, the loaders and the table
// lookup (evaluate_axis); never the chain code. Checked against it:
//  - ErrorModel::exact, both formulations, both conventions, the sample's own
//    errors and random error sets, every sample machine and a head-table
//    machine built here;
//  - error_gains and GainEvaluator against central differences of the
//    reference, one error at a time;
//  - the two conventions differ where they must (EX0C at the home pose).
#include <gtest/gtest.h>

#include <Eigen/Core>
#include <Eigen/Geometry>
#include <algorithm>
#include <array>
#include <cmath>
#include <cstdio>
#include <random>
#include <sstream>
#include <string>
#include <vector>

#include "core/model/error_model.h"
#include "core/model/error_set.h"
#include "core/model/gain_evaluator.h"
#include "core/model/machine_json.h"
#include "core/model/sensitivity.h"
#include "tests/model/error_model_fixtures.h"
#include "tests/support/samples.h"

namespace volmap {
namespace {

using Eigen::Matrix3d;
using Eigen::Matrix4d;
using Eigen::Vector3d;
using Vector6d = Eigen::Matrix<double, 6, 1>;

// ---- the reference model: explicit 4x4 products -------------------------

Matrix4d frame(const Matrix3d& R, const Vector3d& t) {
  Matrix4d T = Matrix4d::Identity();
  T.topLeftCorner<3, 3>() = R;
  T.topRightCorner<3, 1>() = t;
  return T;
}
Matrix4d trans(const Vector3d& t) { return frame(Matrix3d::Identity(), t); }
Matrix4d rot(const Matrix3d& R) { return frame(R, Vector3d::Zero()); }
Matrix4d rigid_inverse(const Matrix4d& T) {
  const Matrix3d Rt = T.topLeftCorner<3, 3>().transpose();
  return frame(Rt, -Rt * T.topRightCorner<3, 1>());
}
Vector3d point(const Matrix4d& T, const Vector3d& p) {
  return T.topLeftCorner<3, 3>() * p + T.topRightCorner<3, 1>();
}
// Right-handed rotation by q about unit vector d.
Matrix3d rot_about(const Vector3d& d, double q) {
  return Eigen::AngleAxisd(q, d).toRotationMatrix();
}
// R(a, b, c) = Rz(c) Ry(b) Rx(a), exact sines and cosines.
Matrix3d rpy(const Vector3d& abc) {
  return rot_about(Vector3d::UnitZ(), abc[2]) * rot_about(Vector3d::UnitY(), abc[1]) *
         rot_about(Vector3d::UnitX(), abc[0]);
}

// E(q) of axis a: identity when the errors have no table for it.
Matrix4d component(const ErrorSet& e, AxisName a, double q) {
  const AxisErrors* ax = e.errors_of(a);
  if (ax == nullptr) return Matrix4d::Identity();
  std::array<double, kComponentCount> v;
  evaluate_axis(*ax, q, 0, OutsidePolicy::kError, v);
  return frame(rpy(Vector3d(v[3], v[4], v[5])), Vector3d(v[0], v[1], v[2]));
}

// Location errors of axis a: (EX0a, EY0a, EZ0a) mm and (EA0a, EB0a, EC0a) rad.
struct Location {
  Vector3d t_mm, angles_rad;
};
Location location_of(const ErrorSet& e, AxisName a) {
  Location L;
  for (int i = 0; i < 3; ++i) {
    const std::string own = std::string("0") + axis_char(a);
    L.t_mm[i] = e.location_error(std::string("E") + "XYZ"[i] + own);
    L.angles_rad[i] = e.location_error(std::string("E") + "ABC"[i] + own);
  }
  return L;
}

Matrix4d motion(const Joint& j, double q) {
  return j.rotary ? rot(rot_about(j.direction_parent, q)) : trans(q * j.direction_parent);
}

// Nominal frame F of joint k (after Trans(o), before its motion) at u;
// k = chain.size(): the chain's end.
Matrix4d nominal_frame(const std::vector<Joint>& chain, size_t k, const AxisVector& u) {
  Matrix4d T = Matrix4d::Identity();
  for (size_t i = 0; i < k; ++i)
    T = T * trans(chain[i].offset_parent_mm) * motion(chain[i], u[chain[i].index]);
  return k < chain.size() ? Matrix4d(T * trans(chain[k].offset_parent_mm)) : T;
}

// Independent formulation: the nominal tool tip (of the measurement's tool)
// at the measurement pose, joint k's own axis at 0, in joint k's frame F.
Vector3d measurement_tip(const Machine& m, const std::vector<Joint>& chain, size_t k) {
  AxisVector pose = m.measured_at[static_cast<size_t>(chain[k].index)];
  pose[chain[k].index] = 0.0;
  const double tool =
      std::isnan(m.measurement_tool_length_mm) ? m.tool_length_mm : m.measurement_tool_length_mm;
  const Matrix4d T_b_s =
      nominal_frame(m.tool_chain, m.tool_chain.size(), pose) * trans(m.spindle_offset_mm);
  return point(rigid_inverse(nominal_frame(chain, k, pose)), point(T_b_s, -tool * m.tool_axis));
}

struct Reference {
  // Tool tip and axis in workpiece coordinates.
  static ToolPose pose(const Machine& m, const ErrorSet& e, Formulation f, LocationConvention c,
                       const AxisVector& u) {
    auto product = [&](const std::vector<Joint>& chain, bool workpiece) {
      Matrix4d T = Matrix4d::Identity();
      for (size_t k = 0; k < chain.size(); ++k) T = T * joint(m, e, f, c, chain, k, workpiece, u);
      return T;
    };
    const Matrix4d T_w_s =
        rigid_inverse(product(m.workpiece_chain, true)) * product(m.tool_chain, false);
    const Vector3d tip_s = m.spindle_offset_mm - m.tool_length_mm * m.tool_axis;
    return ToolPose{point(T_w_s, tip_s) - m.workpiece_origin_mm,
                    T_w_s.topLeftCorner<3, 3>() * m.tool_axis};
  }

  // Parent <- joint k of the chain.
  static Matrix4d joint(const Machine& m, const ErrorSet& e, Formulation f, LocationConvention c,
                        const std::vector<Joint>& chain, size_t k, bool workpiece,
                        const AxisVector& u) {
    const Joint& j = chain[k];
    const double q = u[j.index];
    const Location loc = location_of(e, j.axis);
    const Matrix4d O = trans(j.offset_parent_mm);
    Matrix4d E = component(e, j.axis, q);
    if (j.rotary) {
      const Matrix4d C = E * rot(rot_about(j.direction_parent, q));
      if (c == LocationConvention::kLink) return O * frame(rpy(loc.angles_rad), loc.t_mm) * C;
      const int own = static_cast<int>(j.axis) - static_cast<int>(AxisName::A);
      Vector3d tilts = loc.angles_rad;
      tilts[own] = 0.0;
      const Matrix4d P = frame(rpy(tilts), loc.t_mm);
      const Matrix4d L = P * rot(rot_about(Vector3d::Unit(own), loc.angles_rad[own]));
      return O * L * C * rigid_inverse(P);
    }
    Matrix4d P = rot(rpy(loc.angles_rad));
    if (f == Formulation::kIndependent) {
      const Vector3d r = measurement_tip(m, chain, k);
      const Vector3d r_c = workpiece ? Vector3d(r - q * j.direction_parent) : r;
      // [R_e | delta_e - (R_e - I) r_c]
      E = trans(E.topRightCorner<3, 1>()) * trans(r_c) * rot(E.topLeftCorner<3, 3>()) * trans(-r_c);
      P = trans(r) * P * trans(-r);
    }
    const Matrix4d C = trans(q * j.direction_parent) * E;
    if (c == LocationConvention::kLink) return O * trans(loc.t_mm) * P * C;
    return O * P * C * rigid_inverse(P);
  }
};

PoseError reference_error(const Machine& m, const ErrorSet& e, Formulation f, LocationConvention c,
                          const AxisVector& u) {
  const ToolPose actual = Reference::pose(m, e, f, c, u);
  const ToolPose nominal = Reference::pose(m, ErrorSet{}, f, c, u);
  return PoseError{actual.tip_mm - nominal.tip_mm, actual.axis - nominal.axis};
}

// ---- machines and helpers --------------------------------------------------

// C table on the workpiece chain; X Y Z then a B head on the tool chain.
// Offsets put neither rotary line through the origin.
const char* const kHeadTableJson = R"({
  "format": "volmap-machine/1",
  "name": "head-table-cb",
  "structure": "[w C' b X Y Z B t]",
  "axes": {
    "X": {"type": "linear", "direction": [1, 0, 0], "travel_mm": [-400, 400]},
    "Y": {"type": "linear", "direction": [0, 1, 0], "travel_mm": [-300, 300]},
    "Z": {"type": "linear", "direction": [0, 0, 1], "travel_mm": [-350, 150]},
    "B": {"type": "rotary", "direction": [0, 1, 0], "travel_deg": [-95, 95]},
    "C": {"type": "rotary", "direction": [0, 0, 1], "travel_deg": null}
  },
  "workpiece_chain": [{"axis": "C", "offset_mm": [35, -20, 120]}],
  "workpiece_origin_mm": [15, 10, 45],
  "tool_chain": [
    {"axis": "X", "offset_mm": [0, 0, 0]},
    {"axis": "Y", "offset_mm": [0, 0, 0]},
    {"axis": "Z", "offset_mm": [0, 0, 650]},
    {"axis": "B", "offset_mm": [0, 12, -140]}
  ],
  "spindle_offset_mm": [0, 0, -160],
  "tool": {"length_mm": 110, "axis": [0, 0, 1]},
  "measured_at": {"X": {"Y": 120, "Z": -80, "B": 15}, "Y": {"X": -200, "C": 30},
                  "Z": {"X": 50, "Y": -40}}
})";
const char* const kHeadTable = "head-table-cb";

Machine machine_named(const std::string& name) {
  if (name != kHeadTable) return test::sample_machine(name);
  std::istringstream in(kHeadTableJson);
  Machine m = read_machine_json(in, "head-table-cb.json");
  m.measurement_tool_length_mm = 150.0;  // the laser saw a longer tool
  return m;
}

const char* formulation_name(Formulation f) {
  return f == Formulation::kDependent ? "dependent" : "independent";
}
const char* convention_name(LocationConvention c) {
  return c == LocationConvention::kLink ? "link" : "iso";
}
std::string pose_text(const AxisVector& u) {
  std::ostringstream s;
  s << u.transpose();
  return s.str();
}

constexpr Formulation kFormulations[] = {Formulation::kDependent, Formulation::kIndependent};
constexpr LocationConvention kConventions[] = {LocationConvention::kIso230,
                                               LocationConvention::kLink};

// Largest relative difference seen, and how many comparisons.
struct Worst {
  int count = 0;
  double rel = 0.0;
  void add(double r) {
    ++count;
    rel = std::max(rel, r);
  }
};

// ErrorModel::exact against the reference at 60 random poses, in the
// errors' own convention. Tolerance 1e-6 of max(|dP|, 1 um), max(|dQ|, 1 urad).
void compare_exact(const Machine& m, const ErrorSet& e, Formulation f, const std::string& what,
                   std::mt19937& rng, Worst& worst_P, Worst& worst_Q) {
  const ErrorModel model(m, e, ModelOptions{f, OutsidePolicy::kError});
  for (int t = 0; t < 60; ++t) {
    const AxisVector u = test::random_pose(m, rng);
    const PoseError v = model.exact(u);
    const PoseError r = reference_error(m, e, f, e.convention, u);
    const double rel_P = (v.dP_mm - r.dP_mm).norm() / std::max(r.dP_mm.norm(), 1e-3);
    const double rel_Q = (v.dQ - r.dQ).norm() / std::max(r.dQ.norm(), 1e-6);
    worst_P.add(rel_P);
    worst_Q.add(rel_Q);
    EXPECT_LE(rel_P, 1e-6) << what << " " << formulation_name(f) << " u = " << pose_text(u)
                           << "\n  volmap dP " << v.dP_mm.transpose() << "\n  ref    dP "
                           << r.dP_mm.transpose();
    EXPECT_LE(rel_Q, 1e-6) << what << " " << formulation_name(f) << " u = " << pose_text(u)
                           << "\n  volmap dQ " << v.dQ.transpose() << "\n  ref    dQ "
                           << r.dQ.transpose();
  }
}

// An error set with one error of the given value: a location error, or a
// component error constant over any position (two equal knots far apart: a
// one-knot table is constant only at its knot under OutsidePolicy::kError).
ErrorSet one_error(const std::string& name, double value, LocationConvention c) {
  ErrorSet e;
  e.file = "<one error>";
  e.convention = c;
  const ErrorName n = *parse_error_name(name);
  if (n.location) {
    e.location[name] = value;
    return e;
  }
  AxisErrors ax;
  ax.axis = n.axis;
  ax.plus.axis = n.axis;
  ax.plus.source = "<one error>";
  ax.plus.position = {-1e6, 1e6};
  ax.plus.value.assign(2, std::array<double, kComponentCount>{});
  ax.plus.slope.assign(2, std::array<double, kComponentCount>{});
  for (auto& v : ax.plus.value) v[static_cast<size_t>(n.component)] = value;
  ax.present[static_cast<size_t>(n.component)] = true;
  e.axis[static_cast<size_t>(n.axis)] = ax;
  return e;
}

// (dP, dQ) per unit of the error: central differences of the reference,
// Richardson-extrapolated, (4 D(h/2) - D(h)) / 3 with D(h) = (f(h) - f(-h)) /
// 2h: truncation O(h^4) (1e-12 of a gain at h = 1e-3), rounding (1e-13 mm of
// a 1 m pose) amplified by 1.5/h only, 1e-10. A plain central difference at
// h = 1e-7 would leave 1e-6 of rounding in a mm/mm gain.
Vector6d reference_gain(const Machine& m, Formulation f, LocationConvention c,
                        const std::string& name, const AxisVector& u) {
  auto central = [&](double h) {
    const ToolPose plus = Reference::pose(m, one_error(name, h, c), f, c, u);
    const ToolPose minus = Reference::pose(m, one_error(name, -h, c), f, c, u);
    Vector6d g;
    g << (plus.tip_mm - minus.tip_mm) / (2 * h), (plus.axis - minus.axis) / (2 * h);
    return g;
  };
  const double h = 1e-3;
  return (4 * central(h / 2) - central(h)) / 3;
}

Vector6d stacked(const Vector3d& dP, const Vector3d& dQ) {
  Vector6d g;
  g << dP, dQ;
  return g;
}

// ---- tests ------------------------------------------------------------------

class IsoLocation : public ::testing::TestWithParam<std::string> {};

TEST_P(IsoLocation, ExactPoseErrorMatchesReference) {
  const std::string name = GetParam();
  const Machine m = machine_named(name);
  std::vector<std::pair<std::string, ErrorSet>> sets;
  if (name != kHeadTable) sets.emplace_back("sample errors", test::sample_errors(name));
  std::mt19937 rng(2301);
  for (double scale : {1.0, 20.0}) {
    for (LocationConvention c : kConventions) {
      ErrorSet e = test::random_errors(m, scale, rng);
      e.convention = c;
      sets.emplace_back(
          "random x" + std::to_string(static_cast<int>(scale)) + " " + convention_name(c), e);
    }
  }
  Worst worst_P, worst_Q;
  for (const auto& [what, e] : sets) {
    // random_errors gives every location error of the model.
    if (what != "sample errors")
      for (const std::string& n : model_error_names(m))
        if (parse_error_name(n)->location) {
          EXPECT_EQ(e.location.count(n), 1u) << n;
        }
    for (Formulation f : kFormulations) compare_exact(m, e, f, what, rng, worst_P, worst_Q);
  }
  std::printf("[ %s ] exact: %d poses, worst relative difference dP %.3g, dQ %.3g\n", name.c_str(),
              worst_P.count, worst_P.rel, worst_Q.rel);
}

TEST_P(IsoLocation, GainsMatchCentralDifferencesOfReference) {
  const std::string name = GetParam();
  const Machine m = machine_named(name);
  const std::vector<std::string> names = model_error_names(m);
  std::mt19937 rng(2302);
  Worst worst_gains, worst_evaluator;
  for (LocationConvention c : kConventions) {
    for (Formulation f : kFormulations) {
      GainEvaluator evaluator(m, f, c);
      ASSERT_EQ(evaluator.names(), names);
      for (int t = 0; t < 20; ++t) {
        const AxisVector u = test::random_pose(m, rng);
        const std::vector<ErrorGain> gains = error_gains(m, f, u, c);
        ASSERT_EQ(gains.size(), names.size());
        evaluator.at(u);
        for (size_t k = 0; k < names.size(); ++k) {
          const Vector6d ref = reference_gain(m, f, c, names[k], u);
          // Tolerance 1e-6 |g|, at least 1e-9 (mm/mm, mm/rad, rad/rad).
          const double scale = std::max(ref.norm(), 1e-3);
          const double rel_g = (stacked(gains[k].dP, gains[k].dQ) - ref).norm() / scale;
          const int i = static_cast<int>(k);
          const double rel_e = (stacked(evaluator.dP(i), evaluator.dQ(i)) - ref).norm() / scale;
          worst_gains.add(rel_g);
          worst_evaluator.add(rel_e);
          const std::string what = names[k] + " " + convention_name(c) + " " + formulation_name(f) +
                                   " u = " + pose_text(u);
          EXPECT_EQ(gains[k].name, names[k]);
          EXPECT_LE(rel_g, 1e-6) << "error_gains " << what << "\n  volmap "
                                 << stacked(gains[k].dP, gains[k].dQ).transpose() << "\n  ref    "
                                 << ref.transpose();
          EXPECT_LE(rel_e, 1e-6) << "GainEvaluator " << what << "\n  volmap "
                                 << stacked(evaluator.dP(i), evaluator.dQ(i)).transpose()
                                 << "\n  ref    " << ref.transpose();
        }
      }
    }
  }
  std::printf(
      "[ %s ] gains: %d comparisons each, worst relative difference error_gains %.3g, "
      "GainEvaluator %.3g\n",
      name.c_str(), worst_gains.count, worst_gains.rel, worst_evaluator.rel);
}

INSTANTIATE_TEST_SUITE_P(Machines, IsoLocation,
                         ::testing::Values("lei-hsu-xyzac", "xyzab-tdr", "bc-table-table",
                                           "bridgemill-bc-head", kHeadTable, "hsu-3axis",
                                           "gantry-3axis"),
                         [](const ::testing::TestParamInfo<std::string>& info) {
                           std::string s = info.param;
                           std::replace(s.begin(), s.end(), '-', '_');
                           return s;
                         });

// The old meaning: EX0C a constant shift of the C link, 28 um at every pose.
// ISO 230-1: the offset of the line C turns about. At C = 0 nothing has
// turned, so nothing moves; at C = 90 deg the table has turned about a line
// 28 um off the nominal one and sits sqrt(2) * 28 um away.
TEST(IsoLocationConvention, LinkDiffersFromIsoAtHome) {
  const Machine m = test::lei_hsu();
  const AxisVector home = AxisVector::Zero(m.axis_count());
  for (Formulation f : kFormulations) {
    SCOPED_TRACE(formulation_name(f));
    const ErrorSet iso = one_error("EX0C", 0.028, LocationConvention::kIso230);
    const ErrorSet link = one_error("EX0C", 0.028, LocationConvention::kLink);
    ASSERT_EQ(iso.convention, LocationConvention::kIso230);

    const PoseError ref_iso = reference_error(m, iso, f, LocationConvention::kIso230, home);
    const PoseError ref_link = reference_error(m, link, f, LocationConvention::kLink, home);
    EXPECT_LT(ref_iso.dP_mm.norm(), 1e-9);
    EXPECT_NEAR(ref_link.dP_mm.norm(), 0.028, 1e-12);
    EXPECT_NEAR(ref_link.dP_mm.x(), -0.028, 1e-12);  // the workpiece moved +x

    const PoseError v_iso = ErrorModel(m, iso, ModelOptions{f, OutsidePolicy::kError}).exact(home);
    const PoseError v_link =
        ErrorModel(m, link, ModelOptions{f, OutsidePolicy::kError}).exact(home);
    EXPECT_LT(v_iso.dP_mm.norm(), 1e-9) << v_iso.dP_mm.transpose();
    EXPECT_LT(v_iso.dQ.norm(), 1e-12);
    EXPECT_NEAR(v_link.dP_mm.norm(), 0.028, 1e-12) << v_link.dP_mm.transpose();
    EXPECT_LE((v_link.dP_mm - ref_link.dP_mm).norm(), 1e-12);

    // C turned: the offset line moves the tip.
    AxisVector u = home;
    u[*m.index_of(AxisName::C)] = M_PI / 2;
    const PoseError ref_turned = reference_error(m, iso, f, LocationConvention::kIso230, u);
    const PoseError v_turned = ErrorModel(m, iso, ModelOptions{f, OutsidePolicy::kError}).exact(u);
    EXPECT_NEAR(ref_turned.dP_mm.norm(), std::sqrt(2.0) * 0.028, 1e-12);
    EXPECT_LE((v_turned.dP_mm - ref_turned.dP_mm).norm(), 1e-6 * ref_turned.dP_mm.norm());
  }
}

}  // namespace
}  // namespace volmap
