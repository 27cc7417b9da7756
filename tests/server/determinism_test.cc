// Determinism (issue 16): the same request sent 100 times to one server
// gives bit-identical responses, for every RPC and backend: Plan with
// GEOMETRIC, IPOPT (MUMPS) and CROSS_CHECK, PlanStream, PlanTrajectory,
// PlanFrictionProbe, EstimateForces, EstimateFriction, FitInertia,
// AuditModel and Info.GetServerInfo. "Bit-identical" is the deterministic
// serialisation of the response after clearing the fields that report
// wall-clock time (names ending in "time_us" or "time_seconds"), which
// differ by design; the clearing is checked to touch nothing else.
#include <gtest/gtest.h>

#include <functional>
#include <string>

#include <google/protobuf/descriptor.h>
#include <google/protobuf/io/coded_stream.h>
#include <google/protobuf/io/zero_copy_stream_impl_lite.h>

#include "absl/strings/match.h"
#include "request_builders.h"
#include "tactforce/inertia/simulate.h"
#include "tactforce/v1/audit.grpc.pb.h"
#include "tactforce/v1/estimator.grpc.pb.h"
#include "tactforce/v1/info.grpc.pb.h"
#include "test_support.h"

namespace tactforce::testing {
namespace {

constexpr int kRepeats = 100;

bool IsTiming(const google::protobuf::FieldDescriptor* field) {
  return absl::EndsWith(field->name(), "time_us") || absl::EndsWith(field->name(), "time_seconds");
}

// Clears timing fields in `m` and every nested message; returns how many.
int ClearTimings(google::protobuf::Message* m) {
  const google::protobuf::Reflection* r = m->GetReflection();
  std::vector<const google::protobuf::FieldDescriptor*> fields;
  r->ListFields(*m, &fields);
  int cleared = 0;
  for (const auto* f : fields) {
    if (IsTiming(f)) {
      r->ClearField(m, f);
      ++cleared;
    } else if (f->cpp_type() == google::protobuf::FieldDescriptor::CPPTYPE_MESSAGE &&
               !f->is_map()) {
      if (f->is_repeated()) {
        for (int i = 0; i < r->FieldSize(*m, f); ++i)
          cleared += ClearTimings(r->MutableRepeatedMessage(m, f, i));
      } else {
        cleared += ClearTimings(r->MutableMessage(m, f));
      }
    }
  }
  return cleared;
}

// Deterministic serialisation (map order fixed) without the timings.
std::string Canonical(google::protobuf::Message* m) {
  ClearTimings(m);
  std::string bytes;
  google::protobuf::io::StringOutputStream stream(&bytes);
  google::protobuf::io::CodedOutputStream coded(&stream);
  coded.SetSerializationDeterministic(true);
  m->SerializeToCodedStream(&coded);
  coded.Trim();
  return bytes;
}

// Calls `call` kRepeats times; every canonical response equals the first.
template <class Response>
void ExpectRepeatable(const char* rpc, const std::function<grpc::Status(Response*)>& call) {
  std::string first;
  for (int k = 0; k < kRepeats; ++k) {
    Response response;
    const grpc::Status status = call(&response);
    ASSERT_TRUE(status.ok()) << rpc << " call " << k << ": " << Describe(status);
    const std::string bytes = Canonical(&response);
    if (k == 0) {
      first = bytes;
      ASSERT_FALSE(first.empty()) << rpc;
    } else {
      ASSERT_EQ(bytes, first) << rpc << ": response " << k << " differs from the first";
    }
  }
}

template <class Stub, class Request, class Response>
std::function<grpc::Status(Response*)> Unary(
    Stub* stub, grpc::Status (Stub::*method)(grpc::ClientContext*, const Request&, Response*),
    Request request) {
  return [stub, method, request](Response* response) {
    grpc::ClientContext context;
    context.set_deadline(std::chrono::system_clock::now() + std::chrono::seconds(60));
    return (stub->*method)(&context, request, response);
  };
}

using DeterminismTest = ServerTest;

TEST(DeterminismSupportTest, ClearsOnlyTimings) {
  v1::TrajectoryResponse r;
  r.set_total_time_us(17);
  r.set_optimal_steps(2);
  v1::PlanResponse* step = r.add_steps();
  step->set_solve_time_us(5);
  step->set_message("kept");
  EXPECT_EQ(ClearTimings(&r), 2);
  EXPECT_EQ(r.total_time_us(), 0);
  EXPECT_EQ(r.steps(0).solve_time_us(), 0);
  EXPECT_EQ(r.optimal_steps(), 2);
  EXPECT_EQ(r.steps(0).message(), "kept");
}

TEST_F(DeterminismTest, PlanEveryBackendAndPlanStream) {
  for (v1::Solver solver : {v1::SOLVER_GEOMETRIC, v1::SOLVER_IPOPT, v1::SOLVER_CROSS_CHECK}) {
    SCOPED_TRACE(v1::Solver_Name(solver));
    ExpectRepeatable<v1::PlanResponse>(
        "Plan", Unary(stub_.get(), &v1::Planner::Stub::Plan, RandomRequest(11, 5, solver)));
  }
  // One stream, the same request 100 times.
  grpc::ClientContext context;
  context.set_deadline(std::chrono::system_clock::now() + std::chrono::seconds(60));
  auto stream = stub_->PlanStream(&context);
  const v1::PlanRequest request = RandomRequest(12, 6, v1::SOLVER_GEOMETRIC);
  ExpectRepeatable<v1::PlanResponse>("PlanStream", [&](v1::PlanResponse* response) {
    if (!stream->Write(request) || !stream->Read(response))
      return grpc::Status(grpc::StatusCode::UNAVAILABLE, "stream broken");
    return grpc::Status::OK;
  });
  stream->WritesDone();
  EXPECT_TRUE(stream->Finish().ok());
}

TEST_F(DeterminismTest, TrajectoryProbeAndEstimates) {
  ExpectRepeatable<v1::TrajectoryResponse>(
      "PlanTrajectory", Unary(stub_.get(), &v1::Planner::Stub::PlanTrajectory, LiftRequest(30)));
  ExpectRepeatable<v1::FrictionProbeResponse>(
      "PlanFrictionProbe",
      Unary(stub_.get(), &v1::Planner::Stub::PlanFrictionProbe, ProbeRequest()));

  auto estimator = v1::Estimator::NewStub(channel_);
  v1::EstimateRequest estimate = WrenchEstimateRequest();
  for (auto method : {v1::ESTIMATE_METHOD_PROJECTION, v1::ESTIMATE_METHOD_NORMAL_LSQ}) {
    estimate.set_method(method);
    ExpectRepeatable<v1::EstimateResponse>(
        "EstimateForces", Unary(estimator.get(), &v1::Estimator::Stub::EstimateForces, estimate));
  }
  ExpectRepeatable<v1::FrictionResponse>(
      "EstimateFriction", Unary(estimator.get(), &v1::Estimator::Stub::EstimateFriction,
                                SimulatedFrictionRequest(0.45, 4)));
  auto info = v1::Info::NewStub(channel_);
  ExpectRepeatable<v1::ServerInfoResponse>(
      "GetServerInfo", Unary(info.get(), &v1::Info::Stub::GetServerInfo, v1::ServerInfoRequest()));
}

TEST_F(DeterminismTest, FitInertiaAndAudit) {
  inertia::SimulationOptions o;
  o.duration = 2.0;
  o.rate_hz = 100.0;
  o.seed = 21;
  absl::StatusOr<inertia::SimulationResult> sim = inertia::SimulateInertia(o);
  ASSERT_TRUE(sim.ok()) << sim.status();
  auto estimator = v1::Estimator::NewStub(channel_);
  for (v1::InertiaMethod method :
       {v1::INERTIA_METHOD_BASELINE_LS, v1::INERTIA_METHOD_CONSTRAINED}) {
    SCOPED_TRACE(v1::InertiaMethod_Name(method));
    v1::InertiaFitOptions options;
    options.set_method(method);
    ExpectRepeatable<v1::FitInertiaResponse>("FitInertia", [&](v1::FitInertiaResponse* response) {
      return StreamInertia(*estimator, sim->samples, options, 50, response);
    });
  }
  // A short audit with a hidden threshold, so that a cause is named.
  sim::SensorModel model;
  model.effects.threshold = 0.3;
  v1::AuditRequest audit = SimulatedAuditRequest(model, 6, 5);
  auto auditor = v1::Audit::NewStub(channel_);
  ExpectRepeatable<v1::AuditResponse>("AuditModel",
                                      Unary(auditor.get(), &v1::Audit::Stub::AuditModel, audit));
}

}  // namespace
}  // namespace tactforce::testing
