// How a `tactforce` command calls tactforce-server: RemoteServer (the
// channel, the address named in error messages, the deadline of every call)
// and CallUnary, the one path of a unary call (a context with the deadline,
// the call, a gRPC failure mapped to the one-line error and exit code of
// RpcError, connection.h). `plan`, `estimate`, `plan --trajectory`, `health`
// and the warm-up of `load` call through it; `inertia --server` (the one
// client-streaming call) uses RemoteServer for its channel, deadline and
// errors.
#pragma once

#include <memory>
#include <string>

#include <grpcpp/grpcpp.h>

#include "absl/status/status.h"
#include "absl/status/statusor.h"
#include "connection.h"
#include "tactforce/io/status_macros.h"

namespace tactforce::cli {

class RemoteServer {
 public:
  // A channel to `args.server` with the TLS files of `args`; calls get
  // `args.deadline_ms`. Errors as MakeChannel (InvalidArgument naming the
  // flag of an unreadable PEM file); `channel_args` as there. Does not
  // connect.
  static absl::StatusOr<RemoteServer> Open(const ConnectionArgs& args,
                                           grpc::ChannelArguments channel_args = {});

  // `channel` to `target` (named in errors); each call gets `deadline_ms`
  // (0 = none).
  RemoteServer(std::shared_ptr<grpc::Channel> channel, std::string target, int deadline_ms);

  // Sets the deadline of one call's context to now + deadline_ms.
  void SetDeadline(grpc::ClientContext* context) const;
  // A failed call as the CLI reports it: RpcError(status, target, deadline_ms,
  // channel), which tells an unreachable server from a slow one.
  absl::Status Error(const grpc::Status& status) const;

  const std::shared_ptr<grpc::Channel>& channel() const { return channel_; }
  const std::string& target() const { return target_; }
  int deadline_ms() const { return deadline_ms_; }

 private:
  std::shared_ptr<grpc::Channel> channel_;
  std::string target_;
  int deadline_ms_;
};

// A generated stub's blocking unary method, e.g. &v1::Planner::Stub::Plan.
template <class Stub, class Request, class Response>
using UnaryRpc = grpc::Status (Stub::*)(grpc::ClientContext*, const Request&, Response*);

// One unary call of `rpc` on `stub` (a stub on server.channel(), kept by
// callers that call many times) within the server's deadline.
// ok(): the server's answer. !ok(): server.Error() of the failed call:
// Unavailable "cannot reach ADDR: ...", DeadlineExceeded "ADDR: no answer
// within N ms (--deadline-ms)", InvalidArgument with the server's message
// (the field path), any other code as "ADDR: <message>".
template <class Stub, class Request, class Response>
absl::StatusOr<Response> CallUnary(const RemoteServer& server, Stub& stub,
                                   UnaryRpc<Stub, Request, Response> rpc, const Request& request) {
  grpc::ClientContext context;
  server.SetDeadline(&context);
  Response response;
  const grpc::Status status = (stub.*rpc)(&context, request, &response);
  if (!status.ok()) return server.Error(status);
  return response;
}

// The same on a stub made for this one call.
template <class Stub, class Request, class Response>
absl::StatusOr<Response> CallUnary(const RemoteServer& server,
                                   UnaryRpc<Stub, Request, Response> rpc, const Request& request) {
  Stub stub(server.channel());
  return CallUnary(server, stub, rpc, request);
}

// The same on a new channel to `args.server` (RemoteServer::Open's errors
// first): a command's single call.
template <class Stub, class Request, class Response>
absl::StatusOr<Response> CallUnary(const ConnectionArgs& args,
                                   UnaryRpc<Stub, Request, Response> rpc, const Request& request) {
  TF_ASSIGN_OR_RETURN(RemoteServer server, RemoteServer::Open(args));
  return CallUnary(server, rpc, request);
}

}  // namespace tactforce::cli
