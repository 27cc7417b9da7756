// Info.GetServerInfo's answer (info.h).
#include "tactforce/api/info.h"

#include <algorithm>
#include <utility>

#include "tactforce/api/version.h"

namespace tactforce::api {

v1::ServerInfoResponse ServerInfo(std::vector<std::string> services) {
  std::sort(services.begin(), services.end());
  services.erase(std::unique(services.begin(), services.end()), services.end());
  v1::ServerInfoResponse info;
  info.set_version(kVersion);
  info.set_build_type(kBuildType);
  for (std::string& name : services) info.add_services(std::move(name));
  return info;
}

}  // namespace tactforce::api
