// The FitInertia request stream and the inertia conversions, in process.
#include "tactforce/api/inertia.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <string>

#include <Eigen/Geometry>

#include "absl/strings/str_cat.h"
#include "absl/strings/str_format.h"
#include "tactforce/api/convert.h"
#include "tactforce/inertia/density.h"
#include "tactforce/inertia/simulate.h"

namespace tactforce::api {
namespace {

using inertia::Vec3;

inertia::SimulationResult Simulated(inertia::SimulationMode mode, bool kinematics) {
  inertia::SimulationOptions o;
  o.mode = mode;
  o.duration = 2.0;
  o.rate_hz = 100.0;
  o.write_kinematics = kinematics;
  o.seed = 3;
  absl::StatusOr<inertia::SimulationResult> r = inertia::SimulateInertia(o);
  EXPECT_TRUE(r.ok()) << r.status();
  return *r;
}

v1::FitInertiaRequest Batch(const inertia::InertiaSamples& s, size_t begin, size_t end) {
  v1::FitInertiaRequest m;
  for (size_t i = begin; i < end; ++i)
    *m.add_samples() = InertiaSampleToProto(s.samples[i], s.source);
  return m;
}

// Converting every sample to proto and streaming it back reproduces the
// samples exactly (wrench and contacts, with and without kinematics), so
// the fit equals the direct one.
TEST(InertiaStream, RoundTripGivesTheDirectFit) {
  for (auto mode : {inertia::SimulationMode::kWristWrench, inertia::SimulationMode::kInHand}) {
    for (bool kinematics : {false, true}) {
      const inertia::SimulationResult sim = Simulated(mode, kinematics);
      const inertia::InertiaSamples& s = sim.samples;
      InertiaStream stream;
      const size_t n = s.samples.size();
      for (size_t b = 0; b < n; b += 37)
        ASSERT_TRUE(stream.Add(Batch(s, b, std::min(n, b + 37))).ok());
      EXPECT_EQ(stream.samples_received(), static_cast<int64_t>(n));
      v1::InertiaFitOptions options;
      options.set_method(v1::INERTIA_METHOD_BASELINE_LS);
      absl::StatusOr<v1::FitInertiaResponse> streamed =
          FitInertiaSamples(stream.samples(), stream.options());
      ASSERT_TRUE(streamed.ok()) << streamed.status();
      absl::StatusOr<v1::FitInertiaResponse> direct = FitInertiaSamples(s, v1::InertiaFitOptions());
      ASSERT_TRUE(direct.ok()) << direct.status();
      EXPECT_EQ(streamed->mass(), direct->mass());
      EXPECT_EQ(streamed->inertia().izz(), direct->inertia().izz());
      EXPECT_EQ(streamed->com().x(), direct->com().x());
      EXPECT_EQ(streamed->method(), v1::INERTIA_METHOD_CONSTRAINED);  // the default
      EXPECT_FALSE(streamed->has_errors());                           // no truth given
    }
  }
}

TEST(InertiaStream, ResponseRoundTripsThroughTheLibraryType) {
  const inertia::SimulationResult sim = Simulated(inertia::SimulationMode::kWristWrench, true);
  v1::InertiaFitOptions options;
  *options.mutable_truth() = InertialParametersToProto(sim.truth.params);
  absl::StatusOr<v1::FitInertiaResponse> r = FitInertiaSamples(sim.samples, options);
  ASSERT_TRUE(r.ok()) << r.status();
  ASSERT_TRUE(r->has_errors());
  EXPECT_TRUE(r->errors().consistent());
  // Noise-free measured kinematics: the estimate is close to the truth.
  EXPECT_LT(r->errors().mass_percent(), 0.1);
  EXPECT_LT(r->errors().riemannian(), 0.05);
  const inertia::InertiaFit back = InertiaFitFromProto(*r);
  const v1::FitInertiaResponse again = InertiaFitToProto(back);
  EXPECT_EQ(again.mass(), r->mass());
  EXPECT_EQ(again.inertia().iyz(), r->inertia().iyz());
  EXPECT_EQ(again.principal_axes(2).z(), r->principal_axes(2).z());
  EXPECT_EQ(again.singular_values_size(), r->singular_values_size());
  EXPECT_EQ(again.physically_consistent(), r->physically_consistent());
}

TEST(InertiaStream, InconsistentMessagesAreNamed) {
  const inertia::SimulationResult wrench = Simulated(inertia::SimulationMode::kWristWrench, false);
  const inertia::SimulationResult hand = Simulated(inertia::SimulationMode::kInHand, false);
  {
    InertiaStream stream;
    ASSERT_TRUE(stream.Add(Batch(wrench.samples, 0, 10)).ok());
    const absl::Status s = stream.Add(Batch(hand.samples, 10, 12));
    EXPECT_EQ(s.code(), absl::StatusCode::kInvalidArgument);
    EXPECT_NE(s.message().find("samples[10]: wrench expected"), std::string::npos) << s;
  }
  {
    InertiaStream stream;
    ASSERT_TRUE(stream.Add(Batch(hand.samples, 0, 10)).ok());
    const absl::Status s = stream.Add(Batch(wrench.samples, 10, 11));
    EXPECT_NE(s.message().find("samples[10].wrench: contacts expected"), std::string::npos) << s;
  }
  {
    InertiaStream stream;
    v1::FitInertiaRequest m;
    m.add_samples()->set_t(0.0);  // neither wrench nor contacts
    const absl::Status s = stream.Add(m);
    EXPECT_NE(s.message().find("samples[0]: give exactly one force source"), std::string::npos)
        << s;
  }
  {
    InertiaStream stream(/*max_samples=*/5);
    const absl::Status s = stream.Add(Batch(wrench.samples, 0, 6));
    EXPECT_NE(s.message().find("more than 5 samples"), std::string::npos) << s;
  }
  {
    InertiaStream stream;
    v1::FitInertiaRequest m = Batch(wrench.samples, 0, 3);
    m.mutable_options()->set_method(v1::INERTIA_METHOD_BASELINE_LS);
    ASSERT_TRUE(stream.Add(m).ok());
    const absl::StatusOr<v1::FitInertiaResponse> r =
        FitInertiaSamples(stream.samples(), stream.options());
    EXPECT_EQ(r.status().code(), absl::StatusCode::kInvalidArgument);
    EXPECT_NE(r.status().message().find("3 sample(s), at least 4 needed"), std::string::npos)
        << r.status();
  }
  {
    const InertiaStream stream;  // no message: the fit says so
    EXPECT_EQ(FitInertiaSamples(stream.samples(), stream.options()).status().message(),
              "samples: the stream carried no samples");
  }
  {
    // A sample whose contact count differs from the first: the library's
    // validation names it at the fit.
    InertiaStream stream;
    v1::FitInertiaRequest m = Batch(hand.samples, 0, 20);
    m.mutable_samples(13)->mutable_contacts()->RemoveLast();
    ASSERT_TRUE(stream.Add(m).ok());
    const absl::StatusOr<v1::FitInertiaResponse> r =
        FitInertiaSamples(stream.samples(), stream.options());
    EXPECT_NE(r.status().message().find("samples[13]: 3 contacts, expected 4"), std::string::npos)
        << r.status();
  }
}

// The wire spelling comes from the proto enum (moved here from the
// library's former inertia::ProtoName) and parses back to the method.
TEST(InertiaMethodName, ProtoSpellingRoundTripsThroughTheLibraryParser) {
  for (inertia::InertiaMethod m :
       {inertia::InertiaMethod::kBaselineLs, inertia::InertiaMethod::kFactorGraph,
        inertia::InertiaMethod::kConstrained, inertia::InertiaMethod::kDensity}) {
    EXPECT_EQ(*inertia::ParseInertiaMethod(InertiaMethodName(m)), m);
  }
  EXPECT_EQ(InertiaMethodName(inertia::InertiaMethod::kBaselineLs), "INERTIA_METHOD_BASELINE_LS");
  EXPECT_EQ(InertiaMethodName(inertia::InertiaMethod::kDensity), "INERTIA_METHOD_DENSITY");
}

TEST(InertiaOptionsFromProto, ValidatesAndNamesFields) {
  v1::InertiaFitOptions o;
  o.set_method(static_cast<v1::InertiaMethod>(42));
  EXPECT_NE(InertiaOptionsFromProto(o).status().message().find("options.method: unknown value 42"),
            std::string::npos);
  o.Clear();
  for (int i = 0; i < 3; ++i) *o.add_hull() = v1::Vec3();  // too few points
  EXPECT_NE(InertiaOptionsFromProto(o).status().message().find("options.hull"), std::string::npos)
      << InertiaOptionsFromProto(o).status();
  o.Clear();
  o.mutable_truth()->set_mass(-1.0);
  EXPECT_NE(InertiaOptionsFromProto(o).status().message().find("options.truth"), std::string::npos);
  o.Clear();
  o.mutable_gravity()->set_z(-9.0);
  o.mutable_prior()->mutable_params()->set_mass(2.0);
  v1::Inertia* inertia = o.mutable_prior()->mutable_params()->mutable_inertia();
  inertia->set_ixx(0.01);
  inertia->set_iyy(0.02);
  inertia->set_izz(0.025);
  absl::StatusOr<inertia::InertiaOptions> ok = InertiaOptionsFromProto(o);
  ASSERT_TRUE(ok.ok()) << ok.status();
  EXPECT_EQ(ok->method, inertia::InertiaMethod::kConstrained);
  EXPECT_EQ(ok->gravity.z(), -9.0);
  ASSERT_TRUE(ok->prior.has_value());
  EXPECT_EQ(ok->prior->weight, 1.0);  // 0 = the default weight
  EXPECT_EQ(ok->prior->params.mass, 2.0);
}

// ---------------------------------------------------------------- meshes

// A Wavefront OBJ of `mesh` whose vertices are v_file = (R v + p) / scale,
// i.e. a CAD file in other units and another frame: MeshInput's placement
// (scale, p, R) maps it back to the object frame. `skip` drops a triangle.
std::string ObjText(const io::TriangleMesh& mesh, double scale = 1.0, const Vec3& p = Vec3::Zero(),
                    const Eigen::Quaterniond& q = Eigen::Quaterniond::Identity(), int skip = -1) {
  std::string out = "# test mesh\n";
  for (const Vec3& v : mesh.vertices) {
    const Vec3 f = (q * v + p) / scale;
    out += absl::StrFormat("v %.17g %.17g %.17g\n", f.x(), f.y(), f.z());
  }
  for (size_t t = 0; t < mesh.triangles.size(); ++t) {
    if (static_cast<int>(t) == skip) continue;
    const auto& tri = mesh.triangles[t];
    out += absl::StrFormat("f %d %d %d\n", tri[0] + 1, tri[1] + 1, tri[2] + 1);
  }
  return out;
}

inertia::SimulationResult SimulatedBox() {
  inertia::SimulationOptions o;
  o.object = "box";
  o.mode = inertia::SimulationMode::kWristWrench;
  o.duration = 3.0;
  o.rate_hz = 100.0;
  o.write_kinematics = true;
  o.seed = 4;
  absl::StatusOr<inertia::SimulationResult> r = inertia::SimulateInertia(o);
  EXPECT_TRUE(r.ok()) << r.status();
  return *r;
}

// DENSITY's options (a mesh, regions, truth, gravity set) convert to the
// library's, and the replaced contradiction_ratio is refused by name.
void ExpectDensityOptionsConvertOrAreRefusedByName(v1::InertiaFitOptions options) {
  absl::StatusOr<inertia::InertiaOptions> converted = InertiaOptionsFromProto(options);
  ASSERT_TRUE(converted.ok()) << converted.status();
  EXPECT_EQ(converted->method, inertia::InertiaMethod::kDensity);
  EXPECT_EQ(converted->mesh_name, "box.obj");
  EXPECT_EQ(converted->density.regions.scheme, inertia::RegionScheme::kGrid);
  EXPECT_EQ(converted->density.regions.target_regions, 8);
  EXPECT_LT(converted->density.regularization, 0);  // automatic
  options.set_density_regularization(0.5);
  options.set_mesh_prior_weight(2.0);
  options.set_mesh_tolerance(0.05);
  converted = InertiaOptionsFromProto(options);
  ASSERT_TRUE(converted.ok()) << converted.status();
  EXPECT_EQ(converted->density.regularization, 0.5);
  EXPECT_EQ(converted->constrained.mesh_prior_weight, 2.0);
  EXPECT_EQ(converted->density.mesh_tolerance, 0.05);
  options.clear_mesh_tolerance();
  // The replaced ratio: 0 still disables the mesh test, any other value is refused by name.
  options.set_contradiction_ratio(0.0);
  converted = InertiaOptionsFromProto(options);
  ASSERT_TRUE(converted.ok()) << converted.status();
  EXPECT_EQ(converted->density.mesh_tolerance, 0.0);
  options.set_contradiction_ratio(1.2);
  converted = InertiaOptionsFromProto(options);
  ASSERT_FALSE(converted.ok());
  EXPECT_EQ(converted.status().code(), absl::StatusCode::kInvalidArgument);
  const std::string refused(converted.status().message());
  EXPECT_NE(refused.find("options.contradiction_ratio"), std::string::npos) << refused;
  EXPECT_NE(refused.find("mesh_tolerance"), std::string::npos) << refused;
  options.set_mesh_tolerance(-1);
  options.clear_contradiction_ratio();
  const std::string negative(InertiaOptionsFromProto(options).status().message());
  EXPECT_NE(negative.find("mesh_tolerance"), std::string::npos) << negative;
  options.clear_density_regularization();
  options.clear_mesh_prior_weight();
  options.clear_mesh_tolerance();
}

// The DENSITY fit of the noise-free box fills every new response field, the
// same as the library's fit.
void ExpectTheBoxsDensityFit(const v1::FitInertiaResponse& r,
                             const inertia::InertiaFit& library_fit, const io::TriangleMesh& box) {
  EXPECT_EQ(r.method(), v1::INERTIA_METHOD_DENSITY);
  EXPECT_TRUE(r.density_realizable());
  EXPECT_FALSE(r.mesh_contradicted());
  EXPECT_TRUE(r.mesh_contradiction().empty());
  EXPECT_EQ(r.region_scheme(), v1::REGION_SCHEME_GRID);
  ASSERT_GE(r.densities_size(), 2);
  ASSERT_EQ(static_cast<size_t>(r.densities_size()), library_fit.densities.size());
  ASSERT_NE(library_fit.region_model, nullptr);  // handed out for plots
  double volume = 0;
  for (int i = 0; i < r.densities_size(); ++i) {
    EXPECT_EQ(r.densities(i).label(), library_fit.densities[i].label);
    EXPECT_EQ(r.densities(i).density(), library_fit.densities[i].density);
    EXPECT_GE(r.densities(i).density(), 0.0);
    EXPECT_GT(r.densities(i).volume(), 0.0);
    volume += r.densities(i).volume();
  }
  ASSERT_TRUE(r.has_mesh_check());
  EXPECT_TRUE(r.mesh_check().closed());
  EXPECT_TRUE(r.mesh_check().consistently_oriented());
  EXPECT_EQ(r.mesh_check().faces(), 12);
  EXPECT_EQ(r.mesh_check().vertices(), 8);
  EXPECT_EQ(r.mesh_check().boundary_edges(), 0);
  EXPECT_NEAR(r.mesh_check().volume(), volume, 1e-9 * volume);
  EXPECT_NEAR(r.mesh_check().volume(), inertia::MeshMoments(box).volume, 1e-6 * volume);
  EXPECT_GE(r.density_regularization(), 0.0);
  EXPECT_FALSE(r.density_regularization_rule().empty());
  EXPECT_GT(r.heldout_residual_ratio(), 0.0);
  // Noise-free data of a uniform box: the truth.
  ASSERT_TRUE(r.has_errors());
  EXPECT_LT(r.errors().mass_percent(), 0.01);
  EXPECT_LT(r.errors().riemannian(), 0.02);
}

void ExpectTheFitRoundTripsThroughTheLibraryType(const v1::FitInertiaResponse& r) {
  const inertia::InertiaFit back = InertiaFitFromProto(r);
  EXPECT_EQ(back.method, inertia::InertiaMethod::kDensity);
  EXPECT_TRUE(back.density_realizable);
  ASSERT_TRUE(back.mesh_check.has_value());
  EXPECT_EQ(back.mesh_check->faces, 12);
  EXPECT_NE(inertia::DescribeFit(back).find("density-realizable: yes"), std::string::npos);
  const v1::FitInertiaResponse again = InertiaFitToProto(back);
  EXPECT_EQ(again.densities_size(), r.densities_size());
  EXPECT_EQ(again.densities(0).standard_error(), r.densities(0).standard_error());
  EXPECT_EQ(again.density_regularization_rule(), r.density_regularization_rule());
  EXPECT_EQ(again.heldout_residual_ratio(), r.heldout_residual_ratio());
  EXPECT_EQ(again.mesh_check().volume(), r.mesh_check().volume());
}

// The mesh bytes, read and placed as the server does, give back the
// object-frame box (float precision of the file reader), and a DENSITY fit
// with it fills every new response field and round-trips through the
// library type.
TEST(InertiaMeshInput, PlacedCadMeshGivesTheObjectFrameBoxAndADensityFit) {
  const inertia::SimulationResult sim = SimulatedBox();
  const io::TriangleMesh& box = sim.object.mesh;
  ASSERT_EQ(box.triangles.size(), 12u);
  const double scale = 0.001;  // the file is in mm
  const Vec3 p(0.01, -0.02, 0.03);
  const Eigen::Quaterniond q(Eigen::AngleAxisd(0.3, Vec3(1, 2, 3).normalized()));
  io::MeshPlacement placement;
  placement.scale = scale;
  placement.position = p;
  placement.orientation = q;
  const v1::MeshInput input =
      MeshInputToProto(ObjText(box, scale, p, q), "obj", "box.obj", placement);
  EXPECT_EQ(input.scale(), scale);
  EXPECT_EQ(input.orientation().w(), q.w());

  absl::StatusOr<ObjectMesh> mesh = MeshFromProto(input);
  ASSERT_TRUE(mesh.ok()) << mesh.status();
  EXPECT_EQ(mesh->name, "box.obj");
  ASSERT_EQ(mesh->mesh.vertices.size(), box.vertices.size());
  ASSERT_EQ(mesh->mesh.triangles.size(), box.triangles.size());
  for (size_t i = 0; i < box.vertices.size(); ++i) {  // the reader may reorder the vertices
    double nearest = 1e9;
    for (const Vec3& v : mesh->mesh.vertices)
      nearest = std::min(nearest, (v - box.vertices[i]).norm());
    EXPECT_LT(nearest, 1e-7) << "vertex " << i;
  }

  v1::InertiaFitOptions options;  // UNSPECIFIED + a mesh = DENSITY
  *options.mutable_mesh() = input;
  options.set_regions(v1::REGION_SCHEME_GRID);
  options.set_target_regions(8);
  *options.mutable_truth() = InertialParametersToProto(sim.truth.params);
  *options.mutable_gravity() = ToProto(*sim.truth.gravity_world);
  ASSERT_NO_FATAL_FAILURE(ExpectDensityOptionsConvertOrAreRefusedByName(options));

  inertia::InertiaFit library_fit;
  absl::StatusOr<v1::FitInertiaResponse> r =
      FitInertiaSamples(sim.samples, options, {}, {}, &library_fit);
  ASSERT_TRUE(r.ok()) << r.status();
  ASSERT_NO_FATAL_FAILURE(ExpectTheBoxsDensityFit(*r, library_fit, box));

  ASSERT_NO_FATAL_FAILURE(ExpectTheFitRoundTripsThroughTheLibraryType(*r));

  // Without a mesh the new fields stay empty.
  options.clear_mesh();
  options.set_method(v1::INERTIA_METHOD_CONSTRAINED);
  r = FitInertiaSamples(sim.samples, options);
  ASSERT_TRUE(r.ok()) << r.status();
  EXPECT_EQ(r->densities_size(), 0);
  EXPECT_FALSE(r->density_realizable());
  EXPECT_FALSE(r->has_mesh_check());
}

TEST(InertiaMeshInput, BadMeshesAndPlacementsNameTheField) {
  const inertia::SimulationResult sim = SimulatedBox();
  const io::TriangleMesh& box = sim.object.mesh;
  auto error = [](const v1::InertiaFitOptions& o) {
    absl::StatusOr<inertia::InertiaOptions> r = InertiaOptionsFromProto(o);
    EXPECT_FALSE(r.ok());
    EXPECT_EQ(r.status().code(), absl::StatusCode::kInvalidArgument);
    return std::string(r.status().message());
  };
  auto with_mesh = [&](const std::string& bytes, const std::string& format,
                       const std::string& name) {
    v1::InertiaFitOptions o;
    o.set_method(v1::INERTIA_METHOD_DENSITY);
    o.mutable_mesh()->set_data(bytes);
    o.mutable_mesh()->set_format(format);
    o.mutable_mesh()->set_name(name);
    return o;
  };
  const std::string obj = ObjText(box);
  {
    v1::InertiaFitOptions o;
    o.set_method(v1::INERTIA_METHOD_DENSITY);  // no mesh: the library's error
    EXPECT_NE(error(o).find("options.mesh: the density method needs the object's closed mesh"),
              std::string::npos)
        << error(o);
  }
  {
    v1::InertiaFitOptions o = with_mesh(obj, "obj", "box.obj");
    o.mutable_mesh()->set_scale(-1);
    EXPECT_EQ(error(o), "options.mesh.scale: must be > 0 (got -1)");
    o.mutable_mesh()->set_scale(0.001);
    o.mutable_mesh()->mutable_orientation()->set_w(0);  // present, zero norm
    EXPECT_NE(error(o).find("options.mesh.orientation: quaternion norm 0"), std::string::npos)
        << error(o);
    o.mutable_mesh()->clear_orientation();
    o.mutable_mesh()->mutable_position()->set_y(std::nan(""));
    EXPECT_NE(error(o).find("options.mesh.position: not finite"), std::string::npos) << error(o);
  }
  {
    const std::string e = error(with_mesh("this is not a mesh at all", "ply", "junk.ply"));
    EXPECT_NE(e.find("options.mesh: junk.ply: "), std::string::npos) << e;
  }
  {
    const std::string e = error(with_mesh("", "stl", "empty.stl"));
    EXPECT_NE(e.find("options.mesh.data: empty"), std::string::npos) << e;
    EXPECT_NE(e.find("empty.stl"), std::string::npos) << e;
  }
  {
    const std::string e = error(with_mesh(obj, "", "box.step"));
    EXPECT_NE(e.find("options.mesh.format: "), std::string::npos) << e;
    EXPECT_NE(e.find("box.step"), std::string::npos) << e;
  }
  {
    // The format from the name's extension when not given.
    EXPECT_TRUE(InertiaOptionsFromProto(with_mesh(obj, "", "box.OBJ")).ok());
    const std::string e = error(with_mesh(obj, "", ""));
    EXPECT_NE(e.find("options.mesh.format: empty"), std::string::npos) << e;
  }
  {
    // One triangle missing: the library's mesh check, named by the file.
    const std::string e = error(with_mesh(
        ObjText(box, 1.0, Vec3::Zero(), Eigen::Quaterniond::Identity(), 5), "obj", "open.obj"));
    EXPECT_NE(e.find("options.mesh: open.obj: 3 boundary edges"), std::string::npos) << e;
    EXPECT_NE(e.find("not closed"), std::string::npos) << e;
  }
  {
    v1::InertiaFitOptions o = with_mesh(obj, "obj", "box.obj");
    o.set_target_regions(inertia::kMaxTargetRegions + 1);
    EXPECT_NE(error(o).find("options.target_regions: must be in 1..100"), std::string::npos)
        << error(o);
    o.set_target_regions(0);
    o.set_regions(static_cast<v1::RegionScheme>(9));
    EXPECT_NE(error(o).find("options.regions: unknown value 9"), std::string::npos) << error(o);
    o.set_regions(v1::REGION_SCHEME_SINGLE);
    o.set_mesh_prior_weight(-1);
    EXPECT_NE(error(o).find("options.mesh_prior_weight"), std::string::npos) << error(o);
  }
}

}  // namespace
}  // namespace tactforce::api
