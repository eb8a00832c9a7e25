// The closest valid name to a wrong one ("did you mean `stiffness`?"), for every reader that refuses a
// name: unknown YAML keys, verbs, joint and body names, parameter paths, metric columns.
#pragma once

#include <string>
#include <string_view>
#include <vector>

namespace ff {

// Optimal string alignment distance (Levenshtein with adjacent transpositions), case-insensitive.
std::size_t calc_edit_distance(std::string_view a, std::string_view b);

// The valid name nearest to `wrong`, or "" when none is near enough to be a likely typo: within
// max(1, |wrong| / 3) edits (ties: the first in `valid`).
std::string closest_name(std::string_view wrong, const std::vector<std::string>& valid);

// " (did you mean `name`?)" for the closest valid name, or "" when there is none.
std::string format_did_you_mean(std::string_view wrong, const std::vector<std::string>& valid);

}  // namespace ff
