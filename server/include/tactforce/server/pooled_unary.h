// ServeOnPool: a unary RPC as a thin adapter over api::DispatchOnPool. The
// handler (an api::Handle* function) runs on the WorkerPool, never on a
// gRPC thread; a full pool answers RESOURCE_EXHAUSTED; the deadline and
// cancellation are checked before the work starts and after it ends, and
// polled through CallState::interrupt; one log line per call at info.
#pragma once

#include <memory>
#include <utility>

#include <grpcpp/grpcpp.h>

#include "tactforce/api/dispatch.h"
#include "tactforce/api/services.h"
#include "tactforce/server/rpc_support.h"
#include "tactforce/server/worker_pool.h"

namespace tactforce::server {

template <class Request, class Response>
grpc::ServerUnaryReactor* ServeOnPool(const char* rpc, grpc::CallbackServerContext* context,
                                      const Request* request, Response* response, WorkerPool* pool,
                                      api::CallLimits limits,
                                      api::UnaryHandler<Request, Response> handler) {
  grpc::ServerUnaryReactor* reactor = context->DefaultReactor();
  auto guard = std::make_shared<const RpcGuard>(context);
  api::DispatchOnPool<Request, Response>(*request, response, api::CallLog(rpc, *guard), pool,
                                         *guard, std::move(limits), std::move(handler),
                                         FinishUnary(reactor, guard));
  return reactor;
}

}  // namespace tactforce::server
