// Partial activation from per-taxel data: taxels that never activate. A
// taxel is silent when the largest deviation of its 5-sample moving mean
// from its median stays below silent_sigmas x (its noise / sqrt(5)); its
// noise is estimated robustly from first differences (MAD / 0.6745 /
// sqrt(2)), so a taxel that responds, even rarely, is far above it and one
// that only carries noise (or is stuck at a constant) is not. Units cancel:
// each taxel is compared with its own noise.
#include <algorithm>
#include <cmath>

#include "absl/strings/str_cat.h"
#include "cause_selection.h"

namespace tactforce::audit::internal {
namespace {

double Median(std::vector<double> v) {
  if (v.empty()) return 0;
  std::nth_element(v.begin(), v.begin() + v.size() / 2, v.end());
  return v[v.size() / 2];
}

// Robust noise sigma of x from its first differences.
double DifferenceNoise(const std::vector<double>& x) {
  std::vector<double> dx;
  for (size_t i = 1; i < x.size(); ++i) dx.push_back(x[i] - x[i - 1]);
  const double m = Median(dx);
  for (double& v : dx) v = std::abs(v - m);
  return Median(dx) / 0.6745 / std::sqrt(2.0);
}

constexpr int kWindow = 5;

// Largest |moving mean (kWindow samples) - median| of x.
double PeakDeviation(const std::vector<double>& x) {
  const double med = Median(x);
  double sum = 0, peak = 0;
  for (size_t i = 0; i < x.size(); ++i) {
    sum += x[i] - med;
    if (i >= kWindow) sum -= x[i - kWindow] - med;
    if (i + 1 >= kWindow) peak = std::max(peak, std::abs(sum / kWindow));
  }
  return peak;
}

}  // namespace

std::optional<Cause> FindPartialActivation(const MeasuredData& d, const AuditOptions& o) {
  if (d.taxels.empty()) return std::nullopt;
  std::vector<double> silent;
  for (size_t j = 0; j < d.taxels.size(); ++j) {
    const std::vector<double>& x = d.taxels[j];
    double scale = 0;
    for (double v : x) scale = std::max(scale, std::abs(v));
    // A noise-free taxel: the smallest deviation that is not round-off.
    const double sigma = std::max(DifferenceNoise(x), 1e-9 * std::max(1.0, scale));
    if (PeakDeviation(x) < o.silent_sigmas * sigma / std::sqrt(double(kWindow)))
      silent.push_back(double(j));
  }
  if (silent.empty()) return std::nullopt;
  Cause c;
  c.effect = kPartialActivation;
  c.found_by = "taxels";
  const double n = static_cast<double>(d.taxels.size());
  c.parameters = {
      {"fraction", silent.size() / n}, {"silent_taxels", double(silent.size())}, {"taxels", n}};
  c.array_parameters = {{"silent_taxel_indices", silent}};
  return c;
}

}  // namespace tactforce::audit::internal
