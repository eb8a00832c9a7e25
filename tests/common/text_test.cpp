// Tests of the boundary's text helpers (common/text.hpp): strict integers and numbers, and the CSV
// header every reader of outside input checks.
#include "common/text.hpp"

#include <gtest/gtest.h>

#include <cstdint>
#include <string>

#include "common/errors.hpp"

namespace {

TEST(ParseInteger, TakesTheWholeTextInRangeAndNothingElse) {
  EXPECT_EQ(ff::parse_integer("12"), 12);
  EXPECT_EQ(ff::parse_integer("-3"), -3);
  EXPECT_EQ(ff::parse_integer("9223372036854775807"), 9223372036854775807LL);
  for (const char* bad : {"", "1x", "1e3", " 1", "+1", "0x10", "9223372036854775808", "99999999999999999999"})
    EXPECT_FALSE(ff::parse_integer(bad).has_value()) << bad;
  EXPECT_EQ(ff::parse_integer("2147483647", 0, 2147483647), 2147483647);
  EXPECT_FALSE(ff::parse_integer("99999999999", 0, 2147483647).has_value());
  EXPECT_FALSE(ff::parse_integer("-1", 0, 10).has_value());
  EXPECT_EQ(ff::parse_integer<std::uint64_t>("18446744073709551615"), UINT64_MAX);
  EXPECT_FALSE(ff::parse_integer<std::uint64_t>("-1").has_value());
}

TEST(ParseFinite, TakesAFiniteNumberOfTheWholeText) {
  EXPECT_EQ(ff::parse_finite("0.5"), 0.5);
  EXPECT_EQ(ff::parse_finite("-1e3"), -1000.0);
  for (const char* bad : {"", "3x", "nan", "inf", "-inf", "1e999", " 2"})
    EXPECT_FALSE(ff::parse_finite(bad).has_value()) << bad;
}

TEST(CsvHeader, AByteOrderMarkIsStrippedOnlyAtTheStart) {
  EXPECT_EQ(ff::strip_bom("\xEF\xBB\xBFt,hub_angle"), "t,hub_angle");
  EXPECT_EQ(ff::strip_bom("t,hub_angle"), "t,hub_angle");
  EXPECT_EQ(ff::strip_bom("t,\xEF\xBB\xBF"), "t,\xEF\xBB\xBF");
}

TEST(CsvHeader, ADuplicateOrEmptyColumnNameIsOneErrorNamingBothColumns) {
  EXPECT_NO_THROW(ff::check_csv_header({"t", "hub_angle", "hub_torque"}, "r.csv"));
  try {
    ff::check_csv_header({"t", "hub_torque", "hub_angle", "hub_torque"}, "r.csv");
    ADD_FAILURE() << "accepted";
  } catch (const ff::ConfigError& e) {
    EXPECT_STREQ(e.what(), "r.csv:1: hub_torque: columns 2 and 4 are both named 'hub_torque': each column needs its own name");
  }
  try {
    ff::check_csv_header({"t", ""}, "r.csv", 3);
    ADD_FAILURE() << "accepted";
  } catch (const ff::ConfigError& e) {
    EXPECT_STREQ(e.what(), "r.csv:3: column 2 has no name");
  }
}

}  // namespace
