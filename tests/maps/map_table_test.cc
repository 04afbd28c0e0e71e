// The volumetric table (maps/): node rule, values at the nodes against the
// direct model, interpolation between nodes against the model and against
// hand-computable fields, the correction against its defining equation,
// thread-count independence, the binary file (round trip, damage refused).
#include <gtest/gtest.h>

#include <cmath>
#include <cstring>
#include <random>
#include <sstream>
#include <string>

#include "core/common/input_error.h"
#include "core/model/errors_csv.h"
#include "core/model/machine_json.h"
#include "maps/tables/axis_correction.h"
#include "maps/tables/table_builder.h"
#include "maps/tables/table_file.h"
#include "tests/support/test_paths.h"

namespace volmap::maps {
namespace {

BuildOptions threads(int n) {
  BuildOptions o;
  o.threads = n;
  return o;
}

const ErrorModel& hsu_model() {
  static const ErrorModel model(
      load_machine_json(test::source_path("samples/machines/hsu-3axis.json")),
      load_errors_csv(test::source_path("samples/errors/hsu-3axis.csv")));
  return model;
}

TEST(MapGrid, NodesOnMultiplesOfTheSpacingLastAtTravelEnd) {
  // X travel 0..500 with spacing 70: 0, 70, ..., 490, then 500.
  const GridAxis g = make_grid_axis(hsu_model().machine(), 0, 70.0);
  ASSERT_EQ(g.count, 9);
  for (int k = 0; k < 8; ++k) EXPECT_EQ(g.node(k), 70.0 * k);
  EXPECT_EQ(g.node(8), 500.0);
  EXPECT_FALSE(g.uniform());
  // 0.1 mm divides 300 mm despite 0.1 not being a binary fraction.
  EXPECT_EQ(node_count(0.0, 0.1, 300.0), 3001);
  EXPECT_EQ(node_count(0.0, 50.0, 500.0), 11);
  EXPECT_TRUE(make_grid_axis(hsu_model().machine(), 0, 50.0).uniform());
  EXPECT_THROW(node_count(0.0, 0.0, 1.0), std::invalid_argument);
  EXPECT_THROW(node_count(0.0, -1.0, 1.0), std::invalid_argument);
}

TEST(MapGrid, LocateGivesExactZeroAtNodes) {
  const GridAxis g = make_grid_axis(hsu_model().machine(), 0, 70.0);
  for (int k = 0; k < g.count; ++k) {
    std::int64_t i;
    double s;
    g.locate(g.node(k), i, s);
    EXPECT_EQ(g.node(i) + s * (g.node(i + 1) - g.node(i)), g.node(k));
    EXPECT_TRUE(s == 0.0 || s == 1.0);
  }
  std::int64_t i;
  double s;
  g.locate(495.0, i, s);  // in the short last cell 490..500
  EXPECT_EQ(i, 7);
  EXPECT_DOUBLE_EQ(s, 0.5);
}

TEST(MapTable, LayersOnePerApproachDirectionOfBidirectionalAxes) {
  const VolumetricTable t = make_table_layout(hsu_model(), {100, 100, 100});
  // The Hsu sample's X table is bidirectional, Y and Z are not.
  ASSERT_EQ(t.bidirectional_axes, std::vector<int>{0});
  ASSERT_EQ(t.layer_count(), 2);
  EXPECT_EQ(t.layer_directions(0)[0], +1);
  EXPECT_EQ(t.layer_directions(1)[0], -1);
  EXPECT_EQ(t.layer_of({-1, 0, 0, 0, 0, 0}), 1);
  EXPECT_EQ(t.layer_of({+1, 0, 0, 0, 0, 0}), 0);
  EXPECT_EQ(t.channels, (std::vector<std::string>{"ex", "ey", "ez", "ux", "uy", "uz"}));
}

TEST(MapTable, NodesEqualTheDirectModel) {
  const ErrorModel& model = hsu_model();
  const VolumetricTable t = build_table(model, {70, 45, 50}, threads(2));
  const ThreeAxisCorrection corr(model);
  for (int layer = 0; layer < t.layer_count(); ++layer) {
    const ApproachDirections dir = t.layer_directions(layer);
    for (std::int64_t n = 0; n < t.node_count(); ++n) {
      const AxisVector u = t.node_position(n);
      const PoseError dv = model.exact(u, dir);
      const double* v = t.at(layer, n);
      for (int c = 0; c < 3; ++c)
        ASSERT_NEAR(v[c], dv.dP_mm[c], 1e-15) << "node " << n;  // 1e-12 um
      const Eigen::Vector3d du = corr.solve(u, dir).du_mm;
      for (int c = 0; c < 3; ++c) ASSERT_NEAR(v[3 + c], du[c], 1e-15);
      // Interpolation returns the node value exactly at a node.
      double out[6];
      interpolate(t, u, layer, Interpolation::kLinear, OutsidePolicy::kError, out);
      for (int c = 0; c < 6; ++c) ASSERT_EQ(out[c], v[c]);
      interpolate(t, u, layer, Interpolation::kCubic, OutsidePolicy::kError, out);
      for (int c = 0; c < 6; ++c) ASSERT_NEAR(out[c], v[c], 1e-15);
    }
  }
}

TEST(MapTable, DirectionLayersDifferByTheBacklashOfX) {
  // The sample's X table is bidirectional with the same angular and
  // straightness errors in both directions, so dv_x(X-) - dv_x(X+) at a node
  // is EXX(-) - EXX(+) of the errors file at that X (X carries the tool:
  // +EXX moves the tip +x), and dv_y, dv_z agree to second order (the
  // backlash times the angular errors, below 1e-7 mm).
  const ErrorModel& model = hsu_model();
  const AxisErrors& x_errors = *model.errors().errors_of(AxisName::X);
  const VolumetricTable t = build_table(model, {50, 50, 50});
  for (std::int64_t n = 0; n < t.node_count(); ++n) {
    const double x = t.node_position(n)[0];
    std::array<double, kComponentCount> plus_e, minus_e;
    evaluate_table(x_errors.plus, x, OutsidePolicy::kError, plus_e);
    evaluate_table(x_errors.minus, x, OutsidePolicy::kError, minus_e);
    ASSERT_NE(minus_e[0], plus_e[0]);
    const double* plus = t.at(0, n);
    const double* minus = t.at(1, n);
    EXPECT_NEAR((minus[0] - plus[0]) * 1e3, (minus_e[0] - plus_e[0]) * 1e3, 1e-4);
    EXPECT_NEAR(minus[1], plus[1], 1e-7);
    EXPECT_NEAR(minus[2], plus[2], 1e-7);
  }
}

TEST(MapCorrection, SolvesTheDefiningEquation) {
  // p(x + du) + e(x + du) = p(x), p the nominal tool tip, e = dP.
  const ErrorModel& model = hsu_model();
  const Machine& m = model.machine();
  const ThreeAxisCorrection corr(model);
  std::mt19937 rng(7);
  for (int k = 0; k < 200; ++k) {
    AxisVector x(3);
    for (int i = 0; i < 3; ++i) {
      const AxisLimits& L = m.limits[static_cast<size_t>(i)];
      // Stay 0.1 mm inside so x + du is inside the travel.
      x[i] = std::uniform_real_distribution<double>(L.min + 0.1, L.max - 0.1)(rng);
    }
    const ApproachDirections dir = {static_cast<std::int8_t>(k % 2 ? -1 : 1), 0, 0, 0, 0, 0};
    const ThreeAxisCorrection::Result r = corr.solve(x, dir);
    ASSERT_TRUE(r.converged);
    ASSERT_FALSE(r.clamped);
    AxisVector x_cmd = x;
    for (int i = 0; i < 3; ++i) x_cmd[i] += r.du_mm[i];
    const Eigen::Vector3d actual = nominal_forward(m, x_cmd).tip_mm + model.exact(x_cmd, dir).dP_mm;
    const Eigen::Vector3d wanted = nominal_forward(m, x).tip_mm;
    EXPECT_LT((actual - wanted).norm(), 1e-12) << k;  // mm
    // First order: du ~ -dP(x) for this machine (tool moves with +axes).
    EXPECT_LT((r.du_mm + model.exact(x, dir).dP_mm).norm(), 1e-5);
  }
}

TEST(MapInterpolation, ReproducesAffineFieldsExactly) {
  // A hand-made field f = a + b.x on the grid: multilinear and the cubic
  // Hermite with centred / one-sided slopes both reproduce it exactly,
  // including in the short last cell.
  VolumetricTable t = make_table_layout(hsu_model(), {70, 45, 50});
  const Eigen::Vector3d b(0.01, -0.02, 0.03);
  for (int layer = 0; layer < t.layer_count(); ++layer)
    for (std::int64_t n = 0; n < t.node_count(); ++n) {
      const AxisVector u = t.node_position(n);
      for (int c = 0; c < t.channel_count(); ++c)
        t.at(layer, n)[c] = 0.5 * c + b.dot(Eigen::Vector3d(u[0], u[1], u[2])) * (c + 1);
    }
  std::mt19937 rng(3);
  for (int k = 0; k < 500; ++k) {
    AxisVector u(3);
    u[0] = std::uniform_real_distribution<double>(0, 500)(rng);
    u[1] = std::uniform_real_distribution<double>(0, 400)(rng);
    u[2] = std::uniform_real_distribution<double>(0, 300)(rng);
    for (Interpolation method : {Interpolation::kLinear, Interpolation::kCubic}) {
      double out[6];
      interpolate(t, u, k % 2, method, OutsidePolicy::kError, out);
      for (int c = 0; c < 6; ++c)
        EXPECT_NEAR(out[c], 0.5 * c + b.dot(Eigen::Vector3d(u[0], u[1], u[2])) * (c + 1), 1e-12);
    }
  }
}

TEST(MapInterpolation, TrilinearHandComputedCell) {
  // Corner values v(i,j,k) = i + 10 j + 100 k * k on a 2-cell grid: at the
  // centre of cell (0,0,0) trilinear gives the mean of the 8 corners.
  VolumetricTable t = make_table_layout(hsu_model(), {250, 200, 150});
  ASSERT_EQ(t.node_count(), 27);
  std::int64_t idx[3];
  for (std::int64_t n = 0; n < 27; ++n) {
    t.node_index(n, idx);
    t.at(0, n)[0] = static_cast<double>(idx[0] + 10 * idx[1] + 100 * idx[2] * idx[2]);
  }
  AxisVector u(3);
  u << 125, 100, 75;
  double out[6];
  interpolate(t, u, 0, Interpolation::kLinear, OutsidePolicy::kError, out);
  // mean over i,j,k in {0,1}: 0.5 + 5 + 100 * 0.5
  EXPECT_DOUBLE_EQ(out[0], 55.5);
}

TEST(MapInterpolation, OutsideIsAnErrorOrClampedAndCounted) {
  const VolumetricTable t = build_table(hsu_model(), {100, 100, 100});
  AxisVector u(3);
  u << 501, 10, 10;
  double out[6];
  EXPECT_THROW(interpolate(t, u, 0, Interpolation::kLinear, OutsidePolicy::kError, out),
               std::out_of_range);
  std::uint64_t clamped = 0;
  interpolate(t, u, 0, Interpolation::kLinear, OutsidePolicy::kClamp, out, &clamped);
  EXPECT_EQ(clamped, 1u);
  AxisVector edge(3);
  edge << 500, 10, 10;
  double at_edge[6];
  interpolate(t, edge, 0, Interpolation::kLinear, OutsidePolicy::kError, at_edge);
  for (int c = 0; c < 6; ++c) EXPECT_EQ(out[c], at_edge[c]);
}

TEST(MapTolerance, AutomaticSpacingHoldsBetweenNodes) {
  const ErrorModel& model = hsu_model();
  for (Interpolation method : {Interpolation::kLinear, Interpolation::kCubic}) {
    const double tol_um = 0.5;
    CheckOptions check;
    check.method = method;
    const AutoSpacingResult r = build_for_tolerance(model, tol_um, check, threads(2));
    EXPECT_LE(r.check.max_um(), tol_um);
    // Coarsest: the next coarser spacing of the sequence fails.
    const auto& seq = auto_spacing_sequence();
    const auto it = std::find(seq.begin(), seq.end(), r.spacing_mm);
    ASSERT_NE(it, seq.end());
    if (it != seq.begin()) {
      const double coarser = *(it - 1);
      const VolumetricTable t = build_table(
          model, {std::min(coarser, 500.0), std::min(coarser, 400.0), std::min(coarser, 300.0)});
      EXPECT_GT(check_table(model, t, check).max_um(), tol_um);
    }
    // Independent dense sample (another generator and seed): within tolerance.
    std::mt19937_64 rng(99);
    double worst = 0.0;
    for (int k = 0; k < 20000; ++k) {
      AxisVector u(3);
      u[0] = std::uniform_real_distribution<double>(0, 500)(rng);
      u[1] = std::uniform_real_distribution<double>(0, 400)(rng);
      u[2] = std::uniform_real_distribution<double>(0, 300)(rng);
      const int layer = k % 2;
      double out[6];
      interpolate(r.table, u, layer, method, OutsidePolicy::kError, out);
      const Eigen::Vector3d dP = model.exact(u, r.table.layer_directions(layer)).dP_mm;
      worst = std::max(worst, (Eigen::Vector3d(out[0], out[1], out[2]) - dP).norm() * 1e3);
    }
    EXPECT_LE(worst, tol_um) << interpolation_name(method);
  }
}

TEST(MapTolerance, CubicNeedsFewerNodesThanLinear) {
  const ErrorModel& model = hsu_model();
  CheckOptions lin, cub;
  cub.method = Interpolation::kCubic;
  const VolumetricTable t = build_table(model, {50, 50, 50});
  EXPECT_LT(check_table(model, t, cub).max_um(), check_table(model, t, lin).max_um());
}

std::string bytes_of(const VolumetricTable& t) {
  std::ostringstream out(std::ios::binary);
  write_table(out, t);
  return out.str();
}

TEST(MapBuild, SameBytesForOneAndTwoThreads) {
  const VolumetricTable one = build_table(hsu_model(), {20, 25, 30}, threads(1));
  const VolumetricTable two = build_table(hsu_model(), {20, 25, 30}, threads(2));
  const VolumetricTable five = build_table(hsu_model(), {20, 25, 30}, threads(5));
  EXPECT_EQ(bytes_of(one), bytes_of(two));
  EXPECT_EQ(bytes_of(one), bytes_of(five));
}

TEST(MapBuild, ErrorTableShorterThanTravelIsRefused) {
  // Errors of X measured over 0..400 only; the travel is 0..500.
  std::istringstream csv("X,EXX\n0,1\n200,2\n400,3\n");
  const ErrorModel model(hsu_model().machine(), read_errors_csv(csv, "short.csv"));
  try {
    build_table(model, {50, 50, 50}, threads(2));
    FAIL() << "expected an error";
  } catch (const std::exception& e) {
    EXPECT_NE(std::string(e.what()).find("X"), std::string::npos) << e.what();
  }
}

TEST(MapFile, RoundTripIsExact) {
  VolumetricTable t = build_table(hsu_model(), {70, 45, 50});
  t.tolerance_um = 0.5;
  t.achieved_um = 0.123;
  t.checked_with = Interpolation::kCubic;
  const std::string bytes = bytes_of(t);
  std::istringstream in(bytes, std::ios::binary);
  const VolumetricTable r = read_table(in, "t.vmt");
  EXPECT_EQ(r.machine_name, t.machine_name);
  EXPECT_EQ(r.errors_source, t.errors_source);
  EXPECT_EQ(r.formulation, t.formulation);
  EXPECT_EQ(r.tolerance_um, 0.5);
  EXPECT_EQ(r.achieved_um, 0.123);
  EXPECT_EQ(r.checked_with, Interpolation::kCubic);
  EXPECT_EQ(r.channels, t.channels);
  EXPECT_EQ(r.bidirectional_axes, t.bidirectional_axes);
  ASSERT_EQ(r.grid.size(), t.grid.size());
  for (size_t d = 0; d < t.grid.size(); ++d) {
    EXPECT_EQ(r.grid[d].axis, t.grid[d].axis);
    EXPECT_EQ(r.grid[d].start, t.grid[d].start);
    EXPECT_EQ(r.grid[d].spacing, t.grid[d].spacing);
    EXPECT_EQ(r.grid[d].end, t.grid[d].end);
    EXPECT_EQ(r.grid[d].count, t.grid[d].count);
  }
  ASSERT_EQ(r.values.size(), t.values.size());
  EXPECT_EQ(std::memcmp(r.values.data(), t.values.data(), t.values.size() * 8), 0);
  EXPECT_EQ(bytes_of(r), bytes);
}

TEST(MapFile, LayoutMatchesTheDocumentedFormat) {
  // docs/maps.md: magic, version 1 (u32 LE), 3 axes, 6 channels, 1
  // bidirectional axis; the last 8 bytes are the FNV-1a 64 of the rest; the
  // values start right after the u64 value count.
  const VolumetricTable t = build_table(hsu_model(), {250, 200, 150});
  const std::string b = bytes_of(t);
  EXPECT_EQ(b.substr(0, 8), "VOLMAPTB");
  auto u32 = [&](size_t at) {
    std::uint32_t v = 0;
    for (int i = 3; i >= 0; --i)
      v = v << 8 | static_cast<unsigned char>(b[at + static_cast<size_t>(i)]);
    return v;
  };
  EXPECT_EQ(u32(8), 1u);
  EXPECT_EQ(u32(12), 3u);
  EXPECT_EQ(u32(16), 6u);
  EXPECT_EQ(u32(20), 1u);
  std::uint64_t stored = 0;
  for (int i = 7; i >= 0; --i)
    stored = stored << 8 | static_cast<unsigned char>(b[b.size() - 8 + static_cast<size_t>(i)]);
  EXPECT_EQ(stored, fnv1a64(b.data(), b.size() - 8));
  const size_t values_at = b.size() - 8 - t.values.size() * 8;
  double first;
  std::memcpy(&first, b.data() + values_at, 8);
  EXPECT_EQ(first, t.values[0]);
  // FNV-1a 64 reference values (Fowler/Noll/Vo test vectors).
  EXPECT_EQ(fnv1a64("", 0), 0xcbf29ce484222325ull);
  EXPECT_EQ(fnv1a64("a", 1), 0xaf63dc4c8601ec8cull);
  EXPECT_EQ(fnv1a64("foobar", 6), 0x85944171f73967e8ull);
}

void expect_refused(const std::string& bytes, const std::string& fragment) {
  std::istringstream in(bytes, std::ios::binary);
  try {
    read_table(in, "bad.vmt");
    ADD_FAILURE() << "accepted; expected \"" << fragment << "\"";
  } catch (const InputError& e) {
    const std::string msg = e.what();
    EXPECT_NE(msg.find("bad.vmt"), std::string::npos) << msg;
    EXPECT_NE(msg.find(fragment), std::string::npos) << msg;
  }
}

TEST(MapFile, DamagedFilesAreRefused) {
  const std::string good = bytes_of(build_table(hsu_model(), {100, 100, 100}));
  std::string flipped = good;
  flipped[flipped.size() - 100] ^= 0x01;  // one bit of one value
  expect_refused(flipped, "checksum");
  expect_refused(good.substr(0, good.size() - 1), "truncated");
  expect_refused(good.substr(0, 30), "truncated");
  expect_refused(good + "x", "extra bytes");
  std::string magic = good;
  magic[0] = 'X';
  expect_refused(magic, "not a volmap table");
  std::string version = good;
  version[8] = 2;
  expect_refused(version, "version 2");
  std::string axes = good;
  axes[12] = 9;
  expect_refused(axes, "axis count");
  expect_refused("", "truncated");
}

TEST(MapFile, SaveWritesThroughATemporaryFile) {
  const std::string path = ::testing::TempDir() + "map_table_test_save.vmt";
  const VolumetricTable t = build_table(hsu_model(), {100, 100, 100});
  save_table(path, t);
  const VolumetricTable r = load_table(path);
  EXPECT_EQ(r.values, t.values);
  std::remove(path.c_str());
  EXPECT_THROW(load_table(path), InputError);
}

}  // namespace
}  // namespace volmap::maps
