// The ablation's methods, their options and the runs (ablation.h).
#include <algorithm>
#include <cmath>
#include <limits>

#include "absl/strings/str_cat.h"
#include "tactforce/experiment/ablation.h"
#include "tactforce/inertia/metrics.h"
#include "tactforce/io/status_macros.h"

namespace tactforce::experiment {

const char* ToString(AblationMethod m) {
  switch (m) {
    case AblationMethod::kBaselineLs:
      return "baseline-ls";
    case AblationMethod::kBaselineLsSg:
      return "baseline-ls+sg51";
    case AblationMethod::kBaselineFg:
      return "baseline-fg";
    case AblationMethod::kFgNoC:
      return "fg-no-c";
    case AblationMethod::kFgC:
      return "fg-c";
    case AblationMethod::kFgCG:
      return "fg-c-g";
    case AblationMethod::kConstrained:
      return "constrained";
    case AblationMethod::kDensity:
      return "density";
  }
  return "?";
}

std::vector<AblationMethod> AllAblationMethods() {
  return {AblationMethod::kBaselineLs,  AblationMethod::kBaselineLsSg, AblationMethod::kBaselineFg,
          AblationMethod::kFgNoC,       AblationMethod::kFgC,          AblationMethod::kFgCG,
          AblationMethod::kConstrained, AblationMethod::kDensity};
}

std::string PaperMethodName(AblationMethod m) {
  switch (m) {
    case AblationMethod::kBaselineLsSg:
      return "Baseline";
    case AblationMethod::kBaselineFg:
      return "Baseline-FG";
    case AblationMethod::kFgNoC:
      return "No C, No G";
    case AblationMethod::kFgC:
      return "C, No G";
    case AblationMethod::kFgCG:
      return "C + G";
    default:
      return "";
  }
}

absl::Status ValidateAblationConfig(const AblationConfig& c) {
  if (c.seeds < 1)
    return absl::InvalidArgumentError(absl::StrCat("seeds: must be >= 1, got ", c.seeds));
  if (!(c.duration > 0) || !std::isfinite(c.duration))
    return absl::InvalidArgumentError(absl::StrCat("duration: must be > 0, got ", c.duration));
  if (!(c.rate > 0) || !std::isfinite(c.rate))
    return absl::InvalidArgumentError(absl::StrCat("rate: must be > 0, got ", c.rate));
  return absl::OkStatus();
}

inertia::InertiaOptions AblationOptions(AblationMethod m, const AblationData& data) {
  using inertia::FactorGraphVariant;
  using inertia::InertiaMethod;
  inertia::InertiaOptions o = data.base;
  o.prior.reset();
  if (o.hull.empty() && o.mesh) o.hull = o.mesh->vertices;
  if (m != AblationMethod::kDensity) o.mesh = nullptr;  // only DENSITY uses the mesh itself
  switch (m) {
    case AblationMethod::kBaselineLs:
      o.method = InertiaMethod::kBaselineLs;
      break;
    case AblationMethod::kBaselineLsSg:
      o.method = InertiaMethod::kBaselineLs;
      o.baseline_ls.savitzky_golay = true;
      o.baseline_ls.savitzky_golay_window = 51;
      break;
    case AblationMethod::kBaselineFg:
      o.factor_graph.variant = FactorGraphVariant::kBaselineFg;
      break;
    case AblationMethod::kFgNoC:
      o.factor_graph.variant = FactorGraphVariant::kNoConstraint;
      break;
    case AblationMethod::kFgC:
      o.factor_graph.variant = FactorGraphVariant::kConstraint;
      break;
    case AblationMethod::kFgCG:
      o.factor_graph.variant = FactorGraphVariant::kConstraintPrior;
      o.prior =
          inertia::InertiaPrior{data.truth, 1.0};  // the paper: "the prior ... the ground truth"
      break;
    case AblationMethod::kConstrained:
      o.method = InertiaMethod::kConstrained;
      break;
    case AblationMethod::kDensity:
      o.method = InertiaMethod::kDensity;
      break;
  }
  if (m == AblationMethod::kBaselineFg || m == AblationMethod::kFgNoC ||
      m == AblationMethod::kFgC || m == AblationMethod::kFgCG)
    o.method = InertiaMethod::kFactorGraph;
  return o;
}

std::vector<AblationSource> BuiltInAblationSources(const AblationConfig& config) {
  std::vector<AblationSource> all = SimulationAblationSources(config);
  for (AblationSource& s : InHandAblationSources(config)) all.push_back(std::move(s));
  return all;
}

namespace {

double Median(std::vector<double> v) {
  if (v.empty()) return std::numeric_limits<double>::quiet_NaN();
  std::sort(v.begin(), v.end());
  const size_t n = v.size();
  return n % 2 ? v[n / 2] : 0.5 * (v[n / 2 - 1] + v[n / 2]);  // inf + finite = inf: honest
}

struct Runs {
  std::vector<double> eq38, riem, mass, com;
  std::vector<std::string> objects;
  int consistent = 0, failed = 0;
};

AblationRow Summarise(const std::string& method, const std::string& source, const Runs& r) {
  AblationRow row;
  row.method = method;
  row.source = source;
  row.median_eq38 = Median(r.eq38);
  row.median_riemannian = Median(r.riem);
  row.median_mass_error_percent = Median(r.mass);
  row.median_com_error_mm = Median(r.com);
  row.consistent = r.consistent;
  row.runs = static_cast<int>(r.eq38.size());
  row.failed = r.failed;
  row.objects = r.objects;
  row.eq38 = r.eq38;
  return row;
}

// Every method on one data set, into runs[method index].
void FitAll(const AblationData& data, const std::vector<AblationMethod>& methods,
            std::vector<Runs>* runs) {
  for (size_t i = 0; i < methods.size(); ++i) {
    absl::StatusOr<inertia::InertiaFit> fit =
        inertia::FitInertia(data.samples, AblationOptions(methods[i], data));
    if (!fit.ok()) {
      ++(*runs)[i].failed;
      continue;
    }
    const inertia::InertiaErrors e = inertia::CompareInertia(data.truth, fit->params);
    Runs& r = (*runs)[i];
    r.eq38.push_back(e.paper_metric);
    r.riem.push_back(e.riemannian);
    r.mass.push_back(e.mass_percent);
    r.com.push_back(e.com_mm);
    r.consistent += e.consistent;
    r.objects.push_back(data.object);
  }
}

}  // namespace

absl::StatusOr<AblationTable> RunAblation(const AblationConfig& config) {
  TF_RETURN_IF_ERROR(ValidateAblationConfig(config));
  std::vector<AblationSource> chosen;
  const std::vector<AblationSource> all = BuiltInAblationSources(config);
  for (const std::string& name : config.sources) {
    auto it = std::find_if(all.begin(), all.end(),
                           [&](const AblationSource& s) { return s.name == name; });
    if (it == all.end()) {
      std::string names;
      for (const AblationSource& s : all)
        absl::StrAppend(&names, names.empty() ? "" : ", ", s.name);
      return absl::InvalidArgumentError(
          absl::StrCat("sources: unknown '", name, "' (expected ", names, ")"));
    }
    chosen.push_back(*it);
  }
  return RunAblation(config, config.sources.empty() ? all : chosen);
}

absl::StatusOr<AblationTable> RunAblation(const AblationConfig& config,
                                          const std::vector<AblationSource>& sources) {
  TF_RETURN_IF_ERROR(ValidateAblationConfig(config));
  AblationTable table;
  table.config = config;
  table.sources = sources;
  const std::vector<AblationMethod> methods =
      config.methods.empty() ? AllAblationMethods() : config.methods;
  const double total = static_cast<double>(sources.size()) * config.seeds;
  int done = 0;
  for (const AblationSource& source : sources) {
    std::vector<Runs> runs(methods.size());
    for (int k = 0; k < config.seeds; ++k) {
      absl::StatusOr<AblationData> data = source.make(config.first_seed + k);
      if (!data.ok())
        return io::PrependPath(
            data.status(), absl::StrCat("source ", source.name, ", seed ", config.first_seed + k));
      FitAll(*data, methods, &runs);
      if (config.progress) config.progress(++done / total);
    }
    for (size_t i = 0; i < methods.size(); ++i)
      table.rows.push_back(Summarise(ToString(methods[i]), source.name, runs[i]));
  }
  return table;
}

}  // namespace tactforce::experiment
