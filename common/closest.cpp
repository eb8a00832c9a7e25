#include "common/closest.hpp"

#include <algorithm>
#include <cctype>

namespace ff {

std::size_t calc_edit_distance(std::string_view a, std::string_view b) {
  const auto lower = [](char c) { return static_cast<char>(std::tolower(static_cast<unsigned char>(c))); };
  // d[i][j]: edits turning a[0..i) into b[0..j), three rows kept (the transposition looks two back).
  std::vector<std::size_t> prev2(b.size() + 1), prev(b.size() + 1), cur(b.size() + 1);
  for (std::size_t j = 0; j <= b.size(); ++j) prev[j] = j;
  for (std::size_t i = 1; i <= a.size(); ++i) {
    cur[0] = i;
    for (std::size_t j = 1; j <= b.size(); ++j) {
      const bool same = lower(a[i - 1]) == lower(b[j - 1]);
      cur[j] = std::min({prev[j] + 1, cur[j - 1] + 1, prev[j - 1] + (same ? 0 : 1)});
      if (i > 1 && j > 1 && lower(a[i - 1]) == lower(b[j - 2]) && lower(a[i - 2]) == lower(b[j - 1]))
        cur[j] = std::min(cur[j], prev2[j - 2] + 1);
    }
    std::swap(prev2, prev);
    std::swap(prev, cur);
  }
  return prev[b.size()];
}

std::string closest_name(std::string_view wrong, const std::vector<std::string>& valid) {
  const std::size_t reach = std::max<std::size_t>(1, wrong.size() / 3);
  std::string best;
  std::size_t best_d = reach + 1;
  for (const std::string& v : valid) {
    const std::size_t d = calc_edit_distance(wrong, v);
    if (d < best_d) best_d = d, best = v;
  }
  return best;
}

std::string format_did_you_mean(std::string_view wrong, const std::vector<std::string>& valid) {
  const std::string c = closest_name(wrong, valid);
  return c.empty() ? std::string() : " (did you mean `" + c + "`?)";
}

}  // namespace ff
