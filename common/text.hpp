// Text read from inputs (study and model names, labels, parameter paths, file paths, a record's
// column names) made safe where it is shown: in a Markdown table, and on a terminal.
#pragma once

#include <cstdio>
#include <string>
#include <string_view>
#include <utility>
#include <vector>

namespace ff {

// One Markdown table cell: '|' escaped as "\|" (jobs/report_html's reader and GitHub's show '|'),
// line breaks as spaces, so no name can shift a table's columns or end its row.
std::string md_cell(const std::string& text);

// Text for a terminal: every control character but newline and tab (C0, DEL, and C1 as UTF-8
// U+0080..U+009F) shown as '?', so an escape sequence in a study name reaches the terminal as text.
std::string terminal_safe(const std::string& text);

// A page template with each placeholder ("@@BODY@@", each present once) replaced in one pass: the
// texts put in are never searched, so a study named "@@BODY@@" is only a title. Throws
// std::logic_error when the template lacks one.
std::string fill_template(std::string_view page, const std::vector<std::pair<std::string, std::string>>& parts);

// printf to `out` (stdout, stderr) through terminal_safe: how the verbs print what holds names.
void print_safe(std::FILE* out, const char* format, ...) __attribute__((format(printf, 2, 3)));

}  // namespace ff
