// Runs one unary RPC on the WorkerPool: the handler (an api:: function that
// converts, calls the library and converts back) runs on a worker thread,
// never on a gRPC thread; a full pool answers RESOURCE_EXHAUSTED; the
// deadline and cancellation are checked before the work starts and polled
// through CallLimits::interrupt while it runs. One log line per call at info.
#pragma once

#include <chrono>
#include <functional>
#include <memory>
#include <string>

#include <grpcpp/grpcpp.h>
#include <spdlog/spdlog.h>

#include "absl/status/statusor.h"
#include "absl/strings/str_cat.h"
#include "tactforce/api/services.h"
#include "tactforce/server/rpc_support.h"
#include "tactforce/server/worker_pool.h"

namespace tactforce::server {

// The per-call log line of a pool-run RPC (info level): rpc, code, total
// time, peer, `extra` ("key=value ..." or empty), and the message on error.
inline void LogPoolRpc(const char* rpc, const grpc::Status& status,
                       std::chrono::steady_clock::time_point start, const std::string& peer,
                       const std::string& extra = {}) {
  if (!spdlog::should_log(spdlog::level::info)) return;
  const auto us = std::chrono::duration_cast<std::chrono::microseconds>(
                      std::chrono::steady_clock::now() - start).count();
  std::string line = absl::StrCat("rpc=", rpc, " code=", StatusCodeName(status.error_code()),
                                  extra.empty() ? "" : " ", extra, " where=pool total_us=", us,
                                  " peer=", LogValue(peer));
  if (!status.ok()) absl::StrAppend(&line, " message=", LogValue(status.error_message()));
  spdlog::info("{}", line);
}

// RESOURCE_EXHAUSTED for a full pool.
inline grpc::Status PoolBusyStatus(const WorkerPool& pool) {
  return grpc::Status(grpc::StatusCode::RESOURCE_EXHAUSTED,
                      absl::StrCat("server busy: all ", pool.workers(), " workers busy and ",
                                   pool.max_queued(), " requests queued; retry later"));
}

template <class Request, class Response>
using UnaryHandler = std::function<absl::StatusOr<Response>(const Request&, const api::CallLimits&)>;

template <class Request, class Response>
grpc::ServerUnaryReactor* ServeOnPool(const char* rpc, grpc::CallbackServerContext* context,
                                      const Request* request, Response* response, WorkerPool* pool,
                                      api::CallLimits limits,
                                      UnaryHandler<Request, Response> handler) {
  grpc::ServerUnaryReactor* reactor = context->DefaultReactor();
  const auto start = std::chrono::steady_clock::now();
  auto finish = [rpc, reactor, start](const grpc::Status& status, const std::string& peer) {
    LogPoolRpc(rpc, status, start, peer);
    reactor->Finish(status);
  };
  const std::string peer = spdlog::should_log(spdlog::level::info) ? context->peer() : "";
  const bool queued = pool->TrySubmit([context, request, response, limits, handler, finish, peer]() mutable {
    RpcGuard guard(context);
    if (guard.ShouldStop()) return finish(guard.StopStatus("before the work started"), peer);
    limits.interrupt = guard.Interrupt();
    absl::StatusOr<Response> result = handler(*request, limits);
    if (!result.ok()) return finish(ToGrpcStatus(result.status()), peer);
    if (guard.ShouldStop()) return finish(guard.StopStatus("after the work finished"), peer);
    *response = *std::move(result);
    finish(grpc::Status::OK, peer);
  });
  if (!queued) {
    finish(PoolBusyStatus(*pool), peer);
  }
  return reactor;
}

}  // namespace tactforce::server
