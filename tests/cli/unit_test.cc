// Client pieces without a server: the latency histogram, --target parsing
// and the mapping of gRPC failures to the CLI's errors.
#include <cstdint>
#include <random>
#include <thread>
#include <vector>

#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include "connection.h"
#include "load/latency_histogram.h"

namespace tactforce::cli {
namespace {

TEST(LatencyHistogramTest, BucketsTileTheRange) {
  int previous = -1;
  for (int64_t v :
       {int64_t{0}, int64_t{1}, int64_t{2047}, int64_t{2048}, int64_t{2049}, int64_t{4095},
        int64_t{4096}, int64_t{90'000}, int64_t{1'000'000'007}, (int64_t{1} << 40) - 1}) {
    const int index = LatencyHistogram::BucketIndex(v);
    EXPECT_LE(LatencyHistogram::BucketLow(index), v);
    EXPECT_GT(LatencyHistogram::BucketHigh(index), v);
    EXPECT_GE(index, previous);  // values in increasing order: buckets never go back
    previous = index;
  }
  EXPECT_EQ(LatencyHistogram::BucketIndex(int64_t{1} << 50), LatencyHistogram::BucketCount() - 1);
  for (int i = 1; i < LatencyHistogram::BucketCount(); ++i) {
    ASSERT_EQ(LatencyHistogram::BucketLow(i), LatencyHistogram::BucketHigh(i - 1)) << i;
  }
}

TEST(LatencyHistogramTest, QuantilesMatchASortedVector) {
  std::mt19937_64 rng(7);
  std::lognormal_distribution<double> latency(std::log(90'000.0), 0.6);  // ~90 us
  std::vector<int64_t> values;
  LatencyHistogram histogram;
  for (int i = 0; i < 100'000; ++i) {
    values.push_back(static_cast<int64_t>(latency(rng)));
    histogram.Record(values.back());
  }
  std::sort(values.begin(), values.end());
  EXPECT_EQ(histogram.count(), 100'000);
  EXPECT_EQ(histogram.max(), values.back());
  EXPECT_EQ(histogram.Quantile(1.0), static_cast<double>(values.back()));
  for (double q : {0.5, 0.9, 0.99, 0.999}) {
    const double exact = static_cast<double>(values[static_cast<size_t>(q * values.size()) - 1]);
    EXPECT_NEAR(histogram.Quantile(q), exact, exact / 1000.0) << q;
  }
}

TEST(LatencyHistogramTest, SmallValuesAreExactAndEmptyIsZero) {
  LatencyHistogram histogram;
  EXPECT_EQ(histogram.Quantile(0.5), 0.0);
  for (int v = 1; v <= 100; ++v) histogram.Record(v);
  EXPECT_EQ(histogram.Quantile(0.5), 50.0);
  EXPECT_EQ(histogram.Quantile(0.99), 99.0);
  EXPECT_EQ(histogram.max(), 100);
  histogram.Record(-5);  // clock hiccup: counts as 0
  EXPECT_EQ(histogram.count(), 101);
}

TEST(LatencyHistogramTest, ConcurrentRecordsAreAllCounted) {
  LatencyHistogram histogram;
  std::vector<std::thread> threads;
  for (int t = 0; t < 4; ++t) {
    threads.emplace_back([&histogram, t] {
      for (int i = 0; i < 50'000; ++i) histogram.Record(1000 + t * 100'000 + i);
    });
  }
  for (auto& thread : threads) thread.join();
  EXPECT_EQ(histogram.count(), 200'000);
  EXPECT_EQ(histogram.max(), 1000 + 3 * 100'000 + 49'999);
}

TEST(TargetsTest, SplitsPlainListsAndKeepsUris) {
  using ::testing::ElementsAre;
  EXPECT_THAT(*SplitTargets("localhost:50051"), ElementsAre("localhost:50051"));
  EXPECT_THAT(*SplitTargets("127.0.0.1:1, 127.0.0.1:2"), ElementsAre("127.0.0.1:1", "127.0.0.1:2"));
  EXPECT_THAT(*SplitTargets("ipv4:127.0.0.1:1,127.0.0.1:2"),
              ElementsAre("ipv4:127.0.0.1:1,127.0.0.1:2"));
  EXPECT_THAT(*SplitTargets("[::1]:50051"), ElementsAre("[::1]:50051"));
  EXPECT_FALSE(SplitTargets("a:1,,b:2").ok());
  EXPECT_FALSE(SplitTargets("").ok());
  EXPECT_TRUE(HasUriScheme("dns:///localhost:50051"));
  EXPECT_TRUE(HasUriScheme("unix:/tmp/socket"));
  EXPECT_FALSE(HasUriScheme("localhost:50051"));
}

TEST(RpcErrorTest, MapsCodesToTheDocumentedErrors) {
  absl::Status s = RpcError(grpc::Status(grpc::StatusCode::UNAVAILABLE, "refused"), "h:1", 100);
  EXPECT_EQ(s.code(), absl::StatusCode::kUnavailable);
  EXPECT_EQ(s.message(), "cannot reach h:1: refused");
  s = RpcError(grpc::Status(grpc::StatusCode::INVALID_ARGUMENT, "contacts[0].friction: < 0"), "h:1",
               100);
  EXPECT_EQ(s.code(), absl::StatusCode::kInvalidArgument);
  EXPECT_EQ(s.message(), "contacts[0].friction: < 0");
  s = RpcError(grpc::Status(grpc::StatusCode::DEADLINE_EXCEEDED, "Deadline Exceeded"), "h:1", 100);
  EXPECT_EQ(s.code(), absl::StatusCode::kDeadlineExceeded);
  EXPECT_EQ(s.message(), "h:1: no answer within 100 ms (--deadline-ms)");
  s = RpcError(grpc::Status(grpc::StatusCode::RESOURCE_EXHAUSTED, "busy"), "h:1", 100);
  EXPECT_EQ(s.code(), absl::StatusCode::kResourceExhausted);
  EXPECT_EQ(StatusCodeName(grpc::StatusCode::UNAUTHENTICATED), "UNAUTHENTICATED");
  EXPECT_EQ(StatusCodeName(grpc::StatusCode::DEADLINE_EXCEEDED), "DEADLINE_EXCEEDED");
}

TEST(RpcErrorTest, EveryCanonicalCodeHasItsNameAndOthersTheirNumber) {
  EXPECT_EQ(StatusCodeName(grpc::StatusCode::OK), "OK");
  EXPECT_EQ(StatusCodeName(grpc::StatusCode::CANCELLED), "CANCELLED");
  EXPECT_EQ(StatusCodeName(grpc::StatusCode::RESOURCE_EXHAUSTED), "RESOURCE_EXHAUSTED");
  EXPECT_EQ(StatusCodeName(grpc::StatusCode::UNAVAILABLE), "UNAVAILABLE");
  EXPECT_EQ(StatusCodeName(static_cast<grpc::StatusCode>(17)), "CODE_17");
}

}  // namespace
}  // namespace tactforce::cli
