// `tactforce friction`: static friction from probing trials that end in
// slip, through the Backend (Estimator.EstimateFriction; in this process
// unless --server).
#pragma once

#include <string>
#include <vector>

#include "CLI/CLI.hpp"
#include "backend.h"
#include "cli_common.h"

namespace tactforce::cli {

struct FrictionArgs {
  std::vector<std::string> trial_paths;  // CSV: t,fx,fy,fz,px,py,pz[,slip]
  std::string normal;                    // "x,y,z"
  std::string mesh_path;                 // STL or OBJ
  OutputFormat output;
  BackendArgs backend;  // --local | --server ADDR, TLS, --deadline-ms
  bool linear_fit = false;
  double slip_distance = 1e-3;
  int window = 5;
  double min_normal_force = 0.05;
};
CLI::App* AddFrictionCommand(CLI::App& app, FrictionArgs& args);
int RunFriction(const FrictionArgs& args);

}  // namespace tactforce::cli
