// Residual diagnostics of a model's prediction against the measured reading:
// training and held-out RMS, bias per force bin, loading vs unloading mean
// residual, Ljung-Box whiteness test of the held-out residuals (with the
// chi-square tail GammaQ), the cross-correlation lag between reference and
// reading, and the residual's trend over time. Residuals are divided by the
// model's gain to read in N (> 0: the sensor reports more force).
#include <algorithm>
#include <cmath>

#include "audit_internal.h"

namespace tactforce::audit::internal {

double GammaQ(double a, double x) {
  if (!(x > 0)) return 1;
  const double log_pre = -x + a * std::log(x) - std::lgamma(a);
  if (x < a + 1) {
    double term = 1 / a, sum = term;
    for (int k = 1; k < 1000; ++k) {
      term *= x / (a + k);
      sum += term;
      if (std::abs(term) < std::abs(sum) * 1e-15) break;
    }
    return std::clamp(1 - sum * std::exp(log_pre), 0.0, 1.0);
  }
  // Continued fraction (modified Lentz).
  const double tiny = 1e-300;
  double b = x + 1 - a, c = 1 / tiny, d = 1 / b, h = d;
  for (int i = 1; i < 1000; ++i) {
    const double an = -i * (i - a);
    b += 2;
    d = an * d + b;
    if (std::abs(d) < tiny) d = tiny;
    c = b + an / c;
    if (std::abs(c) < tiny) c = tiny;
    d = 1 / d;
    const double del = d * c;
    h *= del;
    if (std::abs(del - 1) < 1e-15) break;
  }
  return std::clamp(std::exp(log_pre) * h, 0.0, 1.0);
}

namespace {

// Training and held-out RMS of the residuals r (reading units), and the
// held-out RMS in N (divided by |g|).
void ResidualRms(const std::vector<double>& r, int n_train, double g, Diagnostics* out) {
  const int n = static_cast<int>(r.size());
  double s = 0;
  for (int i = 0; i < n_train; ++i) s += r[i] * r[i];
  out->train_rms = std::sqrt(s / std::max(1, n_train));
  s = 0;
  for (int i = n_train; i < n; ++i) s += r[i] * r[i];
  out->heldout_rms = std::sqrt(s / std::max(1, n - n_train));
  out->heldout_rms_force = out->heldout_rms / std::abs(g);
}

// Mean force-domain residual rf (N) and its standard error in 8 equal-width
// bins of the reference force.
void BiasPerForceBin(const MeasuredData& d, const std::vector<double>& rf, Diagnostics* out) {
  const int n = static_cast<int>(rf.size());
  auto [lo_it, hi_it] = std::minmax_element(d.reference.begin(), d.reference.end());
  const double fmin = *lo_it, fmax = *hi_it;
  const int bins = 8;
  out->bias_bins.resize(bins);
  std::vector<double> sum(bins, 0), sum2(bins, 0);
  for (int b = 0; b < bins; ++b) {
    out->bias_bins[b].lo = fmin + (fmax - fmin) * b / bins;
    out->bias_bins[b].hi = fmin + (fmax - fmin) * (b + 1) / bins;
  }
  for (int i = 0; i < n; ++i) {
    int b = static_cast<int>((d.reference[i] - fmin) / (fmax - fmin) * bins);
    b = std::clamp(b, 0, bins - 1);
    out->bias_bins[b].count++;
    sum[b] += rf[i];
    sum2[b] += rf[i] * rf[i];
  }
  for (int b = 0; b < bins; ++b) {
    auto& fb = out->bias_bins[b];
    if (fb.count == 0) continue;
    fb.mean_residual = sum[b] / fb.count;
    const double var = std::max(0.0, sum2[b] / fb.count - fb.mean_residual * fb.mean_residual);
    fb.std_error = std::sqrt(var / fb.count);
  }
}

// The trial segment (index into d.segment_starts) of every sample.
std::vector<int> SegmentOfSample(const MeasuredData& d) {
  const int n = static_cast<int>(d.t.size());
  std::vector<int> seg_of(n, 0);
  size_t si = 0;
  for (int i = 0; i < n; ++i) {
    while (si + 1 < d.segment_starts.size() && i >= d.segment_starts[si + 1]) ++si;
    seg_of[i] = static_cast<int>(si);
  }
  return seg_of;
}

// Mean residual rf (N) while loading and while unloading: the reference's
// rate of change (central difference over +/-2 samples within a segment)
// beyond 10 % of its 95th percentile, either sign.
void LoadingVsUnloading(const MeasuredData& d, const std::vector<int>& seg_of,
                        const std::vector<double>& rf, Diagnostics* out) {
  const int n = static_cast<int>(rf.size());
  std::vector<double> rate(n, 0), absrate;
  const int k = 2;
  for (int i = 0; i < n; ++i) {
    const int a = std::max(0, i - k), b = std::min(n - 1, i + k);
    if (seg_of[a] != seg_of[i] || seg_of[b] != seg_of[i] || d.t[b] <= d.t[a]) continue;
    rate[i] = (d.reference[b] - d.reference[a]) / (d.t[b] - d.t[a]);
    absrate.push_back(std::abs(rate[i]));
  }
  double thr = 0;
  if (!absrate.empty()) {
    std::nth_element(absrate.begin(), absrate.begin() + absrate.size() * 95 / 100, absrate.end());
    thr = 0.1 * absrate[absrate.size() * 95 / 100];
  }
  double ls = 0, us = 0;
  for (int i = 0; i < n; ++i) {
    if (thr <= 0) break;
    if (rate[i] > thr) {
      ls += rf[i];
      out->loading_count++;
    } else if (rate[i] < -thr) {
      us += rf[i];
      out->unloading_count++;
    }
  }
  if (out->loading_count) out->loading_mean = ls / out->loading_count;
  if (out->unloading_count) out->unloading_mean = us / out->unloading_count;
}

// Ljung-Box Q and p on the held-out residuals r, lags min(20, n_h / 4).
void LjungBox(const std::vector<double>& r, int n_train, Diagnostics* out) {
  const int n = static_cast<int>(r.size());
  const int nh = n - n_train;
  const int h = std::clamp(nh / 4, 1, 20);
  if (!(nh > h + 2)) return;
  double m = 0;
  for (int i = n_train; i < n; ++i) m += r[i];
  m /= nh;
  double c0 = 0;
  for (int i = n_train; i < n; ++i) c0 += (r[i] - m) * (r[i] - m);
  double q = 0;
  if (c0 > 0) {
    for (int lag = 1; lag <= h; ++lag) {
      double c = 0;
      for (int i = n_train + lag; i < n; ++i) c += (r[i] - m) * (r[i - lag] - m);
      const double rho = c / c0;
      q += rho * rho / (nh - lag);
    }
    q *= static_cast<double>(nh) * (nh + 2);
  }
  out->ljung_box_lags = h;
  out->ljung_box_q = q;
  out->ljung_box_p = GammaQ(0.5 * h, 0.5 * q);
}

// Lag (samples, within +/- max_lag_seconds) of the cross-correlation peak
// between the reference's and the reading's first differences (reading
// divided by g, so in the force direction; none across a segment start).
void CrossCorrelationLag(const MeasuredData& d, const std::vector<int>& seg_of, double g,
                         double max_lag_seconds, Diagnostics* out) {
  const int n = static_cast<int>(d.t.size());
  const double dt = MedianStep(d.t, 1.0);
  const int lmax =
      std::clamp(static_cast<int>(std::ceil(max_lag_seconds / dt)), 1, std::max(1, n / 4));
  std::vector<double> dx(n, 0), dy(n, 0);
  for (int i = 1; i < n; ++i) {
    if (seg_of[i] != seg_of[i - 1]) continue;
    dx[i] = d.reference[i] - d.reference[i - 1];
    dy[i] = (d.reading[i] - d.reading[i - 1]) / g;
  }
  double best = -1e300;
  for (int L = -lmax; L <= lmax; ++L) {
    double c = 0;
    for (int i = std::max(0, -L); i < n && i + L < n; ++i) c += dx[i] * dy[i + L];
    if (c > best) {
      best = c;
      out->xcorr_lag_samples = L;
    }
  }
  out->xcorr_lag_seconds = out->xcorr_lag_samples * dt;
}

// Least-squares slope of the residual rf (N) against time, and its mean per
// tenth of the run.
void ResidualVsTime(const MeasuredData& d, const std::vector<double>& rf, Diagnostics* out) {
  const int n = static_cast<int>(rf.size());
  double mt = 0, mr = 0;
  for (int i = 0; i < n; ++i) {
    mt += d.t[i];
    mr += rf[i];
  }
  mt /= n;
  mr /= n;
  double stt = 0, str = 0;
  for (int i = 0; i < n; ++i) {
    stt += (d.t[i] - mt) * (d.t[i] - mt);
    str += (d.t[i] - mt) * (rf[i] - mr);
  }
  out->residual_time_slope = stt > 0 ? str / stt : 0;
  const int tb = 10;
  out->residual_time_bins.assign(tb, 0);
  std::vector<int> cnt(tb, 0);
  for (int i = 0; i < n; ++i) {
    const int b = std::min(tb - 1, i * tb / n);
    out->residual_time_bins[b] += rf[i];
    cnt[b]++;
  }
  for (int b = 0; b < tb; ++b)
    if (cnt[b]) out->residual_time_bins[b] /= cnt[b];
}

}  // namespace

Diagnostics Diagnose(const MeasuredData& d, const std::vector<double>& pred, double gain,
                     int n_train, double max_lag_seconds) {
  Diagnostics out;
  const int n = static_cast<int>(d.t.size());
  const double g = gain != 0 ? gain : 1;
  std::vector<double> r(n), rf(n);
  for (int i = 0; i < n; ++i) {
    r[i] = d.reading[i] - pred[i];
    rf[i] = r[i] / g;  // force-domain equivalent (N): > 0 means the sensor reports more force
  }
  const std::vector<int> seg_of = SegmentOfSample(d);
  ResidualRms(r, n_train, g, &out);
  BiasPerForceBin(d, rf, &out);
  LoadingVsUnloading(d, seg_of, rf, &out);
  LjungBox(r, n_train, &out);
  CrossCorrelationLag(d, seg_of, g, max_lag_seconds, &out);
  ResidualVsTime(d, rf, &out);
  return out;
}

}  // namespace tactforce::audit::internal
