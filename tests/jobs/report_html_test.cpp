// jobs/report_html.cpp: the Markdown flexfarm writes as HTML, base64 against RFC 4648, and the run report
// itself: self-contained (nothing fetched), every character of the inputs escaped, and in headless
// Chromium (tests/chromium.hpp) it loads without an error, decodes its plot and shows the verdict table
// in its colours. The screenshot is kept in the tests' artefacts/ folder (report.png).
#include "jobs/report_html.hpp"

#include <gtest/gtest.h>
// OpenCV 4.6 headers mix enum types, which C++20 deprecates; keep that noise out of our build.
#pragma GCC diagnostic push
#pragma GCC diagnostic ignored "-Wdeprecated-enum-enum-conversion"
#include <opencv2/core.hpp>
#include <opencv2/imgcodecs.hpp>
#pragma GCC diagnostic pop

#include <algorithm>
#include <cmath>
#include <regex>

#include "common/files.hpp"
#include "plotting/plot.hpp"
#include "tests/chromium.hpp"
#include "tests/temp_dir.hpp"

namespace ff {
namespace {

TEST(Base64, MatchesTheRfc4648TestVectors) {
  const std::pair<const char*, const char*> vectors[] = {{"", ""},         {"f", "Zg=="},         {"fo", "Zm8="},
                                                         {"foo", "Zm9v"},  {"foob", "Zm9vYg=="},  {"fooba", "Zm9vYmE="},
                                                         {"foobar", "Zm9vYmFy"}};
  for (const auto& [in, out] : vectors) EXPECT_EQ(encode_base64(in), out) << in;
  EXPECT_EQ(encode_base64(std::string("\xff\x00\x80", 3)), "/wCA");
}

TEST(MarkdownHtml, HeadingsTablesListsAndInlineMarksBecomeHtmlAndTheTextIsEscaped) {
  const std::string html = format_markdown_html(
      "# Title <b>\n\nA paragraph with **bold** and `code <x>`\ncontinued.\n\n"
      "| a | b & c |\n|---|---|\n| 1 | <script>alert(1)</script> |\n\n- one\n- two\n");
  EXPECT_NE(html.find("<h2>Title &lt;b&gt;</h2>"), std::string::npos) << html;
  EXPECT_NE(html.find("<p>A paragraph with <strong>bold</strong> and <code>code &lt;x&gt;</code> continued.</p>"), std::string::npos) << html;
  EXPECT_NE(html.find("<tr><th>a</th><th>b &amp; c</th></tr>"), std::string::npos) << html;
  EXPECT_NE(html.find("<tr><td>1</td><td>&lt;script&gt;alert(1)&lt;/script&gt;</td></tr>"), std::string::npos) << html;
  EXPECT_NE(html.find("<ul>\n<li>one</li>\n<li>two</li>\n</ul>"), std::string::npos) << html;
  EXPECT_EQ(html.find("<script>"), std::string::npos);
  EXPECT_EQ(html.find("|---"), std::string::npos);  // the separator row is not a row
}

// (#32.21) A '|' escaped in a cell (common/text.hpp md_cell) stays in its cell; the row keeps its columns.
TEST(MarkdownHtml, AnEscapedBarStaysInItsCell) {
  const std::string html = format_markdown_html("| run | move |\n|---|---|\n| left \\| right | move 1 |\n| a\\|b\\| | `x\\|y` |\n");
  EXPECT_NE(html.find("<tr><td>left | right</td><td>move 1</td></tr>"), std::string::npos) << html;
  EXPECT_NE(html.find("<tr><td>a|b|</td><td><code>x|y</code></td></tr>"), std::string::npos) << html;
}

// A run's page: three verdicts, a diff, a table with a hostile label, one plot.
ReportPage sample_page(const std::string& dir) {
  LinePlot p;
  p.title = "tip angle";
  p.x_label = "time (s)";
  p.y_label = "angle (rad)";
  p.width = 640;
  p.height = 360;
  Series s;
  s.label = "run";
  for (int i = 0; i <= 100; ++i) {
    s.x.push_back(0.05 * i);
    s.y.push_back(0.5 * (1 - std::exp(-0.05 * i)));
  }
  p.series.push_back(s);
  render_line_plot(p, dir + "/tip_angle.png");
  ReportPage page;
  RunRecord& r = page.record;
  r.id = 7;
  r.study = "fbtb_proposal";
  r.study_path = "/studies/fbtb_proposal.yaml";
  r.out = dir;
  r.study_text = "model: ../fbtb.yaml\nrequirements:\n  - P(m1_tip_settling_s <= 3) >= 0.9\n";
  r.model_text = "beam: {length: 4.1656}\n";
  r.version = "0.1.0";
  r.commit = "abc123";
  r.host = "node7";
  r.finished = "2026-12-05T02:10:00Z";
  r.seconds = 12.5;
  r.planned = 400;
  r.variants = 200;
  r.status = {{"ok", 190}, {"not_settled", 10}};
  auto verdict = [](const char* req, const char* v, double est, double lo, double hi, long long more, const char* why) {
    return Verdict{.requirement = req, .verdict = v, .estimate = est, .lower = lo, .upper = hi, .n = 200, .more = more, .evidence = why};
  };
  r.verdicts = {verdict("P(m1_tip_settling_s <= 3) >= 0.9", "pass", 0.95, 0.91, 0.97, 0, "190 of 200 within"),
                verdict("p95(m1_peak_torque_Nm) <= 900", "fail", 0.12, 0.08, 0.17, 0, "P(<= 900) = 0.12"),
                verdict("mean(m1_tip_overshoot_pct) <= 3", "undecided", 2.98, 2.8, 3.2, 1400, "interval straddles 3")};
  page.description = "A proposal's <evaluation> & its requirements.";
  page.results_md = "200 variants.\n\n| run | value |\n|---|---|\n| <img src=x onerror=alert(1)> | 1 |\n";
  page.diff_md = "# What changed\n\n## Result\n\nNothing got worse.\n";
  return page;
}

TEST(ReportHtml, IsOneSelfContainedFileWithEveryInputEscaped) {
  const test::TempDir dir("ff_report_html");
  write_report_html(dir.path.string(), sample_page(dir.path.string()));
  const std::string html = read_file((dir.path / "report.html").string());
  EXPECT_FALSE(std::filesystem::exists(dir.path / "report.html.tmp"));
  // Nothing is fetched: no src or href to another file or the network, the plot is a data URI.
  EXPECT_FALSE(std::regex_search(html, std::regex(R"((src|href)\s*=\s*"(?!data:))")));
  EXPECT_NE(html.find("<img alt=\"tip_angle.png\" src=\"data:image/png;base64,iVBORw0KGgo"), std::string::npos);
  EXPECT_EQ(html.find("<img src=x"), std::string::npos);
  EXPECT_NE(html.find("&lt;img src=x onerror=alert(1)&gt;"), std::string::npos);
  EXPECT_NE(html.find("A proposal's &lt;evaluation&gt; &amp; its"), std::string::npos);
  // The verdicts: one row per requirement, its class the verdict; how many more samples decide the undecided one.
  EXPECT_NE(html.find("<tr class=\"pass\"><td><code>P(m1_tip_settling_s &lt;= 3) &gt;= 0.9</code></td><td class=\"verdict\">pass</td>"),
            std::string::npos);
  EXPECT_NE(html.find("<tr class=\"undecided\">"), std::string::npos);
  EXPECT_NE(html.find("<td>1400</td>"), std::string::npos);
  EXPECT_NE(html.find("200 of 400 variants, 190 ok"), std::string::npos);
  EXPECT_NE(html.find("nothing worse than the last run"), std::string::npos);
  EXPECT_NE(html.find("commit <code>abc123</code>"), std::string::npos);
}

TEST(ReportHtml, LoadsInHeadlessChromiumWithItsPlotDecodedAndTheVerdictTableInColour) {
  const test::TempDir dir("ff_report_html");
  write_report_html(dir.path.string(), sample_page(dir.path.string()));
  const std::vector<std::string> doms =
      test::load_in_chromium({{"file://" + (dir.path / "report.html").string(), "report.png"}}, dir.path, 1000, 900);
  const std::string& dom = doms[0];
  if (dom.empty()) return;  // the harness has failed the test
  const std::string html_tag = dom.substr(0, dom.find('>', dom.find("<html")));
  EXPECT_NE(html_tag.find("data-report-ready=\"1\""), std::string::npos) << html_tag;  // one image, decoded
  EXPECT_EQ(html_tag.find("data-report-error"), std::string::npos) << html_tag;
  EXPECT_NE(dom.find("<table id=\"verdicts\">"), std::string::npos);
  // The fail badge and verdict in the page's red (#b3261e): the stylesheet applied.
  const cv::Mat shot = cv::imread((dir.path / "report.png").string(), cv::IMREAD_COLOR);
  ASSERT_FALSE(shot.empty());
  int red = 0;
  for (int y = 0; y < shot.rows; ++y)
    for (int x = 0; x < shot.cols; ++x) {
      const cv::Vec3b p = shot.at<cv::Vec3b>(y, x);  // BGR
      red += std::abs(p[2] - 0xb3) < 12 && std::abs(p[1] - 0x26) < 12 && std::abs(p[0] - 0x1e) < 12;
    }
  EXPECT_GT(red, 500);
}

// (#32.21) A study named with the template's placeholders: the page is filled in one pass, so its
// title is the name as written and the whole body is there, once.
TEST(ReportHtml, AStudyNamedLikeThePlaceholdersIsOnlyItsTitle) {
  const test::TempDir dir("ff_report_placeholder");
  ReportPage page = sample_page(dir.path.string());
  page.record.study = "@@BODY@@ and @@TITLE@@";
  page.description = "About @@BODY@@.";
  write_report_html(dir.path.string(), page);
  const std::string html = read_file((dir.path / "report.html").string());
  EXPECT_NE(html.find("<title>@@BODY@@ and @@TITLE@@: flexfarm report</title>"), std::string::npos) << html.substr(0, 400);
  EXPECT_NE(html.find("<h1>@@BODY@@ and @@TITLE@@</h1>"), std::string::npos);
  EXPECT_NE(html.find("<p>About @@BODY@@.</p>"), std::string::npos);
  const auto count = [&](const std::string& s) {
    int n = 0;
    for (std::size_t p = html.find(s); p != std::string::npos; p = html.find(s, p + 1)) ++n;
    return n;
  };
  EXPECT_EQ(count("<h2 id=\"provenance\">"), 1);
  EXPECT_EQ(count("<h1>"), 1);
  EXPECT_EQ(count("</html>"), 1);
}

// The title, the description and the requirements once each (issue 32, item 24): the results are table.md's
// without them (StudyReport::results).
TEST(ReportHtml, TheTitleDescriptionAndRequirementsAppearOnce) {
  const test::TempDir dir("ff_report_html");
  write_report_html(dir.path.string(), sample_page(dir.path.string()));
  const std::string html = read_file((dir.path / "report.html").string());
  const auto count = [&](const std::string& s) {
    int n = 0;
    for (std::size_t at = html.find(s); at != std::string::npos; at = html.find(s, at + 1)) ++n;
    return n;
  };
  EXPECT_EQ(count("<h1>fbtb_proposal</h1>"), 1);
  EXPECT_EQ(count(">fbtb_proposal</h"), 1);
  EXPECT_EQ(count("A proposal's &lt;evaluation&gt; &amp; its requirements."), 1);
  EXPECT_EQ(count(">Requirements</h"), 1);
  EXPECT_EQ(count("<code>P(m1_tip_settling_s &lt;= 3) &gt;= 0.9</code>"), 1);  // the verdict table; the study text apart
}

// The regression badge names what got worse, each regression whole in its tooltip; none: "nothing worse".
TEST(ReportHtml, TheRegressionBadgeNamesEachRegression) {
  const test::TempDir dir("ff_report_html");
  ReportPage page = sample_page(dir.path.string());
  page.diff_md = "# What changed\n\n## Result\n\n2 regression(s):\n\n- ...\n";
  page.regressions = {"m1_peak_torque_Nm: mean rose from 950.2 to 1021 (tolerance: increase 3%)",
                      "requirement p95(m1_peak_torque_Nm) <= 1100: undecided before, fail now"};
  write_report_html(dir.path.string(), page);
  const std::string html = read_file((dir.path / "report.html").string());
  EXPECT_NE(html.find("<span class=\"badge fail\" title=\"m1_peak_torque_Nm: mean rose from 950.2 to 1021 (tolerance: "
                      "increase 3%)\nrequirement p95(m1_peak_torque_Nm) &lt;= 1100: undecided before, fail now\">regressions "
                      "since the last run (2): m1_peak_torque_Nm; requirement p95(m1_peak_torque_Nm) &lt;= 1100</span>"),
            std::string::npos)
      << html.substr(html.find("<div class=\"summary\">"), 800);
  EXPECT_EQ(html.find("nothing worse than the last run"), std::string::npos);
}

// Every column of a wide table is on the page at 800 px (issue 32, item 24: "Every metric" lost its
// P(miss) and interval columns, cut off at the right): no table is cut off or scrolls.
TEST(ReportHtml, AWideTableFitsThePageInHeadlessChromium) {
  const test::TempDir dir("ff_report_html");
  ReportPage page = sample_page(dir.path.string());
  std::string md = "## Every metric\n\n| metric | count | not settled | missing | horizon | mean | min | p5 | p50 | p95 | max | "
                   "P(miss spec) | 95% CI |\n|---|---|---|---|---|---|---|---|---|---|---|---|---|\n";
  for (const char* m : {"upper_arm_peak_deflection_m", "forearm_peak_deflection_m", "tool_settling_s"})
    md += std::string("| ") + m + " | 1000 | 17 | 0 | 2.5 | 0.0821345 | 0.0154321 | 0.0201532 | 0.0722745 | 0.172345 | "
          "0.181745 | 0.944123 | [0.742512, 0.990123] |\n";
  page.results_md = md;
  write_report_html(dir.path.string(), page);
  const std::vector<std::string> doms =
      test::load_in_chromium({{"file://" + (dir.path / "report.html").string(), "report_wide.png"}}, dir.path, 800, 900);
  const std::string& dom = doms[0];
  if (dom.empty()) return;  // the harness has failed the test
  const std::string html_tag = dom.substr(0, dom.find('>', dom.find("<html")));
  EXPECT_NE(html_tag.find("data-report-ready="), std::string::npos) << html_tag;
  EXPECT_EQ(html_tag.find("data-report-overflow"), std::string::npos) << html_tag;
}

}  // namespace
}  // namespace ff
