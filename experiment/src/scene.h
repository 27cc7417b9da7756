// Internal: a MuJoCo model + data loaded from MJCF text (RAII).
#pragma once

#include <memory>
#include <string>

#include <mujoco/mujoco.h>

#include "absl/status/statusor.h"
#include "tactforce/experiment/physics.h"

namespace tactforce::experiment {

class Scene {
 public:
  ~Scene();
  Scene(const Scene&) = delete;
  Scene& operator=(const Scene&) = delete;

  // Compiles `mjcf` (an in-memory file, no disk I/O). Errors carry MuJoCo's
  // compiler message.
  static absl::StatusOr<std::unique_ptr<Scene>> FromMjcf(const std::string& mjcf);

  mjModel* m = nullptr;
  mjData* d = nullptr;

  int Body(const char* name) const;  // -1 if absent
  int Geom(const char* name) const;
  int Joint(const char* name) const;

 private:
  Scene() = default;
};

// Contact force (world frame) that geom `a` receives from geom `b` summed over
// their active contacts, and the force-weighted contact point; returns the
// number of contacts.
int PairForce(const mjModel* m, const mjData* d, int geom_a, int geom_b, double force[3],
              double point[3]);

}  // namespace tactforce::experiment
