// Tests of common/text.hpp: names from inputs made safe in Markdown tables and on a terminal, and page
// templates filled in one pass (issue 32, item 21).
#include "common/text.hpp"

#include <gtest/gtest.h>

#include <cstdio>
#include <stdexcept>
#include <string>

namespace {

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
