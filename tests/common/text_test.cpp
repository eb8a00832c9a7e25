// Tests of common/text.hpp: strict integers and numbers, the CSV header every reader of outside input
// checks; names from inputs made safe in Markdown tables and on a terminal, and page templates filled in
// one pass (issue 32, items 17, 18 and 21).
#include "common/text.hpp"

#include <gtest/gtest.h>

#include <cstdint>
#include <cstdio>
#include <stdexcept>
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

TEST(MdCell, ABarIsEscapedAndALineBreakIsASpace) {
  EXPECT_EQ(ff::md_cell("left | right"), "left \\| right");
  EXPECT_EQ(ff::md_cell("a|b|"), "a\\|b\\|");
  EXPECT_EQ(ff::md_cell("two\nlines\r"), "two lines ");
  EXPECT_EQ(ff::md_cell("payload.mass=328.7"), "payload.mass=328.7");
}

TEST(TerminalSafe, ControlCharactersAreShownAsQuestionMarksAndTextIsKept) {
  EXPECT_EQ(ff::terminal_safe("red\x1b[31mname\x07"), "red?[31mname?");
  EXPECT_EQ(ff::terminal_safe("a\rb\x7f" "c"), "a?b?c");
  EXPECT_EQ(ff::terminal_safe("csi \xc2\x9b" "2J, nel \xc2\x85."), "csi ?2J, nel ?.");  // C1 as UTF-8
  const std::string kept = "line\n\ttab, ± ≤ 1 s, héllo, \xe2\x80\xa6";  // UTF-8 with 0x80..0x9f continuation bytes
  EXPECT_EQ(ff::terminal_safe(kept), kept);
}

TEST(PrintSafe, FormatsLikePrintfAndStripsWhatItPrints) {
  std::FILE* f = std::tmpfile();
  ASSERT_NE(f, nullptr);
  ff::print_safe(f, "%s: %d of %.1f\n", "study\x1b]0;title\x07", 3, 4.0);
  std::rewind(f);
  char buf[128] = "";
  ASSERT_NE(std::fgets(buf, sizeof buf, f), nullptr);
  EXPECT_STREQ(buf, "study?]0;title?: 3 of 4.0\n");
  std::fclose(f);
}

// A study named "@@BODY@@" is only a title: what is put in is never searched for placeholders.
TEST(FillTemplate, FillsEveryPlaceholderOnceInOnePass) {
  const std::string page = "<title>@@TITLE@@</title><body>@@BODY@@</body>";
  EXPECT_EQ(ff::fill_template(page, {{"@@TITLE@@", "@@BODY@@ x"}, {"@@BODY@@", "<p>@@TITLE@@</p>"}}),
            "<title>@@BODY@@ x</title><body><p>@@TITLE@@</p></body>");
  EXPECT_EQ(ff::fill_template(page, {{"@@BODY@@", "b"}, {"@@TITLE@@", "t"}}), "<title>t</title><body>b</body>");
  EXPECT_THROW(ff::fill_template(page, {{"@@SCENE@@", "s"}}), std::logic_error);
}

}  // namespace
