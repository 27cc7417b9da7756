// ServerConfig: the limit flags fill its one api::CallLimits, and every
// service's view of the limits (host options, plan settings) is that value.
#include "tactforce/server/server_config.h"

#include <algorithm>
#include <random>
#include <string>
#include <vector>

#include <gtest/gtest.h>

namespace tactforce::server {
namespace {

// Parses `args` (without the program name) into a fresh config.
ServerConfig Parse(std::vector<std::string> args) {
  ServerConfig config;
  CLI::App app;
  RegisterFlags(app, &config);
  std::reverse(args.begin(), args.end());  // CLI11 takes them back to front
  app.parse(args);
  return config;
}

TEST(ServerConfigTest, DefaultsAreTheServersLimits) {
  const ServerConfig config = Parse({});
  EXPECT_EQ(config.limits.max_response_bytes, 4 << 20);
  EXPECT_EQ(config.limits.max_fit_bytes, int64_t{256} << 20);
  EXPECT_EQ(config.solve_timeout_ms(), 10'000);
  EXPECT_DOUBLE_EQ(config.limits.solve_timeout_seconds(), 10.0);
  EXPECT_EQ(config.limits.max_contacts, api::CallLimits{}.max_contacts);
  EXPECT_EQ(config.ToServerOptions().max_message_bytes, 4 << 20);
}

// Values drawn from a seed: each flag lands in the one CallLimits, and the
// host and the Planner see exactly those.
TEST(ServerConfigTest, FlagsFillTheOneCallLimits) {
  std::mt19937 rng(27);
  for (int trial = 0; trial < 20; ++trial) {
    const int contacts = std::uniform_int_distribution<int>(1, 100'000)(rng);
    const int timeout_ms = std::uniform_int_distribution<int>(0, 3'600'000)(rng);
    const int message_bytes = std::uniform_int_distribution<int>(1024, 1 << 30)(rng);
    const int64_t work = std::uniform_int_distribution<int64_t>(1, 1'000'000'000)(rng);
    const int64_t audit = std::uniform_int_distribution<int64_t>(40, 100'000'000)(rng);
    const int64_t fit = std::uniform_int_distribution<int64_t>(0, int64_t{1} << 40)(rng);
    const ServerConfig config =
        Parse({"--max-contacts", std::to_string(contacts), "--solve-timeout-ms",
               std::to_string(timeout_ms), "--max-message-bytes", std::to_string(message_bytes),
               "--max-trajectory-work", std::to_string(work), "--max-audit-samples",
               std::to_string(audit), "--max-fit-bytes", std::to_string(fit),
               "--inline-max-contacts", "3"});
    const api::CallLimits& limits = config.limits;
    EXPECT_EQ(limits.max_contacts, contacts);
    EXPECT_EQ(config.solve_timeout_ms(), timeout_ms);
    EXPECT_DOUBLE_EQ(limits.solve_timeout_seconds(), timeout_ms / 1000.0);
    EXPECT_EQ(limits.max_response_bytes, message_bytes);
    EXPECT_EQ(config.ToServerOptions().max_message_bytes, message_bytes);
    EXPECT_EQ(limits.max_trajectory_work, work);
    EXPECT_EQ(limits.max_audit_samples, audit);
    EXPECT_EQ(limits.max_fit_bytes, fit);

    const api::PlanSettings plan = config.ToPlanSettings();
    EXPECT_EQ(plan.inline_max_contacts, 3);
    EXPECT_EQ(plan.limits.max_contacts, contacts);
    EXPECT_EQ(plan.limits.solve_timeout_ms, limits.solve_timeout_ms);
    EXPECT_EQ(plan.limits.max_response_bytes, message_bytes);
  }
}

TEST(ServerConfigTest, OutOfRangeLimitIsRefusedByName) {
  for (const std::vector<std::string>& args : std::vector<std::vector<std::string>>{
           {"--solve-timeout-ms", "-1"}, {"--max-message-bytes", "10"}, {"--max-contacts", "0"}}) {
    ServerConfig config;
    CLI::App app;
    RegisterFlags(app, &config);
    std::vector<std::string> reversed(args.rbegin(), args.rend());
    try {
      app.parse(reversed);
      ADD_FAILURE() << args[0] << " " << args[1] << " was accepted";
    } catch (const CLI::ParseError& e) {
      EXPECT_NE(std::string(e.what()).find(args[0]), std::string::npos) << e.what();
    }
  }
}

}  // namespace
}  // namespace tactforce::server
