// `tactforce inertia`: fit mass, CoM and inertia to a CSV log, locally or
// streamed to Estimator.FitInertia (--server), optionally on the object's mesh (DENSITY,
// or the mesh as CONSTRAINED's prior) with an SVG plot. Thin over
// tactforce::api and the inertia library. (`simulate inertia`:
// simulate_inertia_command.h.)
#pragma once

#include <string>

#include "CLI/CLI.hpp"
#include "cli_common.h"
#include "backend.h"

namespace tactforce::cli {

struct InertiaArgs {
  std::string csv;         // the inertia CSV (see estimator/inertia/README.md)
  std::string method;      // empty: density with --mesh, else constrained
  std::string gravity;     // "gx,gy,gz" (world); empty: truth's gravity_world or (0,0,-9.81)
  std::string truth_path;  // truth JSON: adds the error metrics
  std::string hull_path;   // STL/OBJ/PLY mesh, mesh descriptor JSON or CSV x,y,z: CoM constraint
  std::string prior_path;  // prior in the truth JSON format
  double prior_weight = 1.0;
  OutputFormat output;  // --json: the FitInertiaResponse as proto3 JSON
  // The object's mesh: a file in the object frame (m) or a descriptor JSON
  // ({"mesh", "scale", "object_in_mesh"}); the overrides are kept as text
  // so that errors can quote them.
  std::string mesh_path;
  std::string mesh_scale;              // "S" (> 0): replaces the descriptor's scale
  std::string mesh_pose;               // "x,y,z,qw,qx,qy,qz": object frame in the mesh frame
  std::string regions = "auto";        // auto | grid | colors | single
  int target_regions = 0;              // 0 = 12
  std::string density_regularization;  // empty: chosen by held-out time blocks
  std::string mesh_prior_weight;       // empty: 1
  std::string mesh_tolerance;          // empty: 0.03
  std::string plot_path;               // SVG of the density fit
  // Noise standard deviations (0 = unknown).
  double force_sigma = 0, torque_sigma = 0, position_sigma = 0, orientation_sigma = 0;
  double angular_velocity_sigma = 0, acceleration_sigma = 0, angular_acceleration_sigma = 0;
  bool savitzky_golay = false;
  std::string fg_variant;  // factor-graph: baseline-fg | fg-no-c | fg-c | fg-c-g; empty: fg-c
  int max_iterations = 0;
  BackendArgs backend;    // --local | --server ADDR, TLS, --deadline-ms
  int batch = 500;        // samples per streamed message
  bool progress = false;  // progress lines even when stderr is not a terminal
};
CLI::App* AddInertiaCommand(CLI::App& app, InertiaArgs& args);
int RunInertia(const InertiaArgs& args);

}  // namespace tactforce::cli
