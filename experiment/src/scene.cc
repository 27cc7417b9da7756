// MuJoCo scenes from MJCF text (scene.h): the physics settings as MJCF, a
// model compiled from an in-memory VFS file under one lock (MuJoCo's parser
// keeps global state), name look-ups, and the force between two geoms.
#include "scene.h"

#include <cstring>
#include <mutex>

#include "absl/strings/str_cat.h"
#include "absl/strings/str_format.h"

namespace tactforce::experiment {

PhysicsSettings PhysicsSettings::MujocoDefaults() {
  PhysicsSettings p;
  p.timestep = 0.002;
  p.elliptic_cone = false;
  p.impratio = 1;
  p.solref_timeconst = 0.02;
  p.solref_dampratio = 1;
  p.solimp_dmin = 0.9;
  p.solimp_dmax = 0.95;
  p.solimp_width = 0.001;
  p.iterations = 100;
  p.tolerance = 1e-8;
  p.noslip_iterations = 0;
  return p;
}

absl::Status ValidatePhysics(const PhysicsSettings& p, const std::string& prefix) {
  auto bad = [&](const char* field, const std::string& why) {
    return absl::InvalidArgumentError(absl::StrCat(prefix, field, ": ", why));
  };
  if (!(p.timestep > 0 && p.timestep <= 0.01))
    return bad("timestep", absl::StrFormat("must be in (0, 0.01] s, got %g", p.timestep));
  if (!(p.impratio >= 1))
    return bad("impratio", absl::StrFormat("must be >= 1, got %g", p.impratio));
  if (!(p.solref_timeconst >= 2 * p.timestep))
    return bad("solref_timeconst", absl::StrFormat("must be >= 2 timesteps (%g s), got %g",
                                                   2 * p.timestep, p.solref_timeconst));
  if (!(p.solref_dampratio > 0))
    return bad("solref_dampratio", absl::StrFormat("must be > 0, got %g", p.solref_dampratio));
  if (!(p.solimp_dmin > 0 && p.solimp_dmin <= p.solimp_dmax && p.solimp_dmax < 1))
    return bad("solimp_dmin", "need 0 < solimp_dmin <= solimp_dmax < 1");
  if (!(p.solimp_width > 0)) return bad("solimp_width", "must be > 0");
  if (p.iterations < 1) return bad("iterations", "must be >= 1");
  if (!(p.tolerance >= 0)) return bad("tolerance", "must be >= 0");
  if (p.noslip_iterations < 0) return bad("noslip_iterations", "must be >= 0");
  if (p.condim_fingertip != 3 && p.condim_fingertip != 4)
    return bad("condim_fingertip", absl::StrFormat("must be 3 or 4, got %d", p.condim_fingertip));
  if (!(p.torsional_friction >= 0)) return bad("torsional_friction", "must be >= 0");
  return absl::OkStatus();
}

std::string OptionMjcf(const PhysicsSettings& p) {
  return absl::StrFormat(
      "<option timestep=\"%.9g\" cone=\"%s\" impratio=\"%.9g\" iterations=\"%d\" "
      "tolerance=\"%.3g\" "
      "noslip_iterations=\"%d\" gravity=\"0 0 -9.81\"/>\n",
      p.timestep, p.elliptic_cone ? "elliptic" : "pyramidal", p.impratio, p.iterations, p.tolerance,
      p.noslip_iterations);
}

std::string SolrefAttr(const PhysicsSettings& p) {
  return absl::StrFormat("solref=\"%.9g %.9g\" solimp=\"%.9g %.9g %.9g\"", p.solref_timeconst,
                         p.solref_dampratio, p.solimp_dmin, p.solimp_dmax, p.solimp_width);
}

namespace {
std::mutex& LoadMutex() {  // the MJCF parser keeps global state
  static std::mutex mu;
  return mu;
}
}  // namespace

Scene::~Scene() {
  if (d) mj_deleteData(d);
  if (m) mj_deleteModel(m);
}

absl::StatusOr<std::unique_ptr<Scene>> Scene::FromMjcf(const std::string& mjcf) {
  std::unique_ptr<Scene> s(new Scene());
  auto vfs = std::make_unique<mjVFS>();
  mj_defaultVFS(vfs.get());
  const char* name = "tactforce_scene.xml";
  if (mj_makeEmptyFileVFS(vfs.get(), name, static_cast<int>(mjcf.size())) != 0)
    return absl::InternalError("mujoco: cannot create the in-memory model file");
  const int idx = mj_findFileVFS(vfs.get(), name);
  std::memcpy(vfs->filedata[idx], mjcf.data(), mjcf.size());
  char error[1024] = {0};
  {
    std::lock_guard<std::mutex> lock(LoadMutex());
    s->m = mj_loadXML(name, vfs.get(), error, sizeof(error));
  }
  mj_deleteVFS(vfs.get());
  if (!s->m) return absl::InternalError(absl::StrCat("mujoco: model does not compile: ", error));
  s->d = mj_makeData(s->m);
  if (!s->d) return absl::InternalError("mujoco: mj_makeData failed");
  mj_forward(s->m, s->d);
  return s;
}

int Scene::Body(const char* name) const { return mj_name2id(m, mjOBJ_BODY, name); }
int Scene::Geom(const char* name) const { return mj_name2id(m, mjOBJ_GEOM, name); }
int Scene::Joint(const char* name) const { return mj_name2id(m, mjOBJ_JOINT, name); }

int PairForce(const mjModel* m, const mjData* d, int geom_a, int geom_b, double force[3],
              double point[3]) {
  force[0] = force[1] = force[2] = 0;
  point[0] = point[1] = point[2] = 0;
  double wsum = 0;
  int count = 0;
  for (int i = 0; i < d->ncon; ++i) {
    const mjContact& c = d->contact[i];
    double sign;
    if (c.geom1 == geom_b && c.geom2 == geom_a) {
      sign = 1;  // normal points from geom1 to geom2: the force on geom2 is +
    } else if (c.geom1 == geom_a && c.geom2 == geom_b) {
      sign = -1;
    } else {
      continue;
    }
    if (c.efc_address < 0) continue;
    mjtNum local[6];
    mj_contactForce(m, d, i, local);
    // frame rows: normal, tangent1, tangent2 (world).
    double w[3];
    for (int k = 0; k < 3; ++k)
      w[k] = local[0] * c.frame[k] + local[1] * c.frame[3 + k] + local[2] * c.frame[6 + k];
    for (int k = 0; k < 3; ++k) force[k] += sign * w[k];
    const double wn = std::abs(local[0]) + 1e-12;
    for (int k = 0; k < 3; ++k) point[k] += wn * c.pos[k];
    wsum += wn;
    ++count;
  }
  if (wsum > 0)
    for (int k = 0; k < 3; ++k) point[k] /= wsum;
  return count;
}

}  // namespace tactforce::experiment
