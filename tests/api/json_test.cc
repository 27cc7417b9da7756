#include "tactforce/api/json.h"

#include <random>
#include <string>
#include <vector>

#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include "absl/strings/str_cat.h"
#include "google/protobuf/util/message_differencer.h"
#include "tactforce/api/convert.h"
#include "support/test_seed.h"

namespace tactforce::api {
namespace {

using google::protobuf::util::MessageDifferencer;
using ::testing::HasSubstr;
using ::testing::Not;

constexpr char kSnakeCase[] = R"({
  "object": {"mass": 0.082, "com": {"x": 0, "y": 0, "z": 0.001},
             "gravity": {"x": 0, "y": 0, "z": -9.81}},
  "contacts": [
    {"name": "thumb", "position": {"x": 0.03}, "normal": {"x": -1},
     "friction": 0.8, "kind": "CONTACT_KIND_INTRINSIC", "sigma": 0.2,
     "min_normal_force": 0.1, "max_normal_force": 10},
    {"name": "index", "position": {"x": -0.03}, "normal": {"x": 1},
     "friction": 0.8, "kind": "CONTACT_KIND_EXTRINSIC"}
  ],
  "external_wrench": {"force": {"z": -0.5}, "torque": {"y": 0.01}},
  "cone": "CONE_MODEL_PYRAMID",
  "cone_sides": 16,
  "confidence": 2,
  "solver": "SOLVER_CROSS_CHECK"
})";

constexpr char kCamelCase[] = R"({
  "object": {"mass": 0.082, "com": {"x": 0, "y": 0, "z": 0.001},
             "gravity": {"x": 0, "y": 0, "z": -9.81}},
  "contacts": [
    {"name": "thumb", "position": {"x": 0.03}, "normal": {"x": -1},
     "friction": 0.8, "kind": "CONTACT_KIND_INTRINSIC", "sigma": 0.2,
     "minNormalForce": 0.1, "maxNormalForce": 10},
    {"name": "index", "position": {"x": -0.03}, "normal": {"x": 1},
     "friction": 0.8, "kind": "CONTACT_KIND_EXTRINSIC"}
  ],
  "externalWrench": {"force": {"z": -0.5}, "torque": {"y": 0.01}},
  "cone": "CONE_MODEL_PYRAMID",
  "coneSides": 16,
  "confidence": 2,
  "solver": "SOLVER_CROSS_CHECK"
})";

TEST(JsonTest, SnakeCaseAndCamelCaseGiveTheSameRequest) {
  absl::StatusOr<v1::PlanRequest> snake = ParsePlanRequestJson(kSnakeCase);
  absl::StatusOr<v1::PlanRequest> camel = ParsePlanRequestJson(kCamelCase);
  ASSERT_TRUE(snake.ok()) << snake.status();
  ASSERT_TRUE(camel.ok()) << camel.status();
  EXPECT_TRUE(MessageDifferencer::Equals(*snake, *camel)) << snake->DebugString() << "\nvs\n"
                                                          << camel->DebugString();

  EXPECT_EQ(snake->contacts_size(), 2);
  EXPECT_EQ(snake->contacts(0).min_normal_force(), 0.1);
  EXPECT_EQ(snake->contacts(0).max_normal_force(), 10);
  EXPECT_EQ(snake->external_wrench().force().z(), -0.5);
  EXPECT_EQ(snake->cone_sides(), 16u);
  EXPECT_TRUE(snake->has_confidence());
  EXPECT_EQ(snake->confidence(), 2.0);
  EXPECT_TRUE(snake->object().has_gravity());
  EXPECT_EQ(snake->solver(), v1::SOLVER_CROSS_CHECK);
}

TEST(JsonTest, AbsentOptionalFieldsStayAbsent) {
  absl::StatusOr<v1::PlanRequest> r = ParsePlanRequestJson(R"({"object": {"mass": 1}})");
  ASSERT_TRUE(r.ok()) << r.status();
  EXPECT_FALSE(r->has_confidence());
  EXPECT_FALSE(r->object().has_gravity());
}

TEST(JsonTest, UnknownFieldIsAnErrorNamingIt) {
  absl::StatusOr<v1::PlanRequest> r =
      ParsePlanRequestJson(R"({"contacts": [{"name": "a", "frictoin": 0.5}]})");
  ASSERT_FALSE(r.ok());
  EXPECT_EQ(r.status().code(), absl::StatusCode::kInvalidArgument);
  EXPECT_THAT(std::string(r.status().message()), HasSubstr("frictoin"));
}

TEST(JsonTest, UnknownEnumNameIsAnError) {
  absl::StatusOr<v1::PlanRequest> r =
      ParsePlanRequestJson(R"({"contacts": [{"kind": "CONTACT_KIND_MAGNETIC"}]})");
  ASSERT_FALSE(r.ok());
  EXPECT_EQ(r.status().code(), absl::StatusCode::kInvalidArgument);
  EXPECT_THAT(std::string(r.status().message()), HasSubstr("contacts[0].kind"));
}

TEST(JsonTest, UnknownNumericEnumIsCaughtByTheConversion) {
  // proto3 enums are open: protobuf keeps the number, FromProto rejects it.
  absl::StatusOr<v1::PlanRequest> r =
      ParsePlanRequestJson(R"({"contacts": [{}, {"kind": 7}], "solver": 1})");
  ASSERT_TRUE(r.ok()) << r.status();
  absl::StatusOr<PlanCall> call = FromProto(*r);
  ASSERT_FALSE(call.ok());
  EXPECT_EQ(call.status().message(), "contacts[1].kind: unknown value 7");
}

TEST(JsonTest, MalformedJsonIsAnErrorOnOneLine) {
  for (const char* text : {R"({"contacts": [ {"name": "a"})", "{", "not json", "[1, 2]",
                           R"({"cone_sides": -1})", ""}) {
    SCOPED_TRACE(text);
    absl::StatusOr<v1::PlanRequest> r = ParsePlanRequestJson(text);
    ASSERT_FALSE(r.ok());
    EXPECT_EQ(r.status().code(), absl::StatusCode::kInvalidArgument);
    const std::string message(r.status().message());
    EXPECT_THAT(message, HasSubstr("request JSON:"));
    EXPECT_THAT(message, Not(HasSubstr("\n")));
  }
}

// "<source>:<line>:<column>: <what>" for syntax errors, unknown fields and
// enum names, with the nearest valid names.
TEST(JsonTest, ErrorsNameFileLineColumnAndSuggestNames) {
  struct Case {
    const char* text;
    const char* located;  // "line:column: " after the source
    const char* what;
  };
  const Case cases[] = {
      {"{\n  \"object\": {\"mas\": 0.1}\n}",
       "2:14: ", "object: unknown field 'mas' in ObjectModel; did you mean 'mass'?"},
      {"{\"contacts\": [{}, {\"nromal\": {\"x\": 1}}]}",
       "1:20: ", "contacts[1]: unknown field 'nromal' in Contact; did you mean 'normal'?"},
      {"{\"cone\": \"CONE_MODEL_PYRAMD\"}", "1:",
       "cone: unknown ConeModel value 'CONE_MODEL_PYRAMD'; did you mean "
       "'CONE_MODEL_PYRAMID'?"},
      {"{\n\n  \"contacts\": [\n    {\"position\": {\"x\": 1,}}]}", "4:", "expected"},
      {"{\"contacts\": {\"name\": \"a\"}}", "1:14: ", "contacts: expected a JSON array"},
      {"{\"zzzzzzzz\": 1}",
       "1:2: ", "unknown field 'zzzzzzzz' in PlanRequest; expected one of: object, contacts"},
  };
  for (const Case& c : cases) {
    SCOPED_TRACE(c.text);
    v1::PlanRequest request;
    absl::Status status = ParseJson(c.text, &request, "grasp.json");
    ASSERT_FALSE(status.ok());
    EXPECT_EQ(status.code(), absl::StatusCode::kInvalidArgument);
    const std::string message(status.message());
    EXPECT_EQ(message.rfind(std::string("grasp.json:") + c.located, 0), 0u) << message;
    EXPECT_THAT(message, HasSubstr(c.what));
  }
  // lowerCamelCase names are fields too, and a wrong value type still names its field.
  v1::PlanRequest request;
  EXPECT_TRUE(
      ParseJson(R"({"coneSides": 8, "contacts": [{"minNormalForce": 1}]})", &request, "a.json")
          .ok());
  absl::Status wrong_type = ParseJson(R"({"cone_sides": "many"})", &request, "a.json");
  EXPECT_THAT(std::string(wrong_type.message()), HasSubstr("cone_sides"));
}

// A value of the wrong JSON kind keeps its file:line:column like a misspelt
// name (protobuf's own message has neither). Where the value sits is drawn
// from a seed at test time.
TEST(JsonTest, WrongValueTypesNameFileLineColumn) {
  struct Case {
    std::string field, value, path, what;
  };
  const std::vector<Case> cases = {
      {R"("object": {"mass": )", R"("heavy"})", "object.mass",
       R"(expected a number (double), got the string "heavy")"},
      {R"("cone_sides": )", "4.5", "cone_sides",
       "expected an integer (uint32), got the number 4.5"},
      {R"("cone_sides": )", R"("12x")", "cone_sides",
       R"(expected an integer (uint32), got the string "12x")"},
      {R"("contacts": [{"name": )", "3}]", "contacts[0].name",
       "expected a string, got the number 3"},
      {R"("contacts": [{"friction": )", "true}]", "contacts[0].friction",
       "expected a number (double), got true"},
      {R"("object": {"com": {"x": )", "[1]}}", "object.com.x",
       "expected a number (double), got an array"},
  };
  std::mt19937 rng(::tactforce::testing::GtestSeed() + 7);
  for (const Case& c : cases) {
    const int blank_lines = std::uniform_int_distribution<int>(0, 5)(rng);
    const int indent = std::uniform_int_distribution<int>(0, 8)(rng);
    const std::string prefix =
        std::string("{") + std::string(blank_lines, '\n') + std::string(indent, ' ') + c.field;
    const std::string text = prefix + c.value + "}";
    SCOPED_TRACE(text);
    v1::PlanRequest request;
    const absl::Status status = ParseJson(text, &request, "w.json");
    ASSERT_FALSE(status.ok());
    const size_t line_start = blank_lines > 0 ? prefix.rfind('\n') + 1 : 0;
    const size_t column = prefix.size() - line_start + 1;  // 1-based, of the value
    const std::string located = absl::StrCat("w.json:", blank_lines + 1, ":", column, ": ");
    EXPECT_EQ(std::string(status.message()), located + c.path + ": " + c.what);
  }
  // Quoted numbers and the special values are proto3 JSON and stay accepted.
  v1::PlanRequest request;
  EXPECT_TRUE(
      ParseJson(R"({"object": {"mass": "0.5", "com": {"x": "NaN"}}, "cone_sides": "8"})", &request)
          .ok());
}

TEST(JsonTest, RequestJsonRoundTrip) {
  absl::StatusOr<v1::PlanRequest> first = ParsePlanRequestJson(kCamelCase);
  ASSERT_TRUE(first.ok()) << first.status();
  for (bool compact : {false, true}) {
    const std::string json = ToJson(*first, compact);
    absl::StatusOr<v1::PlanRequest> second = ParsePlanRequestJson(json);
    ASSERT_TRUE(second.ok()) << second.status() << "\n" << json;
    EXPECT_TRUE(MessageDifferencer::Equals(*first, *second)) << json;
  }
}

TEST(JsonTest, ResponseJsonKeepsProtoNamesAndPrintsZeros) {
  v1::PlanResponse response;
  response.set_status(v1::PLAN_STATUS_OPTIMAL);
  response.add_normal_forces(1.5);
  const std::string json = ToJson(response);
  EXPECT_THAT(json, HasSubstr(R"("status": "PLAN_STATUS_OPTIMAL")"));
  EXPECT_THAT(json, HasSubstr(R"("normal_forces")"));
  EXPECT_THAT(json, HasSubstr(R"("min_margin": 0)"));
  EXPECT_THAT(json, HasSubstr(R"("iterations": 0)"));
  EXPECT_THAT(json, HasSubstr(R"("solve_time_us")"));
  EXPECT_THAT(json, HasSubstr(R"("message": "")"));
  EXPECT_THAT(json, Not(HasSubstr("minMargin")));
  EXPECT_THAT(json, Not(HasSubstr("cross_check")));  // absent message field
  EXPECT_EQ(json.back(), '\n');

  response.mutable_cross_check()->set_agree(true);
  EXPECT_THAT(ToJson(response, /*compact=*/true), HasSubstr(R"("cross_check":{"agree":true)"));
}

}  // namespace
}  // namespace tactforce::api
