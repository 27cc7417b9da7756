// Measured data for the audit: one CSV (t, reference, reading[, shear][,
// trial]) read into MeasuredData and validated (sizes, finite values, time
// order per trial, non-constant columns, sample count; errors name file, line
// and column), or two streams on their own clocks aligned by interpolating
// the reference onto the reading times after subtracting the clock offset,
// which is given or estimated by maximising the correlation of the streams
// (coarse grid, finer grid, golden section). Also the median time step the
// audit's fits and diagnostics scale with.
#include "tactforce/audit/measured_data.h"

#include <algorithm>
#include <cmath>
#include <functional>
#include <limits>
#include <string_view>

#include "absl/strings/str_cat.h"
#include "absl/strings/str_format.h"
#include "audit_internal.h"
#include "tactforce/planner/validation.h"
#include "tactforce/io/status_macros.h"

namespace tactforce::audit {

double internal::MedianStep(const std::vector<double>& t, double fallback) {
  std::vector<double> steps;
  for (size_t i = 1; i < t.size(); ++i)
    if (t[i] > t[i - 1]) steps.push_back(t[i] - t[i - 1]);
  if (steps.empty()) return fallback;
  std::nth_element(steps.begin(), steps.begin() + steps.size() / 2, steps.end());
  return steps[steps.size() / 2];
}

namespace {

// Sample i's value in column `col`: "<file>:<line>: column 'col'" for a
// CSV, the message path "samples[i].col" otherwise (no line numbers).
std::string Where(const MeasuredData& d, int i, const char* col) {
  if (i >= 0 && i < static_cast<int>(d.line.size()))
    return absl::StrCat(d.source, ":", d.line[i], ": column '", col, "'");
  return absl::StrCat("samples[", i, "].", col);
}

// A whole column: "<file>: column 'col'" or "samples[*].col".
std::string Column(const MeasuredData& d, const char* col) {
  if (!d.line.empty()) return absl::StrCat(d.source, ": column '", col, "'");
  return absl::StrCat("samples[*].", col);
}

}  // namespace

absl::Status ValidateMeasuredData(const MeasuredData& d, int min_samples) {
  const size_t n = d.t.size();
  if (d.reference.size() != n || d.reading.size() != n)
    return absl::InvalidArgumentError(
        absl::StrCat(d.source, ": columns t, reference, reading differ in length"));
  if (!d.shear.empty() && d.shear.size() != n)
    return absl::InvalidArgumentError(absl::StrCat(Column(d, "shear"), " differs in length"));
  if (static_cast<int>(n) < min_samples) {
    return absl::InvalidArgumentError(absl::StrCat(
        d.source, ": too few samples: ", n, " valid rows",
        d.skipped_nan_rows ? absl::StrCat(" (", d.skipped_nan_rows, " NaN rows skipped)") : "",
        ", the audit needs at least ", min_samples,
        " (a training block and a later held-out block)"));
  }
  auto check_finite = [&](const std::vector<double>& v, const char* col) -> absl::Status {
    for (size_t i = 0; i < v.size(); ++i)
      if (!std::isfinite(v[i]))
        return absl::InvalidArgumentError(absl::StrCat(Where(d, i, col), ": not a finite number"));
    return absl::OkStatus();
  };
  // Taxels first: a bad taxel value also spoils the reading (their sum).
  for (size_t j = 0; j < d.taxels.size(); ++j) {
    const std::string col = absl::StrCat("taxel_", j);
    if (d.taxels[j].size() != n)
      return absl::InvalidArgumentError(absl::StrCat(Column(d, col.c_str()), " differs in length"));
    TF_RETURN_IF_ERROR(check_finite(d.taxels[j], col.c_str()));
  }
  for (auto st : {check_finite(d.t, "t"), check_finite(d.reference, "reference"),
                  check_finite(d.reading, "reading"), check_finite(d.shear, "shear")})
    TF_RETURN_IF_ERROR(st);
  // Magnitudes far beyond any sensor: their squares and products (the fits'
  // sums) stay finite, so no answer is computed from an overflow.
  auto check_bounded = [&](const std::vector<double>& v, const char* col, double limit,
                           const char* unit) -> absl::Status {
    for (size_t i = 0; i < v.size(); ++i)
      if (!planner::IsBounded(v[i], limit))
        return planner::MagnitudeError(Where(d, i, col), v[i], limit, unit);
    return absl::OkStatus();
  };
  for (size_t j = 0; j < d.taxels.size(); ++j)
    TF_RETURN_IF_ERROR(
        check_bounded(d.taxels[j], absl::StrCat("taxel_", j).c_str(), kMaxReading, "sensor units"));
  for (auto st : {check_bounded(d.t, "t", planner::kMaxTime, "s"),
                  check_bounded(d.reference, "reference", planner::kMaxForce, "N"),
                  check_bounded(d.reading, "reading", kMaxReading, "sensor units"),
                  check_bounded(d.shear, "shear", planner::kMaxForce, "N")})
    TF_RETURN_IF_ERROR(st);
  std::vector<int> starts = d.segment_starts.empty() ? std::vector<int>{0} : d.segment_starts;
  for (size_t i = 1; i < n; ++i) {
    if (std::binary_search(starts.begin(), starts.end(), static_cast<int>(i))) continue;
    if (!(d.t[i] > d.t[i - 1]))
      return absl::InvalidArgumentError(absl::StrCat(Where(d, i, "t"), ": time not increasing (",
                                                     d.t[i], " after ", d.t[i - 1],
                                                     "); sort the rows by time"));
    // Delay, lag and drift are fitted over time: steps below the resolution are noise.
    if (d.t[i] - d.t[i - 1] < planner::kMinTimeStep)
      return planner::CheckTime(Where(d, static_cast<int>(i), "t"), d.t[i], &d.t[i - 1]);
  }
  auto check_const = [&](const std::vector<double>& v, const char* col,
                         const char* why) -> absl::Status {
    auto [lo, hi] = std::minmax_element(v.begin(), v.end());
    if (*hi - *lo <= 1e-12 * std::max(1.0, std::abs(*hi)))
      return absl::InvalidArgumentError(
          absl::StrCat(Column(d, col), " is constant (", *lo, "): ", why));
    return absl::OkStatus();
  };
  TF_RETURN_IF_ERROR(
      check_const(d.reference, "reference",
                  "the audit needs a varying reference force (press, ramp or random profile)"));
  return check_const(d.reading, "reading", "the sensor does not respond; nothing to audit");
}

namespace {

// The taxel index of a column named taxel_<j> (j a decimal integer), or -1.
int TaxelIndex(const std::string& column) {
  constexpr std::string_view kPrefix = "taxel_";
  if (column.size() <= kPrefix.size() || column.compare(0, kPrefix.size(), kPrefix) != 0) return -1;
  long j = 0;
  for (size_t k = kPrefix.size(); k < column.size(); ++k) {
    if (column[k] < '0' || column[k] > '9' || j > kMaxTaxels) return -1;
    j = 10 * j + (column[k] - '0');
  }
  return j <= kMaxTaxels ? static_cast<int>(j) : -1;
}

// The taxel columns of `table` into d->taxels (taxel_0 ... taxel_<N-1>);
// 'reading' = their sum when the table has none. Errors name the missing
// taxel columns.
absl::Status ReadTaxelColumns(const io::CsvTable& table, int expected, MeasuredData* d) {
  if (expected < 0 || expected > kMaxTaxels)
    return absl::InvalidArgumentError(
        absl::StrCat("taxels: must be in [1, ", kMaxTaxels, "], got ", expected));
  int highest = -1;
  for (const auto& c : table.columns) highest = std::max(highest, TaxelIndex(c));
  const int n_taxels = expected > 0 ? expected : highest + 1;
  if (n_taxels == 0) return absl::OkStatus();
  if (highest >= n_taxels)
    return absl::InvalidArgumentError(
        absl::StrCat(table.source, ": column 'taxel_", highest, "' beyond the ", n_taxels,
                     " taxels expected (taxel_0 ... taxel_", n_taxels - 1, ")"));
  std::string missing;
  for (int j = 0; j < n_taxels; ++j)
    if (!table.Has(absl::StrCat("taxel_", j)))
      absl::StrAppend(&missing, missing.empty() ? "" : ", ", "taxel_", j);
  if (!missing.empty())
    return absl::InvalidArgumentError(absl::StrCat(table.source, ": missing column(s) ", missing,
                                                   " (per-taxel data needs taxel_0 ... taxel_",
                                                   n_taxels - 1, ")"));
  for (int j = 0; j < n_taxels; ++j) d->taxels.push_back(table.Column(absl::StrCat("taxel_", j)));
  if (!table.Has("reading")) {
    d->reading.assign(d->t.size(), 0.0);
    for (const auto& col : d->taxels)
      for (size_t i = 0; i < col.size(); ++i) d->reading[i] += col[i];
    d->notes.push_back(absl::StrCat("reading = the sum of the ", n_taxels,
                                    " taxel columns (the fingertip force)"));
  }
  return absl::OkStatus();
}

}  // namespace

absl::StatusOr<MeasuredData> MeasuredDataFromCsv(const io::CsvTable& table, int expected_taxels) {
  TF_RETURN_IF_ERROR(table.Require({"t", "reference"}));
  MeasuredData d;
  d.source = table.source;
  d.t = table.Column("t");
  d.reference = table.Column("reference");
  if (table.Has("reading")) d.reading = table.Column("reading");
  TF_RETURN_IF_ERROR(ReadTaxelColumns(table, expected_taxels, &d));
  if (d.reading.empty()) {
    if (auto st = table.Require({"t", "reference", "reading"}); !st.ok())
      return absl::InvalidArgumentError(
          absl::StrCat(st.message(), " (or per-taxel columns taxel_0 ... taxel_<N-1>)"));
  }
  if (table.Has("shear")) d.shear = table.Column("shear");
  d.line = table.line_numbers;
  d.skipped_nan_rows = table.skipped_rows;
  const size_t n = d.t.size();
  d.trial.assign(n, 0);
  if (table.Has("trial")) {
    const auto tr = table.Column("trial");
    std::vector<int> seen;
    for (size_t i = 0; i < n; ++i) {
      if (tr[i] != std::round(tr[i]) || std::abs(tr[i]) > std::numeric_limits<int>::max())
        return absl::InvalidArgumentError(
            absl::StrCat(table.source, ":", d.line[i],
                         ": column 'trial': not an integer in int's range (", tr[i], ")"));
      d.trial[i] = static_cast<int>(tr[i]);
      if (i == 0 || d.trial[i] != d.trial[i - 1]) {
        if (std::find(seen.begin(), seen.end(), d.trial[i]) != seen.end())
          return absl::InvalidArgumentError(
              absl::StrCat(table.source, ":", d.line[i], ": column 'trial': trial ", d.trial[i],
                           " resumes after another trial; keep each trial's rows together"));
        seen.push_back(d.trial[i]);
        d.segment_starts.push_back(static_cast<int>(i));
      }
    }
  }
  if (d.segment_starts.empty()) d.segment_starts.push_back(0);
  if (d.skipped_nan_rows > 0)
    d.notes.push_back(absl::StrCat(d.skipped_nan_rows, " row(s) with NaN/empty fields skipped"));
  TF_RETURN_IF_ERROR(ValidateMeasuredData(d));
  return d;
}

absl::StatusOr<MeasuredData> ParseMeasuredCsv(const std::string& text, const std::string& source,
                                              int expected_taxels) {
  io::CsvOptions opt;
  opt.skip_nan_rows = true;
  TF_ASSIGN_OR_RETURN(auto table, io::ParseCsv(text, source, opt));
  return MeasuredDataFromCsv(table, expected_taxels);
}

absl::StatusOr<MeasuredData> ReadMeasuredCsv(const std::string& path, int expected_taxels) {
  io::CsvOptions opt;
  opt.skip_nan_rows = true;
  TF_ASSIGN_OR_RETURN(auto table, io::ReadCsvFile(path, opt));
  return MeasuredDataFromCsv(table, expected_taxels);
}

namespace {

// Times with enough digits for epoch clocks (1.7e9 s to the microsecond).
std::string G(double v) {
  return std::abs(v) >= 1e5 ? absl::StrFormat("%.6f", v) : absl::StrFormat("%.7g", v);
}

// |Pearson correlation| of the reading samples idx with the reference
// (linearly interpolated) at t - offset.
double OffsetCorrelation(const std::vector<double>& rt, const std::vector<double>& rv,
                         const std::vector<double>& qt, const std::vector<double>& qv, size_t first,
                         size_t last, double offset) {
  double sx = 0, sy = 0, sxx = 0, syy = 0, sxy = 0;
  size_t k = 0;
  const double n = static_cast<double>(last - first);
  for (size_t i = first; i < last; ++i) {
    const double tq = qt[i] - offset;
    while (k + 2 < rt.size() && rt[k + 1] < tq) ++k;
    const double w = std::clamp((tq - rt[k]) / (rt[k + 1] - rt[k]), 0.0, 1.0);
    const double x = rv[k] + w * (rv[k + 1] - rv[k]);
    const double y = qv[i];
    sx += x;
    sy += y;
    sxx += x * x;
    syy += y * y;
    sxy += x * y;
  }
  const double vx = sxx - sx * sx / n, vy = syy - sy * sy / n, cxy = sxy - sx * sy / n;
  if (!(vx > 0) || !(vy > 0)) return 0;
  return std::abs(cxy) / std::sqrt(vx * vy);
}

// Checks the search arguments and that the streams overlap at the centre by
// more than the search range.
absl::Status CheckClockOffsetSearch(const std::vector<double>& rt, const std::vector<double>& rv,
                                    const std::vector<double>& qt, const std::vector<double>& qv,
                                    double centre, double max_offset) {
  if (!std::isfinite(centre))
    return absl::InvalidArgumentError("clock offset: the search centre is not a finite number");
  if (!(max_offset > 0) || !std::isfinite(max_offset))
    return absl::InvalidArgumentError(
        absl::StrCat("max clock offset: must be a finite number > 0 s, got ", max_offset));
  if (rt.size() < 2 || rv.size() != rt.size() || qt.size() < 2 || qv.size() != qt.size())
    return absl::InvalidArgumentError("clock offset: each stream needs at least 2 samples");
  // Overlap of the streams at the search centre (in reading time).
  const double ov_lo = std::max(rt.front() + centre, qt.front());
  const double ov_hi = std::min(rt.back() + centre, qt.back());
  const double overlap = ov_hi - ov_lo;
  if (!(overlap > 2 * max_offset))
    return absl::InvalidArgumentError(absl::StrCat(
        "clock offset search +/-", G(max_offset), " s around ", G(centre),
        " s exceeds the streams' overlap (", G(std::max(0.0, overlap)), " s: reference ",
        G(rt.front()), "..", G(rt.back()), " s, reading ", G(qt.front()), "..", G(qt.back()),
        " s); the overlap must be longer than the search range (", G(2 * max_offset), " s): ",
        overlap > 0 ? "give a smaller --max-clock-offset or the offset itself with --clock-offset"
                    : "the clocks may have different epochs: give --clock-offset-centre (about "
                      "reading start minus "
                      "reference start) or the offset itself with --clock-offset"));
  return absl::OkStatus();
}

// A correlation maximum: offset (s) and |r| there.
struct CorrelationPeak {
  double offset;
  double correlation;
};

// Maximum of corr over a grid of step `coarse` on centre +/- max_offset, then
// over a grid of step `fine` within one coarse step of it (inside the range).
CorrelationPeak GridPeak(const std::function<double(double)>& corr, double centre,
                         double max_offset, double coarse, double fine) {
  CorrelationPeak peak{centre, -1};
  for (double off = centre - max_offset; off <= centre + max_offset + 1e-12; off += coarse) {
    const double r = corr(off);
    if (r > peak.correlation) peak = {off, r};
  }
  if (coarse > fine) {
    const double c0 = peak.offset;
    for (double off = c0 - coarse; off <= c0 + coarse + 1e-12; off += fine) {
      if (off < centre - max_offset || off > centre + max_offset) continue;
      const double r = corr(off);
      if (r > peak.correlation) peak = {off, r};
    }
  }
  return peak;
}

// Golden-section search of corr within `fine` of the peak (inside
// centre +/- max_offset); the better of its result and the peak.
CorrelationPeak GoldenSectionPeak(const std::function<double(double)>& corr, double centre,
                                  double max_offset, double fine, CorrelationPeak peak) {
  double a = std::max(centre - max_offset, peak.offset - fine),
         b = std::min(centre + max_offset, peak.offset + fine);
  const double g = 0.5 * (std::sqrt(5.0) - 1);
  double x1 = b - g * (b - a), x2 = a + g * (b - a);
  double f1 = corr(x1), f2 = corr(x2);
  for (int it = 0; it < 60 && b - a > 1e-9; ++it) {
    if (f1 > f2) {
      b = x2;
      x2 = x1;
      f2 = f1;
      x1 = b - g * (b - a);
      f1 = corr(x1);
    } else {
      a = x1;
      x1 = x2;
      f1 = f2;
      x2 = a + g * (b - a);
      f2 = corr(x2);
    }
  }
  const double xm = 0.5 * (a + b), fm = corr(xm);
  if (fm > peak.correlation) peak = {xm, fm};
  return peak;
}

}  // namespace

absl::StatusOr<ClockOffsetEstimate> EstimateClockOffset(const std::vector<double>& rt,
                                                        const std::vector<double>& rv,
                                                        const std::vector<double>& qt,
                                                        const std::vector<double>& qv,
                                                        double centre, double max_offset) {
  TF_RETURN_IF_ERROR(CheckClockOffsetSearch(rt, rv, qt, qv, centre, max_offset));
  // Reading samples inside the reference span for every offset searched.
  const double lo = rt.front() + centre + max_offset, hi = rt.back() + centre - max_offset;
  const size_t first = std::lower_bound(qt.begin(), qt.end(), lo) - qt.begin();
  const size_t last = std::upper_bound(qt.begin(), qt.end(), hi) - qt.begin();
  const int used = last > first ? static_cast<int>(last - first) : 0;
  if (used < kMinAuditSamples)
    return absl::InvalidArgumentError(
        absl::StrCat("clock offset: only ", used,
                     " reading samples lie inside the reference span for every offset in ",
                     G(centre), " +/- ", G(max_offset), " s; need at least ", kMinAuditSamples,
                     " (give a smaller --max-clock-offset or the offset with --clock-offset)"));
  const double h =
      std::max(1e-9, std::min(internal::MedianStep(rt, 0.0), internal::MedianStep(qt, 0.0)));
  // Coarse grid (at most 2001 points), then a grid of step h/2 around the
  // best, then golden section within one fine step.
  const double coarse = std::max(0.5 * h, 2 * max_offset / 2000);
  const double fine = std::min(coarse, 0.5 * h);
  const std::function<double(double)> corr = [&](double off) {
    return OffsetCorrelation(rt, rv, qt, qv, first, last, off);
  };
  const CorrelationPeak peak = GoldenSectionPeak(corr, centre, max_offset, fine,
                                                 GridPeak(corr, centre, max_offset, coarse, fine));
  if (peak.offset - (centre - max_offset) < h || (centre + max_offset) - peak.offset < h)
    return absl::InvalidArgumentError(absl::StrCat(
        "clock offset: the correlation peak (", G(peak.offset), " s, |r| = ", peak.correlation,
        ") is at the edge of the search range ", G(centre), " +/- ", G(max_offset),
        " s; the true offset may lie outside: widen --max-clock-offset or give --clock-offset"));
  if (peak.correlation < 0.3)
    return absl::InvalidArgumentError(absl::StrCat(
        "clock offset: no clear correlation between the streams (peak |r| = ", peak.correlation,
        " at ", G(peak.offset),
        " s); check that the files belong together, or give --clock-offset"));
  ClockOffsetEstimate e;
  e.offset = peak.offset;
  e.correlation = peak.correlation;
  e.samples = used;
  return e;
}

namespace {

// InvalidArgument naming the file and line where the time t (column 't' of
// table tb) does not increase.
absl::Status CheckTimeIncreasing(const io::CsvTable& tb, const std::vector<double>& t) {
  for (size_t i = 1; i < t.size(); ++i)
    if (!(t[i] > t[i - 1]))
      return absl::InvalidArgumentError(
          absl::StrCat(tb.source, ":", tb.line_numbers[i], ": column 't': time not increasing (",
                       t[i], " after ", t[i - 1], "); sort the rows by time"));
  return absl::OkStatus();
}

// Appends to d every reading sample (qt, qv; lines from rd) whose time minus
// clock_offset lies in the reference span, with the reference (rt, rv) and
// shear (rs, empty when absent) interpolated linearly there. Returns the
// number of samples outside.
int InterpolateReference(const std::vector<double>& rt, const std::vector<double>& rv,
                         const std::vector<double>& rs, const io::CsvTable& rd,
                         const std::vector<double>& qt, const std::vector<double>& qv,
                         double clock_offset, MeasuredData* d) {
  int outside = 0;
  size_t k = 0;
  for (size_t i = 0; i < qt.size(); ++i) {
    const double tq = qt[i] - clock_offset;
    if (tq < rt.front() || tq > rt.back()) {
      ++outside;
      continue;
    }
    while (k + 2 < rt.size() && rt[k + 1] < tq) ++k;
    const double w = (tq - rt[k]) / (rt[k + 1] - rt[k]);
    d->t.push_back(qt[i]);
    d->reading.push_back(qv[i]);
    d->reference.push_back(rv[k] + w * (rv[k + 1] - rv[k]));
    if (!rs.empty()) d->shear.push_back(rs[k] + w * (rs[k + 1] - rs[k]));
    d->line.push_back(rd.line_numbers[i]);
  }
  return outside;
}

}  // namespace

absl::StatusOr<MeasuredData> AlignStreams(const io::CsvTable& ref, const io::CsvTable& rd,
                                          const AlignOptions& options) {
  TF_RETURN_IF_ERROR(ref.Require({"t", "value"}));
  TF_RETURN_IF_ERROR(rd.Require({"t", "value"}));
  if (!std::isfinite(options.clock_offset))
    return absl::InvalidArgumentError("clock_offset: not a finite number");
  const auto rt = ref.Column("t"), rv = ref.Column("value");
  const auto rs = ref.Has("shear") ? ref.Column("shear") : std::vector<double>{};
  const auto qt = rd.Column("t"), qv = rd.Column("value");
  TF_RETURN_IF_ERROR(CheckTimeIncreasing(ref, rt));
  TF_RETURN_IF_ERROR(CheckTimeIncreasing(rd, qt));
  if (rt.size() < 2)
    return absl::InvalidArgumentError(absl::StrCat(ref.source, ": too few samples: ", rt.size(),
                                                   ", need at least 2 to interpolate"));
  MeasuredData d;
  d.source = absl::StrCat(ref.source, " + ", rd.source);
  double clock_offset = options.clock_offset;
  d.clock_offset_source = MeasuredData::ClockOffset::kFixed;
  if (options.mode == ClockOffsetMode::kEstimate) {
    auto est = EstimateClockOffset(rt, rv, qt, qv, options.clock_offset, options.max_clock_offset);
    if (!est.ok())
      return absl::InvalidArgumentError(
          absl::StrCat(ref.source, " + ", rd.source, ": ", est.status().message()));
    clock_offset = est->offset;
    d.clock_offset_source = MeasuredData::ClockOffset::kEstimated;
    d.clock_offset_correlation = est->correlation;
    // Named apart from the header's clock offset, which adds the audit's
    // refinement to this one.
    d.notes.push_back(absl::StrCat(
        "cross-correlation clock offset (before the audit's refinement): ", G(est->offset),
        " s (peak |r| ", est->correlation, ", ", est->samples, " reading samples, search ",
        G(options.clock_offset), " +/- ", G(options.max_clock_offset), " s)"));
  }
  d.clock_offset = clock_offset;
  const int outside = InterpolateReference(rt, rv, rs, rd, qt, qv, clock_offset, &d);
  d.trial.assign(d.t.size(), 0);
  d.segment_starts = {0};
  d.skipped_nan_rows = ref.skipped_rows + rd.skipped_rows;
  auto rate = [](const std::vector<double>& t) {
    return t.size() > 1 ? (t.size() - 1) / (t.back() - t.front()) : 0.0;
  };
  d.notes.push_back(absl::StrCat(
      "two streams aligned: reference ", rt.size(), " samples at ~", rate(rt),
      " Hz interpolated onto ", d.t.size(), " reading samples at ~", rate(qt), " Hz",
      clock_offset == 0 ? ""
      : d.clock_offset_source == MeasuredData::ClockOffset::kEstimated
          ? absl::StrCat(" (shifted by the cross-correlation clock offset ", G(clock_offset), " s)")
          : absl::StrCat(" (clock offset ", G(clock_offset), " s)")));
  if (outside > 0)
    d.notes.push_back(
        absl::StrCat(outside, " reading sample(s) outside the reference time span dropped"));
  if (d.skipped_nan_rows > 0)
    d.notes.push_back(absl::StrCat(d.skipped_nan_rows, " row(s) with NaN/empty fields skipped"));
  if (d.t.empty())
    return absl::InvalidArgumentError(absl::StrCat(
        d.source, ": the streams do not overlap in time (reference ", G(rt.front()), "..",
        G(rt.back()), " s, reading ", G(qt.front()), "..", G(qt.back()), " s, clock offset ",
        G(clock_offset),
        " s); give the clock offset (--clock-offset) or a search centre (--clock-offset-centre)"));
  TF_RETURN_IF_ERROR(ValidateMeasuredData(d));
  return d;
}

absl::StatusOr<MeasuredData> ReadAndAlignStreams(const std::string& reference_path,
                                                 const std::string& reading_path,
                                                 const AlignOptions& options) {
  io::CsvOptions opt;
  opt.skip_nan_rows = true;
  TF_ASSIGN_OR_RETURN(auto ref, io::ReadCsvFile(reference_path, opt));
  TF_ASSIGN_OR_RETURN(auto rd, io::ReadCsvFile(reading_path, opt));
  return AlignStreams(ref, rd, options);
}

}  // namespace tactforce::audit
