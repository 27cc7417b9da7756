// tactforce.v1.Info (info.proto): what a server is — tactforce's version
// and build type (version.h) and the services it serves. The server's
// handler only passes the names of its services.
#pragma once

#include <string>
#include <vector>

#include "tactforce/v1/info.pb.h"

namespace tactforce::api {

// version = kVersion, build_type = kBuildType, services = `services`
// sorted, without duplicates.
v1::ServerInfoResponse ServerInfo(std::vector<std::string> services);

}  // namespace tactforce::api
