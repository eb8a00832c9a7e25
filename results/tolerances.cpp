#include "results/tolerances.hpp"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstdlib>

namespace ff {

namespace {

std::string amount_text(double x) {
  char buf[32];
  std::snprintf(buf, sizeof buf, "%.4g", x);
  return buf;
}

// "0.05" or "5%": an amount in the metric's unit, or relative to the earlier run's statistic.
void read_amount(YamlReader& r, const std::string& key, double& out, bool& relative) {
  std::string text;
  r.optional(key, text);
  if (text.empty()) return;
  relative = text.back() == '%';
  const std::string number = relative ? text.substr(0, text.size() - 1) : text;
  char* end = nullptr;
  out = std::strtod(number.c_str(), &end);
  if (number.empty() || *end != '\0' || !std::isfinite(out) || out < 0)
    r.fail(key, "expected an amount >= 0 in the metric's unit (0.05) or a percentage of the earlier run's value (5%), got '" +
                    text + "'");
  if (relative) out /= 100.0;
}

const char* const kStatistics[] = {"mean", "p5", "p50", "p95", "p_miss", "not_settled"};

}  // namespace

std::string Tolerance::describe() const {
  auto one = [](const char* word, double x, bool rel) {
    return std::string(word) + " > " + (rel ? amount_text(100.0 * x) + " %" : amount_text(x));
  };
  std::string s;
  if (!std::isnan(increase)) s = one("increase", increase, increase_relative);
  if (!std::isnan(decrease)) s += (s.empty() ? "" : ", ") + one("decrease", decrease, decrease_relative);
  return statistic + " " + s;
}

std::vector<KeyDoc> tolerance_keys() {
  return {{"tolerances.METRIC.increase", "the metric's, or %", "no", "none"},
          {"tolerances.METRIC.decrease", "the metric's, or %", "no", "none"},
          {"tolerances.METRIC.statistic", "", "no", "mean"}};
}

std::vector<Tolerance> read_tolerances(YamlReader& top) {
  std::vector<Tolerance> out;
  for (auto& [metric, r] : top.named_blocks("tolerances", "a map of METRIC: {increase, decrease, statistic}")) {
    Tolerance t;
    t.metric = metric;
    t.line = r.line();
    r.only({"increase", "decrease", "statistic"});
    read_amount(r, "increase", t.increase, t.increase_relative);
    read_amount(r, "decrease", t.decrease, t.decrease_relative);
    r.optional("statistic", t.statistic);
    if (std::find(std::begin(kStatistics), std::end(kStatistics), t.statistic) == std::end(kStatistics))
      r.fail("statistic", "expected mean, p5, p50, p95, p_miss or not_settled, got '" + t.statistic + "'");
    if (std::isnan(t.increase) && std::isnan(t.decrease))
      r.fail("increase", "a tolerance needs increase or decrease (or both): the change that counts as a regression");
    r.finish();
    out.push_back(t);
  }
  return out;
}

}  // namespace ff
