// The closest valid name to a typo: edit distances against hand-counted values, and the reach.
#include "common/closest.hpp"

#include <gtest/gtest.h>

namespace ff {

TEST(EditDistance, CountsInsertionsDeletionsSubstitutionsAndSwaps) {
  EXPECT_EQ(calc_edit_distance("stifness", "stiffness"), 1u);  // one insertion
  EXPECT_EQ(calc_edit_distance("kitten", "sitting"), 3u);      // the textbook pair
  EXPECT_EQ(calc_edit_distance("simualte", "simulate"), 1u);   // adjacent letters swapped
  EXPECT_EQ(calc_edit_distance("", "abc"), 3u);
  EXPECT_EQ(calc_edit_distance("Elbow", "elbow"), 0u);         // case is not a typo
}

TEST(ClosestName, FindsALikelyTypoAndNothingFarOff) {
  const std::vector<std::string> keys = {"stiffness", "damping", "segments", "length"};
  EXPECT_EQ(closest_name("stifness", keys), "stiffness");
  EXPECT_EQ(closest_name("dampnig", keys), "damping");
  EXPECT_EQ(closest_name("colour", keys), "");  // no key within 2 edits
  EXPECT_EQ(format_did_you_mean("lenght", keys), " (did you mean `length`?)");
  EXPECT_EQ(format_did_you_mean("xyz", keys), "");
  EXPECT_EQ(closest_name("ab", std::vector<std::string>{}), "");
}

}  // namespace ff
