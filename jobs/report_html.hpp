// A run's report for a reviewer: DIR/report.html, one self-contained page (its plots inlined as
// data URIs, no script or style from elsewhere): the study's description, the requirements and their
// verdicts, the diff against the study's previous run, the tables of table.md, every plot of DIR, and
// the provenance (inputs with their hashes, version, machine, timings).
#pragma once

#include <string>
#include <vector>

#include "results/history.hpp"

namespace ff {

struct ReportPage {
  RunRecord record;          // provenance and verdicts
  std::string description;   // the study's
  std::string results_md;    // table.md's results (StudyReport::results: the page has its own title,
                             // description and requirements)
  std::string diff_md;       // the diff against the previous run (results/diff.hpp); "" when none
  std::vector<std::string> regressions;  // the diff's (RunDiff::regressions), "metric: what got worse"
  std::string diff_note;     // why there is none ("the first run of this study in the history")
};

// Writes DIR/report.html (atomically); the plots are DIR's *.png, in name order.
void write_report_html(const std::string& dir, const ReportPage& page);

// The Markdown that flexfarm writes (headings, pipe tables, lists, paragraphs, **bold**, `code`) as
// HTML, every character of the text escaped.
std::string format_markdown_html(const std::string& md);

// RFC 4648 base64.
std::string encode_base64(const std::string& bytes);

}  // namespace ff
