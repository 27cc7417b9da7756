#include "tactforce/server/rpc_support.h"

#include <gtest/gtest.h>

#include "tactforce/server/server_host.h"

namespace tactforce::server {
namespace {

TEST(RpcSupportTest, StatusMapping) {
  grpc::Status s = ToGrpcStatus(absl::InvalidArgumentError("contacts[2].normal: zero length"));
  EXPECT_EQ(s.error_code(), grpc::StatusCode::INVALID_ARGUMENT);
  EXPECT_EQ(s.error_message(), "contacts[2].normal: zero length");
  EXPECT_TRUE(ToGrpcStatus(absl::OkStatus()).ok());
  EXPECT_STREQ(StatusCodeName(grpc::StatusCode::RESOURCE_EXHAUSTED), "RESOURCE_EXHAUSTED");
  EXPECT_STREQ(StatusCodeName(grpc::StatusCode::DEADLINE_EXCEEDED), "DEADLINE_EXCEEDED");
}

TEST(RpcSupportTest, GuardWithoutContextNeverStops) {
  RpcGuard guard(nullptr);
  EXPECT_FALSE(guard.has_deadline());
  EXPECT_FALSE(guard.ShouldStop());
  EXPECT_FALSE(guard.Interrupt()());
}

TEST(RpcSupportTest, GuardSeesTheCancelFlag) {
  std::atomic<bool> cancelled{false};
  RpcGuard guard(nullptr, &cancelled);
  auto interrupt = guard.Interrupt();
  EXPECT_FALSE(interrupt());
  cancelled = true;
  EXPECT_TRUE(interrupt());
  EXPECT_EQ(guard.StopStatus("during the solve").error_code(), grpc::StatusCode::CANCELLED);
}

TEST(RpcSupportTest, LogValueQuotesWhenNeeded) {
  EXPECT_EQ(LogValue("ipv4:127.0.0.1:5"), "ipv4:127.0.0.1:5");
  EXPECT_EQ(LogValue(""), "\"\"");
  EXPECT_EQ(LogValue("a b"), "\"a b\"");
  EXPECT_EQ(LogValue("say \"hi\"\n"), "\"say \\\"hi\\\"\\n\"");
}

TEST(ServerHostTest, WithBoundPort) {
  EXPECT_EQ(WithBoundPort("127.0.0.1:0", 43211), "127.0.0.1:43211");
  EXPECT_EQ(WithBoundPort("[::1]:0", 5), "[::1]:5");
  EXPECT_EQ(WithBoundPort("0.0.0.0:50051", 50051), "0.0.0.0:50051");
  EXPECT_EQ(WithBoundPort("127.0.0.1:10", 10), "127.0.0.1:10");
  EXPECT_EQ(WithBoundPort("unix:/tmp/s:0", 1), "unix:/tmp/s:0");
}

}  // namespace
}  // namespace tactforce::server
