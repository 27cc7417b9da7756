// MuJoCo solver settings shared by every experiment scene. They go into the
// generated MJCF's <option> and the contact pairs' solref/solimp.
#pragma once

#include <string>

#include "absl/status/status.h"

namespace tactforce::experiment {

struct PhysicsSettings {
  double timestep = 0.001;          // s
  bool elliptic_cone = true;        // false: MuJoCo's default pyramidal cone
  double impratio = 10;             // friction-to-normal impedance ratio (>= 1)
  double solref_timeconst = 0.004;  // s, contact stiffness time constant (>= 2 timesteps)
  double solref_dampratio = 1.0;
  double solimp_dmin = 0.95, solimp_dmax = 0.99, solimp_width = 0.001;  // solimp
  int iterations = 100;                                                 // main solver
  double tolerance = 1e-10;
  int noslip_iterations = 10;         // MuJoCo's post-hoc no-slip pass (0 = off)
  int condim_fingertip = 4;           // 3 sliding, 4 adds torsional friction (soft pad)
  double torsional_friction = 0.002;  // m (torque per N of normal force)

  // MuJoCo's own defaults (2 ms, pyramidal, impratio 1, solref 0.02 1,
  // solimp 0.9 0.95 0.001): the baseline the creep measurement compares to.
  static PhysicsSettings MujocoDefaults();
};

// InvalidArgument naming the field (prefix + "timestep: ...").
absl::Status ValidatePhysics(const PhysicsSettings& p, const std::string& prefix = "physics.");

// The <option> element and <default> contact settings as MJCF text.
std::string OptionMjcf(const PhysicsSettings& p);
std::string SolrefAttr(const PhysicsSettings& p);  // solref="..." solimp="..."

}  // namespace tactforce::experiment
