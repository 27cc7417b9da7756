// The log-linear latency histogram of `tactforce load`: bucket layout
// (exact below 2^kSubBucketBits ns, then kHalf buckets per power of two),
// lock-free recording, quantiles and log-spaced bins.
#include "latency_histogram.h"

#include <algorithm>
#include <bit>
#include <cmath>

namespace tactforce::cli {
namespace {

constexpr int64_t kLinear = int64_t{1} << LatencyHistogram::kSubBucketBits;  // exact range
constexpr int64_t kHalf = kLinear / 2;  // buckets per power of two above it
constexpr int64_t kLargest = (int64_t{1} << LatencyHistogram::kMaxBits) - 1;

}  // namespace

// Layout: values below kLinear have one bucket each. Above, a value with
// highest set bit e keeps its top kSubBucketBits bits: it falls into one of
// kHalf buckets of width 2^shift, shift = e - kSubBucketBits + 1 >= 1.
int LatencyHistogram::BucketIndex(int64_t nanos) {
  const int64_t v = std::clamp<int64_t>(nanos, 0, kLargest);
  if (v < kLinear) return static_cast<int>(v);
  const int e = std::bit_width(static_cast<uint64_t>(v)) - 1;
  const int shift = e - kSubBucketBits + 1;
  const int64_t mantissa = v >> shift;  // in [kHalf, kLinear)
  return static_cast<int>(kLinear + (shift - 1) * kHalf + (mantissa - kHalf));
}

int64_t LatencyHistogram::BucketLow(int index) {
  if (index < kLinear) return index;
  const int64_t j = index - kLinear;
  const int shift = static_cast<int>(j / kHalf) + 1;
  const int64_t mantissa = j % kHalf + kHalf;
  return mantissa << shift;
}

int64_t LatencyHistogram::BucketHigh(int index) {
  if (index < kLinear) return index + 1;
  const int64_t j = index - kLinear;
  const int shift = static_cast<int>(j / kHalf) + 1;
  const int64_t mantissa = j % kHalf + kHalf;
  return (mantissa + 1) << shift;
}

int LatencyHistogram::BucketCount() { return BucketIndex(kLargest) + 1; }

LatencyHistogram::LatencyHistogram()
    : buckets_(std::make_unique<std::atomic<int64_t>[]>(BucketCount())) {
  for (int i = 0; i < BucketCount(); ++i) buckets_[i].store(0, std::memory_order_relaxed);
}

void LatencyHistogram::Record(int64_t nanos) {
  const int64_t v = std::clamp<int64_t>(nanos, 0, kLargest);
  buckets_[BucketIndex(v)].fetch_add(1, std::memory_order_relaxed);
  count_.fetch_add(1, std::memory_order_relaxed);
  int64_t seen = max_.load(std::memory_order_relaxed);
  while (v > seen && !max_.compare_exchange_weak(seen, v, std::memory_order_relaxed)) {
  }
}

double LatencyHistogram::Quantile(double q) const {
  const int64_t n = count();
  if (n == 0) return 0.0;
  const double top = static_cast<double>(max());
  if (q >= 1.0) return top;
  const int64_t rank = std::max<int64_t>(1, static_cast<int64_t>(std::ceil(std::max(q, 0.0) * n)));
  int64_t seen = 0;
  const int buckets = BucketCount();
  for (int i = 0; i < buckets; ++i) {
    seen += buckets_[i].load(std::memory_order_relaxed);
    if (seen >= rank) {
      if (i < kLinear) return std::min(static_cast<double>(i), top);  // exact
      const double middle = 0.5 * static_cast<double>(BucketLow(i) + BucketHigh(i) - 1);
      return std::min(middle, top);
    }
  }
  return top;
}

std::vector<LatencyHistogram::Bin> LatencyHistogram::LogBins(int per_decade) const {
  per_decade = std::max(per_decade, 1);
  std::vector<Bin> bins;
  int first = 0;  // log-bin index of bins[0]
  const int buckets = BucketCount();
  for (int i = 0; i < buckets; ++i) {
    const int64_t count = buckets_[i].load(std::memory_order_relaxed);
    if (count == 0) continue;
    const double low = static_cast<double>(std::max<int64_t>(BucketLow(i), 1));
    // Nudged up so that a lower edge exactly at a power of ten is not
    // pushed into the bin below by rounding.
    const int k = static_cast<int>(std::floor(std::log10(low) * per_decade + 1e-9));
    if (bins.empty()) first = k;
    while (first + static_cast<int>(bins.size()) <= k) {
      const int j = first + static_cast<int>(bins.size());
      bins.push_back({std::pow(10.0, static_cast<double>(j) / per_decade),
                      std::pow(10.0, static_cast<double>(j + 1) / per_decade), 0});
    }
    bins[k - first].count += count;
  }
  return bins;
}

}  // namespace tactforce::cli
