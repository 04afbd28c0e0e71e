// Five-axis tables (X'Y'ZA'C' of Lei & Hsu 2003): the table against
// independent derivations — the direct model at the nodes, the defining
// equation of the correction (Lei & Hsu eq. 4) and its first-order form
// (eq. 6, with J_v_u solved by SVD here, not by CorrectionSolver's block
// solve), interpolation within the tolerance at points of another random
// generator, the file round trip, the csv columns of shared/spec/cli.md and
// the controllers' refusals.
#include <gtest/gtest.h>

#include <Eigen/SVD>
#include <algorithm>
#include <cmath>
#include <cstring>
#include <nlohmann/json.hpp>
#include <random>
#include <sstream>
#include <string>
#include <vector>

#include "core/common/input_error.h"
#include "core/kinematics/jacobian.h"
#include "core/model/errors_csv.h"
#include "core/model/machine_json.h"
#include "maps/exports/exporters.h"
#include "maps/tables/node_uncertainty.h"
#include "maps/tables/table_builder.h"
#include "maps/tables/table_file.h"
#include "tests/support/test_paths.h"

namespace volmap::maps {
namespace {

constexpr double kDeg = M_PI / 180.0;

const ErrorModel& xyzac() {
  static const ErrorModel model(
      load_machine_json(test::source_path("samples/machines/lei-hsu-xyzac.json")),
      load_errors_csv(test::source_path("samples/errors/lei-hsu-xyzac.csv")));
  return model;
}

// A small grid: 150 mm, 125 mm, 125 mm, A 26 deg (-100 .. 30: 0 is not a
// node), C 45 deg.
const VolumetricTable& small_table() {
  static const VolumetricTable t = build_table(xyzac(), {150, 125, 125, 26 * kDeg, 45 * kDeg});
  return t;
}

// u + du within the travel of every limited axis (the errors beyond it are
// the table's business, not eq. 4's).
bool inside(const AxisVector& u, const AxisVector& du) {
  const Machine& m = xyzac().machine();
  for (int a = 0; a < m.axis_count(); ++a) {
    const AxisLimits& L = m.limits[static_cast<size_t>(a)];
    if (!L.unlimited && (u[a] + du[a] < L.min || u[a] + du[a] > L.max)) return false;
  }
  return true;
}

int channel(const VolumetricTable& t, const char* name) {
  const std::optional<int> c = t.channel(name);
  EXPECT_TRUE(c.has_value()) << name;
  return c.value_or(0);
}

TEST(MapFiveAxis, ChannelsAreDvAndTheCorrectionOfEveryAxis) {
  const VolumetricTable& t = small_table();
  EXPECT_EQ(t.channels, (std::vector<std::string>{"ex", "ey", "ez", "ei", "ej", "ek", "ux", "uy",
                                                  "uz", "ua", "uc"}));
  EXPECT_TRUE(t.pose_correction());
  EXPECT_FALSE(t.three_axis_correction());
  ASSERT_EQ(t.axis_count(), 5);
  EXPECT_EQ(t.grid[3].count, 6);  // -100 -74 -48 -22 4 30
  EXPECT_TRUE(t.grid[4].periodic);
  EXPECT_EQ(t.grid[4].count, 9);
}

TEST(MapFiveAxis, NodesEqualTheDirectModel) {
  const VolumetricTable& t = small_table();
  for (int layer = 0; layer < t.layer_count(); ++layer)
    for (std::int64_t n = 0; n < t.node_count(); n += 7) {
      const AxisVector u = t.node_position(n);
      const PoseError e = xyzac().exact(u, t.layer_directions(layer));
      const double* v = t.at(layer, n);
      for (int i = 0; i < 3; ++i) {
        EXPECT_EQ(v[i], e.dP_mm[i]);
        EXPECT_EQ(v[3 + i], e.dQ[i]);
      }
    }
}

// Eq. 4: the actual machine at u + du puts the tool where the nominal one
// puts it at u (position and tool axis), away from the singular position.
TEST(MapFiveAxis, CorrectionSolvesLeiHsuEq4AtTheNodes) {
  const VolumetricTable& t = small_table();
  const int u0 = channel(t, "ux");
  int checked = 0;
  for (std::int64_t n = 0; n < t.node_count(); n += 3) {
    const AxisVector u = t.node_position(n);
    AxisVector du(5);
    for (int a = 0; a < 5; ++a) du[a] = t.at(0, n)[u0 + a];
    if (!inside(u, du)) continue;
    const ToolPose actual = xyzac().actual(u + du);
    const ToolPose nominal = nominal_forward(xyzac().machine(), u);
    EXPECT_LT((actual.tip_mm - nominal.tip_mm).norm(), 1e-9) << n;
    EXPECT_LT((actual.axis - nominal.axis).norm(), 1e-11) << n;
    ++checked;
  }
  EXPECT_GT(checked, 200);
}

// Eq. 6 (first order, dv = actual - nominal): du1 = -J^+ dv with the 6 x 5
// Jacobian solved by SVD (least squares, exact for a consistent dv). The
// iterated table value differs from it by second-order terms only: the
// change of J over du (rotary du times a lever of up to ~1000 mm) and of
// the errors over du (rotary du times their rate of change).
TEST(MapFiveAxis, CorrectionAgreesWithEq6ToFirstOrder) {
  const VolumetricTable& t = small_table();
  const int u0 = channel(t, "ux");
  for (std::int64_t n = 0; n < t.node_count(); n += 11) {
    const AxisVector u = t.node_position(n);
    const PoseJacobian J = nominal_jacobian(xyzac().machine(), u);
    const PoseError e = xyzac().exact(u);
    Eigen::Matrix<double, 6, 1> dv;
    dv << e.dP_mm, e.dQ;
    const Eigen::MatrixXd Jd = J;
    const Eigen::VectorXd du1 = Jd.jacobiSvd(Eigen::ComputeThinU | Eigen::ComputeThinV).solve(-dv);
    const double rot2 = du1[3] * du1[3] + du1[4] * du1[4];
    for (int a = 0; a < 5; ++a) {
      const double value = t.at(0, n)[u0 + a];
      // The errors' change over the rotary step: ISO 230-1 location errors
      // of the rotary axes act as (I - R(q)) delta and (eps - R(q) eps) x r,
      // changing per rad by up to |delta| + |eps| |r| (below 0.2 mm/rad on
      // the sample) and, in the tool axis, by |eps| (below 1e-3 rad/rad).
      const double rot = std::sqrt(rot2);
      const double tol =
          a < 3 ? 1e-7 + 1e3 * rot2 + 0.2 * rot : 1e-9 + 10 * rot2 + 1e-3 * rot;  // mm, rad
      EXPECT_NEAR(value, du1[a], tol + 2e-3 * std::abs(du1[a])) << "node " << n << " axis " << a;
    }
  }
}

// Lei & Hsu section 4.1: at A = 0 the tool axis lies along C, whose
// correction is suppressed (0); the linear axes still put the tip exactly.
TEST(MapFiveAxis, SingularPositionAEqualsZeroSuppressesC) {
  BuildSummary s;
  const VolumetricTable t = build_table(xyzac(), {300, 250, 250, 10 * kDeg, 90 * kDeg}, {}, &s);
  const int uc = channel(t, "uc"), u0 = channel(t, "ux");
  std::int64_t at_zero = 0;
  for (std::int64_t n = 0; n < t.node_count(); ++n) {
    const AxisVector u = t.node_position(n);
    if (std::abs(u[3]) > 1e-12) continue;
    ++at_zero;
    EXPECT_EQ(t.at(0, n)[uc], 0.0);
    AxisVector du(5);
    for (int a = 0; a < 5; ++a) du[a] = t.at(0, n)[u0 + a];
    if (!inside(u, du)) continue;
    const ToolPose actual = xyzac().actual(u + du);
    EXPECT_LT((actual.tip_mm - nominal_forward(xyzac().machine(), u).tip_mm).norm(), 1e-9);
  }
  EXPECT_GT(at_zero, 0);
  EXPECT_EQ(s.correction_singular, at_zero * t.layer_count());
}

TEST(MapFiveAxis, AutomaticSpacingHoldsBetweenNodes) {
  CheckOptions check;
  check.random_points = 4000;
  const double tol_um = 2.0, tol_urad = 2.0;
  const AutoSpacingResult r =
      build_for_tolerance(xyzac(), tol_um, check, {}, kMaxTableBytes, tol_urad);
  EXPECT_LE(r.check.max_dv_um, tol_um);
  EXPECT_LE(r.check.max_dq_urad, tol_urad);
  EXPECT_GT(r.spacing_rad, 0.0);
  // Independent points (another generator) anywhere in the travel.
  std::mt19937_64 rng(77);
  const VolumetricTable& t = r.table;
  std::vector<double> v(static_cast<size_t>(t.channel_count()));
  double worst_um = 0, worst_urad = 0;
  for (int k = 0; k < 3000; ++k) {
    AxisVector u(5);
    for (int d = 0; d < 5; ++d) {
      const GridAxis& g = t.grid[static_cast<size_t>(d)];
      u[d] = std::uniform_real_distribution<double>(g.start, g.end)(rng);
    }
    interpolate(t, u, 0, Interpolation::kLinear, OutsidePolicy::kError, v.data());
    const PoseError e = xyzac().exact(u);
    worst_um = std::max(worst_um, (Eigen::Vector3d(v[0], v[1], v[2]) - e.dP_mm).norm() * 1e3);
    worst_urad = std::max(worst_urad, (Eigen::Vector3d(v[3], v[4], v[5]) - e.dQ).norm() * 1e6);
  }
  EXPECT_LE(worst_um, tol_um);
  EXPECT_LE(worst_urad, tol_urad);
  EXPECT_GE(r.tables_tried, 2);
  // Coarsest: one step coarser in either group (the other kept) fails.
  const std::vector<double>& lin = auto_spacing_sequence();
  const std::vector<double>& rot = auto_rotary_spacing_sequence();
  const size_t li =
      static_cast<size_t>(std::find(lin.begin(), lin.end(), r.spacing_mm) - lin.begin());
  const size_t ri = static_cast<size_t>(
      std::find_if(rot.begin(), rot.end(),
                   [&](double d) { return std::abs(d * kDeg - r.spacing_rad) < 1e-12; }) -
      rot.begin());
  ASSERT_LT(li, lin.size());
  ASSERT_LT(ri, rot.size());
  auto passes = [&](double mm, double deg) {
    const VolumetricTable c =
        build_table(xyzac(), {mm, mm, mm, std::min(deg, 130.0) * kDeg, deg * kDeg});
    const CheckResult k = check_table(xyzac(), c, check);
    return k.max_dv_um <= tol_um && k.max_dq_urad <= tol_urad;
  };
  if (li > 0) {
    EXPECT_FALSE(passes(lin[li - 1], rot[ri])) << lin[li - 1] << " mm";
  }
  if (ri > 0) {
    EXPECT_FALSE(passes(lin[li], rot[ri - 1])) << rot[ri - 1] << " deg";
  }
  EXPECT_TRUE(li > 0 || ri > 0);
}

// Bidirectional X (a minus-direction table 5 um longer in EXX): two layers,
// each equal to the direct model and to CorrectionSolver in its direction.
TEST(MapFiveAxis, DirectionLayersOfABidirectionalAxis) {
  ErrorSet e = xyzac().errors();
  AxisErrors& x = *e.axis[static_cast<size_t>(AxisName::X)];
  x.minus = x.plus;
  for (auto& v : x.minus.value) v[0] += 5e-3;
  const ErrorModel model(xyzac().machine(), e);
  const VolumetricTable t = build_table(model, {300, 250, 250, 65 * kDeg, 90 * kDeg});
  ASSERT_EQ(t.layer_count(), 2);
  EXPECT_EQ(t.bidirectional_axes, std::vector<int>{0});
  const ErrorModel clamped(model.machine(), model.errors(),
                           ModelOptions{Formulation::kIndependent, OutsidePolicy::kClamp});
  const CorrectionSolver solver(clamped, table_correction_options());
  const int u0 = channel(t, "ux");
  for (int layer = 0; layer < 2; ++layer) {
    const ApproachDirections dir = t.layer_directions(layer);
    EXPECT_EQ(dir[0], layer == 0 ? 1 : -1);
    for (std::int64_t n = 0; n < t.node_count(); n += 3) {
      const AxisVector u = t.node_position(n);
      const PoseError dv = model.exact(u, dir);
      const CorrectionResult c = solver.correct(u, dir);
      for (int i = 0; i < 3; ++i) EXPECT_EQ(t.at(layer, n)[i], dv.dP_mm[i]);
      for (int a = 0; a < 5; ++a) EXPECT_EQ(t.at(layer, n)[u0 + a], c.du[a]);
    }
  }
  // The layers differ by the 5 um of EXX: a translation along X, which A
  // (about X) and C = 0 (node 0) leave along the workpiece's x (to second
  // order: the exact HTM product turns it by the angular errors, ~1e-4).
  ASSERT_EQ(t.node_position(0)[4], 0.0);
  EXPECT_NEAR(std::abs(t.at(1, 0)[0] - t.at(0, 0)[0]), 5e-3, 1e-6);
  EXPECT_NEAR(t.at(1, 0)[1] - t.at(0, 0)[1], 0.0, 1e-6);
}

TEST(MapFiveAxis, TooLargeATableIsRefusedBeforeAllocating) {
  BuildOptions o;
  o.max_bytes = std::size_t{1} << 20;
  try {
    (void)build_table(xyzac(), {10, 10, 10, 5 * kDeg, 5 * kDeg}, o);
    FAIL() << "no exception";
  } catch (const TableTooLarge& e) {
    const std::string what = e.what();
    EXPECT_NE(what.find("`spacing`"), std::string::npos) << what;
    EXPECT_EQ(what.find('\n'), std::string::npos) << what;
  }
  CheckOptions c;
  EXPECT_THROW(build_for_tolerance(xyzac(), 1e-6, c, {}, std::size_t{4} << 20, 1e-6),
               TableTooLarge);
}

TEST(MapFiveAxis, SameBytesForOneAndTwoThreads) {
  BuildOptions one, two;
  one.threads = 1;
  two.threads = 2;
  const std::vector<double> s = {200, 250, 250, 26 * kDeg, 60 * kDeg};
  EXPECT_EQ(build_table(xyzac(), s, one).values, build_table(xyzac(), s, two).values);
}

TEST(MapFiveAxis, FileRoundTripIsExact) {
  const VolumetricTable& t = small_table();
  std::ostringstream out(std::ios::binary);
  write_table(out, t);
  std::istringstream in(out.str(), std::ios::binary);
  const VolumetricTable r = read_table(in, "t.vmt");
  EXPECT_EQ(r.channels, t.channels);
  ASSERT_EQ(r.values.size(), t.values.size());
  EXPECT_EQ(0, std::memcmp(r.values.data(), t.values.data(), t.size_bytes()));
  for (int d = 0; d < 5; ++d) {
    EXPECT_EQ(r.grid[static_cast<size_t>(d)].start, t.grid[static_cast<size_t>(d)].start);
    EXPECT_EQ(r.grid[static_cast<size_t>(d)].spacing, t.grid[static_cast<size_t>(d)].spacing);
    EXPECT_EQ(r.grid[static_cast<size_t>(d)].periodic, t.grid[static_cast<size_t>(d)].periodic);
  }
  EXPECT_TRUE(r.pose_correction());
  // Version 2 (docs/maps.md): a version-1 reader refuses it; a version-1
  // header on these channels is refused here.
  EXPECT_EQ(out.str()[8], 2);
  std::string v1 = out.str();
  v1[8] = 1;
  std::istringstream in1(v1, std::ios::binary);
  EXPECT_THROW(read_table(in1, "v1.vmt"), InputError);
}

TEST(MapFiveAxis, CsvHasAngleColumnsAndUnits) {
  const VolumetricTable& t = small_table();
  const std::vector<ExportFile> files = export_table(t, "csv");
  ASSERT_EQ(files.size(), 1u);
  const std::string& text = files[0].text;
  const std::string header = text.substr(0, text.find('\n'));
  EXPECT_EQ(header,
            "x_mm,y_mm,z_mm,a_deg,c_deg,ex_um,ey_um,ez_um,ei_urad,ej_urad,ek_urad,ux_um,uy_um,"
            "uz_um,ua_urad,uc_urad");
  // Second row: node 1 (X = -150), values in um and urad.
  std::istringstream rows(text.substr(header.size() + 1));
  std::string row;
  std::getline(rows, row);
  std::getline(rows, row);
  std::vector<double> cells;
  std::stringstream ss(row);
  for (std::string cell; std::getline(ss, cell, ',');) cells.push_back(std::stod(cell));
  ASSERT_EQ(cells.size(), 16u);
  EXPECT_DOUBLE_EQ(cells[0], -150.0);
  EXPECT_DOUBLE_EQ(cells[3], -100.0);
  EXPECT_NEAR(cells[5], t.at(0, 1)[0] * 1e3, 1e-6);
  EXPECT_NEAR(cells[8], t.at(0, 1)[3] * 1e6, 1e-6);
  EXPECT_NEAR(cells[15], t.at(0, 1)[10] * 1e6, 1e-6);
  EXPECT_NEAR(cells[11], t.at(0, 1)[6] * 1e3, 1e-6);
  EXPECT_NO_THROW(export_table(t, "json"));
}

TEST(MapFiveAxis, ThreeAxisControllersRefuseWithOneLine) {
  const VolumetricTable& t = small_table();
  for (const char* format : {"linuxcnc", "siemens-lec", "siemens-cec", "fanuc", "heidenhain"}) {
    try {
      (void)export_table(t, format);
      ADD_FAILURE() << format << ": no refusal";
    } catch (const ExportError& e) {
      const std::string what = e.what();
      EXPECT_NE(what.find(format), std::string::npos) << what;
      EXPECT_NE(what.find("three-axis"), std::string::npos) << what;
      EXPECT_EQ(what.find('\n'), std::string::npos) << what;
    }
  }
}

// Covariance of identified location errors (an identify --json report):
// u at a node against sqrt(g^T Sigma g) summed over x, y, z with the gains g
// taken by finite differences of the exact model (perturbing the errors
// file's location errors), not from the gain evaluator.
TEST(MapFiveAxis, IdentifiedCovariancePropagatesToTheNodes) {
  const nlohmann::json report = nlohmann::json::parse(R"({
    "format": "volmap-identify/1",
    "parameters": [
      {"name": "EY0A", "kind": "location", "unit": "um", "status": "estimated", "estimate": 3, "std_error": 2.0},
      {"name": "offset_x.run1", "kind": "setup_offset", "unit": "um", "status": "estimated", "estimate": 1, "std_error": 9.0},
      {"name": "EB0A", "kind": "location", "unit": "urad", "status": "estimated", "estimate": 4, "std_error": 5.0}
    ],
    "correlation": {"names": ["EY0A", "offset_x.run1", "EB0A"],
                    "matrix": [[1, 0.2, 0.6], [0.2, 1, 0.1], [0.6, 0.1, 1]]}})");
  const Machine& m = xyzac().machine();
  const ParameterCovariance c =
      covariance_from_identify(report, m, Formulation::kIndependent, "id.json");
  ASSERT_EQ(c.names, (std::vector<std::string>{"EY0A", "EB0A"}));
  BuildOptions o;
  o.repeatability = Repeatability{};  // only the covariance
  o.covariance = &c;
  const VolumetricTable t = build_table(xyzac(), {300, 250, 250, 65 * kDeg, 90 * kDeg}, o);
  const int uc = channel(t, "u");
  auto gain = [&](const char* name, double delta, const AxisVector& u) {
    ErrorSet e = xyzac().errors();
    e.location[name] += delta;
    const ErrorModel perturbed(m, e);
    return Eigen::Vector3d((perturbed.exact(u).dP_mm - xyzac().exact(u).dP_mm) / delta);
  };
  for (std::int64_t n = 0; n < t.node_count(); n += 5) {
    const AxisVector u = t.node_position(n);
    const Eigen::Vector3d g1 = gain("EY0A", 1e-4, u), g2 = gain("EB0A", 1e-7, u);
    const double s1 = 2e-3, s2 = 5e-6, rho = 0.6;
    const double var =
        s1 * s1 * g1.squaredNorm() + s2 * s2 * g2.squaredNorm() + 2 * rho * s1 * s2 * g1.dot(g2);
    EXPECT_NEAR(t.at(0, n)[uc], std::sqrt(var), 1e-3 * std::sqrt(var)) << n;
  }
  nlohmann::json bad = report;
  bad["parameters"][0]["kind"] = "component";
  bad["parameters"][0]["name"] = "EXX.p2";
  EXPECT_THROW(covariance_from_identify(bad, m, Formulation::kIndependent, "id.json"),
               std::invalid_argument);
}

}  // namespace
}  // namespace volmap::maps
