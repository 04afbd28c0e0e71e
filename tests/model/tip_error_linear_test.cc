// ErrorModel::tip_error_linear, the three-axis hot path: exact()'s bits on
// random poses and at every edge (knots, signed zeros, outside the tables,
// non-finite positions), the same exceptions and clamped counts.
#include <fmt/format.h>
#include <gtest/gtest.h>

#include <cmath>
#include <cstring>
#include <limits>
#include <random>
#include <sstream>
#include <string>
#include <vector>

#include "core/model/error_model.h"
#include "core/model/errors_csv.h"
#include "core/model/machine_json.h"
#include "tests/model/error_model_fixtures.h"
#include "tests/support/test_paths.h"

namespace volmap {
namespace {

using test::hsu3;
using test::lei_hsu;
using test::random_errors;

}  // namespace
}  // namespace volmap

namespace volmap {
namespace {

// The post-processor's three-axis evaluator is exact()'s arithmetic on the
// tool tip alone: the same numbers to the bit, on both sides of the chain
// and for every approach direction.
TEST(ErrorModel, TipErrorLinearIsExactToTheBit) {
  // A bed-type machine: X and Y carry the workpiece, Z the spindle; the
  // location errors give every joint a rotated location frame.
  std::istringstream bed(R"({
    "format": "volmap-machine/1", "name": "bed-3axis", "structure": "[w X' Y' b Z t]",
    "axes": {
      "X": {"type": "linear", "direction": [1, 0, 0], "travel_mm": [0, 500]},
      "Y": {"type": "linear", "direction": [0, 1, 0], "travel_mm": [0, 400]},
      "Z": {"type": "linear", "direction": [0, 0, 1], "travel_mm": [0, 300]}},
    "workpiece_chain": [{"axis": "Y", "offset_mm": [0, 0, 50]}, {"axis": "X", "offset_mm": [0, 0, 80]}],
    "tool_chain": [{"axis": "Z", "offset_mm": [0, 0, 600]}],
    "spindle_offset_mm": [0, 0, -150], "tool": {"length_mm": 120, "axis": [0, 0, 1]},
    "workpiece_origin_mm": [0, 0, 30],
    "measured_at": {"X": {"Y": 200, "Z": 100}, "Y": {"X": 250, "Z": 100}, "Z": {"X": 250, "Y": 200}}})");
  std::mt19937 rng(7);
  const Machine bed_machine = read_machine_json(bed, "<bed>");
  ErrorSet bed_errors =
      random_errors(bed_machine, 30.0, rng);  // 0.6 mm, 0.6 mrad: second order shows
  for (const char* n : {"EA0X", "EB0Y", "EC0Z", "EA0Z", "EC0X"}) bed_errors.location[n] = 2e-4;
  struct Case {
    Machine machine;
    ErrorSet errors;
  };
  ErrorSet bed_link = bed_errors;  // the link meaning's path: no P, L moves what X carries
  bed_link.convention = LocationConvention::kLink;
  const Case cases[] = {
      {hsu3(),
       load_errors_csv(test::source_path("samples/errors/hsu-3axis.csv"))},  // bidirectional
      {bed_machine, bed_errors},
      {bed_machine, bed_link}};
  for (const Case& k : cases) {
    SCOPED_TRACE(k.machine.name);
    const ErrorModel model(k.machine, k.errors);
    ASSERT_TRUE(model.all_joints_linear());
    std::uniform_real_distribution<double> f(0.0, 1.0);
    std::uniform_int_distribution<int> die(-1, 1), coin(0, 2);
    double u[3] = {10, 10, 10};
    ApproachDirections dir{};
    for (int trial = 0; trial < 3000; ++trial) {
      // Each axis moves, or stays, or turns round in place.
      for (int a = 0; a < 3; ++a) {
        const int what = coin(rng);
        if (what == 0)
          u[a] = k.machine.limits[static_cast<size_t>(a)].min +
                 f(rng) * (k.machine.limits[static_cast<size_t>(a)].max -
                           k.machine.limits[static_cast<size_t>(a)].min);
        if (what != 1) dir[static_cast<size_t>(a)] = static_cast<std::int8_t>(die(rng));
      }
      AxisVector uv(3);
      uv << u[0], u[1], u[2];
      const Eigen::Vector3d want = model.exact(uv, dir).dP_mm;
      const Eigen::Vector3d got = model.tip_error_linear(u, dir);
      for (int i = 0; i < 3; ++i) {
        std::uint64_t g, w;
        std::memcpy(&g, &got[i], 8);
        std::memcpy(&w, &want[i], 8);
        ASSERT_EQ(g, w) << "trial " << trial << " coordinate " << i << ": " << got[i] << " vs "
                        << want[i];
      }
    }
  }
  // A machine with a rotary joint is not for it.
  EXPECT_FALSE(ErrorModel(lei_hsu(), ErrorSet{}).all_joints_linear());
}

}  // namespace
}  // namespace volmap

namespace volmap {
namespace {

// Bit patterns equal, or both NaN (a NaN's sign and payload are not
// arithmetic: the compiler may swap the operands of a commutative operation).
bool same_bits(double a, double b) {
  if (std::isnan(a) && std::isnan(b)) return true;
  std::uint64_t x, y;
  std::memcpy(&x, &a, 8);
  std::memcpy(&y, &b, 8);
  return x == y;
}

// tip_error_linear against exact() at one u: the same bits, the same
// exception, the same clamped count (in *clamped_out, or in clamped_count()
// without it).
void expect_tip_error_linear_is_exact(const ErrorModel& model, const double* u,
                                      const ApproachDirections& dir) {
  AxisVector uv(3);
  uv << u[0], u[1], u[2];
  const auto where = [&] {
    return fmt::format("u = ({}, {}, {}) dir = ({}, {}, {})", u[0], u[1], u[2], dir[0], dir[1],
                       dir[2]);
  };
  Eigen::Vector3d want = Eigen::Vector3d::Zero(), got = Eigen::Vector3d::Zero();
  std::string want_error, got_error;
  const std::uint64_t c0 = model.clamped_count();
  try {
    want = model.exact(uv, dir).dP_mm;
  } catch (const std::out_of_range& e) {
    want_error = e.what();
  }
  const std::uint64_t c1 = model.clamped_count();
  std::uint64_t clamped = 0;
  try {
    got = model.tip_error_linear(u, dir, &clamped);
  } catch (const std::out_of_range& e) {
    got_error = e.what();
  }
  ASSERT_EQ(got_error, want_error) << where();
  EXPECT_EQ(model.clamped_count(), c1) << where();  // counted in `clamped` instead
  EXPECT_EQ(clamped, c1 - c0) << where();
  if (!want_error.empty()) return;
  for (int i = 0; i < 3; ++i)
    ASSERT_TRUE(same_bits(got[i], want[i]))
        << where() << " coordinate " << i << ": " << got[i] << " vs " << want[i];
  // Without clamped_out the count goes to the model, as exact()'s does.
  const Eigen::Vector3d again = model.tip_error_linear(u, dir);
  EXPECT_EQ(model.clamped_count(), c1 + clamped) << where();
  for (int i = 0; i < 3; ++i) ASSERT_TRUE(same_bits(again[i], want[i])) << where();
}

// The second table of every axis: the first one's values and slopes scaled,
// so that dir = -1, 0, +1 give three different answers.
void make_bidirectional(ErrorSet& e, double scale) {
  for (auto& ax : e.axis) {
    if (!ax) continue;
    ax->minus = ax->plus;
    for (auto& row : ax->minus.value)
      for (double& x : row) x *= scale;
    for (auto& row : ax->minus.slope)
      for (double& x : row) x *= scale;
  }
}

// Edge positions of axis a: the table knots of both directions, the travel
// ends, +-0, the smallest subnormals, outside the tables, +-inf and NaN.
std::vector<double> edge_positions(const ErrorSet& e, const Machine& m, int a) {
  std::vector<double> out = {0.0,
                             -0.0,
                             5e-324,
                             -5e-324,
                             std::numeric_limits<double>::infinity(),
                             -std::numeric_limits<double>::infinity(),
                             std::numeric_limits<double>::quiet_NaN()};
  const AxisLimits& L = m.limits[static_cast<size_t>(a)];
  for (double x : {L.min, L.max, L.min - 7.5, L.max + 7.5, 0.5 * (L.min + L.max)}) out.push_back(x);
  if (const AxisErrors* ax = e.errors_of(m.axis_order[static_cast<size_t>(a)])) {
    for (const AxisErrorTable* t : {&ax->plus, &ax->minus})
      for (double x : t->position) {
        out.push_back(x);
        out.push_back(std::nextafter(x, -1e300));
        out.push_back(std::nextafter(x, 1e300));
      }
  }
  return out;
}

// Approach directions of X, Y, Z numbered 0..26: every combination of -1, 0, +1.
ApproachDirections linear_approach_directions(int d) {
  return ApproachDirections{static_cast<std::int8_t>(d % 3 - 1),
                            static_cast<std::int8_t>(d / 3 % 3 - 1),
                            static_cast<std::int8_t>(d / 9 - 1),
                            0,
                            0,
                            0};
}

struct EdgeCase {
  std::string name;
  Machine machine;
  ErrorSet errors;
};

// The machines and error sets of TipErrorLinearIsExactToTheBitAtTheEdges.
std::vector<EdgeCase> edge_cases(std::mt19937& rng) {
  using Case = EdgeCase;
  std::vector<Case> cases;
  // 1. The sample machine and its measured (bidirectional) errors.
  cases.push_back(
      {"hsu sample", hsu3(), load_errors_csv(test::source_path("samples/errors/hsu-3axis.csv"))});
  // 2. Workpiece chain of one axis, tool chain of two; non-uniform knots
  //    (binary search), rotated location frames on both sides.
  {
    std::istringstream js(R"({
      "format": "volmap-machine/1", "name": "split-3axis",
      "axes": {
        "X": {"type": "linear", "direction": [1, 0, 0], "travel_mm": [-250, 250]},
        "Y": {"type": "linear", "direction": [0, 1, 0], "travel_mm": [0, 400]},
        "Z": {"type": "linear", "direction": [0, 0, 1], "travel_mm": [-300, 0]}},
      "workpiece_chain": [{"axis": "Y", "offset_mm": [0, 0, 40]}],
      "tool_chain": [{"axis": "X", "offset_mm": [0, 0, 700]}, {"axis": "Z", "offset_mm": [10, -20, 150]}],
      "spindle_offset_mm": [0, 0, -90], "tool": {"length_mm": 75, "axis": [0, 0, 1]},
      "workpiece_origin_mm": [5, -3, 25],
      "measured_at": {"X": {"Y": 200, "Z": -100}, "Y": {"X": 0, "Z": -100}, "Z": {"X": 0, "Y": 200}}})");
    const Machine m = read_machine_json(js, "<split>");
    ErrorSet e = random_errors(m, 10.0, rng);
    make_bidirectional(e, -0.7);
    for (auto& ax : e.axis)
      if (ax) {
        std::vector<double>& x = ax->plus.position;
        for (size_t k = 1; k + 1 < x.size(); ++k) x[k] += (k % 2 ? 3.25 : -1.5);
        ax->minus.position = x;
      }
    for (const char* n : {"EA0X", "EB0Y", "EC0Z", "EB0X", "EA0Y", "EX0Z", "EY0Y"})
      e.location[n] = 1.5e-4;
    cases.push_back({"split", m, e});
  }
  // 3. One axis without error tables (its joint is the identity), one
  //    unidirectional, one bidirectional.
  {
    const Machine m = hsu3();
    ErrorSet e = random_errors(m, 5.0, rng);
    e.axis[static_cast<size_t>(AxisName::Y)].reset();
    auto& z = *e.axis[static_cast<size_t>(AxisName::Z)];
    z.minus = z.plus;
    for (auto& row : z.minus.value) row[3] += 1e-5;
    cases.push_back({"no Y tables", m, e});
  }
  // 4. Signed zeros everywhere: no offsets, the spindle at -0 (the tip
  //    starts as (-0, -0, -0)), no tool, all-zero error tables on X, none on
  //    Y, zero angles with nonzero translations on Z (rotations with entries
  //    1 and +-0); and the same machine without any error table (identity
  //    joints only).
  {
    std::istringstream js(R"({
      "format": "volmap-machine/1", "name": "zero-3axis",
      "axes": {
        "X": {"type": "linear", "direction": [1, 0, 0], "travel_mm": [-100, 100]},
        "Y": {"type": "linear", "direction": [0, 1, 0], "travel_mm": [-100, 100]},
        "Z": {"type": "linear", "direction": [0, 0, 1], "travel_mm": [-100, 100]}},
      "workpiece_chain": [{"axis": "X", "offset_mm": [-0.0, -0.0, -0.0]}],
      "tool_chain": [{"axis": "Y", "offset_mm": [-0.0, -0.0, -0.0]}, {"axis": "Z", "offset_mm": [0, 0, -0.0]}],
      "spindle_offset_mm": [-0.0, -0.0, -0.0], "tool": {"length_mm": 0, "axis": [0, 0, 1]},
      "workpiece_origin_mm": [0, -0.0, 0],
      "measured_at": {"X": {"Y": 0, "Z": 0}, "Y": {"X": 0, "Z": 0}, "Z": {"X": 0, "Y": 0}}})");
    const Machine m = read_machine_json(js, "<zero>");
    ErrorSet e = random_errors(m, 1.0, rng);
    e.location.clear();
    for (auto& row : e.axis[static_cast<size_t>(AxisName::X)]->plus.value) row.fill(0.0);
    for (auto& row : e.axis[static_cast<size_t>(AxisName::X)]->plus.slope) row.fill(0.0);
    e.axis[static_cast<size_t>(AxisName::Y)].reset();
    for (auto& row : e.axis[static_cast<size_t>(AxisName::Z)]->plus.value)
      row[3] = row[4] = row[5] = 0.0;
    for (auto& row : e.axis[static_cast<size_t>(AxisName::Z)]->plus.slope)
      row[3] = row[4] = row[5] = 0.0;
    make_bidirectional(e, -1.0);
    cases.push_back({"zeros", m, e});
    // Location translations of -0: t_parent_loc = offset + delta stays -0.
    ErrorSet minus_zero;
    for (const char* n : {"EX0X", "EY0X", "EZ0X", "EX0Y", "EY0Y", "EZ0Y", "EX0Z", "EY0Z", "EZ0Z"})
      minus_zero.location[n] = -0.0;
    cases.push_back({"zeros, -0 location errors only", m, minus_zero});
    cases.push_back({"zeros, no errors", m, ErrorSet{}});
  }
  // 5. Large angles (small_sincos's other ranges) on the bed machine of the
  //    test above.
  {
    const Machine m = hsu3();
    ErrorSet e = random_errors(m, 300.0, rng);  // 6 mrad: past the 1e-3 series
    make_bidirectional(e, 1.7);                 // 10 mrad: past the 1e-2 series
    cases.push_back({"large angles", m, e});
  }

  return cases;
}

// Bit for bit on every kind of machine and error set: both formulations,
// both outside policies, every approach direction, positions at and beside
// the table knots, signed zeros, outside the tables, non-finite.
TEST(ErrorModel, TipErrorLinearIsExactToTheBitAtTheEdges) {
  std::mt19937 rng(2024);
  using Case = EdgeCase;
  const std::vector<Case> cases = edge_cases(rng);
  for (const Case& k : cases) {
    for (Formulation f : {Formulation::kIndependent, Formulation::kDependent}) {
      for (OutsidePolicy p : {OutsidePolicy::kError, OutsidePolicy::kClamp}) {
        SCOPED_TRACE(fmt::format("{}, {}, {}", k.name,
                                 f == Formulation::kIndependent ? "independent" : "dependent",
                                 p == OutsidePolicy::kError ? "error" : "clamp"));
        const ErrorModel model(k.machine, k.errors, {f, p});
        ASSERT_TRUE(model.all_joints_linear());
        std::vector<double> edges[3];
        for (int a = 0; a < 3; ++a) edges[a] = edge_positions(k.errors, k.machine, a);
        std::uniform_real_distribution<double> unit(0.0, 1.0);
        for (int trial = 0; trial < 300; ++trial) {
          double u[3];
          for (int a = 0; a < 3; ++a) {
            const AxisLimits& L = k.machine.limits[static_cast<size_t>(a)];
            if (trial % 3 == 0) {
              u[a] = L.min + unit(rng) * (L.max - L.min);
            } else {
              std::uniform_int_distribution<size_t> pick(0, edges[a].size() - 1);
              u[a] = edges[a][pick(rng)];
            }
          }
          // Every approach direction.
          for (int d = 0; d < 27; ++d) {
            const ApproachDirections dir = linear_approach_directions(d);
            expect_tip_error_linear_is_exact(model, u, dir);
            if (::testing::Test::HasFatalFailure()) return;
          }
        }
        // Outside the tables: refused (kError) or clamped and counted once
        // per axis (kClamp), as exact() does.
        const AxisLimits& X = k.machine.limits[0];
        const double outside[3] = {X.max + 50, k.machine.limits[1].min - 50,
                                   k.machine.limits[2].max + 50};
        for (int d = 0; d < 27; ++d) {
          const ApproachDirections dir = linear_approach_directions(d);
          expect_tip_error_linear_is_exact(model, outside, dir);
        }
        if (p == OutsidePolicy::kClamp && k.errors.errors_of(AxisName::X) &&
            k.errors.errors_of(AxisName::Z)) {
          std::uint64_t clamped = 0;
          model.tip_error_linear(outside, ApproachDirections{}, &clamped);
          EXPECT_EQ(clamped, k.errors.errors_of(AxisName::Y) ? 3u : 2u);
        }
      }
    }
  }
}

}  // namespace
}  // namespace volmap
