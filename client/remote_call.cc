// RemoteServer: opening the channel of a remote command and stamping each
// call with its deadline and its failures with the CLI's error mapping
// (connection.cc does the work; this binds it to one server).
#include "remote_call.h"

#include <utility>
#include "tactforce/io/status_macros.h"

namespace tactforce::cli {

absl::StatusOr<RemoteServer> RemoteServer::Open(const ConnectionArgs& args,
                                                grpc::ChannelArguments channel_args) {
  TF_ASSIGN_OR_RETURN(std::shared_ptr<grpc::Channel> channel,
                      MakeChannel(args, args.server, std::move(channel_args)));
  return RemoteServer(std::move(channel), args.server, args.deadline_ms);
}

RemoteServer::RemoteServer(std::shared_ptr<grpc::Channel> channel, std::string target,
                           int deadline_ms)
    : channel_(std::move(channel)), target_(std::move(target)), deadline_ms_(deadline_ms) {}

void RemoteServer::SetDeadline(grpc::ClientContext* context) const {
  cli::SetDeadline(context, deadline_ms_);
}

absl::Status RemoteServer::Error(const grpc::Status& status) const {
  return RpcError(status, target_, deadline_ms_, channel_.get());
}

}  // namespace tactforce::cli
