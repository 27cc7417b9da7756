// Requests shared by the handler tests of tests/api/.
#pragma once

#include "tactforce/v1/planner.pb.h"

namespace tactforce::api::fixtures {

// A probe on top of `holding` (at z = 0.02 m, pressing along -z, pushing
// along +x with 1 N) ramped from 3 N to 0.5 N at 1 N/s: 2.5 s of samples
// at `sample_rate` Hz.
inline v1::FrictionProbeRequest ProbeRequest(const v1::PlanRequest& holding, double sample_rate) {
  v1::FrictionProbeRequest probe;
  *probe.mutable_plan() = holding;
  probe.mutable_position()->set_z(0.02);
  probe.mutable_normal()->set_z(-1);
  probe.mutable_tangent()->set_x(1);
  probe.set_tangential_force(1);
  probe.set_initial_normal_force(3);
  probe.set_final_normal_force(0.5);
  probe.set_ramp_rate(1);
  probe.set_sample_rate(sample_rate);
  return probe;
}

}  // namespace tactforce::api::fixtures
