#include "test_support.h"

#include <random>

#include <fstream>
#include <sstream>

#include <google/protobuf/descriptor.pb.h>
#include <google/protobuf/dynamic_message.h>
#include <grpcpp/generic/generic_stub.h>

#include "absl/strings/str_cat.h"
#include "grpc/health/v1/health.grpc.pb.h"
#include "tactforce/api/convert.h"
#include "tactforce/planner/examples.h"
#include "tactforce/planner/random_grasps.h"
#include "tactforce/io/status_macros.h"

namespace tactforce::testing {
namespace {

planner::SolverKind ToKind(v1::Solver solver) {
  switch (solver) {
    case v1::SOLVER_IPOPT:
      return planner::SolverKind::kIpopt;
    case v1::SOLVER_CROSS_CHECK:
      return planner::SolverKind::kCrossCheck;
    default:
      return planner::SolverKind::kGeometric;
  }
}

void SetDeadline(grpc::ClientContext* context, std::chrono::milliseconds timeout) {
  context->set_deadline(std::chrono::system_clock::now() + timeout);
}

// The standard reflection protocol, from a descriptor set of grpc-proto's
// reflection.proto, in a private pool (see tests/server/CMakeLists.txt).
class ReflectionProtocol {
 public:
  ReflectionProtocol() {
    std::ifstream in(TACTFORCE_REFLECTION_DESCRIPTOR_SET, std::ios::binary);
    std::stringstream bytes;
    bytes << in.rdbuf();
    google::protobuf::FileDescriptorSet files;
    if (!files.ParseFromString(bytes.str())) return;
    for (const google::protobuf::FileDescriptorProto& file : files.file()) {
      if (pool_.BuildFile(file) == nullptr) return;
    }
    request_ = pool_.FindMessageTypeByName("grpc.reflection.v1alpha.ServerReflectionRequest");
    response_ = pool_.FindMessageTypeByName("grpc.reflection.v1alpha.ServerReflectionResponse");
  }
  bool ok() const { return request_ != nullptr && response_ != nullptr; }

  // One request on ServerReflectionInfo, one response back.
  absl::StatusOr<std::unique_ptr<google::protobuf::Message>> Ask(
      const std::shared_ptr<grpc::Channel>& channel, const std::string& field,
      const std::string& value) {
    using google::protobuf::Message;
    std::unique_ptr<Message> request(factory_.GetPrototype(request_)->New());
    request->GetReflection()->SetString(request.get(), request_->FindFieldByName(field), value);
    std::string bytes;
    request->SerializeToString(&bytes);
    grpc::Slice slice(bytes);
    grpc::ByteBuffer send(&slice, 1);

    grpc::GenericStub stub(channel);
    grpc::CompletionQueue cq;
    grpc::ClientContext context;
    SetDeadline(&context, std::chrono::seconds(10));
    auto call = stub.PrepareCall(
        &context, "/grpc.reflection.v1alpha.ServerReflection/ServerReflectionInfo", &cq);
    void* tag = nullptr;
    bool ok = false;
    auto step = [&](int expected) {
      return cq.Next(&tag, &ok) && tag == reinterpret_cast<void*>(expected) && ok;
    };
    call->StartCall(reinterpret_cast<void*>(1));
    if (!step(1)) return absl::UnavailableError("reflection: call did not start");
    call->Write(send, reinterpret_cast<void*>(2));
    if (!step(2)) return absl::UnavailableError("reflection: write failed");
    call->WritesDone(reinterpret_cast<void*>(3));
    if (!step(3)) return absl::UnavailableError("reflection: WritesDone failed");
    grpc::ByteBuffer received;
    call->Read(&received, reinterpret_cast<void*>(4));
    const bool got = step(4);
    grpc::Status status;
    call->Finish(&status, reinterpret_cast<void*>(5));
    cq.Next(&tag, &ok);
    cq.Shutdown();
    while (cq.Next(&tag, &ok)) {
    }
    if (!status.ok()) return absl::UnavailableError("reflection: " + Describe(status));
    if (!got) return absl::UnavailableError("reflection: no response");
    std::vector<grpc::Slice> slices;
    (void)received.Dump(&slices);
    std::string data;
    for (const grpc::Slice& s : slices)
      data.append(reinterpret_cast<const char*>(s.begin()), s.size());
    std::unique_ptr<Message> response(factory_.GetPrototype(response_)->New());
    if (!response->ParseFromString(data)) return absl::DataLossError("reflection: bad response");
    return response;
  }

 private:
  google::protobuf::DescriptorPool pool_;
  google::protobuf::DynamicMessageFactory factory_{&pool_};
  const google::protobuf::Descriptor* request_ = nullptr;
  const google::protobuf::Descriptor* response_ = nullptr;
};

}  // namespace

v1::PlanRequest WrenchRequest(v1::Solver solver) {
  for (const planner::ExampleGrasp& g : planner::BuiltInGrasps()) {
    if (g.name == "wrench-3f") return api::ToRequest(g.problem, g.options, ToKind(solver));
  }
  ADD_FAILURE() << "no wrench-3f example";
  return {};
}

v1::PlanRequest RandomRequest(uint64_t seed, int contacts, v1::Solver solver,
                              bool allow_infeasible) {
  std::mt19937_64 rng(seed);
  planner::RandomGraspOptions options;
  options.min_contacts = contacts;
  options.max_contacts = contacts;
  if (!allow_infeasible) options.infeasible_fraction = 0.0;
  planner::RandomGrasp grasp = planner::MakeRandomGrasp(rng, options);
  return api::ToRequest(grasp.problem, planner::PlanOptions{}, ToKind(solver));
}

v1::PlanRequest SlowIpoptRequest(uint64_t seed) {
  return RandomRequest(seed, 60, v1::SOLVER_IPOPT);
}

std::shared_ptr<grpc::Channel> Connect(const std::string& address,
                                       std::shared_ptr<grpc::ChannelCredentials> credentials,
                                       grpc::ChannelArguments args) {
  return grpc::CreateCustomChannel(address, credentials, args);
}

grpc::Status CallPlan(v1::Planner::Stub& stub, const v1::PlanRequest& request,
                      v1::PlanResponse* response, std::chrono::milliseconds deadline) {
  grpc::ClientContext context;
  SetDeadline(&context, deadline);
  return stub.Plan(&context, request, response);
}

std::string Describe(const grpc::Status& status) {
  std::string code;
  switch (status.error_code()) {
    case grpc::StatusCode::OK:
      code = "OK";
      break;
    case grpc::StatusCode::CANCELLED:
      code = "CANCELLED";
      break;
    case grpc::StatusCode::INVALID_ARGUMENT:
      code = "INVALID_ARGUMENT";
      break;
    case grpc::StatusCode::DEADLINE_EXCEEDED:
      code = "DEADLINE_EXCEEDED";
      break;
    case grpc::StatusCode::RESOURCE_EXHAUSTED:
      code = "RESOURCE_EXHAUSTED";
      break;
    case grpc::StatusCode::UNAVAILABLE:
      code = "UNAVAILABLE";
      break;
    default:
      code = absl::StrCat("code ", static_cast<int>(status.error_code()));
  }
  return code + ": " + status.error_message();
}

absl::StatusOr<int> HealthCheck(const std::shared_ptr<grpc::Channel>& channel,
                                const std::string& service) {
  auto stub = grpc::health::v1::Health::NewStub(channel);
  grpc::health::v1::HealthCheckRequest request;
  request.set_service(service);
  grpc::health::v1::HealthCheckResponse response;
  grpc::ClientContext context;
  SetDeadline(&context, std::chrono::seconds(10));
  grpc::Status status = stub->Check(&context, request, &response);
  if (!status.ok()) {
    return absl::Status(static_cast<absl::StatusCode>(status.error_code()), status.error_message());
  }
  return static_cast<int>(response.status());
}

absl::StatusOr<std::vector<std::string>> ReflectionListServices(
    const std::shared_ptr<grpc::Channel>& channel) {
  ReflectionProtocol protocol;
  if (!protocol.ok()) return absl::InternalError("cannot load reflection.proto");
  TF_ASSIGN_OR_RETURN(auto response, protocol.Ask(channel, "list_services", "*"));
  const google::protobuf::Message& m = *response;
  const auto* field = m.GetDescriptor()->FindFieldByName("list_services_response");
  if (!m.GetReflection()->HasField(m, field))
    return absl::NotFoundError("no list_services_response");
  const google::protobuf::Message& list = m.GetReflection()->GetMessage(m, field);
  const auto* service = list.GetDescriptor()->FindFieldByName("service");
  std::vector<std::string> names;
  for (int i = 0; i < list.GetReflection()->FieldSize(list, service); ++i) {
    const google::protobuf::Message& s = list.GetReflection()->GetRepeatedMessage(list, service, i);
    names.push_back(s.GetReflection()->GetString(s, s.GetDescriptor()->FindFieldByName("name")));
  }
  return names;
}

absl::StatusOr<std::vector<std::string>> ReflectionFilesContainingSymbol(
    const std::shared_ptr<grpc::Channel>& channel, const std::string& symbol) {
  ReflectionProtocol protocol;
  if (!protocol.ok()) return absl::InternalError("cannot load reflection.proto");
  TF_ASSIGN_OR_RETURN(auto response, protocol.Ask(channel, "file_containing_symbol", symbol));
  const google::protobuf::Message& m = *response;
  const auto* field = m.GetDescriptor()->FindFieldByName("file_descriptor_response");
  if (!m.GetReflection()->HasField(m, field))
    return absl::NotFoundError("no file_descriptor_response");
  const google::protobuf::Message& files = m.GetReflection()->GetMessage(m, field);
  const auto* bytes = files.GetDescriptor()->FindFieldByName("file_descriptor_proto");
  std::vector<std::string> names;
  for (int i = 0; i < files.GetReflection()->FieldSize(files, bytes); ++i) {
    google::protobuf::FileDescriptorProto file;
    file.ParseFromString(files.GetReflection()->GetRepeatedString(files, bytes, i));
    names.push_back(file.name());
  }
  return names;
}

void ServerTest::SetUp() { Restart(server_flags()); }

void ServerTest::Restart(const std::vector<std::string>& flags) {
  stub_.reset();
  channel_.reset();
  if (server_ != nullptr) {
    EXPECT_EQ(server_->Stop(), 0) << server_->StderrText();
  }
  std::string error;
  server_ = ServerProcess::Start(flags, &error);
  ASSERT_NE(server_, nullptr) << error;
  channel_ = Connect(server_->address());
  ASSERT_TRUE(
      channel_->WaitForConnected(std::chrono::system_clock::now() + std::chrono::seconds(10)))
      << "cannot connect to " << server_->address();
  stub_ = v1::Planner::NewStub(channel_);
}

void ServerTest::TearDown() {
  stub_.reset();
  channel_.reset();
  if (server_ != nullptr) {
    EXPECT_EQ(server_->Stop(), 0) << server_->StderrText();
    server_.reset();
  }
}

}  // namespace tactforce::testing
