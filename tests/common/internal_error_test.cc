// Which exceptions are errors volmap raises for the user, and how any other
// one is reported (issue 35: every exception that reaches main is a bug).
#include "core/common/internal_error.h"

#include <gtest/gtest.h>

#include <filesystem>
#include <new>
#include <stdexcept>
#include <string>
#include <system_error>

#include "core/common/input_error.h"

namespace volmap {
namespace {

TEST(InternalError, TheErrorsRaisedForTheUserAreExpected) {
  EXPECT_TRUE(is_expected_error(InputError("p.nc", 3, "bad word")));
  EXPECT_TRUE(is_expected_error(std::invalid_argument("`tolerance_um` must be positive")));
  EXPECT_TRUE(is_expected_error(OutsideTable("e.csv: X axis position 600 is outside")));
  EXPECT_TRUE(is_expected_error(std::runtime_error("out.nc: cannot create the file")));
  EXPECT_TRUE(is_expected_error(std::filesystem::filesystem_error(
      "cannot read", std::filesystem::path("d"), std::make_error_code(std::errc::io_error))));
}

TEST(InternalError, EverythingElseIsABug) {
  EXPECT_FALSE(is_expected_error(std::length_error("basic_string::_M_create")));
  EXPECT_FALSE(is_expected_error(std::out_of_range("vector::_M_range_check")));
  EXPECT_FALSE(is_expected_error(std::invalid_argument("stoi")));  // std::stoi's own
  EXPECT_FALSE(is_expected_error(std::logic_error("no joint for X")));
  EXPECT_FALSE(is_expected_error(std::bad_alloc()));
  EXPECT_FALSE(is_expected_error(std::range_error("x")));
  EXPECT_FALSE(
      is_expected_error(InternalError("p.nc", 3, std::length_error("basic_string::_M_create"))));
}

TEST(InternalError, TheMessageSaysWhereWhatAndToReportIt) {
  const InternalError located("p.nc", 1407, std::length_error("basic_string::_M_create"));
  EXPECT_EQ(located.file(), "p.nc");
  EXPECT_EQ(located.line(), 1407);
  EXPECT_EQ(internal_error_message(located),
            "internal error at p.nc:1407: std::length_error: basic_string::_M_create; this is a "
            "bug in volmap, not a fault of the input: please report it with the command line and "
            "its input files");
  EXPECT_EQ(internal_error_message(std::out_of_range("map::at")),
            "internal error: std::out_of_range: map::at; this is a bug in volmap, not a fault of "
            "the input: please report it with the command line and its input files");
  EXPECT_EQ(describe_exception(std::runtime_error("a\nb")), "std::runtime_error: a b");
}

TEST(InternalError, ThrowIfUnexpectedWrapsOnlyBugs) {
  EXPECT_NO_THROW(throw_if_unexpected(InputError("p.nc", 2, "bad"), "p.nc", 2));
  EXPECT_NO_THROW(throw_if_unexpected(std::invalid_argument("a bad value"), "p.nc", 2));
  try {
    throw_if_unexpected(std::length_error("basic_string::_M_create"), "p.nc", 9);
    ADD_FAILURE() << "not thrown";
  } catch (const InternalError& e) {
    EXPECT_EQ(e.line(), 9);
    EXPECT_STREQ(e.what(), "internal error at p.nc:9: std::length_error: basic_string::_M_create");
  }
  // One already made keeps the place it was made at.
  try {
    throw_if_unexpected(InternalError("sub.nc", 4, std::bad_alloc()), "p.nc", 9);
    ADD_FAILURE() << "not thrown";
  } catch (const InternalError& e) {
    EXPECT_EQ(e.file(), "sub.nc");
    EXPECT_EQ(e.line(), 4);
  }
}

}  // namespace
}  // namespace volmap
