// Text at the boundary: strict numbers from command-line options, parameter paths and CSV files, the
// header row every CSV reader of outside input checks the same way; and text read from inputs (study and
// model names, labels, paths, column names) made safe where it is shown: in a Markdown table, on a terminal.
#pragma once

#include <charconv>
#include <concepts>
#include <cstdio>
#include <optional>
#include <string>
#include <string_view>
#include <utility>
#include <vector>

namespace YAML {
class Exception;
}

namespace ff {

// What a YAML parse error says, for one line: yaml-cpp's own message, except for its depth limit, which
// it reports as "bad file" (lists and maps nested more than 500 deep).
std::string yaml_error_message(const YAML::Exception& e);

// A decimal integer, the whole text ("12", "-3"; not "", "1x", "1e3", " 1"), nullopt when it is not
// one or lies outside T's range.
template <std::integral T = long long>
std::optional<T> parse_integer(std::string_view text) {
  T x = 0;
  const char* end = text.data() + text.size();
  const auto [at, ec] = std::from_chars(text.data(), end, x);
  if (text.empty() || ec != std::errc() || at != end) return std::nullopt;
  return x;
}
// parse_integer within [lo, hi], else nullopt.
std::optional<long long> parse_integer(std::string_view text, long long lo, long long hi);
// A finite number, the whole text ("0.5", "-1e3"; not "", "3x", "nan", "inf", "1e999"), else nullopt.
std::optional<double> parse_finite(std::string_view text);

// A CSV file's first line without a leading UTF-8 byte-order mark (EF BB BF), which spreadsheet
// programs write and which would otherwise join the first column's name.
std::string strip_bom(std::string line);
// Throws ConfigError(source, line, name, ...) at the first column without a name or with the name of an
// earlier column: a record or table with two columns of one name is ambiguous.
void check_csv_header(const std::vector<std::string>& names, const std::string& source, int line = 1);

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
