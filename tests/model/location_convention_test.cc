// Location errors between ISO 230-1 and link meaning (core/model/
// location_convention.h): round trips on every sample, the set-up part by
// hand, the check of the two models, and the errors file's convention line.
#include "core/model/location_convention.h"

#include <gtest/gtest.h>

#include <sstream>

#include "core/common/input_error.h"
#include "core/model/errors_csv.h"
#include "core/model/machine_json.h"
#include "tests/support/test_paths.h"

namespace volmap {
namespace {

Machine sample_machine(const std::string& name) {
  return load_machine_json(test::source_path("samples/machines/" + name + ".json"));
}
ErrorSet sample_errors(const std::string& name) {
  return load_errors_csv(test::source_path("samples/errors/" + name + ".csv"));
}

/// One link error on its own, and its conversion to ISO 230-1 on the
/// lei-hsu sample.
ErrorSet one_link_error(const std::string& name, double value) {
  ErrorSet link;
  link.convention = LocationConvention::kLink;
  link.location[name] = value;
  return link;
}
ConventionConversion to_iso(const Machine& m, const ErrorSet& e) {
  return convert_location_convention(m, e, LocationConvention::kIso230, Formulation::kIndependent);
}

// ISO -> link -> ISO gives every location error back, and the two models
// with the set-up parts agree up to the second-order product of the shift
// along a line and a component error's rotation (nanometres).
TEST(LocationConvention, RoundTripOnEverySample) {
  for (const char* name : {"lei-hsu-xyzac", "xyzab-tdr", "bc-table-table", "bridgemill-bc-head",
                           "hsu-3axis", "gantry-3axis"}) {
    const Machine m = sample_machine(name);
    const ErrorSet iso = sample_errors(name);
    ASSERT_EQ(iso.convention, LocationConvention::kIso230) << name;
    for (Formulation f : {Formulation::kIndependent, Formulation::kDependent}) {
      const ConventionConversion to_link =
          convert_location_convention(m, iso, LocationConvention::kLink, f);
      EXPECT_EQ(to_link.errors.convention, LocationConvention::kLink);
      EXPECT_LT(to_link.check_tip_mm, 2e-6) << name;
      EXPECT_LT(to_link.check_axis_rad, 1e-9) << name;
      EXPECT_GT(to_link.check_poses, 0);
      const ConventionConversion back =
          convert_location_convention(m, to_link.errors, LocationConvention::kIso230, f);
      EXPECT_LT(back.check_tip_mm, 2e-6) << name;
      for (const auto& [n, v] : iso.location) EXPECT_NEAR(back.errors.location_error(n), v, 1e-12);
      for (const auto& [n, v] : back.errors.location)
        EXPECT_NEAR(iso.location_error(n), v, 1e-12) << n;
      // The set-up parts of the two directions are the same transforms.
      EXPECT_TRUE(back.workpiece_setup.isApprox(to_link.workpiece_setup, 1e-12)) << name;
      EXPECT_TRUE(back.tool_setup.isApprox(to_link.tool_setup, 1e-12)) << name;
    }
  }
}

// Without component errors the conversion is exact: the models agree to
// rounding, and a link offset of the C line is, in ISO meaning, the same
// offset of the line plus the part set up 28 um further in x.
TEST(LocationConvention, SetUpPartByHand) {
  const Machine m = sample_machine("lei-hsu-xyzac");
  const ErrorSet link = one_link_error("EX0C", 28e-3);
  const ConventionConversion r = to_iso(m, link);
  EXPECT_NEAR(r.errors.location_error("EX0C"), 28e-3, 1e-15);
  EXPECT_EQ(r.errors.location.size(), 1u);
  EXPECT_LT((r.workpiece_setup.translation() - Eigen::Vector3d(28e-3, 0, 0)).norm(), 1e-15);
  EXPECT_TRUE(r.workpiece_setup.linear().isIdentity(1e-15));
  EXPECT_TRUE(r.tool_setup.isApprox(Eigen::Isometry3d::Identity(), 1e-15));
  EXPECT_LT(r.check_tip_mm, 1e-12);

  // At home the link model moves the part by the offset, ISO does not.
  AxisVector home = m.home;
  EXPECT_NEAR(ErrorModel(m, link).exact(home).dP_mm.norm(), 28e-3, 1e-12);
  EXPECT_NEAR(ErrorModel(m, r.errors).exact(home).dP_mm.norm(), 0.0, 1e-12);
}

// A squareness of a linear axis that carries others: in link meaning it
// turns what X carries (the A and C tables); in ISO meaning that part goes
// to the rotary axes' lines and the set-up.
TEST(LocationConvention, SquarenessOfATableCarryingAxis) {
  const ConventionConversion r =
      to_iso(sample_machine("lei-hsu-xyzac"), one_link_error("EC0X", 10e-6));
  EXPECT_NEAR(r.errors.location_error("EC0X"), 10e-6, 1e-15);
  // The A line (along x) turned 10 urad about z: EC0A.
  EXPECT_NEAR(r.errors.location_error("EC0A"), 10e-6, 1e-12);
  EXPECT_LT(r.check_tip_mm, 1e-12);
}

// A linear axis that moves against its letter's direction (X along -x):
// its own turn still goes to the set-up, the round trip still holds.
TEST(LocationConvention, LinearAxisAgainstItsLetter) {
  Machine m = sample_machine("lei-hsu-xyzac");
  for (Joint& j : m.workpiece_chain)
    if (j.axis == AxisName::X) j.direction_parent = -Eigen::Vector3d::UnitX();
  ErrorSet iso = sample_errors("lei-hsu-xyzac");
  iso.location["EA0Y"] = 15e-6;
  const ConventionConversion link =
      convert_location_convention(m, iso, LocationConvention::kLink, Formulation::kIndependent);
  EXPECT_LT(link.check_tip_mm, 2e-6);
  const ConventionConversion back = to_iso(m, link.errors);
  for (const auto& [n, v] : iso.location) EXPECT_NEAR(back.errors.location_error(n), v, 1e-12) << n;
}

// Errors that are no small errors (a unit mistake) are refused, not
// decomposed into garbage.
TEST(LocationConvention, LargeErrorsAreRefused) {
  const Machine m = sample_machine("lei-hsu-xyzac");
  EXPECT_THROW(to_iso(m, one_link_error("EX0C", 200.0)), std::invalid_argument);
  EXPECT_THROW(to_iso(m, one_link_error("EA0C", 0.5)), std::invalid_argument);
  EXPECT_NO_THROW(to_iso(m, one_link_error("EA0C", 5e-3)));
}

TEST(LocationConvention, FileSaysItsConvention) {
  std::istringstream link("# volmap component errors v1\n# convention: link\n\nEX0C\n28\n");
  EXPECT_EQ(read_errors_csv(link, "l.csv").convention, LocationConvention::kLink);
  std::istringstream iso("# convention: ISO 230-1\n\nEX0C\n28\n");
  EXPECT_EQ(read_errors_csv(iso, "i.csv").convention, LocationConvention::kIso230);
  std::istringstream none("EX0C\n28\n");
  EXPECT_EQ(read_errors_csv(none, "n.csv").convention, LocationConvention::kIso230);
  std::istringstream bad("# volmap component errors v1\n# convention: links\n\nEX0C\n28\n");
  try {
    read_errors_csv(bad, "b.csv");
    FAIL() << "no error";
  } catch (const InputError& e) {
    EXPECT_EQ(std::string(e.what()).rfind("b.csv:2: unknown convention", 0), 0u) << e.what();
  }
}

}  // namespace
}  // namespace volmap
