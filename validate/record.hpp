// Measurement records (docs/formats.md, "Measurement record"; reference-rig.md): one header row,
// comma separated, SI units, time strictly increasing. Columns t, ref, hub_torque, hub_angle,
// tip_deflection, and any others (hub_rate, tip_accel, pressure_a ...).
#pragma once

#include <map>
#include <string>
#include <vector>

namespace ff {

struct Record {
  std::string source;                                   // the file
  std::vector<double> t;                                // s, strictly increasing
  std::map<std::string, std::vector<double>> columns;   // every other column, by its header name
  // Cells a slower logger channel left empty (not sampled at that row), by column: each holds the column's
  // last value (sample and hold). Columns without empty cells are not listed.
  std::map<std::string, std::size_t> held;

  bool has(const std::string& name) const { return columns.count(name) > 0; }
  const std::vector<double>& at(const std::string& name) const { return columns.at(name); }
  std::size_t size() const { return t.size(); }
};

// The fewest samples a record may have.
inline constexpr std::size_t kMinRecordSamples = 20;

// Reads a record and checks it: the `required` columns exist; every cell is a finite number or empty
// (not sampled there: the column's last value held, Record::held; not in `t` nor in the first row);
// time strictly increases; at least kMinRecordSamples rows; angle columns (ref, hub_angle,
// tip_angle) that look like degrees (a swing beyond 2 pi) are refused. Throws ConfigError naming
// the file, the line and the column, with one clear message.
Record read_record_csv(const std::string& path, const std::vector<std::string>& required);

// Writes a record (columns in the order given), atomically: with digits 0, t as %.6f and the others
// %.10g (the rig's records); else every cell with `digits` significant digits (17: every double exactly).
void write_record_csv(const Record& r, const std::vector<std::string>& order, const std::string& path, int digits = 0);

// Central differences of y(t), one-sided at the ends (units of y per s).
std::vector<double> time_derivative(const std::vector<double>& t, const std::vector<double>& y);

// Linear interpolation of (t, y) at time x; clamped to the ends.
double interpolate(const std::vector<double>& t, const std::vector<double>& y, double x);

// A piecewise-smooth column (a reference: moves joined at knots where its second derivative jumps) and
// its first two derivatives at x_k = t0 + k T, k < n (clamped to the record's span). On each record
// interval: the cubic through the four samples around it whose third divided difference is the smallest
// (the ENO choice, Harten et al. 1987: that stencil does not reach across a knot, where the third
// difference is O(jump / h)). An interval whose neighbours' cubics differ in y'' by more than their own
// change over two intervals, and agree in slope inside it, holds a knot: the left neighbour's cubic is used up to the knot
// and the right's after it, the knot where the two cubics' slopes agree (the sub-cell resolution of
// Harten 1989: a C1 knot is a double root of their difference). Exact for piecewise cubics whose knots
// are at least four samples apart; central differences smear a knot's jump over two samples each side.
struct SmoothSamples {
  std::vector<double> value, rate, accel;  // y, y' (per s), y'' (per s^2)
};
SmoothSamples sample_piecewise_smooth(const std::vector<double>& t, const std::vector<double>& y, double t0, double T,
                                      long n);

}  // namespace ff
