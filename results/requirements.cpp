#include "results/requirements.hpp"

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <limits>
#include <stdexcept>

#include "common/errors.hpp"
#include "results/censoring.hpp"
#include "results/summaries.hpp"
#include "common/text.hpp"

namespace ff {

const char* comparison_text(Comparison op) {
  switch (op) {
    case Comparison::kLess: return "<";
    case Comparison::kLessEqual: return "<=";
    case Comparison::kGreater: return ">";
    case Comparison::kGreaterEqual: return ">=";
  }
  return "?";
}

bool compare(double a, Comparison op, double b) {
  switch (op) {
    case Comparison::kLess: return a < b;
    case Comparison::kLessEqual: return a <= b;
    case Comparison::kGreater: return a > b;
    case Comparison::kGreaterEqual: return a >= b;
  }
  return false;
}

namespace {

constexpr double kInf = std::numeric_limits<double>::infinity();
constexpr int kBootstrapResamples = 1000;

bool is_upper_bound(Comparison op) { return op == Comparison::kLess || op == Comparison::kLessEqual; }

// ---- parsing ------------------------------------------------------------------------------

class Parser {
 public:
  explicit Parser(const std::string& s) : s_(s) {}

  [[noreturn]] void fail(const std::string& expected) const {
    const std::string where = i_ >= s_.size() ? "at the end" : "at character " + std::to_string(i_ + 1) + " ('" + s_.substr(i_, 8) + "')";
    throw std::invalid_argument(where + ": expected " + expected);
  }
  void skip() {
    while (i_ < s_.size() && std::isspace(static_cast<unsigned char>(s_[i_]))) ++i_;
  }
  bool at_end() {
    skip();
    return i_ >= s_.size();
  }
  void expect(char c, const std::string& what) {
    skip();
    if (i_ >= s_.size() || s_[i_] != c) fail(what);
    ++i_;
  }
  // A run of letters, digits and dots (the statistic's name: P, p95, mean, ...).
  std::string word() {
    skip();
    const std::size_t a = i_;
    while (i_ < s_.size() && (std::isalnum(static_cast<unsigned char>(s_[i_])) || s_[i_] == '.')) ++i_;
    return s_.substr(a, i_ - a);
  }
  std::string metric() {
    skip();
    const std::size_t a = i_;
    while (i_ < s_.size() && !std::isspace(static_cast<unsigned char>(s_[i_])) && std::string("()<>=,!").find(s_[i_]) == std::string::npos)
      ++i_;
    if (i_ == a) fail("a metric (a result column, e.g. m1_tip_settling_s)");
    return s_.substr(a, i_ - a);
  }
  Comparison comparison(const std::string& after) {
    skip();
    const std::string what = "a comparison (<=, <, >= or >) " + after;
    if (i_ >= s_.size() || (s_[i_] != '<' && s_[i_] != '>')) fail(what);
    const bool less = s_[i_++] == '<';
    if (i_ < s_.size() && s_[i_] == '=') {
      ++i_;
      return less ? Comparison::kLessEqual : Comparison::kGreaterEqual;
    }
    return less ? Comparison::kLess : Comparison::kGreater;
  }
  double number(const std::string& what) {
    skip();
    const std::size_t a = i_;
    if (i_ >= s_.size() || !(std::isdigit(static_cast<unsigned char>(s_[i_])) || std::string("+-.").find(s_[i_]) != std::string::npos))
      fail(what);
    const char* begin = s_.c_str() + a;
    char* end = nullptr;
    const double x = std::strtod(begin, &end);
    if (end == begin || !std::isfinite(x)) fail(what);
    i_ = a + static_cast<std::size_t>(end - begin);
    return x;
  }
  std::size_t position() const { return i_; }
  void rewind(std::size_t i) { i_ = i; }

 private:
  const std::string& s_;
  std::size_t i_ = 0;
};

}  // namespace

Requirement parse_requirement(const std::string& text) {
  Requirement r;
  r.text = text;
  Parser p(text);
  const std::size_t start = (p.skip(), p.position());
  const std::string name = p.word();
  const std::string forms = "P(METRIC OP X) OP PROB, pNN(METRIC) OP X, mean(METRIC) OP X, max(METRIC) OP X or min(METRIC) OP X";
  if (name == "P") {
    r.kind = RequirementKind::kProbability;
    p.expect('(', "'(' after P");
    r.metric = p.metric();
    r.op = p.comparison("after the metric");
    r.threshold = p.number("a number after the comparison");
    p.expect(')', "')' after the number");
    r.prob_op = p.comparison("after P(...)");
    const std::size_t at = (p.skip(), p.position());
    r.probability = p.number("a probability in [0, 1]");
    if (!(r.probability >= 0.0 && r.probability <= 1.0)) {
      p.rewind(at);
      p.fail("a probability in [0, 1]");
    }
  } else {
    if (name == "mean") r.kind = RequirementKind::kMean;
    else if (name == "max") r.kind = RequirementKind::kMax;
    else if (name == "min") r.kind = RequirementKind::kMin;
    else if (name.size() > 1 && name[0] == 'p' && (std::isdigit(static_cast<unsigned char>(name[1])) || name[1] == '.')) {
      r.kind = RequirementKind::kPercentile;
      char* end = nullptr;
      const double nn = std::strtod(name.c_str() + 1, &end);
      if (*end != '\0' || !(nn > 0.0 && nn < 100.0)) {
        p.rewind(start);
        p.fail("a percentile pNN with NN in (0, 100), e.g. p95 or p99.9");
      }
      r.probability = nn / 100.0;
    } else {
      p.rewind(start);
      p.fail(forms);
    }
    p.expect('(', "'(' after " + name);
    r.metric = p.metric();
    p.expect(')', "')' after the metric");
    r.op = p.comparison("after " + name + "(...)");
    r.threshold = p.number("a number after the comparison");
  }
  if (!p.at_end()) p.fail("the end of the statement");
  return r;
}

// ---- YAML ---------------------------------------------------------------------------------

namespace {
const std::array<Field<RequirementSet>, 3> kRequirementFields = {{
    {"confidence", &RequirementSet::confidence, "", false, Bound::kPositive},
    {"stop_when_decided", &RequirementSet::stop_when_decided},
    {"check_every", &RequirementSet::check_every, "", false, Bound::kPositive},
}};
}  // namespace

std::vector<KeyDoc> requirements_keys() {
  std::vector<KeyDoc> out{{"requirements.statements", "", "yes", ""}};
  add_keys(out, "requirements.", kRequirementFields);
  return out;
}

RequirementSet read_requirements(YamlReader& top) {
  RequirementSet set;
  set.file = top.file();
  set.key = top.full_key("requirements");
  if (!top.has("requirements")) return set;
  const YAML::Node node = top.raw("requirements");
  set.line = set.stop_line = node.Mark().line + 1;
  YAML::Node list = node;
  std::string list_key = set.key;
  if (node.IsMap()) {
    YamlReader r = top.child("requirements");
    r.only({"statements", "confidence", "stop_when_decided", "check_every"});
    if (!r.has("statements")) r.fail_missing("statements", "missing required value (a list of statements)");
    list.reset(r.raw("statements"));  // reset: a Node's operator= would write into `requirements:` itself
    list_key = r.full_key("statements");
    read_present(r, kRequirementFields, set);
    set.stop_line = r.has("stop_when_decided") ? node["stop_when_decided"].Mark().line + 1 : set.line;
    if (!(set.confidence < 1.0)) r.fail("confidence", "must be in (0, 1), got " + format_key_number(set.confidence));
    r.finish();
  } else if (!node.IsSequence()) {
    top.fail("requirements", "expected a list of statements, or a map with `statements:`");
  }
  if (!list.IsSequence() || list.size() == 0)
    throw ConfigError(set.file, list.Mark().line + 1, list_key, "expected a non-empty list of statements, e.g. "
                                                                "[\"P(m1_tip_settling_s <= 3.0) >= 0.95\"]");
  for (std::size_t i = 0; i < list.size(); ++i) {
    const std::string key = list_key + "[" + std::to_string(i) + "]";
    const int line = list[i].Mark().line + 1;
    if (!list[i].IsScalar()) throw ConfigError(set.file, line, key, "expected a statement (text), e.g. \"p95(m1_peak_torque_Nm) <= 8000\"");
    const std::string text = list[i].as<std::string>();
    try {
      Requirement r = parse_requirement(text);
      r.key = key;
      r.line = line;
      set.statements.push_back(std::move(r));
    } catch (const std::invalid_argument& e) {
      throw ConfigError(set.file, line, key, "'" + text + "': " + e.what());
    }
  }
  return set;
}

void check_requirement_columns(const RequirementSet& set, const std::vector<std::string>& columns) {
  for (const Requirement& r : set.statements)
    if (const std::string why = explain_unknown_column(r.metric, columns); !why.empty()) throw ConfigError(set.file, r.line, r.key, why);
}

// ---- verdicts -----------------------------------------------------------------------------

namespace {

std::string num(double x) {
  if (std::isnan(x)) return "-";
  if (std::isinf(x)) return x > 0 ? "+inf" : "-inf";
  char buf[32];
  std::snprintf(buf, sizeof buf, "%.4g", x);
  return buf;
}

// The rows of a metric: value, and whether it is not settled (censored) or missing.
struct Column {
  std::vector<double> values, horizons;
  int censored = 0, missing = 0;
  bool is_censored(std::size_t i) const { return std::isnan(values[i]) && !horizons.empty() && !std::isnan(horizons[i]); }
};

Column read_column(const ResultTable& t, const std::string& metric) {
  Column c;
  c.values = column_values(t, metric);
  c.horizons = horizon_values(t, metric);
  for (std::size_t i = 0; i < c.values.size(); ++i)
    if (std::isnan(c.values[i])) ++(c.is_censored(i) ? c.censored : c.missing);
  return c;
}

std::string no_value_note(const Column& c) {
  if (c.censored + c.missing == 0) return "";
  std::string s;
  if (c.censored) s += std::to_string(c.censored) + " not settled";
  if (c.missing) s += (s.empty() ? "" : ", ") + std::to_string(c.missing) + " without a value";
  return " (" + s + ")";
}

// Verdict of a probability statement P(...) OP p from its Wilson interval.
std::string decide_probability(const Interval& w, Comparison op, double p) {
  if (std::isnan(w.estimate)) return "undecided";
  switch (op) {
    case Comparison::kGreaterEqual: return w.lower >= p ? "pass" : w.upper < p ? "fail" : "undecided";
    case Comparison::kGreater: return w.lower > p ? "pass" : w.upper <= p ? "fail" : "undecided";
    case Comparison::kLessEqual: return w.upper <= p ? "pass" : w.lower > p ? "fail" : "undecided";
    case Comparison::kLess: return w.upper < p ? "pass" : w.lower >= p ? "fail" : "undecided";
  }
  return "undecided";
}

// The same for an interval of a statistic against the bound X.
std::string decide_interval(double lower, double upper, Comparison op, double x) {
  if (std::isnan(lower) || std::isnan(upper)) return "undecided";
  switch (op) {
    case Comparison::kLessEqual: return upper <= x ? "pass" : lower > x ? "fail" : "undecided";
    case Comparison::kLess: return upper < x ? "pass" : lower >= x ? "fail" : "undecided";
    case Comparison::kGreaterEqual: return lower >= x ? "pass" : upper < x ? "fail" : "undecided";
    case Comparison::kGreater: return lower > x ? "pass" : upper <= x ? "fail" : "undecided";
  }
  return "undecided";
}

// The fewest more rows m that decide P(...) OP p when they keep the proportion k/n: with n + m rows and
// round(k/n (n + m)) successes the Wilson interval clears p. kCannotDecide when no m up to 10^9 does
// (the proportion is at the bound, or the bound is 0 or 1 and the proportion too).
long long calc_more_probability(int k, int n, Comparison op, double p, double confidence) {
  if (n <= 0) return kCannotDecide;
  const double ph = static_cast<double>(k) / n;
  auto decided = [&](long long m) {
    const long long nn = n + m;
    const auto kk = static_cast<std::size_t>(std::llround(ph * static_cast<double>(nn)));
    return decide_probability(calc_wilson_interval(kk, static_cast<std::size_t>(nn), confidence), op, p) != "undecided";
  };
  constexpr long long kMax = 1000000000LL;
  long long hi = 1;
  while (hi <= kMax && !decided(hi)) hi *= 2;
  if (hi > kMax) return kCannotDecide;
  long long lo = hi / 2;  // not decided (or 0)
  while (hi - lo > 1) {
    const long long mid = lo + (hi - lo) / 2;
    (decided(mid) ? hi : lo) = mid;
  }
  return hi;
}

// Type-7 percentile of sorted values that may hold infinities of one sign: an interpolation that touches
// an infinity is that infinity.
double sorted_percentile(const std::vector<double>& x, double p) {
  const double h = (static_cast<double>(x.size()) - 1.0) * p;
  const auto lo = static_cast<std::size_t>(std::floor(h));
  const std::size_t hi = std::min(lo + 1, x.size() - 1);
  const double f = h - static_cast<double>(lo);
  if (f == 0.0 || x[lo] == x[hi]) return x[lo];
  if (std::isinf(x[lo])) return x[lo];
  if (std::isinf(x[hi])) return x[hi];
  return x[lo] + f * (x[hi] - x[lo]);
}

// A probability statement on a metric: successes = rows meeting METRIC op X (a row without a value never does).
void judge_probability(Verdict& v, const Column& c, Comparison op, double x, Comparison prob_op, double p, double confidence) {
  int k = 0;
  for (double y : c.values) k += !std::isnan(y) && compare(y, op, x);
  const Interval w = calc_wilson_interval(static_cast<std::size_t>(k), c.values.size(), confidence);
  v.estimate = w.estimate;
  v.lower = w.lower;
  v.upper = w.upper;
  v.misses = v.n - k;
  v.verdict = decide_probability(w, prob_op, p);
  v.more = v.verdict != "undecided" ? 0 : calc_more_probability(k, v.n, prob_op, p, confidence);
}

std::string interval_text(const Verdict& v, double confidence) {
  char buf[96];
  std::snprintf(buf, sizeof buf, "%s [%s, %s] (%g %%)", num(v.estimate).c_str(), num(v.lower).c_str(), num(v.upper).c_str(),
                confidence * 100.0);
  return buf;
}

std::string more_text(const Verdict& v) {
  if (v.verdict != "undecided") return "";
  if (v.more == kCannotDecide) return "; more rows at this estimate would not decide it";
  return "; about " + std::to_string(v.more) + " more rows at this estimate would decide it";
}

}  // namespace

std::vector<Verdict> evaluate_requirements(const RequirementSet& set, const ResultTable& table, bool complete, int total) {
  std::vector<Verdict> out;
  for (const Requirement& r : set.statements) {
    Verdict v;
    v.requirement = r.text;
    const Column c = read_column(table, r.metric);
    v.n = static_cast<int>(c.values.size());
    v.censored = c.censored;
    v.missing = c.missing;
    const std::string cond = r.metric + " " + comparison_text(r.op) + " " + num(r.threshold);
    switch (r.kind) {
      case RequirementKind::kProbability: {
        judge_probability(v, c, r.op, r.threshold, r.prob_op, r.probability, set.confidence);
        v.statistic = v.estimate;
        v.evidence = std::to_string(v.n - v.misses) + " of " + std::to_string(v.n) + " rows meet " + cond +
                     no_value_note(c) + "; P = " + interval_text(v, set.confidence) + " vs " + comparison_text(r.prob_op) +
                     " " + num(r.probability) + more_text(v);
        break;
      }
      case RequirementKind::kPercentile: {
        // pNN(M) <= X <=> P(M <= X) >= q;  pNN(M) < X <=> P(M < X) >= q;
        // pNN(M) > X <=> P(M > X) > 1 - q;  pNN(M) >= X <=> P(M >= X) > 1 - q  (q = NN / 100).
        const double q = r.probability;
        const bool upper = is_upper_bound(r.op);
        const Comparison prob_op = upper ? Comparison::kGreaterEqual : Comparison::kGreater;
        const double p = upper ? q : 1.0 - q;
        judge_probability(v, c, r.op, r.threshold, prob_op, p, set.confidence);
        const KaplanMeier km = calc_kaplan_meier(c.values, c.horizons);
        v.statistic = calc_km_percentile(km, q * 100.0);
        const std::string pname = "p" + num(q * 100.0);
        const std::string stat = std::isinf(v.statistic) && !std::isnan(km.horizon) ? "> " + num(km.horizon) + " (not settled)"
                                                                                     : num(v.statistic);
        v.evidence = pname + " = " + stat + (c.censored ? " (Kaplan–Meier)" : "") + "; as P(" + cond + ") " +
                     comparison_text(prob_op) + " " + num(p) + ": " + std::to_string(v.n - v.misses) + " of " +
                     std::to_string(v.n) + " rows" + no_value_note(c) + ", P = " + interval_text(v, set.confidence) + more_text(v);
        break;
      }
      case RequirementKind::kMean: {
        // Worst-case values: for an upper bound a row without a value is +inf; for a lower bound a
        // missing one is -inf and a not-settled one its horizon (it is known to exceed it).
        const bool upper = is_upper_bound(r.op);
        std::vector<double> x(c.values.size());
        for (std::size_t i = 0; i < x.size(); ++i)
          x[i] = !std::isnan(c.values[i]) ? c.values[i] : upper ? kInf : c.is_censored(i) ? c.horizons[i] : -kInf;
        const std::size_t n = x.size();
        if (n == 0) {
          v.verdict = "undecided";
          v.more = kCannotDecide;
          v.evidence = "no rows";
          break;
        }
        auto mean = [](const std::vector<double>& y) {
          double s = 0.0;
          for (double e : y) s += e;
          return s / static_cast<double>(y.size());
        };
        v.estimate = v.statistic = mean(x);
        std::vector<double> means(kBootstrapResamples), resample(n);
        for (int b = 0; b < kBootstrapResamples; ++b) {
          for (std::size_t j = 0; j < n; ++j)
            resample[j] = x[draw_index(set.seed, static_cast<std::uint64_t>(b) * n + j, n)];
          means[static_cast<std::size_t>(b)] = mean(resample);
        }
        std::sort(means.begin(), means.end());
        v.lower = sorted_percentile(means, (1.0 - set.confidence) / 2.0);
        v.upper = sorted_percentile(means, (1.0 + set.confidence) / 2.0);
        v.verdict = decide_interval(v.lower, v.upper, r.op, r.threshold);
        if (v.verdict != "undecided") {
          v.more = 0;
        } else {
          // The interval's half-width shrinks as 1/sqrt(n): the rows at which the side facing the
          // bound would clear it.
          const double d = std::fabs(v.estimate - r.threshold);
          const double half = v.estimate > r.threshold ? v.estimate - v.lower : v.upper - v.estimate;
          if (!(d > 0.0) || !std::isfinite(half) || !std::isfinite(v.estimate)) {
            v.more = kCannotDecide;
          } else {
            const double need = std::ceil(static_cast<double>(n) * (half / d) * (half / d));
            v.more = std::max<long long>(1, static_cast<long long>(std::min(need, 1e12)) - static_cast<long long>(n));
          }
        }
        v.evidence = "mean of " + std::to_string(n) + " rows" + no_value_note(c) + (c.censored + c.missing ? " at their worst case" : "") +
                     " = " + interval_text(v, set.confidence) + " (percentile bootstrap, " + std::to_string(kBootstrapResamples) +
                     " resamples) vs " + comparison_text(r.op) + " " + num(r.threshold) + more_text(v);
        break;
      }
      case RequirementKind::kMax:
      case RequirementKind::kMin: {
        // Every row must meet it (max <, <=; min >, >=), or one row must (max >, >=; min <, <=).
        const bool is_max = r.kind == RequirementKind::kMax;
        const bool every = is_max == is_upper_bound(r.op);
        int meet = 0;
        double s = kStatsNaN;
        for (double y : c.values) {
          if (std::isnan(y)) continue;
          meet += compare(y, r.op, r.threshold);
          s = std::isnan(s) ? y : is_max ? std::max(s, y) : std::min(s, y);
        }
        v.estimate = v.statistic = s;
        v.misses = v.n - meet;
        if (every) v.verdict = v.misses > 0 ? "fail" : complete ? "pass" : "undecided";
        else v.verdict = meet > 0 ? "pass" : complete ? "fail" : "undecided";
        v.more = v.verdict != "undecided" ? 0 : total > v.n ? total - v.n : kCannotDecide;
        v.evidence = std::string(is_max ? "max" : "min") + " = " + num(s) + " over " + std::to_string(v.n) + " rows" +
                     no_value_note(c) + "; " + std::to_string(v.misses) + " do not meet " + cond +
                     (v.verdict == "undecided" ? (v.more > 0 ? "; " + std::to_string(v.more) + " rows still to run" : "; the study is not complete")
                                               : "");
        break;
      }
    }
    out.push_back(std::move(v));
  }
  return out;
}

bool all_decided(const std::vector<Verdict>& verdicts) {
  return std::all_of(verdicts.begin(), verdicts.end(), [](const Verdict& v) { return v.verdict != "undecided"; });
}

std::string format_requirements_md(const std::vector<Verdict>& verdicts) {
  std::string md = "| requirement | verdict | estimate [interval] | n | evidence |\n|---|---|---|---|---|\n";
  for (const Verdict& v : verdicts) {
    std::string est = num(v.estimate);
    if (!std::isnan(v.lower)) est += " [" + num(v.lower) + ", " + num(v.upper) + "]";
    md += "| `" + md_cell(v.requirement) + "` | " + v.verdict + " | " + est + " | " + std::to_string(v.n) + " | " + md_cell(v.evidence) + " |\n";
  }
  return md;
}

std::string format_verdict_lines(const std::vector<Verdict>& verdicts) {
  std::string out;
  for (const Verdict& v : verdicts) {
    std::string word = v.verdict == "pass" ? "PASS     " : v.verdict == "fail" ? "FAIL     " : "UNDECIDED";
    out += word + " " + v.requirement + ": " + v.evidence + "\n";
  }
  return out;
}

int find_stop_point(const RequirementSet& set, int total, int prefix, const std::function<bool(int)>& decided, int* next) {
  if (!set.stop_when_decided || set.statements.empty()) return total;
  int k = next && *next > 0 ? *next : set.check_every;
  int found = total;
  for (; k < total; k += set.check_every) {
    if (k > prefix) {
      found = -1;
      break;
    }
    if (decided(k)) {
      found = k;
      break;
    }
  }
  if (next) *next = k;
  return found;
}

}  // namespace ff
