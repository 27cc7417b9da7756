#include "tactforce/audit/measured_data.h"

#include <algorithm>
#include <cmath>

#include "absl/strings/str_cat.h"

namespace tactforce::audit {
namespace {

std::string Where(const MeasuredData& d, int i) {
  if (i >= 0 && i < static_cast<int>(d.line.size())) return absl::StrCat(d.source, ":", d.line[i]);
  return absl::StrCat(d.source, ": sample ", i);
}

}  // namespace

absl::Status ValidateMeasuredData(const MeasuredData& d, int min_samples) {
  const size_t n = d.t.size();
  if (d.reference.size() != n || d.reading.size() != n)
    return absl::InvalidArgumentError(absl::StrCat(d.source, ": columns t, reference, reading differ in length"));
  if (!d.shear.empty() && d.shear.size() != n)
    return absl::InvalidArgumentError(absl::StrCat(d.source, ": column 'shear' differs in length"));
  if (static_cast<int>(n) < min_samples) {
    return absl::InvalidArgumentError(absl::StrCat(
        d.source, ": too few samples: ", n, " valid rows",
        d.skipped_nan_rows ? absl::StrCat(" (", d.skipped_nan_rows, " NaN rows skipped)") : "",
        ", the audit needs at least ", min_samples, " (a training block and a later held-out block)"));
  }
  auto check_finite = [&](const std::vector<double>& v, const char* col) -> absl::Status {
    for (size_t i = 0; i < v.size(); ++i)
      if (!std::isfinite(v[i]))
        return absl::InvalidArgumentError(absl::StrCat(Where(d, i), ": column '", col, "': not a finite number"));
    return absl::OkStatus();
  };
  for (auto st : {check_finite(d.t, "t"), check_finite(d.reference, "reference"),
                  check_finite(d.reading, "reading"), check_finite(d.shear, "shear")})
    if (!st.ok()) return st;
  std::vector<int> starts = d.segment_starts.empty() ? std::vector<int>{0} : d.segment_starts;
  for (size_t i = 1; i < n; ++i) {
    if (std::binary_search(starts.begin(), starts.end(), static_cast<int>(i))) continue;
    if (!(d.t[i] > d.t[i - 1]))
      return absl::InvalidArgumentError(absl::StrCat(Where(d, i), ": column 't': time not increasing (", d.t[i],
                                                     " after ", d.t[i - 1], "); sort the rows by time"));
  }
  auto check_const = [&](const std::vector<double>& v, const char* col, const char* why) -> absl::Status {
    auto [lo, hi] = std::minmax_element(v.begin(), v.end());
    if (*hi - *lo <= 1e-12 * std::max(1.0, std::abs(*hi)))
      return absl::InvalidArgumentError(
          absl::StrCat(d.source, ": column '", col, "' is constant (", *lo, "): ", why));
    return absl::OkStatus();
  };
  if (auto st = check_const(d.reference, "reference",
                            "the audit needs a varying reference force (press, ramp or random profile)");
      !st.ok())
    return st;
  if (auto st = check_const(d.reading, "reading", "the sensor does not respond; nothing to audit"); !st.ok())
    return st;
  return absl::OkStatus();
}

absl::StatusOr<MeasuredData> MeasuredDataFromCsv(const estimator::CsvTable& table) {
  if (auto st = table.Require({"t", "reference", "reading"}); !st.ok()) return st;
  MeasuredData d;
  d.source = table.source;
  d.t = table.Column("t");
  d.reference = table.Column("reference");
  d.reading = table.Column("reading");
  if (table.Has("shear")) d.shear = table.Column("shear");
  d.line = table.line_numbers;
  d.skipped_nan_rows = table.skipped_rows;
  const size_t n = d.t.size();
  d.trial.assign(n, 0);
  if (table.Has("trial")) {
    const auto tr = table.Column("trial");
    std::vector<int> seen;
    for (size_t i = 0; i < n; ++i) {
      if (tr[i] != std::round(tr[i]))
        return absl::InvalidArgumentError(
            absl::StrCat(table.source, ":", d.line[i], ": column 'trial': not an integer (", tr[i], ")"));
      d.trial[i] = static_cast<int>(tr[i]);
      if (i == 0 || d.trial[i] != d.trial[i - 1]) {
        if (std::find(seen.begin(), seen.end(), d.trial[i]) != seen.end())
          return absl::InvalidArgumentError(absl::StrCat(table.source, ":", d.line[i], ": column 'trial': trial ",
                                                         d.trial[i], " resumes after another trial; keep each trial's rows together"));
        seen.push_back(d.trial[i]);
        d.segment_starts.push_back(static_cast<int>(i));
      }
    }
  }
  if (d.segment_starts.empty()) d.segment_starts.push_back(0);
  if (d.skipped_nan_rows > 0)
    d.notes.push_back(absl::StrCat(d.skipped_nan_rows, " row(s) with NaN/empty fields skipped"));
  if (auto st = ValidateMeasuredData(d); !st.ok()) return st;
  return d;
}

absl::StatusOr<MeasuredData> ParseMeasuredCsv(const std::string& text, const std::string& source) {
  estimator::CsvOptions opt;
  opt.skip_nan_rows = true;
  auto table = estimator::ParseCsv(text, source, opt);
  if (!table.ok()) return table.status();
  return MeasuredDataFromCsv(*table);
}

absl::StatusOr<MeasuredData> ReadMeasuredCsv(const std::string& path) {
  estimator::CsvOptions opt;
  opt.skip_nan_rows = true;
  auto table = estimator::ReadCsvFile(path, opt);
  if (!table.ok()) return table.status();
  return MeasuredDataFromCsv(*table);
}

absl::StatusOr<MeasuredData> AlignStreams(const estimator::CsvTable& ref, const estimator::CsvTable& rd,
                                          const AlignOptions& options) {
  if (auto st = ref.Require({"t", "value"}); !st.ok()) return st;
  if (auto st = rd.Require({"t", "value"}); !st.ok()) return st;
  if (!std::isfinite(options.clock_offset))
    return absl::InvalidArgumentError("clock_offset: not a finite number");
  const auto rt = ref.Column("t"), rv = ref.Column("value");
  const bool has_shear = ref.Has("shear");
  const auto rs = has_shear ? ref.Column("shear") : std::vector<double>{};
  const auto qt = rd.Column("t"), qv = rd.Column("value");
  auto check_sorted = [](const estimator::CsvTable& tb, const std::vector<double>& t) -> absl::Status {
    for (size_t i = 1; i < t.size(); ++i)
      if (!(t[i] > t[i - 1]))
        return absl::InvalidArgumentError(absl::StrCat(tb.source, ":", tb.line_numbers[i],
                                                       ": column 't': time not increasing (", t[i], " after ",
                                                       t[i - 1], "); sort the rows by time"));
    return absl::OkStatus();
  };
  if (auto st = check_sorted(ref, rt); !st.ok()) return st;
  if (auto st = check_sorted(rd, qt); !st.ok()) return st;
  if (rt.size() < 2)
    return absl::InvalidArgumentError(absl::StrCat(ref.source, ": too few samples: ", rt.size(),
                                                   ", need at least 2 to interpolate"));
  MeasuredData d;
  d.source = absl::StrCat(ref.source, " + ", rd.source);
  int outside = 0;
  size_t k = 0;
  for (size_t i = 0; i < qt.size(); ++i) {
    const double tq = qt[i] - options.clock_offset;
    if (tq < rt.front() || tq > rt.back()) {
      ++outside;
      continue;
    }
    while (k + 2 < rt.size() && rt[k + 1] < tq) ++k;
    const double w = (tq - rt[k]) / (rt[k + 1] - rt[k]);
    d.t.push_back(qt[i]);
    d.reading.push_back(qv[i]);
    d.reference.push_back(rv[k] + w * (rv[k + 1] - rv[k]));
    if (has_shear) d.shear.push_back(rs[k] + w * (rs[k + 1] - rs[k]));
    d.line.push_back(rd.line_numbers[i]);
  }
  d.trial.assign(d.t.size(), 0);
  d.segment_starts = {0};
  d.skipped_nan_rows = ref.skipped_rows + rd.skipped_rows;
  auto rate = [](const std::vector<double>& t) {
    return t.size() > 1 ? (t.size() - 1) / (t.back() - t.front()) : 0.0;
  };
  d.notes.push_back(absl::StrCat("two streams aligned: reference ", rt.size(), " samples at ~", rate(rt),
                                 " Hz interpolated onto ", d.t.size(), " reading samples at ~", rate(qt), " Hz",
                                 options.clock_offset != 0 ? absl::StrCat(" (clock offset ", options.clock_offset, " s)") : ""));
  if (outside > 0)
    d.notes.push_back(absl::StrCat(outside, " reading sample(s) outside the reference time span dropped"));
  if (d.skipped_nan_rows > 0)
    d.notes.push_back(absl::StrCat(d.skipped_nan_rows, " row(s) with NaN/empty fields skipped"));
  if (d.t.empty())
    return absl::InvalidArgumentError(absl::StrCat(
        d.source, ": the streams do not overlap in time (reference ", rt.front(), "..", rt.back(), " s, reading ",
        qt.front(), "..", qt.back(), " s); give the clock offset"));
  if (auto st = ValidateMeasuredData(d); !st.ok()) return st;
  return d;
}

absl::StatusOr<MeasuredData> ReadAndAlignStreams(const std::string& reference_path, const std::string& reading_path,
                                                 const AlignOptions& options) {
  estimator::CsvOptions opt;
  opt.skip_nan_rows = true;
  auto ref = estimator::ReadCsvFile(reference_path, opt);
  if (!ref.ok()) return ref.status();
  auto rd = estimator::ReadCsvFile(reading_path, opt);
  if (!rd.ok()) return rd.status();
  return AlignStreams(*ref, *rd, options);
}

}  // namespace tactforce::audit
