// Status mapping and the RPC guard (rpc_support.h).
#include "tactforce/server/rpc_support.h"

#include <string>
#include <utility>
#include <vector>

namespace tactforce::server {

const char* StatusCodeName(grpc::StatusCode code) {
  // absl and gRPC share the numbering 0..16; absl names every code. Built
  // once and never freed (threads may still log during exit).
  static const std::vector<std::string>* const kNames = [] {
    auto* names = new std::vector<std::string>();
    for (int c = 0; c <= static_cast<int>(absl::StatusCode::kUnauthenticated); ++c) {
      names->push_back(absl::StatusCodeToString(static_cast<absl::StatusCode>(c)));
    }
    return names;
  }();
  const auto number = static_cast<size_t>(code);
  return number < kNames->size() ? (*kNames)[number].c_str() : "UNKNOWN_CODE";
}

std::string BoundedStatusMessage(std::string_view message) {
  if (message.size() <= kMaxStatusMessageBytes) return std::string(message);
  const std::string_view kMarker = "... [";
  // Room for the marker and its count ("... [12345678 bytes cut]").
  size_t keep = kMaxStatusMessageBytes - 32;
  // Back up over UTF-8 continuation bytes (10xxxxxx) to a character start.
  while (keep > 0 && (static_cast<unsigned char>(message[keep]) & 0xC0) == 0x80) --keep;
  return std::string(message.substr(0, keep)) + std::string(kMarker) +
         std::to_string(message.size() - keep) + " bytes cut]";
}

grpc::Status ToGrpcStatus(const absl::Status& status) {
  if (status.ok()) return grpc::Status::OK;
  return grpc::Status(
      static_cast<grpc::StatusCode>(status.code()),
      BoundedStatusMessage(std::string_view(status.message().data(), status.message().size())));
}

RpcGuard::RpcGuard(const grpc::CallbackServerContext* context, const std::atomic<bool>* cancelled)
    : context_(context), cancelled_(cancelled) {
  if (context_ == nullptr) return;
  const auto wall_deadline = context_->deadline();
  if (wall_deadline == std::chrono::system_clock::time_point::max()) return;
  // Remaining time, measured once, then tracked on the steady clock.
  const auto remaining = wall_deadline - std::chrono::system_clock::now();
  has_deadline_ = true;
  deadline_ = std::chrono::steady_clock::now() +
              std::chrono::duration_cast<std::chrono::steady_clock::duration>(remaining);
}

bool RpcGuard::Expired() const {
  return has_deadline_ && std::chrono::steady_clock::now() >= deadline_;
}

bool RpcGuard::Cancelled() const {
  if (cancelled_ != nullptr && cancelled_->load(std::memory_order_relaxed)) return true;
  return context_ != nullptr && context_->IsCancelled();
}

absl::Status RpcGuard::StopReason(std::string_view what) const {
  if (Expired()) return absl::DeadlineExceededError("deadline exceeded " + std::string(what));
  return absl::CancelledError("cancelled " + std::string(what));
}

std::string RpcGuard::Peer() const {
  return context_ != nullptr ? context_->peer() : std::string();
}

std::function<bool()> RpcGuard::Interrupt() const {
  return [guard = *this] { return guard.ShouldStop(); };
}

api::CallDone FinishUnary(grpc::ServerUnaryReactor* reactor,
                          std::shared_ptr<const RpcGuard> guard) {
  return [reactor, guard = std::move(guard)](const absl::Status& status) {
    reactor->Finish(ToGrpcStatus(status));
  };
}

api::CallDone FinishUnary(grpc::ServerUnaryReactor* reactor) {
  return [reactor](const absl::Status& status) { reactor->Finish(ToGrpcStatus(status)); };
}

}  // namespace tactforce::server
