// The one path of a service call (dispatch.h), in process: where a plan
// runs, what a refused or stopped call answers, and the log line, with a
// pool whose tasks the test runs by hand and a caller the test controls.
#include "tactforce/api/dispatch.h"

#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include <deque>
#include <functional>
#include <memory>
#include <new>
#include <optional>
#include <sstream>
#include <stdexcept>
#include <string>
#include <thread>

#include "absl/strings/str_cat.h"
#include "spdlog/sinks/ostream_sink.h"
#include "spdlog/spdlog.h"
#include "tactforce/api/convert.h"
#include "tactforce/planner/examples.h"

namespace tactforce::api {
namespace {

using ::testing::HasSubstr;
using ::testing::Not;
using ::testing::StartsWith;

// Holds submitted tasks until RunAll(); refuses beyond `capacity`.
class ManualPool final : public Executor {
 public:
  explicit ManualPool(int capacity) : capacity_(capacity) {}
  bool TrySubmit(std::function<void()> task) override {
    if (static_cast<int>(tasks_.size()) >= capacity_) return false;
    tasks_.push_back(std::move(task));
    return true;
  }
  int workers() const override { return 1; }
  int max_queued() const override { return capacity_ > 0 ? capacity_ - 1 : 0; }
  int pending() const { return static_cast<int>(tasks_.size()); }
  void RunAll() {
    while (!tasks_.empty()) {
      std::function<void()> task = std::move(tasks_.front());
      tasks_.pop_front();
      task();
    }
  }

 private:
  int capacity_;
  std::deque<std::function<void()>> tasks_;
};

// A caller whose deadline passes when the test says so.
class TestCaller final : public CallControl {
 public:
  bool ShouldStop() const override { return expired; }
  absl::Status StopReason(std::string_view when) const override {
    return absl::DeadlineExceededError("deadline exceeded " + std::string(when));
  }
  std::string Peer() const override { return "test-peer"; }
  bool expired = false;
};

// Captures what the default spdlog logger writes, one "%v" per line.
class LogCapture {
 public:
  explicit LogCapture(spdlog::level::level_enum level = spdlog::level::info)
      : previous_(spdlog::default_logger()) {
    auto logger = std::make_shared<spdlog::logger>(
        "dispatch_test", std::make_shared<spdlog::sinks::ostream_sink_st>(out_));
    logger->set_pattern("%v");
    logger->set_level(level);
    spdlog::set_default_logger(logger);
  }
  ~LogCapture() { spdlog::set_default_logger(previous_); }
  std::string text() const { return out_.str(); }

 private:
  std::ostringstream out_;
  std::shared_ptr<spdlog::logger> previous_;
};

// Remembers the status `done` was called with (and how often).
struct Outcome {
  std::optional<absl::Status> status;
  int calls = 0;
  CallDone Done() {
    return [this](const absl::Status& s) {
      status = s;
      ++calls;
    };
  }
};

v1::PlanRequest Grasp(v1::Solver solver) {
  const planner::ExampleGrasp grasp = planner::BuiltInGrasps()[1];  // wrench-3f
  v1::PlanRequest request =
      ToRequest(grasp.problem, grasp.options, planner::SolverKind::kGeometric);
  request.set_solver(solver);
  return request;
}

// One plan dispatched through a ManualPool of `capacity` slots.
class ApiPlanDispatchTest : public ::testing::Test {
 protected:
  void Dispatch(const v1::PlanRequest& request, const PlanSettings& settings = {}, int capacity = 4,
                const char* rpc = "Plan", int64_t index = -1) {
    pool_.emplace(capacity);
    dispatcher_.emplace(&*pool_, settings);
    dispatcher_->Dispatch(request, &response_, CallLog(rpc, caller_, index), caller_,
                          outcome_.Done());
  }

  std::optional<ManualPool> pool_;
  std::optional<PlanDispatcher> dispatcher_;
  TestCaller caller_;
  v1::PlanResponse response_;
  Outcome outcome_;
};

TEST_F(ApiPlanDispatchTest, SmallGeometricPlanRunsInlineAndLogsOneLine) {
  LogCapture log;
  Dispatch(Grasp(v1::SOLVER_GEOMETRIC));
  ASSERT_EQ(outcome_.calls, 1);  // before Dispatch returned
  EXPECT_TRUE(outcome_.status->ok()) << *outcome_.status;
  EXPECT_EQ(pool_->pending(), 0);
  EXPECT_EQ(response_.status(), v1::PLAN_STATUS_OPTIMAL);
  EXPECT_THAT(log.text(), StartsWith("rpc=Plan code=OK solver=GEOMETRIC contacts=3 where=inline "
                                     "plan_status=OPTIMAL solve_us="));
  EXPECT_THAT(log.text(), HasSubstr(" peer=test-peer\n"));
}

TEST_F(ApiPlanDispatchTest, IpoptPlanRunsOnThePool) {
  LogCapture log(spdlog::level::debug);
  Dispatch(Grasp(v1::SOLVER_IPOPT), {}, 4, "PlanStream", 7);
  EXPECT_EQ(outcome_.calls, 0);
  ASSERT_EQ(pool_->pending(), 1);
  EXPECT_THAT(log.text(), HasSubstr("rpc=PlanStream event=queued solver=IPOPT contacts=3\n"));
  pool_->RunAll();
  ASSERT_EQ(outcome_.calls, 1);
  EXPECT_TRUE(outcome_.status->ok()) << *outcome_.status;
  EXPECT_EQ(response_.status(), v1::PLAN_STATUS_OPTIMAL);
  EXPECT_EQ(response_.solver(), v1::SOLVER_IPOPT);
  EXPECT_THAT(log.text(), HasSubstr("rpc=PlanStream index=7 code=OK solver=IPOPT contacts=3 "
                                    "where=pool plan_status=OPTIMAL solve_us="));
}

TEST_F(ApiPlanDispatchTest, InlineLimitZeroSendsEveryPlanToThePool) {
  PlanSettings settings;
  settings.inline_max_contacts = 0;
  Dispatch(Grasp(v1::SOLVER_GEOMETRIC), settings);
  EXPECT_EQ(outcome_.calls, 0);
  EXPECT_EQ(pool_->pending(), 1);
  pool_->RunAll();
  EXPECT_EQ(outcome_.calls, 1);
}

TEST_F(ApiPlanDispatchTest, BadPoolBoundRequestIsRejectedWithoutAQueueSlot) {
  LogCapture log;
  v1::PlanRequest request = Grasp(v1::SOLVER_IPOPT);
  request.mutable_contacts(2)->mutable_normal()->Clear();
  Dispatch(request, {}, /*capacity=*/0);  // a request reaching the pool would be refused
  ASSERT_EQ(outcome_.calls, 1);
  EXPECT_EQ(outcome_.status->code(), absl::StatusCode::kInvalidArgument);
  EXPECT_EQ(outcome_.status->message(), "contacts[2].normal: zero length");
  EXPECT_THAT(log.text(), StartsWith("rpc=Plan code=INVALID_ARGUMENT solver=IPOPT contacts=3 "
                                     "where=inline total_us="));
  EXPECT_THAT(log.text(), HasSubstr("message=\"contacts[2].normal: zero length\""));
}

TEST_F(ApiPlanDispatchTest, UnknownSolverIsLoggedWithoutASolver) {
  LogCapture log;
  Dispatch(Grasp(static_cast<v1::Solver>(9)));
  ASSERT_EQ(outcome_.calls, 1);
  EXPECT_EQ(outcome_.status->message(), "solver: unknown value 9");
  EXPECT_THAT(log.text(), StartsWith("rpc=Plan code=INVALID_ARGUMENT solver=- contacts=3 "));
}

TEST_F(ApiPlanDispatchTest, LimitsComeFromTheSettings) {
  PlanSettings settings;
  settings.limits.max_contacts = 2;
  Dispatch(Grasp(v1::SOLVER_GEOMETRIC), settings);
  ASSERT_EQ(outcome_.calls, 1);
  EXPECT_EQ(outcome_.status->message(), "contacts: 3 contacts exceed the limit of 2");
}

TEST_F(ApiPlanDispatchTest, FullPoolIsResourceExhaustedNamingTheSolvers) {
  LogCapture log(spdlog::level::debug);
  Dispatch(Grasp(v1::SOLVER_IPOPT), {}, /*capacity=*/0);
  ASSERT_EQ(outcome_.calls, 1);
  EXPECT_EQ(outcome_.status->code(), absl::StatusCode::kResourceExhausted);
  EXPECT_EQ(outcome_.status->message(),
            "server busy: all 1 solver workers busy and 0 solves queued; retry later");
  EXPECT_THAT(log.text(), StartsWith("rpc=Plan code=RESOURCE_EXHAUSTED solver=IPOPT contacts=3 "
                                     "where=pool total_us="));
  EXPECT_THAT(log.text(), Not(HasSubstr("event=queued")));
}

TEST_F(ApiPlanDispatchTest, QueuedPlanPastItsDeadlineIsNotSolved) {
  Dispatch(Grasp(v1::SOLVER_IPOPT));
  caller_.expired = true;
  pool_->RunAll();
  ASSERT_EQ(outcome_.calls, 1);
  EXPECT_EQ(outcome_.status->code(), absl::StatusCode::kDeadlineExceeded);
  EXPECT_EQ(outcome_.status->message(), "deadline exceeded before the solve started");
  EXPECT_EQ(response_.forces_size(), 0);
}

absl::StatusOr<v1::PlanResponse> EchoMaxContacts(const v1::PlanRequest&, const CallLimits& limits,
                                                 const CallState& state) {
  v1::PlanResponse response;
  response.set_iterations(limits.max_contacts);
  response.set_message(state.interrupt && !state.interrupt() ? "interruptible" : "no interrupt");
  return response;
}

TEST(ApiPlanDispatchLaneTest, IpoptAndCrossCheckGoToTheIpoptLaneGeometricToThePool) {
  PlanSettings settings;
  settings.inline_max_contacts = 0;  // every geometric plan pooled too
  for (v1::Solver solver : {v1::SOLVER_GEOMETRIC, v1::SOLVER_IPOPT, v1::SOLVER_CROSS_CHECK}) {
    ManualPool pool(4), lane(4);
    PlanDispatcher dispatcher(&pool, settings, &lane);
    TestCaller caller;
    v1::PlanResponse response;
    Outcome outcome;
    dispatcher.Dispatch(Grasp(solver), &response, CallLog("Plan", caller), caller, outcome.Done());
    EXPECT_EQ(lane.pending(), UsesIpopt(solver) ? 1 : 0) << v1::Solver_Name(solver);
    EXPECT_EQ(pool.pending(), UsesIpopt(solver) ? 0 : 1) << v1::Solver_Name(solver);
    lane.RunAll();
    pool.RunAll();
    ASSERT_EQ(outcome.calls, 1);
    EXPECT_TRUE(outcome.status->ok()) << *outcome.status;
  }
}

TEST(ApiPlanDispatchLaneTest, FullIpoptLaneRefusesIpoptButNotGeometricWork) {
  ManualPool pool(4), lane(0);
  PlanDispatcher dispatcher(&pool, {}, &lane);
  TestCaller caller;
  v1::PlanResponse response;
  Outcome ipopt, geometric;
  dispatcher.Dispatch(Grasp(v1::SOLVER_IPOPT), &response, CallLog("Plan", caller), caller,
                      ipopt.Done());
  ASSERT_EQ(ipopt.calls, 1);
  EXPECT_EQ(ipopt.status->code(), absl::StatusCode::kResourceExhausted);
  PlanSettings pooled;
  pooled.inline_max_contacts = 0;
  PlanDispatcher pooled_dispatcher(&pool, pooled, &lane);
  pooled_dispatcher.Dispatch(Grasp(v1::SOLVER_GEOMETRIC), &response, CallLog("Plan", caller),
                             caller, geometric.Done());
  EXPECT_EQ(pool.pending(), 1);
  pool.RunAll();
  ASSERT_EQ(geometric.calls, 1);
  EXPECT_TRUE(geometric.status->ok()) << *geometric.status;
}

TEST(ApiRunCallTest, ExceptionsBecomeStatusesInlineAndOnThePool) {
  struct Case {
    std::function<void()> thrower;
    absl::StatusCode code;
    const char* text;
  };
  const std::vector<Case> cases = {
      {[] { throw std::bad_alloc(); }, absl::StatusCode::kResourceExhausted, "out of memory"},
      {[] { throw std::runtime_error("assimp said no"); }, absl::StatusCode::kInternal,
       "assimp said no"},
      {[] { throw 42; }, absl::StatusCode::kInternal, "unknown exception"}};
  for (const Case& c : cases) {
    for (bool pooled : {false, true}) {
      ManualPool pool(1);
      TestCaller caller;
      Outcome outcome;
      RunCall(
          CallLog("X", caller), pooled ? &pool : nullptr,
          [&c](CallLog&) -> absl::Status {
            c.thrower();
            return absl::OkStatus();
          },
          outcome.Done());
      pool.RunAll();
      ASSERT_EQ(outcome.calls, 1);
      EXPECT_EQ(outcome.status->code(), c.code) << *outcome.status;
      EXPECT_THAT(outcome.status->message(), HasSubstr(c.text));
    }
  }
}

TEST(ApiDispatchOnPoolTest, HandlerRunsOnThePoolWithTheLimits) {
  LogCapture log;
  ManualPool pool(4);
  TestCaller caller;
  CallLimits limits;
  limits.max_contacts = 5;
  v1::PlanRequest request;
  v1::PlanResponse response;
  Outcome outcome;
  DispatchOnPool<v1::PlanRequest, v1::PlanResponse>(request, &response, CallLog("Echo", caller),
                                                    &pool, caller, limits, &EchoMaxContacts,
                                                    outcome.Done());
  EXPECT_EQ(outcome.calls, 0);
  pool.RunAll();
  ASSERT_EQ(outcome.calls, 1);
  EXPECT_TRUE(outcome.status->ok());
  EXPECT_EQ(response.iterations(), 5);
  EXPECT_EQ(response.message(), "interruptible");
  EXPECT_THAT(log.text(), StartsWith("rpc=Echo code=OK where=pool total_us="));
}

TEST(ApiDispatchOnPoolTest, StoppedCallAndFullPool) {
  ManualPool pool(1);
  TestCaller caller;
  v1::PlanRequest request;
  v1::PlanResponse first, second;
  Outcome stopped, refused;
  DispatchOnPool<v1::PlanRequest, v1::PlanResponse>(request, &first, CallLog("Echo", caller), &pool,
                                                    caller, {}, &EchoMaxContacts, stopped.Done());
  DispatchOnPool<v1::PlanRequest, v1::PlanResponse>(request, &second, CallLog("Echo", caller),
                                                    &pool, caller, {}, &EchoMaxContacts,
                                                    refused.Done());
  ASSERT_EQ(refused.calls, 1);
  EXPECT_EQ(refused.status->message(),
            "server busy: all 1 workers busy and 0 requests queued; retry later");
  caller.expired = true;
  pool.RunAll();
  ASSERT_EQ(stopped.calls, 1);
  EXPECT_EQ(stopped.status->message(), "deadline exceeded before the work started");
}

// A handler that loops until its interrupt fires, as the long RPCs do.
absl::StatusOr<v1::PlanResponse> SpinUntilInterrupted(const v1::PlanRequest&, const CallLimits&,
                                                      const CallState& state) {
  const auto give_up = std::chrono::steady_clock::now() + std::chrono::seconds(10);
  int steps = 0;
  while (!(state.interrupt && state.interrupt())) {
    if (std::chrono::steady_clock::now() > give_up) return v1::PlanResponse();  // never interrupted
    ++steps;
  }
  return absl::CancelledError(absl::StrCat("interrupted after ", steps, " steps"));
}

TEST(ApiWorkBudgetTest, SpentBudgetBecomesResourceExhaustedNamingTheFlag) {
  ManualPool pool(1);
  TestCaller caller;
  CallLimits limits;
  limits.solve_timeout_ms = 20;
  v1::PlanRequest request;
  v1::PlanResponse response;
  Outcome outcome;
  DispatchOnPool<v1::PlanRequest, v1::PlanResponse>(request, &response, CallLog("Spin", caller),
                                                    &pool, caller, limits, &SpinUntilInterrupted,
                                                    outcome.Done());
  pool.RunAll();
  ASSERT_EQ(outcome.calls, 1);
  EXPECT_EQ(outcome.status->code(), absl::StatusCode::kResourceExhausted) << *outcome.status;
  EXPECT_THAT(
      std::string(outcome.status->message()),
      StartsWith("stopped at the server's limit of 20 ms of work per call (--solve-timeout-ms): "
                 "interrupted after "));
}

TEST(ApiWorkBudgetTest, NoBudgetAndUnspentBudgetLeaveStatusesAlone) {
  const WorkBudget none(0.0, nullptr);
  EXPECT_FALSE(none.Interrupt());  // nothing to poll
  EXPECT_EQ(none.Explain(absl::CancelledError("x")).code(), absl::StatusCode::kCancelled);
  bool caller_stopped = false;
  const WorkBudget long_one(3600.0, [&caller_stopped] { return caller_stopped; });
  const std::function<bool()> interrupt = long_one.Interrupt();
  EXPECT_FALSE(interrupt());
  caller_stopped = true;
  EXPECT_TRUE(interrupt());  // the caller's interrupt still counts
  EXPECT_FALSE(long_one.Spent());
  EXPECT_EQ(long_one.Explain(absl::CancelledError("x")).code(), absl::StatusCode::kCancelled);
  const WorkBudget tiny(1e-9, nullptr);
  std::this_thread::sleep_for(std::chrono::milliseconds(1));
  EXPECT_TRUE(tiny.Spent());
  EXPECT_TRUE(tiny.Interrupt()());
  EXPECT_TRUE(tiny.Explain(absl::OkStatus()).ok());  // a finished call keeps its answer
}

TEST(ApiCallLogTest, FieldsInOrderAndQuotedMessage) {
  LogCapture capture;
  TestCaller caller;
  CallLog log("FitInertia", caller, 3);
  log.set_details("messages=2 samples=10");
  log.set_results("ignored=on-error");
  log.set_pooled();
  log.Emit(absl::InvalidArgumentError("samples[4].t: not finite"));
  EXPECT_THAT(capture.text(),
              StartsWith("rpc=FitInertia index=3 code=INVALID_ARGUMENT messages=2 samples=10 "
                         "where=pool total_us="));
  EXPECT_THAT(capture.text(), HasSubstr(" peer=test-peer message=\"samples[4].t: not finite\"\n"));
}

TEST(ApiCallLogTest, NothingBelowInfo) {
  LogCapture capture(spdlog::level::warn);
  TestCaller caller;
  CallLog("Plan", caller).Emit(absl::OkStatus());
  EXPECT_EQ(capture.text(), "");
}

TEST(ApiLogValueTest, ControlCharactersBecomeSpaces) {
  EXPECT_EQ(LogValue("a\rb"), "\"a b\"");
  EXPECT_EQ(LogValue("tab\there"), "\"tab\\there\"");
  EXPECT_EQ(LogValue("x=1"), "\"x=1\"");
}

}  // namespace
}  // namespace tactforce::api
