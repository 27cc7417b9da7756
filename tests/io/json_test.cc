// io/json.h: the reader (values, lines, errors with line and column,
// duplicate keys, \u escapes, depth) and the writer (exact layout, round trip
// through the reader).
#include "tactforce/io/json.h"

#include <cmath>
#include <random>
#include <regex>
#include <string>

#include "gtest/gtest.h"

namespace tactforce::io {
namespace {

TEST(Json, ParserHandlesTheBasics) {
  auto v = io::ParseJson(R"({"a": [1, -2.5e3, true, null, "x\n\u00e9"], "b": {}})", "s");
  ASSERT_TRUE(v.ok()) << v.status();
  const auto* a = v->Find("a");
  ASSERT_NE(a, nullptr);
  ASSERT_EQ(a->array().size(), 5u);
  EXPECT_EQ(a->array()[1].number(), -2500);
  EXPECT_EQ(a->array()[4].string(), "x\n\xc3\xa9");
  EXPECT_FALSE(io::ParseJson("[1,]", "s").ok());
  EXPECT_FALSE(io::ParseJson("{\"a\":1,\"a\":2}", "s").ok());
  EXPECT_EQ(io::JsonNumber(0.1), "0.1");
  EXPECT_EQ(io::JsonNumber(NAN), "null");
}

// The one JSON string quoter of the project (io/json.h), also used by the
// CLI's JSON output.
TEST(Json, EscapeQuotesAndEscapes) {
  EXPECT_EQ(io::JsonEscape("plain"), "\"plain\"");
  EXPECT_EQ(io::JsonEscape("a\"b\\c\nd\x01"), "\"a\\\"b\\\\c\\nd\\u0001\"");
}

// ---------------------------------------------------------------- errors

struct Located {
  int line = 0;
  int column = 0;
  std::string what;
};

// The parts of "in.json:<line>:<column>: <what>".
Located ErrorOf(const std::string& text) {
  absl::StatusOr<JsonValue> v = ParseJson(text, "in.json");
  EXPECT_FALSE(v.ok()) << text;
  if (v.ok()) return {};
  EXPECT_EQ(v.status().code(), absl::StatusCode::kInvalidArgument);
  const std::string message(v.status().message());
  static const std::regex format(R"(^in\.json:([0-9]+):([0-9]+): (.*)$)");
  std::smatch m;
  EXPECT_TRUE(std::regex_match(message, m, format)) << message;
  if (m.empty()) return {0, 0, message};
  return {std::stoi(m[1]), std::stoi(m[2]), m[3]};
}

TEST(JsonErrors, NameTheLineAndColumnOfTheOffendingToken) {
  Located e = ErrorOf("{\"gain\" 1}");
  EXPECT_EQ(e.line, 1);
  EXPECT_EQ(e.column, 9);  // the 1
  EXPECT_EQ(e.what, "expected ':', found number literal '1'");

  e = ErrorOf("[1,\n 2,\n ]");  // trailing comma
  EXPECT_EQ(e.line, 3);
  EXPECT_EQ(e.column, 2);
  EXPECT_EQ(e.what, "expected '[', '{', or a literal, found ']'");

  e = ErrorOf("{\n  \"mass\": 1,\n  \"com\": [0, 0, 0] \"inertia\": []\n}");  // missing comma
  EXPECT_EQ(e.line, 3);
  EXPECT_EQ(e.column, 28);  // the closing quote of "inertia"
  EXPECT_EQ(e.what, "expected '}', found string literal \"inertia\"");

  e = ErrorOf("{\n  \"a\": tru\n}");
  EXPECT_EQ(e.line, 2);
  EXPECT_EQ(e.column, 11);  // the line break that ends the bad literal
  EXPECT_EQ(e.what.rfind("invalid literal", 0), 0u) << e.what;

  e = ErrorOf("[\"one\",\n \"two]\n");
  EXPECT_EQ(e.line, 2);
  EXPECT_EQ(e.column, 7);  // the raw line break inside the string
  EXPECT_NE(e.what.find("control character U+000A"), std::string::npos) << e.what;

  e = ErrorOf("");
  EXPECT_EQ(e.line, 1);
  EXPECT_EQ(e.column, 1);
  EXPECT_EQ(e.what, "expected '[', '{', or a literal, found end of input");

  e = ErrorOf("{}\n{}");
  EXPECT_EQ(e.line, 2);
  EXPECT_EQ(e.column, 1);
  EXPECT_EQ(e.what, "expected end of input, found '{'");

  e = ErrorOf("[1e999]");
  EXPECT_EQ(e.what, "number overflow parsing '1e999'");
}

TEST(JsonErrors, DuplicateKeysNameTheSecondOccurrence) {
  Located e = ErrorOf("{\n  \"a\": 1,\n  \"b\": {\"a\": 2},\n  \"a\": 3\n}");
  EXPECT_EQ(e.line, 4);
  EXPECT_EQ(e.column, 3);  // the opening quote of the second "a"
  EXPECT_EQ(e.what, "duplicate key 'a'");
  // Keys are compared after unescaping.
  e = ErrorOf(R"({"a": 1, "\u0061": 2})");
  EXPECT_EQ(e.what, "duplicate key 'a'");
  EXPECT_EQ(e.column, 10);
  // A key with escaped quotes is located at its start.
  e = ErrorOf(R"({"q\"": 1, "q\"": 2})");
  EXPECT_EQ(e.what, "duplicate key 'q\"'");
  EXPECT_EQ(e.column, 12);
}

TEST(JsonErrors, NestingIsLimited) {
  auto nested = [](int depth) { return std::string(depth, '[') + "1" + std::string(depth, ']'); };
  EXPECT_TRUE(ParseJson(nested(kMaxJsonDepth), "in.json").ok());
  const Located e = ErrorOf(nested(kMaxJsonDepth + 1));
  EXPECT_EQ(e.what, "nesting deeper than 64 levels");
  EXPECT_EQ(e.column, kMaxJsonDepth + 1);
}

// ---------------------------------------------------------------- values

TEST(Json, UnicodeEscapesBecomeUtf8) {
  absl::StatusOr<JsonValue> v =
      ParseJson(R"(["\u00e9", "\u20AC", "\ud83d\ude00", "\u0000x", "é"])", "in.json");
  ASSERT_TRUE(v.ok()) << v.status();
  const auto& a = v->array();
  EXPECT_EQ(a[0].string(), "\xc3\xa9");             // U+00E9, two bytes
  EXPECT_EQ(a[1].string(), "\xe2\x82\xac");         // U+20AC, three bytes
  EXPECT_EQ(a[2].string(), "\xf0\x9f\x98\x80");     // a surrogate pair, four bytes
  EXPECT_EQ(a[3].string(), std::string("\0x", 2));  // NUL kept
  EXPECT_EQ(a[4].string(), "\xc3\xa9");             // raw UTF-8 as is
  EXPECT_NE(ErrorOf(R"(["\ud83d"])").what.find("surrogate"), std::string::npos);
  EXPECT_NE(ErrorOf(R"(["\u00g0"])").what.find("\\u"), std::string::npos);
}

TEST(Json, ValuesKnowTheLineTheyStartOn) {
  const std::string text =
      "{\n"                        // 1
      "  \"z\": [1,\n"             // 2
      "     2\n"                   // 3
      "     , \"three\"],\n"       // 4
      "  \"a\":\n"                 // 5
      "    {\"inner\": null,\n"    // 6
      "     \"deep\": [true]},\n"  // 7
      "  \"m\": -1.5e-3\n"         // 8
      "}\n";
  absl::StatusOr<JsonValue> v = ParseJson(text, "in.json");
  ASSERT_TRUE(v.ok()) << v.status();
  EXPECT_EQ(v->line(), 1);
  ASSERT_EQ(v->members().size(), 3u);
  // Members in file order, not sorted.
  EXPECT_EQ(v->members()[0].first, "z");
  EXPECT_EQ(v->members()[1].first, "a");
  EXPECT_EQ(v->members()[2].first, "m");
  const JsonValue& z = *v->Find("z");
  EXPECT_EQ(z.line(), 2);
  ASSERT_EQ(z.array().size(), 3u);
  EXPECT_EQ(z.array()[0].line(), 2);
  EXPECT_EQ(z.array()[1].line(), 3);
  EXPECT_EQ(z.array()[2].line(), 4);
  const JsonValue& a = *v->Find("a");
  EXPECT_EQ(a.line(), 6);  // where its '{' is, not where its key is
  EXPECT_EQ(a.Find("inner")->line(), 6);
  EXPECT_TRUE(a.Find("inner")->is_null());
  EXPECT_EQ(a.Find("deep")->line(), 7);
  EXPECT_EQ(a.Find("deep")->array()[0].line(), 7);
  EXPECT_EQ(v->Find("m")->line(), 8);
  EXPECT_EQ(v->Find("m")->number(), -1.5e-3);
  EXPECT_EQ(v->Find("missing"), nullptr);
}

TEST(Json, NumbersAreDoubles) {
  absl::StatusOr<JsonValue> v =
      ParseJson("[9007199254740993, -0, 18446744073709551615, 2.5e-320]", "in.json");
  ASSERT_TRUE(v.ok()) << v.status();
  EXPECT_EQ(v->array()[0].number(), 9007199254740992.0);  // nearest double
  EXPECT_TRUE(v->array()[0].is_number());
  EXPECT_EQ(v->array()[1].number(), 0.0);
  EXPECT_EQ(v->array()[2].number(), 18446744073709551615.0);
  EXPECT_GT(v->array()[3].number(), 0.0);  // subnormal, not flushed
}

// ---------------------------------------------------------------- writer

TEST(JsonWriter, PrettyLayoutIsStable) {
  JsonWriter w;
  w.BeginObject();
  w.Field("name", "x\"y");
  w.FieldInt("n", 3);
  w.NumberArray("v", {0, 0.05, 1e6, -2500, NAN});
  w.Key("list");
  w.BeginArray();
  w.Number(1.5);
  w.Null();
  w.BeginObject();
  w.EndObject();
  w.BeginArray();
  w.EndArray();
  w.EndArray();
  w.Key("empty");
  w.BeginArray();
  w.EndArray();
  w.FieldBool("ok", true);
  w.EndObject();
  EXPECT_EQ(w.str(),
            "{\n"
            "  \"name\": \"x\\\"y\",\n"
            "  \"n\": 3,\n"
            "  \"v\": [0, 0.05, 1e+06, -2500, null],\n"
            "  \"list\": [\n"
            "    1.5,\n"
            "    null,\n"
            "    {},\n"
            "    []\n"
            "  ],\n"
            "  \"empty\": [],\n"
            "  \"ok\": true\n"
            "}\n");
}

// Random nested values from a seed, written compact with random spacing:
// IndentJson keeps the value (strings with brackets, quotes and escapes
// included), lays it out as JsonWriter does, and is idempotent.
std::string RandomCompactJson(std::mt19937_64& rng, int depth) {
  std::uniform_int_distribution<int> kind(0, depth > 3 ? 3 : 5), count(0, 3), pad(0, 2);
  const std::string space(static_cast<size_t>(pad(rng)), ' ');
  const std::vector<std::string> strings = {R"("a{b")", R"("[,]:")", R"("q\"x\\")", R"("")",
                                            R"("t\n")"};
  switch (kind(rng)) {
    case 0:
      return JsonNumber(std::uniform_real_distribution<double>(-1e3, 1e3)(rng));
    case 1:
      return strings[static_cast<size_t>(count(rng)) % strings.size()];
    case 2:
      return "true";
    case 3:
      return "null";
    case 4: {
      std::string out = "[" + space;
      const int n = count(rng);
      for (int i = 0; i < n; ++i) out += (i ? "," + space : "") + RandomCompactJson(rng, depth + 1);
      return out + space + "]";
    }
    default: {
      std::string out = "{";
      const int n = count(rng);
      for (int i = 0; i < n; ++i) {
        out += (i ? "," : "") + space + "\"k" + std::to_string(i) + "\"" + space + ":" +
               RandomCompactJson(rng, depth + 1);
      }
      return out + "}";
    }
  }
}

// `json` without the spaces and newlines outside its strings.
std::string WithoutLayout(const std::string& json) {
  std::string out;
  JsonStringTracker strings;
  for (char c : json) {
    if (!strings.InString(c) && (c == ' ' || c == '\n')) continue;
    out += c;
  }
  return out;
}

TEST(JsonStringTracker, MarksQuotesEscapesAndContentsAsInString) {
  const std::string text = R"({"k":"a\"b\\","n":[1]})";
  // One flag per character: 1 = inside a string literal (quotes included).
  const std::string expected = "0111011111111011100000";
  JsonStringTracker strings;
  std::string flags;
  for (char c : text) flags += strings.InString(c) ? '1' : '0';
  EXPECT_EQ(flags, expected) << text;
}

TEST(IndentJson, KeepsTheValueInTheWritersLayout) {
  EXPECT_EQ(
      IndentJson(R"({"name":"x\"y","list":[1.5,null,{},[ ]],"ok":true})"),
      "{\n  \"name\": \"x\\\"y\",\n  \"list\": [\n    1.5,\n    null,\n    {},\n    []\n  ],\n"
      "  \"ok\": true\n}\n");
  std::mt19937_64 rng(25);
  for (int trial = 0; trial < 200; ++trial) {
    const std::string compact = "{\"v\": " + RandomCompactJson(rng, 0) + "}";
    const std::string pretty = IndentJson(compact);
    absl::StatusOr<JsonValue> a = ParseJson(compact, "compact"), b = ParseJson(pretty, "pretty");
    ASSERT_TRUE(a.ok()) << a.status() << compact;
    ASSERT_TRUE(b.ok()) << b.status() << pretty;
    // The same text once whitespace outside strings is gone.
    EXPECT_EQ(WithoutLayout(pretty), WithoutLayout(compact));
    EXPECT_EQ(IndentJson(pretty), pretty);  // idempotent
    EXPECT_EQ(pretty.back(), '\n');
  }
}

TEST(JsonWriter, RoundTripsThroughTheReader) {
  const std::vector<double> numbers = {0.1, -2.5e-300, 1e300, 123456789.125, 1.0 / 3, 5e-324};
  const std::string text = "tab\t quote\" backslash\\ bell\x07 \xc3\xa9 \xf0\x9f\x98\x80";
  JsonWriter w;
  w.BeginObject();
  w.Field("text", text);
  w.NumberArray("numbers", numbers);
  w.Key("nested");
  w.BeginArray();
  w.BeginObject();
  w.FieldBool("flag", false);
  w.FieldInt("big", 1LL << 52);
  w.EndObject();
  w.EndArray();
  w.EndObject();
  absl::StatusOr<JsonValue> v = ParseJson(w.str(), "written");
  ASSERT_TRUE(v.ok()) << v.status() << "\n" << w.str();
  EXPECT_EQ(v->Find("text")->string(), text);
  ASSERT_EQ(v->Find("numbers")->array().size(), numbers.size());
  for (size_t i = 0; i < numbers.size(); ++i)
    EXPECT_EQ(v->Find("numbers")->array()[i].number(), numbers[i]) << i;
  const JsonValue& inner = v->Find("nested")->array()[0];
  EXPECT_TRUE(inner.Find("flag")->is_bool());
  EXPECT_FALSE(inner.Find("flag")->boolean());
  EXPECT_EQ(inner.Find("big")->number(), 4503599627370496.0);
  EXPECT_EQ(inner.line(), 5);  // the writer's layout: one member a line
}

TEST(Json, EscapeWritesValidJsonForAnyBytes) {
  EXPECT_EQ(JsonEscape("\b\f\x1f"), "\"\\b\\f\\u001f\"");
  // Invalid UTF-8 is replaced (U+FFFD), so the output always parses.
  const std::string escaped = JsonEscape(
      "a\xff"
      "b");
  EXPECT_EQ(escaped,
            "\"a\xef\xbf\xbd"
            "b\"");
  EXPECT_TRUE(ParseJson(escaped, "escaped").ok());
}

}  // namespace
}  // namespace tactforce::io
