// Measured data for the sensor-model audit: a reference force (N) and the
// sensor's reading (its own units) on one clock.
//
// Formats (see README):
//   one CSV      t,reference,reading[,shear][,trial]
//   per taxel    t,reference,taxel_0,...,taxel_<N-1>[,reading][,shear][,trial]:
//                one column per taxel (its reading, any units); 'reading'
//                (the fingertip's) defaults to the sum of the taxels, as
//                GeoDEx defines the fingertip force. Taxel columns must be
//                numbered 0..N-1 without gaps (N = expected_taxels when given,
//                else the highest index + 1); a gap is an error naming it.
//   two streams  reference file t,value[,shear]; reading file t,value.
//                The reference is interpolated (linearly) onto the reading
//                times; reading samples outside the reference span are
//                dropped (counted in notes). Rates may differ. The clock
//                offset (reading clock minus reference clock) is either given
//                (ClockOffsetMode::kFixed; any remaining offset then shows up
//                as the 'delay' cause) or estimated (kEstimate: maximum of the
//                correlation of the reading with the interpolated reference
//                over clock_offset +/- max_clock_offset, refined sub-sample;
//                the audit then refines it further as a nuisance delay and
//                reports it as clock_offset_s instead of naming 'delay': a
//                constant sensor delay and a clock offset are
//                indistinguishable from two streams).
// NaN/empty rows are SKIPPED AND COUNTED (MeasuredData::skipped_nan_rows).
// Time must increase strictly within each trial (rows of one trial are
// contiguous; a 'trial' change starts a new segment whose time may restart).
#pragma once

#include <string>
#include <vector>

#include "absl/status/statusor.h"
#include "tactforce/io/csv.h"

namespace tactforce::audit {

struct MeasuredData {
  std::string source;               // file name(s), for messages
  std::vector<double> t;            // s
  std::vector<double> reference;    // N
  std::vector<double> reading;      // sensor units
  std::vector<double> shear;        // N, empty when absent
  std::vector<int> trial;           // per sample (0 when absent)
  std::vector<int> segment_starts;  // first sample index of each trial (starts with 0)
  std::vector<int> line;            // source line per sample (may be empty)
  // Per-taxel readings (sensor units), taxels[j][i] = taxel j at sample i;
  // empty unless the CSV has taxel_<j> columns.
  std::vector<std::vector<double>> taxels;
  int skipped_nan_rows = 0;
  std::vector<std::string> notes;  // e.g. alignment facts
  // Two streams only.
  enum class ClockOffset { kNone, kFixed, kEstimated };
  ClockOffset clock_offset_source = ClockOffset::kNone;
  double clock_offset = 0;              // s, applied (reading time - offset = reference time)
  double clock_offset_correlation = 0;  // kEstimated: peak |correlation|
};

// Largest reading magnitude accepted (sensor units; raw 32-bit counts fit).
// Time stamps, reference and shear take planner/validation.h's limits
// (kMaxTime, kMinTimeStep between samples of a trial, kMaxForce).
inline constexpr double kMaxReading = 1e12;

// Minimum number of samples an audit needs (train + held-out block).
inline constexpr int kMinAuditSamples = 40;

// Errors (InvalidArgument): "<file>: missing column(s) reading";
// "<file>:<line>: column 't': time not increasing (0.5 after 0.6)";
// "<file>: column 'reference' is constant (2 N): ..."; too few samples
// ("<file>: too few samples: 12 valid rows (3 NaN rows skipped), the audit
// needs at least 40").
// Per-taxel CSVs: "<file>: missing column(s) taxel_5, taxel_17 (per-taxel
// data needs taxel_0 ... taxel_41)". expected_taxels = 0: N is the highest
// taxel index + 1 (a CSV without taxel columns is single-channel data).
absl::StatusOr<MeasuredData> MeasuredDataFromCsv(const io::CsvTable& table,
                                                 int expected_taxels = 0);
absl::StatusOr<MeasuredData> ReadMeasuredCsv(const std::string& path, int expected_taxels = 0);
absl::StatusOr<MeasuredData> ParseMeasuredCsv(const std::string& text, const std::string& source,
                                              int expected_taxels = 0);
// The largest taxel count a per-taxel CSV may declare.
inline constexpr int kMaxTaxels = 4096;

enum class ClockOffsetMode {
  kFixed,     // use clock_offset as given (default: 0)
  kEstimate,  // estimate it within clock_offset +/- max_clock_offset
};
struct AlignOptions {
  double clock_offset =
      0;  // s: reading time minus this = reference time (kEstimate: search centre)
  ClockOffsetMode mode = ClockOffsetMode::kFixed;
  double max_clock_offset = 1.0;  // s, kEstimate: half-width of the search
};

struct ClockOffsetEstimate {
  double offset = 0;       // s, reading clock minus reference clock
  double correlation = 0;  // |Pearson correlation| at the peak
  int samples = 0;         // reading samples used (inside the overlap for every offset searched)
};
// Maximises |corr(reading(t), reference(t - offset))| (reference linearly
// interpolated) over centre +/- max_offset: coarse grid, then a finer grid and
// a golden-section search to well below a sample period. Errors
// (InvalidArgument): the search range is not shorter than the streams'
// overlap, too few samples inside the overlap for every searched offset, the
// peak on the edge of the range, no clear correlation (peak |r| < 0.3).
absl::StatusOr<ClockOffsetEstimate> EstimateClockOffset(const std::vector<double>& reference_t,
                                                        const std::vector<double>& reference_value,
                                                        const std::vector<double>& reading_t,
                                                        const std::vector<double>& reading_value,
                                                        double centre, double max_offset);
absl::StatusOr<MeasuredData> AlignStreams(const io::CsvTable& reference,
                                          const io::CsvTable& reading,
                                          const AlignOptions& options = {});
absl::StatusOr<MeasuredData> ReadAndAlignStreams(const std::string& reference_path,
                                                 const std::string& reading_path,
                                                 const AlignOptions& options = {});

// Checks sizes, finiteness, magnitudes (kMaxReading and the planner's
// limits, see above), time order and resolution, non-constant columns,
// sample count.
absl::Status ValidateMeasuredData(const MeasuredData& data, int min_samples = kMinAuditSamples);

}  // namespace tactforce::audit
