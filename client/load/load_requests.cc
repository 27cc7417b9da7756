// The requests of `tactforce load` (load_requests.h): request files (one
// JSON message, a JSON list of them, or for fit-inertia an inertia CSV log)
// and the built-in examples of estimate, audit and fit-inertia.
#include "load_requests.h"

#include <cmath>
#include <string_view>
#include <utility>

#include "absl/strings/ascii.h"
#include "absl/strings/str_cat.h"
#include "cli_common.h"
#include "load_generator.h"
#include "tactforce/api/convert.h"
#include "tactforce/api/json.h"
#include "tactforce/inertia/samples.h"
#include "tactforce/inertia/simulate.h"
#include "tactforce/io/json.h"
#include "tactforce/io/text_file.h"
#include "tactforce/planner/examples.h"
#include "tactforce/sim/simulate.h"
#include "tactforce/io/status_macros.h"

namespace tactforce::cli {
namespace {

// Built-in fit-inertia stream: samples per message.
constexpr int kExampleInertiaBatch = 100;

// The first character that is not white space ('\0' when none).
char FirstNonSpace(const std::string& text) {
  for (char c : text) {
    if (!absl::ascii_isspace(static_cast<unsigned char>(c))) return c;
  }
  return '\0';
}

// InvalidArgument "SOURCE:LINE:COLUMN: what" at byte `offset` of `text`.
absl::Status JsonListError(const std::string& text, size_t offset, const std::string& source,
                           const std::string& what) {
  const io::TextPosition at = io::PositionInText(text, offset);
  return absl::InvalidArgumentError(absl::StrCat(source, ":", at.line, ":", at.column, ": ", what));
}

// The byte ranges [first, second) of the elements of the JSON list `text`
// holds (white space around it allowed). Only the list's own structure is
// checked here (brackets, strings, commas); each element is parsed on its
// own.
absl::StatusOr<std::vector<std::pair<size_t, size_t>>> SplitJsonList(const std::string& text,
                                                                     const std::string& source) {
  std::vector<std::pair<size_t, size_t>> elements;
  size_t i = text.find('[') + 1, start = i;
  int depth = 0;
  io::JsonStringTracker strings;
  for (; i < text.size(); ++i) {
    const char c = text[i];
    if (strings.InString(c)) continue;
    if (c == '{' || c == '[') ++depth;
    if ((c == '}' || c == ']') && depth > 0) {
      --depth;
    } else if (depth == 0 && (c == ',' || c == ']')) {
      const absl::string_view element =
          absl::StripAsciiWhitespace(absl::string_view(text).substr(start, i - start));
      if (element.empty() && (c == ',' || !elements.empty())) {
        return JsonListError(text, i, source, "expected a list element");
      }
      if (!element.empty()) {
        const size_t begin = static_cast<size_t>(element.data() - text.data());
        elements.emplace_back(begin, begin + element.size());
      }
      if (c == ']') break;
      start = i + 1;
    }
  }
  if (i >= text.size()) return JsonListError(text, i, source, "unterminated JSON list");
  if (FirstNonSpace(text.substr(i + 1)) != '\0') {
    return JsonListError(text, i + 1, source, "content after the JSON list");
  }
  return elements;
}

// `text` as messages of type T: one JSON object, or a JSON list of them.
// Errors name `source` (the file) and the position in it.
template <class T>
absl::StatusOr<std::vector<T>> ParseJsonMessages(const std::string& text,
                                                 const std::string& source) {
  std::vector<T> out;
  if (FirstNonSpace(text) != '[') {
    T message;
    TF_RETURN_IF_ERROR(api::ParseJson(text, &message, source));
    out.push_back(std::move(message));
    return out;
  }
  TF_ASSIGN_OR_RETURN(auto elements, SplitJsonList(text, source));
  for (const auto& [begin, end] : elements) {
    // Preceded by as many line breaks and spaces as the element has before
    // it in the file, so that positions in errors are the file's.
    const io::TextPosition at = io::PositionInText(text, begin);
    const std::string element =
        absl::StrCat(std::string(at.line - 1, '\n'), std::string(at.column - 1, ' '),
                     absl::string_view(text).substr(begin, end - begin));
    T message;
    TF_RETURN_IF_ERROR(api::ParseJson(element, &message, source));
    out.push_back(std::move(message));
  }
  if (out.empty()) return absl::InvalidArgumentError(absl::StrCat(source, ": empty list"));
  return out;
}

// A fit-inertia request file: JSON (a list of FitInertiaRequest messages or
// one) or an inertia CSV log sent with default options in `batch`es.
absl::StatusOr<std::vector<v1::FitInertiaRequest>> FitInertiaStreamFromFile(
    const std::string& text, const LoadRequestSource& source) {
  const char first = FirstNonSpace(text);
  if (first == '[' || first == '{') {
    return ParseJsonMessages<v1::FitInertiaRequest>(text, InputName(source.path));
  }
  absl::StatusOr<inertia::InertiaSamples> samples =
      inertia::ParseInertiaCsv(text, InputName(source.path));
  if (!samples.ok()) {
    return absl::InvalidArgumentError(
        absl::StrCat("--request: neither FitInertiaRequest JSON nor an inertia CSV log: ",
                     samples.status().message()));
  }
  return AllFitInertiaMessages(*samples, v1::InertiaFitOptions(),
                               static_cast<size_t>(source.batch));
}

// The requests of `spec->rpc` from the file's `text`.
absl::Status SetRequestsFromFile(const std::string& text, const LoadRequestSource& source,
                                 LoadSpec* spec) {
  const std::string name = InputName(source.path);
  switch (spec->rpc) {
    case LoadRpc::kPlan:
    case LoadRpc::kStream: {
      TF_ASSIGN_OR_RETURN(spec->requests, ParseJsonMessages<v1::PlanRequest>(text, name));
      return absl::OkStatus();
    }
    case LoadRpc::kEstimate: {
      TF_ASSIGN_OR_RETURN(spec->estimate_requests,
                          ParseJsonMessages<v1::EstimateRequest>(text, name));
      return absl::OkStatus();
    }
    case LoadRpc::kAudit: {
      TF_ASSIGN_OR_RETURN(spec->audit_requests, ParseJsonMessages<v1::AuditRequest>(text, name));
      return absl::OkStatus();
    }
    case LoadRpc::kFitInertia: {
      TF_ASSIGN_OR_RETURN(spec->fit_inertia_stream, FitInertiaStreamFromFile(text, source));
      return absl::OkStatus();
    }
    case LoadRpc::kHealth:
      break;
  }
  return absl::OkStatus();
}

}  // namespace

absl::Status SetLoadRequests(const LoadRequestSource& source, LoadSpec* spec) {
  if (spec->rpc == LoadRpc::kHealth) return absl::OkStatus();
  if (!source.path.empty()) {
    TF_ASSIGN_OR_RETURN(std::string text, ReadInput(source.path));
    return SetRequestsFromFile(text, source, spec);
  }
  switch (spec->rpc) {
    case LoadRpc::kPlan:
    case LoadRpc::kStream:
      spec->requests = RandomRequestMix(source.seed, source.mix_size);
      break;
    case LoadRpc::kEstimate:
      spec->estimate_requests = {ExampleEstimateRequest()};
      break;
    case LoadRpc::kAudit:
      spec->audit_requests = {ExampleAuditRequest()};
      break;
    case LoadRpc::kFitInertia:
      spec->fit_inertia_stream = ExampleFitInertiaStream();
      break;
    case LoadRpc::kHealth:
      break;
  }
  return absl::OkStatus();
}

v1::EstimateRequest ExampleEstimateRequest() {
  v1::EstimateRequest request;
  for (const planner::ExampleGrasp& grasp : planner::BuiltInGrasps()) {
    if (grasp.name != "wrench-3f") continue;
    const v1::PlanRequest plan =
        api::ToRequest(grasp.problem, grasp.options, planner::SolverKind::kGeometric);
    *request.mutable_object() = plan.object();
    *request.mutable_contacts() = plan.contacts();
  }
  for (double reading : {2.0, 1.5, 3.5}) request.add_readings(reading);  // N
  return request;
}

v1::AuditRequest ExampleAuditRequest() {
  sim::SensorModel model;
  model.noise = 0.02;
  model.effects.threshold = 0.3;
  sim::SimOptions options;
  options.seconds = 10;
  options.rate = 100;
  options.seed = 1;
  v1::AuditRequest request;
  request.set_source("tactforce load: built-in example");
  absl::StatusOr<sim::SimRun> run = sim::SimulateSensor(model, options);
  if (!run.ok()) return request;  // not for these fixed options
  for (size_t k = 0; k < run->t.size(); ++k) {
    v1::AuditSample* sample = request.add_samples();
    sample->set_t(run->t[k]);
    sample->set_reference(run->reference[k]);
    sample->set_reading(run->reading[k]);
  }
  return request;
}

std::vector<v1::FitInertiaRequest> ExampleFitInertiaStream() {
  inertia::SimulationOptions options;
  options.duration = 3.0;
  options.rate_hz = 100.0;
  options.noise.force_sigma = std::sqrt(0.1);  // N; the paper's 0.1 N^2
  options.seed = 7;
  absl::StatusOr<inertia::SimulationResult> sim = inertia::SimulateInertia(options);
  if (!sim.ok()) return {};  // not for these fixed options
  v1::InertiaFitOptions fit;
  fit.set_method(v1::INERTIA_METHOD_CONSTRAINED);
  return AllFitInertiaMessages(sim->samples, fit, kExampleInertiaBatch);
}

}  // namespace tactforce::cli
