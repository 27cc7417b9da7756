// `tactforce load` against real tactforce-server processes (loopback only):
// the JSON report, each RPC kind and engine, open loop, request files and
// built-in examples of estimate, fit-inertia and audit, the --plot SVG
// (parsed back as XML), flag validation, and client-side round-robin over
// two replicas.
#include <cctype>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <map>
#include <sstream>
#include <string>
#include <string_view>
#include <vector>

#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include "support/svg_legibility.h"
#include "absl/strings/str_cat.h"
#include "support/cli_fixture.h"
#include "tactforce/api/inertia.h"
#include "tactforce/api/json.h"
#include "tactforce/inertia/simulate.h"
#include "tactforce/io/status_macros.h"

namespace tactforce::cli_testing {
namespace {

using ::testing::HasSubstr;

// Parses `load --json` output and checks the documented fields.
google::protobuf::Struct ParseReport(const ProcessResult& run) {
  absl::StatusOr<google::protobuf::Struct> json = ParseJsonObject(run.out);
  EXPECT_TRUE(json.ok()) << json.status() << "\n" << Describe(run);
  if (!json.ok()) return {};
  const auto& f = json->fields();
  for (const char* field :
       {"rpc", "concurrency", "requests", "duration_s", "qps", "latency_us", "errors"}) {
    EXPECT_TRUE(f.contains(field)) << field << " missing: " << run.out;
  }
  if (!f.contains("latency_us")) return *json;
  const auto& latency = f.at("latency_us").struct_value().fields();
  double previous = 0;
  for (const char* p : {"p50", "p90", "p99", "p999", "max"}) {
    EXPECT_TRUE(latency.contains(p)) << p << " missing: " << run.out;
    if (!latency.contains(p)) continue;
    const double value = latency.at(p).number_value();
    EXPECT_GE(value, previous) << p << " below the lower percentile: " << run.out;
    previous = value;
  }
  EXPECT_GT(latency.at("p50").number_value(), 0);
  return *json;
}

double Number(const google::protobuf::Struct& json, const std::string& field) {
  return json.fields().contains(field) ? json.fields().at(field).number_value() : -1;
}

int ErrorKinds(const google::protobuf::Struct& json) {
  return json.fields().contains("errors") ? json.fields().at("errors").struct_value().fields_size()
                                          : -1;
}

class LoadTest : public RemoteCliTest {};

TEST_F(LoadTest, PlanMixJsonHasNoErrors) {
  const ProcessResult run = Tactforce({"load", "--target", address(), "--rpc", "plan", "--requests",
                                       "2000", "--concurrency", "8", "--mix", "--json"});
  ASSERT_EQ(run.exit_code, 0) << Describe(run);
  const google::protobuf::Struct json = ParseReport(run);
  EXPECT_EQ(json.fields().at("rpc").string_value(), "plan");
  EXPECT_EQ(Number(json, "concurrency"), 8);
  EXPECT_EQ(Number(json, "requests"), 2000);
  EXPECT_EQ(ErrorKinds(json), 0) << run.out;
  EXPECT_GT(Number(json, "qps"), 0);
  EXPECT_GT(Number(json, "duration_s"), 0);
}

TEST_F(LoadTest, StreamCallbackAndSync) {
  for (const char* engine : {"callback", "sync"}) {
    SCOPED_TRACE(engine);
    const ProcessResult run =
        Tactforce({"load", "--target", address(), "--rpc", "stream", "--requests", "1000",
                   "--concurrency", "4", "--engine", engine, "--json"});
    ASSERT_EQ(run.exit_code, 0) << Describe(run);
    const google::protobuf::Struct json = ParseReport(run);
    EXPECT_EQ(json.fields().at("rpc").string_value(), "stream");
    EXPECT_EQ(Number(json, "requests"), 1000);
    EXPECT_EQ(ErrorKinds(json), 0) << run.out;
  }
}

TEST_F(LoadTest, HealthAndSyncPlan) {
  ProcessResult run = Tactforce({"load", "--target", address(), "--rpc", "health", "--requests",
                                 "1000", "-c", "4", "--json"});
  ASSERT_EQ(run.exit_code, 0) << Describe(run);
  google::protobuf::Struct json = ParseReport(run);
  EXPECT_EQ(json.fields().at("rpc").string_value(), "health");
  EXPECT_EQ(Number(json, "requests"), 1000);

  run = Tactforce({"load", "--target", address(), "--rpc", "plan", "--engine", "sync", "--requests",
                   "500", "-c", "3", "--json"});
  ASSERT_EQ(run.exit_code, 0) << Describe(run);
  json = ParseReport(run);
  EXPECT_EQ(Number(json, "requests"), 500);
  EXPECT_EQ(ErrorKinds(json), 0) << run.out;
}

TEST_F(LoadTest, OpenLoopKeepsTheRate) {
  // 300 calls at 1000/s: ~0.3 s on schedule.
  const ProcessResult run =
      Tactforce({"load", "--target", address(), "--rate", "1000", "--requests", "300", "--json"});
  ASSERT_EQ(run.exit_code, 0) << Describe(run);
  const google::protobuf::Struct json = ParseReport(run);
  EXPECT_EQ(json.fields().at("mode").string_value(), "open");
  EXPECT_EQ(Number(json, "requests"), 300);
  EXPECT_GE(Number(json, "duration_s"), 0.29);
}

TEST_F(LoadTest, DurationBoundAndTextReport) {
  const ProcessResult run =
      Tactforce({"load", "--target", address(), "--duration", "0.5", "-c", "2", "--progress"});
  ASSERT_EQ(run.exit_code, 0) << Describe(run);
  EXPECT_THAT(run.out, HasSubstr("throughput"));
  EXPECT_THAT(run.out, HasSubstr("p99.9"));
  EXPECT_THAT(run.out, HasSubstr("errors      none"));
  EXPECT_TRUE(run.err.empty()) << run.err;  // no progress line before 2 s
}

TEST_F(LoadTest, RequestFileAndItsErrors) {
  const std::string good = dir_.Write("pinch.json", ExampleRequestJson());
  ProcessResult run =
      Tactforce({"load", "--target", address(), "--request", good, "--requests", "200", "--json"});
  ASSERT_EQ(run.exit_code, 0) << Describe(run);
  EXPECT_EQ(Number(ParseReport(run), "requests"), 200);

  v1::PlanRequest request = RandomRequest(41, 3, v1::SOLVER_GEOMETRIC);
  request.mutable_contacts(2)->set_friction(-1);
  const std::string bad = dir_.Write("bad.json", RequestJson(request));
  run = Tactforce({"load", "--target", address(), "--request", bad, "--requests", "10"});
  EXPECT_EQ(run.exit_code, 2) << Describe(run);
  EXPECT_THAT(run.err, HasSubstr("contacts[2].friction"));

  run = Tactforce(
      {"load", "--target", address(), "--rpc", "stream", "--rate", "10", "--requests", "10"});
  EXPECT_EQ(run.exit_code, 2) << Describe(run);
}

// ------------------------------------------- estimate, fit-inertia, audit

TEST_F(LoadTest, NewRpcsWithBuiltInRequestsHaveNoErrors) {
  for (const char* rpc : {"estimate", "fit-inertia", "audit"}) {
    SCOPED_TRACE(rpc);
    const ProcessResult run = Tactforce(
        {"load", "--target", address(), "--rpc", rpc, "--duration", "0.5", "-c", "2", "--json"});
    ASSERT_EQ(run.exit_code, 0) << Describe(run);
    const google::protobuf::Struct json = ParseReport(run);
    EXPECT_EQ(json.fields().at("rpc").string_value(), rpc);
    EXPECT_GT(Number(json, "requests"), 0) << run.out;
    EXPECT_EQ(Number(json, "ok"), Number(json, "requests")) << run.out;
    EXPECT_EQ(ErrorKinds(json), 0) << run.out;
    EXPECT_GT(Number(json, "qps"), 0);
  }
}

TEST_F(LoadTest, NewRpcsSyncEngineAndOpenLoop) {
  ProcessResult run = Tactforce({"load", "--target", address(), "--rpc", "estimate", "--engine",
                                 "sync", "--requests", "200", "-c", "2", "--json"});
  ASSERT_EQ(run.exit_code, 0) << Describe(run);
  EXPECT_EQ(Number(ParseReport(run), "requests"), 200);
  run = Tactforce({"load", "--target", address(), "--rpc", "fit-inertia", "--engine", "sync",
                   "--requests", "6", "-c", "2", "--json"});
  ASSERT_EQ(run.exit_code, 0) << Describe(run);
  EXPECT_EQ(ErrorKinds(ParseReport(run)), 0) << run.out;
  // 20 whole streams at 100/s: ~0.2 s on schedule.
  run = Tactforce({"load", "--target", address(), "--rpc", "fit-inertia", "--rate", "100",
                   "--requests", "20", "--json"});
  ASSERT_EQ(run.exit_code, 0) << Describe(run);
  const google::protobuf::Struct json = ParseReport(run);
  EXPECT_EQ(json.fields().at("mode").string_value(), "open");
  EXPECT_EQ(Number(json, "requests"), 20);
  EXPECT_EQ(ErrorKinds(json), 0) << run.out;
}

// An EstimateRequest for the pinch of sphere_pinch.json with both readings.
constexpr char kEstimateJson[] = R"({
  "object": {"mass": 0.082},
  "contacts": [
    {"name": "thumb", "position": {"x": -0.035}, "normal": {"x": 1}, "friction": 0.8, "sigma": 0.3},
    {"name": "index", "position": {"x": 0.035}, "normal": {"x": -1}, "friction": 0.8, "sigma": 0.3}
  ],
  "readings": [1.0, 1.0]
})";

// A FitInertia stream as a JSON list: the options with the first 100
// samples, then the rest (2 s at 100 Hz of the simulated object).
std::string FitInertiaStreamJson() {
  inertia::SimulationOptions options;
  options.duration = 2.0;
  options.seed = 3;
  absl::StatusOr<inertia::SimulationResult> sim = inertia::SimulateInertia(options);
  EXPECT_TRUE(sim.ok()) << sim.status();
  if (!sim.ok()) return "[]";
  v1::FitInertiaRequest first, second;
  first.mutable_options()->set_method(v1::INERTIA_METHOD_CONSTRAINED);
  const std::vector<inertia::InertiaSample>& samples = sim->samples.samples;
  for (size_t i = 0; i < samples.size(); ++i) {
    *(i < 100 ? first : second).add_samples() =
        api::InertiaSampleToProto(samples[i], sim->samples.source);
  }
  return absl::StrCat("[", api::ToJson(first, /*compact=*/true), ", ", api::ToJson(second, true),
                      "]");
}

TEST_F(LoadTest, NewRpcsWithRequestFiles) {
  const std::string estimate = dir_.Write("estimate.json", kEstimateJson);
  const std::string estimates =
      dir_.Write("estimates.json", absl::StrCat("[", kEstimateJson, ",", kEstimateJson, "]"));
  const std::string stream = dir_.Write("stream.json", FitInertiaStreamJson());
  const ProcessResult sim =
      Tactforce({"simulate", "inertia", "--seconds", "2", "--out", dir_.Path("sim")});
  ASSERT_EQ(sim.exit_code, 0) << Describe(sim);
  const std::vector<std::vector<std::string>> cases = {
      {"--rpc", "estimate", "--request", estimate},
      {"--rpc", "estimate", "--request", estimates},
      {"--rpc", "fit-inertia", "--request", stream},
      {"--rpc", "fit-inertia", "--request", dir_.Path("sim") + "/inertia.csv", "--batch", "64"}};
  for (const std::vector<std::string>& flags : cases) {
    SCOPED_TRACE(flags[1] + " " + flags[3]);
    std::vector<std::string> args = {"load", "--target", address(), "--requests",
                                     "8",    "-c",       "2",       "--json"};
    args.insert(args.end(), flags.begin(), flags.end());
    const ProcessResult run = Tactforce(args);
    ASSERT_EQ(run.exit_code, 0) << Describe(run);
    const google::protobuf::Struct json = ParseReport(run);
    EXPECT_EQ(Number(json, "requests"), 8);
    EXPECT_EQ(ErrorKinds(json), 0) << run.out;
  }
}

TEST_F(LoadTest, NewRpcsRejectBadRequestFiles) {
  // The server refuses the warm-up call: INVALID_ARGUMENT naming the field.
  std::string one_reading = kEstimateJson;
  one_reading.replace(one_reading.find("[1.0, 1.0]"), 10, "[1.0]");
  ProcessResult run = Tactforce({"load", "--target", address(), "--rpc", "estimate", "--request",
                                 dir_.Write("short.json", one_reading), "--requests", "5"});
  EXPECT_EQ(run.exit_code, 2) << Describe(run);
  EXPECT_THAT(run.err, HasSubstr("readings"));
  // Neither JSON nor an inertia CSV.
  run = Tactforce({"load", "--target", address(), "--rpc", "fit-inertia", "--request",
                   dir_.Write("junk.txt", "hello\n"), "--requests", "5"});
  EXPECT_EQ(run.exit_code, 2) << Describe(run);
  EXPECT_THAT(run.err, HasSubstr("--request"));
  // A misspelt field in the second request of a list: named with its line.
  const std::string bad_list =
      dir_.Write("bad_list.json", "[\n  {\"readings\": [1]},\n  {\"readngs\": [1]}\n]\n");
  run = Tactforce({"load", "--target", address(), "--rpc", "estimate", "--request", bad_list,
                   "--requests", "5"});
  EXPECT_EQ(run.exit_code, 2) << Describe(run);
  EXPECT_THAT(run.err, HasSubstr("bad_list.json:3:"));
  EXPECT_THAT(run.err, HasSubstr("readngs"));
  // A misspelt field in an AuditRequest.
  run = Tactforce({"load", "--target", address(), "--rpc", "audit", "--request",
                   dir_.Write("audit.json", R"({"sampels": []})"), "--requests", "5"});
  EXPECT_EQ(run.exit_code, 2) << Describe(run);
  EXPECT_THAT(run.err, HasSubstr("audit.json"));
}

// ----------------------------------------------------------------- --plot

// An XML element of the SVG as parsed back.
struct XmlElement {
  std::string name;
  std::map<std::string, std::string> attributes;
  std::string text;  // character data directly inside, entities as written
  std::vector<XmlElement> children;

  std::string Attribute(const std::string& key) const {
    auto it = attributes.find(key);
    return it == attributes.end() ? "" : it->second;
  }
};

// A strict small XML parser for what SvgCanvas writes: the root element with
// nested elements, attributes in quotes, character data and comments. Every
// element must be closed by its own name and nothing may follow the root;
// errors say where.
class XmlParser {
 public:
  explicit XmlParser(std::string_view text) : text_(text) {}

  absl::StatusOr<XmlElement> Document() {
    Skip();
    if (text_.substr(at_, 5) == "<?xml") at_ = text_.find("?>", at_) + 2;
    Skip();
    XmlElement root;
    TF_RETURN_IF_ERROR(Element(&root));
    Skip();
    if (at_ != text_.size()) return Error("content after the root element");
    return root;
  }

 private:
  absl::Status Error(const std::string& what) const {
    return absl::InvalidArgumentError(what + " at byte " + std::to_string(at_));
  }
  void Skip() {
    while (at_ < text_.size() && std::isspace(static_cast<unsigned char>(text_[at_]))) ++at_;
  }
  std::string Name() {
    const size_t start = at_;
    while (at_ < text_.size() && (std::isalnum(static_cast<unsigned char>(text_[at_])) ||
                                  std::string_view("-_:.").find(text_[at_]) != std::string::npos)) {
      ++at_;
    }
    return std::string(text_.substr(start, at_ - start));
  }

  absl::Status Attributes(XmlElement* e) {
    for (Skip(); at_ < text_.size() && text_[at_] != '>' && text_[at_] != '/'; Skip()) {
      const std::string key = Name();
      Skip();
      if (key.empty() || at_ >= text_.size() || text_[at_] != '=') return Error("bad attribute");
      ++at_;
      Skip();
      const char quote = at_ < text_.size() ? text_[at_] : '\0';
      const size_t end =
          quote == '"' || quote == '\'' ? text_.find(quote, at_ + 1) : std::string::npos;
      if (end == std::string::npos) return Error("unquoted or unterminated attribute " + key);
      if (!e->attributes.emplace(key, std::string(text_.substr(at_ + 1, end - at_ - 1))).second) {
        return Error("duplicate attribute " + key);
      }
      at_ = end + 1;
    }
    return at_ < text_.size() ? absl::OkStatus() : Error("unterminated start tag");
  }

  absl::Status Element(XmlElement* e) {
    if (at_ >= text_.size() || text_[at_] != '<') return Error("expected an element");
    ++at_;
    e->name = Name();
    if (e->name.empty()) return Error("element without a name");
    TF_RETURN_IF_ERROR(Attributes(e));
    if (text_[at_] == '/') {
      at_ += 2;  // "/>"
      return text_[at_ - 1] == '>' ? absl::OkStatus() : Error("bad empty-element tag");
    }
    ++at_;  // '>'
    while (true) {
      const size_t lt = text_.find('<', at_);
      if (lt == std::string::npos) return Error("unclosed <" + e->name + ">");
      e->text += std::string(text_.substr(at_, lt - at_));
      at_ = lt;
      if (text_.substr(at_, 4) == "<!--") {
        at_ = text_.find("-->", at_) + 3;
      } else if (text_.substr(at_, 2) == "</") {
        at_ += 2;
        if (Name() != e->name) return Error("</...> does not close <" + e->name + ">");
        Skip();
        if (at_ >= text_.size() || text_[at_] != '>') return Error("bad end tag");
        ++at_;
        return absl::OkStatus();
      } else {
        e->children.emplace_back();
        TF_RETURN_IF_ERROR(Element(&e->children.back()));
      }
    }
  }

  std::string_view text_;
  size_t at_ = 0;
};

// Every element below `e` (depth first) named `name`.
void FindAll(const XmlElement& e, const std::string& name, std::vector<const XmlElement*>* out) {
  for (const XmlElement& child : e.children) {
    if (child.name == name) out->push_back(&child);
    FindAll(child, name, out);
  }
}

const XmlElement* FindById(const XmlElement& root, const std::string& id) {
  std::vector<const XmlElement*> groups;
  FindAll(root, "g", &groups);
  for (const XmlElement* g : groups) {
    if (g->Attribute("id") == id) return g;
  }
  return nullptr;
}

std::string AllText(const XmlElement& root) {
  std::vector<const XmlElement*> texts;
  FindAll(root, "text", &texts);
  std::string out;
  for (const XmlElement* t : texts) out += t->text + "\n";
  return out;
}

std::string ReadWholeFile(const std::string& path) {
  std::ifstream in(path, std::ios::binary);
  std::stringstream buffer;
  buffer << in.rdbuf();
  return buffer.str();
}

TEST_F(LoadTest, PlotHasHistogramBarsAndCallsPerSecond) {
  const std::string plot = dir_.Path("latency.svg");
  const ProcessResult run = Tactforce({"load", "--target", address(), "--rpc", "estimate",
                                       "--duration", "0.6", "-c", "2", "--json", "--plot", plot});
  ASSERT_EQ(run.exit_code, 0) << Describe(run);
  const double ok = Number(ParseReport(run), "ok");
  ASSERT_GT(ok, 0);
  // Written under a temporary name and renamed: only the plot is left.
  int files = 0;
  const std::filesystem::path dir = std::filesystem::path(plot).parent_path();
  for (const auto& entry : std::filesystem::directory_iterator(dir)) {
    EXPECT_EQ(entry.path().filename().string(), "latency.svg");
    ++files;
  }
  EXPECT_EQ(files, 1);

  const std::string svg = ReadWholeFile(plot);
  absl::StatusOr<XmlElement> root = XmlParser(svg).Document();
  ASSERT_TRUE(root.ok()) << root.status() << "\n" << svg.substr(0, 500);
  EXPECT_EQ(root->name, "svg");
  EXPECT_EQ(root->Attribute("xmlns"), "http://www.w3.org/2000/svg");

  const XmlElement* histogram = FindById(*root, "latency-histogram");
  ASSERT_NE(histogram, nullptr) << svg;
  int64_t counted = 0;
  int bars = 0;
  for (const XmlElement& bar : histogram->children) {
    ASSERT_EQ(bar.Attribute("class"), "bar");
    ASSERT_EQ(bar.children.size(), 2u);
    EXPECT_EQ(bar.children[0].name, "rect");
    EXPECT_GT(std::stod(bar.children[0].Attribute("height")), 0);
    EXPECT_LT(std::stod(bar.Attribute("data-low-us")), std::stod(bar.Attribute("data-high-us")));
    counted += std::stoll(bar.Attribute("data-count"));
    ++bars;
  }
  EXPECT_GT(bars, 0);
  EXPECT_EQ(counted, static_cast<int64_t>(ok)) << "every successful call in one bar";

  const XmlElement* qps = FindById(*root, "qps");
  ASSERT_NE(qps, nullptr) << svg;
  std::vector<const XmlElement*> paths, points;
  FindAll(*qps, "path", &paths);
  FindAll(*qps, "circle", &points);
  ASSERT_EQ(paths.size(), 1u);
  EXPECT_EQ(paths[0]->Attribute("d").rfind("M", 0), 0u);
  EXPECT_NE(paths[0]->Attribute("d").find('L'), std::string::npos) << "a line through the points";
  EXPECT_GE(points.size(), 4u) << "0.6 s in 0.1 s intervals";
  EXPECT_EQ(FindById(*root, "qps-failed"), nullptr) << "no failed calls";

  const std::string text = AllText(*root);
  EXPECT_THAT(text, HasSubstr("--rpc estimate"));
  EXPECT_THAT(text, HasSubstr("concurrency 2"));
  EXPECT_THAT(text, HasSubstr("calls/s"));
  EXPECT_THAT(text, HasSubstr("[s]"));
  EXPECT_THAT(text, HasSubstr("µs"));
  test_support::ExpectLegible(svg, "load plot");
}

// ------------------------------------------------------------- bad flags

TEST_F(LoadTest, BadFlagsExitTwoNamingThemselves) {
  const std::string request = dir_.Write("estimate.json", kEstimateJson);
  const std::vector<std::pair<std::vector<std::string>, std::string>> cases = {
      {{"--concurrency", "0"}, "--concurrency"},
      {{"-c", "many"}, "--concurrency"},
      {{"--duration", "0"}, "--duration"},
      {{"--duration", "-2"}, "--duration"},
      {{"--duration", "nan"}, "--duration"},
      {{"--rate", "-1"}, "--rate"},
      {{"--rate", "nan"}, "--rate"},
      {{"--requests", "0"}, "--requests"},
      {{"--channels", "0"}, "--channels"},
      {{"--mix-size", "0"}, "--mix-size"},
      {{"--seed", "-1"}, "--seed"},
      {{"--rpc", "fit-inertia", "--batch", "0"}, "--batch"},
      {{"--deadline-ms", "-5"}, "--deadline-ms"},
      {{"--rpc", "bogus"}, "--rpc"},
      {{"--rpc", "audit", "--mix"}, "--mix"},
      {{"--rpc", "health", "--request", request}, "--request"},
      {{"--rpc", "estimate", "--batch", "10"}, "--batch"},
      {{"--rpc", "stream", "--rate", "10"}, "--rate"},
      {{"--plot", dir_.Path("no_such_dir/latency.svg")}, "--plot"},
  };
  for (const auto& [flags, name] : cases) {
    SCOPED_TRACE(flags[0] + " " + flags[1]);
    std::vector<std::string> args = {"load", "--target", address(), "--requests", "5"};
    if (flags[0] == "--requests") args.resize(3);
    args.insert(args.end(), flags.begin(), flags.end());
    const ProcessResult run = Tactforce(args);
    EXPECT_EQ(run.exit_code, 2) << Describe(run);
    EXPECT_THAT(run.err, HasSubstr(name));
    EXPECT_TRUE(run.out.empty()) << run.out;
  }
}

// ---------------------------------------------------------- two replicas

// Requests each replica logged (one "rpc=Plan " line per call at info).
int PlanLines(const ServerProcess& server) {
  const std::string log = server.StderrText();
  int lines = 0;
  for (size_t at = log.find("rpc=Plan "); at != std::string::npos;
       at = log.find("rpc=Plan ", at + 1)) {
    ++lines;
  }
  return lines;
}

TEST(LoadReplicasTest, TargetListSpreadsOverBothReplicas) {
  std::unique_ptr<ServerProcess> a = StartServer({"--log-level", "info"});
  std::unique_ptr<ServerProcess> b = StartServer({"--log-level", "info"});
  ASSERT_NE(a, nullptr);
  ASSERT_NE(b, nullptr);
  // gRPC's round_robin policy over an ipv4: target, then one channel per
  // address with the client's own rotation.
  const std::vector<std::string> targets = {"ipv4:" + a->address() + "," + b->address(),
                                            a->address() + "," + b->address()};
  for (const std::string& target : targets) {
    SCOPED_TRACE(target);
    const int before_a = PlanLines(*a), before_b = PlanLines(*b);
    const ProcessResult run =
        Tactforce({"load", "--target", target, "--requests", "1000", "-c", "4", "--json"});
    ASSERT_EQ(run.exit_code, 0) << Describe(run);
    EXPECT_EQ(Number(ParseReport(run), "requests"), 1000);
    // Logging is synchronous per call, so the lines are there.
    const int served_a = PlanLines(*a) - before_a, served_b = PlanLines(*b) - before_b;
    EXPECT_GE(served_a + served_b, 1000);
    EXPECT_GE(served_a, 250) << "replica a served " << served_a << ", b " << served_b;
    EXPECT_GE(served_b, 250) << "replica a served " << served_a << ", b " << served_b;
  }
  EXPECT_EQ(a->Stop(), 0);
  EXPECT_EQ(b->Stop(), 0);
}

}  // namespace
}  // namespace tactforce::cli_testing
