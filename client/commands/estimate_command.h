// `tactforce estimate`: contact forces from tactile readings, through the
// Backend (Estimator.EstimateForces; in this process unless --server).
#pragma once

#include <string>

#include "CLI/CLI.hpp"
#include "backend.h"
#include "cli_common.h"

namespace tactforce::cli {

struct EstimateArgs {
  BackendArgs backend;       // --local | --server ADDR, TLS, --deadline-ms
  std::string request_path;  // EstimateRequest JSON, "-" = stdin
  OutputFormat output;
};
CLI::App* AddEstimateCommand(CLI::App& app, EstimateArgs& args);
int RunEstimate(const EstimateArgs& args);

}  // namespace tactforce::cli
