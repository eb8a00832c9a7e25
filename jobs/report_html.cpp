#include "jobs/report_html.hpp"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <string_view>

#include "common/files.hpp"
#include "common/text.hpp"
#include "plotting/view_html.hpp"

// The page's template (jobs/report/report.html), compiled in by cmake/embed.cmake.
namespace ff::report_assets {
extern const std::string_view report_html;
}

namespace ff {

std::string encode_base64(const std::string& bytes) {
  static const char* abc = "ABCDEFGHIJKLMNOPQRSTUVWXYZabcdefghijklmnopqrstuvwxyz0123456789+/";
  std::string out;
  out.reserve((bytes.size() + 2) / 3 * 4);
  std::size_t i = 0;
  for (; i + 2 < bytes.size(); i += 3) {
    const unsigned v = (static_cast<unsigned char>(bytes[i]) << 16) | (static_cast<unsigned char>(bytes[i + 1]) << 8) |
                       static_cast<unsigned char>(bytes[i + 2]);
    for (int s : {18, 12, 6, 0}) out += abc[(v >> s) & 63];
  }
  if (i < bytes.size()) {
    const bool two = i + 1 < bytes.size();
    const unsigned v = (static_cast<unsigned char>(bytes[i]) << 16) | (two ? static_cast<unsigned char>(bytes[i + 1]) << 8 : 0);
    out += abc[(v >> 18) & 63];
    out += abc[(v >> 12) & 63];
    out += two ? abc[(v >> 6) & 63] : '=';
    out += '=';
  }
  return out;
}

namespace {

// A line's inline Markdown: **bold** and `code`, the rest escaped.
std::string inline_html(const std::string& s) {
  std::string out;
  for (std::size_t i = 0; i < s.size();) {
    if (s.compare(i, 2, "**") == 0) {
      const std::size_t end = s.find("**", i + 2);
      if (end != std::string::npos) {
        out += "<strong>" + inline_html(s.substr(i + 2, end - i - 2)) + "</strong>";
        i = end + 2;
        continue;
      }
    }
    if (s[i] == '`') {
      const std::size_t end = s.find('`', i + 1);
      if (end != std::string::npos) {
        out += "<code>" + html_escape(s.substr(i + 1, end - i - 1)) + "</code>";
        i = end + 1;
        continue;
      }
    }
    out += html_escape(std::string_view(s).substr(i, 1));
    ++i;
  }
  return out;
}

// A table row's cells, split at each '|' that is not escaped ("\|", common/text.hpp md_cell: a '|' in the cell).
std::vector<std::string> table_cells(const std::string& line) {
  std::vector<std::string> cells;
  std::string t = line;
  if (!t.empty() && t.front() == '|') t.erase(0, 1);
  if (!t.empty() && t.back() == '|' && (t.size() < 2 || t[t.size() - 2] != '\\')) t.pop_back();
  std::string cell;
  const auto end_cell = [&] {
    const auto a = cell.find_first_not_of(' '), b = cell.find_last_not_of(' ');
    cells.push_back(a == std::string::npos ? "" : cell.substr(a, b - a + 1));
    cell.clear();
  };
  for (std::size_t i = 0; i < t.size(); ++i) {
    if (t[i] == '\\' && i + 1 < t.size() && t[i + 1] == '|') cell += t[++i];
    else if (t[i] == '|') end_cell();
    else cell += t[i];
  }
  end_cell();
  return cells;
}

}  // namespace

std::string format_markdown_html(const std::string& md) {
  std::vector<std::string> lines;
  for (std::size_t pos = 0; pos <= md.size();) {
    const std::size_t end = md.find('\n', pos);
    lines.push_back(md.substr(pos, end == std::string::npos ? std::string::npos : end - pos));
    if (end == std::string::npos) break;
    pos = end + 1;
  }
  std::string html, paragraph;
  bool list = false;
  auto flush = [&] {
    if (!paragraph.empty()) html += "<p>" + inline_html(paragraph) + "</p>\n";
    paragraph.clear();
    if (list) html += "</ul>\n";
    list = false;
  };
  for (std::size_t i = 0; i < lines.size(); ++i) {
    const std::string& line = lines[i];
    if (line.empty()) {
      flush();
    } else if (line[0] == '#') {
      flush();
      const std::size_t level = std::min<std::size_t>(line.find_first_not_of('#'), 4);
      const std::string h = std::to_string(level + 1);  // the page's own title is the h1
      html += "<h" + h + ">" + inline_html(line.substr(line.find_first_not_of("# "))) + "</h" + h + ">\n";
    } else if (line[0] == '|') {
      flush();
      html += "<table>\n";
      bool head = i + 1 < lines.size() && lines[i + 1].rfind("|-", 0) == 0;
      for (; i < lines.size() && !lines[i].empty() && lines[i][0] == '|'; ++i) {
        if (lines[i].rfind("|-", 0) == 0) continue;
        const char* tag = head ? "th" : "td";
        html += "<tr>";
        for (const std::string& c : table_cells(lines[i])) html += std::string("<") + tag + ">" + inline_html(c) + "</" + tag + ">";
        html += "</tr>\n";
        head = false;
      }
      --i;
      html += "</table>\n";
    } else if (line.rfind("- ", 0) == 0) {
      if (!paragraph.empty()) flush();
      if (!list) html += "<ul>\n";
      list = true;
      html += "<li>" + inline_html(line.substr(2)) + "</li>\n";
    } else {
      if (list) flush();
      paragraph += (paragraph.empty() ? "" : " ") + line;
    }
  }
  flush();
  return html;
}

namespace {

std::string num(double x, const char* f = "%.4g") {
  if (std::isnan(x)) return "-";
  if (std::isinf(x)) return x > 0 ? "&gt; horizon" : "-inf";
  char buf[64];
  std::snprintf(buf, sizeof buf, f, x);
  return buf;
}

std::string row(const std::string& key, const std::string& value) {
  return "<tr><th>" + html_escape(key) + "</th><td>" + value + "</td></tr>\n";
}

}  // namespace

void write_report_html(const std::string& dir, const ReportPage& page) {
  const RunRecord& r = page.record;
  std::string b = "<h1>" + html_escape(r.study) + "</h1>\n<p class=\"subtitle\">flexfarm run of " + html_escape(r.study_path) +
                  ", finished " + html_escape(r.finished) + " on " + html_escape(r.host.empty() ? "(unknown host)" : r.host) +
                  (r.id > 0 ? ", run " + std::to_string(r.id) + " of the history" : "") + "</p>\n";
  if (!page.description.empty()) b += "<p>" + html_escape(page.description) + "</p>\n";

  // At a glance: the verdicts, the variants, what changed.
  int pass = 0, fail = 0, undecided = 0;
  for (const Verdict& v : r.verdicts) (v.verdict == "pass" ? pass : v.verdict == "fail" ? fail : undecided)++;
  b += "<div class=\"summary\">\n";
  if (!r.verdicts.empty()) {
    if (pass) b += "<span class=\"badge pass\">" + std::to_string(pass) + " pass</span>\n";
    if (fail) b += "<span class=\"badge fail\">" + std::to_string(fail) + " fail</span>\n";
    if (undecided) b += "<span class=\"badge undecided\">" + std::to_string(undecided) + " not decided</span>\n";
  }
  b += "<span class=\"badge\">" + std::to_string(r.variants) + (r.planned > r.variants ? " of " + std::to_string(r.planned) : "") +
       " variants, " + std::to_string(r.status.count("ok") ? r.status.at("ok") : 0) + " ok</span>\n";
  if (!page.diff_md.empty() && page.regressions.empty()) b += "<span class=\"badge pass\">nothing worse than the last run</span>\n";
  if (!page.diff_md.empty() && !page.regressions.empty()) {
    // Named by what got worse (a regression's text up to its first ": "), each whole in the tooltip.
    std::string names, whole;
    for (const std::string& g : page.regressions) {
      names += (names.empty() ? "" : "; ") + g.substr(0, g.find(": "));
      whole += (whole.empty() ? "" : "\n") + g;
    }
    b += "<span class=\"badge fail\" title=\"" + html_escape(whole) + "\">regressions since the last run (" +
         std::to_string(page.regressions.size()) + "): " + html_escape(names) + "</span>\n";
  }
  b += "</div>\n";

  b += "<h2 id=\"requirements\">Requirements</h2>\n";
  if (r.verdicts.empty()) {
    b += "<p>The study states no requirements.</p>\n";
  } else {
    b += "<table id=\"verdicts\">\n<tr><th>requirement</th><th>verdict</th><th>estimate [interval]</th><th>samples</th>"
         "<th>more samples to decide</th><th>evidence</th></tr>\n";
    for (const Verdict& v : r.verdicts)
      b += "<tr class=\"" + html_escape(v.verdict) + "\"><td><code>" + html_escape(v.requirement) + "</code></td><td class=\"verdict\">" +
           html_escape(v.verdict == "undecided" ? "not decided" : v.verdict) + "</td><td>" + num(v.estimate) + " [" + num(v.lower) +
           ", " + num(v.upper) + "]</td><td>" + std::to_string(v.n) + "</td><td>" +
           (v.verdict != "undecided" ? std::string("-") : v.more < 0 ? std::string("none would") : std::to_string(v.more)) +
           "</td><td>" + html_escape(v.evidence) + "</td></tr>\n";
    b += "</table>\n";
  }

  b += "<h2 id=\"changes\">Since the last run</h2>\n";
  b += page.diff_md.empty() ? "<p>" + html_escape(page.diff_note) + "</p>\n" : format_markdown_html(page.diff_md);

  b += "<h2 id=\"results\">Results</h2>\n" + format_markdown_html(page.results_md);

  // Every plot of the run, inlined.
  std::vector<std::string> plots;
  for (const auto& e : std::filesystem::directory_iterator(dir))
    if (e.is_regular_file() && e.path().extension() == ".png") plots.push_back(e.path().filename().string());
  std::sort(plots.begin(), plots.end());
  if (!plots.empty()) {
    b += "<h2 id=\"plots\">Plots</h2>\n";
    for (const std::string& p : plots)
      b += "<figure><img alt=\"" + html_escape(p) + "\" src=\"data:image/png;base64," + encode_base64(read_file(dir + "/" + p)) +
           "\"><figcaption>" + html_escape(p) + "</figcaption></figure>\n";
  }

  b += "<h2 id=\"provenance\">Provenance</h2>\n<table>\n";
  b += row("study file", html_escape(r.study_path) + "<br>SHA-256 <code>" + html_escape(r.study_sha256) + "</code>");
  b += row("model file", html_escape(r.model_path) + "<br>SHA-256 <code>" + html_escape(r.model_sha256) + "</code>");
  b += row("study hash (journals)", "<code>" + html_escape(r.study_hash) + "</code>");
  b += row("output directory", html_escape(r.out));
  b += row("flexfarm", html_escape(r.version) + (r.commit.empty() ? "" : " (commit <code>" + html_escape(r.commit) + "</code>)"));
  b += row("host", html_escape(r.host));
  b += row("started", html_escape(r.started.empty() ? "(not known: merged from shards)" : r.started));
  b += row("finished", html_escape(r.finished));
  b += row("wall time", std::isnan(r.seconds) ? "-" : num(r.seconds, "%.1f") + " s");
  b += row("processes x threads, lanes",
           std::to_string(r.processes) + " x " + std::to_string(r.threads) + ", " + std::to_string(r.lanes));
  b += "</table>\n";
  b += "<details><summary>The study file as it ran</summary><pre>" + html_escape(r.study_text) + "</pre></details>\n";
  b += "<details><summary>The model file as it ran</summary><pre>" + html_escape(r.model_text) + "</pre></details>\n";

  write_file_atomic(dir + "/report.html", fill_template(report_assets::report_html, {{"@@TITLE@@", html_escape(r.study + ": flexfarm report")},
                                                                                    {"@@BODY@@", std::move(b)}}));
}

}  // namespace ff
