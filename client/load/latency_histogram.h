// Latency recording for `tactforce load`: a log-linear histogram in the
// style of HdrHistogram. Constant memory whatever the run length, lock-free
// Record() from any thread, quantiles within 0.1 % of the recorded values
// (1024 linear sub-buckets per power of two), exact maximum; the recorded
// values regrouped into log-spaced bins for a plot.
#pragma once

#include <array>
#include <atomic>
#include <cstdint>
#include <memory>
#include <vector>

namespace tactforce::cli {

class LatencyHistogram {
 public:
  LatencyHistogram();

  // Records one value (nanoseconds; negatives count as 0, values above
  // ~18 minutes as 18 minutes). Thread-safe.
  void Record(int64_t nanos);

  int64_t count() const { return count_.load(std::memory_order_relaxed); }
  int64_t max() const { return max_.load(std::memory_order_relaxed); }

  // The value at quantile q in [0, 1] (nanoseconds): the smallest recorded
  // value v such that at least q * count() values are <= v, reported as the
  // middle of v's bucket (relative error <= 1/2048) and never above max().
  // 0 when empty; q >= 1 gives max().
  double Quantile(double q) const;

  // The recorded values in bins of equal width on a log scale, `per_decade`
  // bins per factor of 10 (bin k covers [10^(k/per_decade),
  // 10^((k+1)/per_decade)) ns; values below 1 ns count as 1 ns), from the
  // lowest to the highest bin holding a value, empty bins between included.
  // Each internal bucket goes whole to the bin of its lower edge (buckets
  // are 0.1 % wide, so the bin edges are that exact). Empty when nothing
  // was recorded. Not synchronised with concurrent Record() calls beyond
  // each count being read atomically.
  struct Bin {
    double low_ns = 0, high_ns = 0;
    int64_t count = 0;
  };
  std::vector<Bin> LogBins(int per_decade) const;

  // --- exposed for tests ---
  static constexpr int kSubBucketBits = 11;  // 2048 values below 2^11 ns are exact
  static constexpr int kMaxBits = 40;        // 2^40 ns ~ 18.3 min
  static int BucketIndex(int64_t nanos);
  // [low, high) of bucket `index`.
  static int64_t BucketLow(int index);
  static int64_t BucketHigh(int index);
  static int BucketCount();

 private:
  std::unique_ptr<std::atomic<int64_t>[]> buckets_;
  std::atomic<int64_t> count_{0};
  std::atomic<int64_t> max_{0};
};

}  // namespace tactforce::cli
