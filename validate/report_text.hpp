// The text pieces of the comparison reports (validate/compare.cpp, validate/arm_compare.cpp): numbers
// for Markdown tables and compare.json, JSON strings.
#pragma once

#include <cmath>
#include <cstdio>
#include <string>
#include <vector>

namespace ff::report_text {

inline std::string fmt(const char* f, double x) {
  char buf[64];
  std::snprintf(buf, sizeof buf, f, x);
  return buf;
}

// Fit % and other numbers for a table: "failed" when the prediction failed.
inline std::string fit_cell(double x) { return std::isfinite(x) ? fmt("%.2f", x) : "failed"; }
inline std::string num_cell(double x) { return std::isfinite(x) ? fmt("%.4g", x) : "failed"; }

// JSON: a number (null when not finite), a boolean, a string with its escapes.
inline std::string jnum(double x) { return std::isfinite(x) ? fmt("%.10g", x) : "null"; }
inline std::string jbool(bool b) { return b ? "true" : "false"; }
inline std::string jstr(const std::string& s) {
  std::string o = "\"";
  for (char c : s) {
    if (c == '"' || c == '\\') o += '\\', o += c;
    else if (static_cast<unsigned char>(c) < 0x20) o += fmt("\\u%04x", static_cast<unsigned char>(c));
    else o += c;
  }
  return o + "\"";
}

inline bool all_finite(const std::vector<double>& x) {
  for (double v : x)
    if (!std::isfinite(v)) return false;
  return true;
}

}  // namespace ff::report_text
