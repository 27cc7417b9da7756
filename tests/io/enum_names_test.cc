// The enum-name convention (io/enum_names.h): one normalisation, the wire
// prefix, aliases, and the error naming the field and the accepted names.
#include "tactforce/io/enum_names.h"

#include <random>
#include <string>

#include <gtest/gtest.h>

namespace tactforce::io {
namespace {

enum class Shade { kLight, kDarkGrey, kNone };

constexpr EnumNameRow<Shade> kShades[] = {{Shade::kLight, "light"},
                                          {Shade::kDarkGrey, "dark-grey", "grey"},
                                          {Shade::kNone, "none"},
                                          {Shade::kDarkGrey, "dark-gray", "", false}};

TEST(EnumNames, PrintsTheFirstRowAndParsesEveryRow) {
  EXPECT_STREQ(EnumName(kShades, Shade::kDarkGrey), "dark-grey");
  for (const EnumNameRow<Shade>& r : kShades) {
    const absl::StatusOr<Shade> s = ParseEnumName(kShades, r.name, "shade");
    ASSERT_TRUE(s.ok()) << s.status();
    EXPECT_EQ(*s, r.value);
  }
}

TEST(EnumNames, CaseAndSeparatorsDrawnFromASeedAreOneName) {
  std::mt19937 rng(11);
  for (int trial = 0; trial < 200; ++trial) {
    std::string text = "dark-grey";
    for (char& c : text) {
      if (c == '-' && rng() % 2) c = '_';
      if (c != '-' && c != '_' && rng() % 2) c = static_cast<char>(c - 'a' + 'A');
    }
    const absl::StatusOr<Shade> s = ParseEnumName(kShades, text, "shade");
    ASSERT_TRUE(s.ok()) << text << ": " << s.status();
    EXPECT_EQ(*s, Shade::kDarkGrey) << text;
  }
}

TEST(EnumNames, WireSpellingNeedsThePrefix) {
  EXPECT_EQ(*ParseEnumName(kShades, "SHADE_GREY", "shade", "shade_"), Shade::kDarkGrey);
  EXPECT_EQ(*ParseEnumName(kShades, "SHADE_LIGHT", "shade", "shade-"), Shade::kLight);
  EXPECT_FALSE(
      ParseEnumName(kShades, "grey", "shade", "shade_").ok());  // the wire name alone is not a name
  EXPECT_FALSE(ParseEnumName(kShades, "SHADE_GREY", "shade").ok());  // no prefix given
}

TEST(EnumNames, ErrorNamesTheFieldAndListsTheListedNames) {
  const absl::StatusOr<Shade> s = ParseEnumName(kShades, "Dim", "options.shade");
  ASSERT_FALSE(s.ok());
  EXPECT_EQ(s.status().code(), absl::StatusCode::kInvalidArgument);
  EXPECT_EQ(s.status().message(),
            "options.shade: unknown 'Dim' (expected light, dark-grey or none)");
  EXPECT_EQ(UnknownEnumName("f", "x", {"a", "b"}).message(), "f: unknown 'x' (expected a or b)");
  EXPECT_EQ(UnknownEnumName("f", "x", {"a"}).message(), "f: unknown 'x' (expected a)");
}

}  // namespace
}  // namespace tactforce::io
