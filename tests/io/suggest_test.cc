#include "tactforce/io/suggest.h"

#include <gtest/gtest.h>

namespace tactforce::io {
namespace {

TEST(Suggest, EditDistanceCountsEditsAndSwapsIgnoringCase) {
  EXPECT_EQ(EditDistance("mass", "mass"), 0);
  EXPECT_EQ(EditDistance("mas", "mass"), 1);       // insertion
  EXPECT_EQ(EditDistance("nromal", "normal"), 1);  // swap of neighbours
  EXPECT_EQ(EditDistance("Mass", "mAss"), 0);      // case
  EXPECT_EQ(EditDistance("", "abc"), 3);
  EXPECT_EQ(EditDistance("kitten", "sitting"), 3);
}

TEST(Suggest, NearestNamesFirstAndAListWhenNothingIsClose) {
  const std::vector<std::string> fields = {"mass", "com", "inertia", "gravity"};
  EXPECT_EQ(DidYouMean("mas", fields), "; did you mean 'mass'?");
  EXPECT_EQ(DidYouMean("gravty", fields), "; did you mean 'gravity'?");
  EXPECT_EQ(DidYouMean("xyzzyq", fields), "; expected one of: mass, com, inertia, gravity");
  EXPECT_EQ(DidYouMean("anything", {}), "");
  const std::vector<std::string> near = NearestNames("cat", {"car", "cut", "dog", "cap"});
  ASSERT_EQ(near.size(), 3u);
  EXPECT_EQ(near[0], "car");  // ties keep candidate order
  EXPECT_EQ(DidYouMean("cat", {"car", "cut"}), "; did you mean 'car' or 'cut'?");
}

}  // namespace
}  // namespace tactforce::io
