// Meshes (io/mesh.h): reading a unit cube written in every format,
// the shared workshop tools through their descriptors, descriptor errors,
// placement, the closed-solid checks and reading errors; and the qhull
// convex hull (inertia/hull.h) of a cube and of the tools' vertices.
#include "tactforce/io/mesh.h"

#include <unistd.h>

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <limits>
#include <optional>
#include <regex>
#include <set>
#include <sstream>
#include <string>
#include <vector>

#include <gtest/gtest.h>

#include "absl/strings/str_format.h"
#include "inertia/test_util.h"
#include "tactforce/inertia/hull.h"
#include "tactforce/inertia/truth.h"

namespace tactforce::estimator {
namespace {

namespace fs = std::filesystem;
using Eigen::Vector3d;

bool Has(const std::string& s, const std::string& what) {
  return s.find(what) != std::string::npos;
}

io::MeshRequest Request(const std::string& path, std::optional<double> scale = std::nullopt,
                        std::optional<io::MeshPlacement> pose = std::nullopt) {
  io::MeshRequest r;
  r.path = path;
  r.scale = scale;
  r.pose = pose;
  return r;
}

// ------------------------------------------------------------ the unit cube

// Corner i of [0, 1]^3: x = bit 0, y = bit 1, z = bit 2.
Vector3d Corner(int i) {
  return Vector3d(double(i & 1), double((i >> 1) & 1), double((i >> 2) & 1));
}

// The six faces as quads (corner numbers), counter-clockwise seen from outside.
constexpr int kQuads[6][4] = {{0, 2, 3, 1}, {4, 5, 7, 6}, {0, 1, 5, 4},
                              {2, 6, 7, 3}, {0, 4, 6, 2}, {1, 3, 7, 5}};
constexpr uint32_t kFaceColors[6] = {0xff0000, 0x00ff00, 0x0000ff, 0xffff00, 0x00ffff, 0x808080};

// The 12 triangles (corner numbers), two per quad, quad order.
std::vector<std::array<int, 3>> CubeTriangles() {
  std::vector<std::array<int, 3>> t;
  for (const auto& q : kQuads) {
    t.push_back({q[0], q[1], q[2]});
    t.push_back({q[0], q[2], q[3]});
  }
  return t;
}

io::TriangleMesh Cube() {
  io::TriangleMesh m;
  for (int i = 0; i < 8; ++i) m.vertices.push_back(Corner(i));
  m.triangles = CubeTriangles();
  return m;
}

std::string AsciiStl() {
  std::string s = "solid cube\n";
  for (const auto& t : CubeTriangles()) {
    const Vector3d n =
        (Corner(t[1]) - Corner(t[0])).cross(Corner(t[2]) - Corner(t[0])).normalized();
    s += absl::StrFormat(" facet normal %g %g %g\n  outer loop\n", n.x(), n.y(), n.z());
    for (int i : t)
      s += absl::StrFormat("   vertex %g %g %g\n", Corner(i).x(), Corner(i).y(), Corner(i).z());
    s += "  endloop\n endfacet\n";
  }
  return s + "endsolid cube\n";
}

template <typename T>
void AppendBinary(std::string* s, T v) {
  char b[sizeof(T)];
  std::memcpy(b, &v, sizeof(T));  // little-endian hosts (x86-64, arm64), as STL and PLY here
  s->append(b, sizeof(T));
}

std::string BinaryStl() {
  std::string s(80, ' ');
  s.replace(0, 11, "binary cube");  // must not start with "solid"
  AppendBinary<uint32_t>(&s, 12);
  for (const auto& t : CubeTriangles()) {
    const Vector3d n =
        (Corner(t[1]) - Corner(t[0])).cross(Corner(t[2]) - Corner(t[0])).normalized();
    for (int k = 0; k < 3; ++k) AppendBinary<float>(&s, static_cast<float>(n(k)));
    for (int i : t)
      for (int k = 0; k < 3; ++k) AppendBinary<float>(&s, static_cast<float>(Corner(i)(k)));
    AppendBinary<uint16_t>(&s, 0);
  }
  return s;
}

// Quads, 1-based indices.
std::string ObjWithQuads() {
  std::string s = "# unit cube\no cube\n";
  for (int i = 0; i < 8; ++i)
    s += absl::StrFormat("v %g %g %g\n", Corner(i).x(), Corner(i).y(), Corner(i).z());
  for (const auto& q : kQuads)
    s += absl::StrFormat("f %d %d %d %d\n", q[0] + 1, q[1] + 1, q[2] + 1, q[3] + 1);
  return s;
}

// Quads with a colour per face.
std::string AsciiPlyWithFaceColors() {
  std::string s =
      "ply\nformat ascii 1.0\ncomment unit cube\nelement vertex 8\nproperty float x\nproperty "
      "float y\n"
      "property float z\nelement face 6\nproperty list uchar int vertex_indices\nproperty uchar "
      "red\n"
      "property uchar green\nproperty uchar blue\nend_header\n";
  for (int i = 0; i < 8; ++i)
    s += absl::StrFormat("%g %g %g\n", Corner(i).x(), Corner(i).y(), Corner(i).z());
  for (int f = 0; f < 6; ++f) {
    const auto& q = kQuads[f];
    const uint32_t c = kFaceColors[f];
    s += absl::StrFormat("4 %d %d %d %d %d %d %d\n", q[0], q[1], q[2], q[3], c >> 16,
                         (c >> 8) & 0xff, c & 0xff);
  }
  return s;
}

// Triangles, one colour (0x336699) on every vertex.
std::string BinaryPlyWithVertexColors() {
  std::string s =
      "ply\nformat binary_little_endian 1.0\nelement vertex 8\nproperty float x\nproperty float y\n"
      "property float z\nproperty uchar red\nproperty uchar green\nproperty uchar blue\nelement "
      "face 12\n"
      "property list uchar int vertex_indices\nend_header\n";
  for (int i = 0; i < 8; ++i) {
    for (int k = 0; k < 3; ++k) AppendBinary<float>(&s, static_cast<float>(Corner(i)(k)));
    for (uint8_t c : {0x33, 0x66, 0x99}) AppendBinary<uint8_t>(&s, c);
  }
  for (const auto& t : CubeTriangles()) {
    AppendBinary<uint8_t>(&s, 3);
    for (int i : t) AppendBinary<int32_t>(&s, i);
  }
  return s;
}

// ------------------------------------------------------------------ fixture

class MeshFiles : public ::testing::Test {
 protected:
  void SetUp() override {
    const auto* info = ::testing::UnitTest::GetInstance()->current_test_info();
    dir_ = fs::path(::testing::TempDir()) /
           absl::StrFormat("tactforce_mesh_test_%d_%s", static_cast<int>(getpid()), info->name());
    fs::remove_all(dir_);
    fs::create_directories(dir_);
  }
  void TearDown() override {
    std::error_code ec;
    fs::remove_all(dir_, ec);
  }
  std::string Write(const std::string& name, const std::string& bytes) {
    const std::string path = (dir_ / name).string();
    std::ofstream(path, std::ios::binary) << bytes;
    return path;
  }
  fs::path dir_;
};

// The welded cube: its 8 corners, 12 triangles, closed, outward, volume 1.
void ExpectUnitCube(const io::TriangleMesh& m, const std::string& what) {
  SCOPED_TRACE(what);
  ASSERT_EQ(m.vertices.size(), 8u);
  ASSERT_EQ(m.triangles.size(), 12u);
  std::set<std::array<double, 3>> corners, expected;
  for (const Vector3d& v : m.vertices) corners.insert({v.x(), v.y(), v.z()});
  for (int i = 0; i < 8; ++i) expected.insert({Corner(i).x(), Corner(i).y(), Corner(i).z()});
  EXPECT_EQ(corners, expected);
  const io::MeshCheck c = io::CheckMesh(m);
  EXPECT_TRUE(c.closed);
  EXPECT_TRUE(c.consistently_oriented);
  EXPECT_EQ(c.boundary_edges, 0);
  EXPECT_EQ(c.non_manifold_edges, 0);
  EXPECT_EQ(c.inconsistent_edges, 0);
  EXPECT_EQ(c.degenerate_faces, 0);
  EXPECT_NEAR(c.volume, 1.0, 1e-12);
  EXPECT_NEAR(c.area, 6.0, 1e-12);
  EXPECT_TRUE(io::RequireClosedSolid(c, what).ok()) << io::RequireClosedSolid(c, what);
}

struct Format {
  const char* file;
  const char* format;
  std::string (*bytes)();
  int colors;  // face colours expected: 0 or 12
};
const Format kFormats[] = {
    {"cube_ascii.stl", "stl", AsciiStl, 0},
    {"cube_binary.stl", "stl", BinaryStl, 0},
    {"cube.obj", "obj", ObjWithQuads, 0},
    {"cube_ascii.ply", "ply", AsciiPlyWithFaceColors, 12},
    {"cube_binary.ply", "ply", BinaryPlyWithVertexColors, 12},
};

TEST_F(MeshFiles, EveryFormatGivesTheWeldedUnitCube) {
  for (const Format& f : kFormats) {
    const std::string bytes = f.bytes();
    const std::string path = Write(f.file, bytes);
    absl::StatusOr<io::TriangleMesh> from_file = io::ReadMeshFile(path);
    ASSERT_TRUE(from_file.ok()) << f.file << ": " << from_file.status();
    ExpectUnitCube(*from_file, f.file);
    EXPECT_EQ(static_cast<int>(from_file->face_colors.size()), f.colors) << f.file;
    EXPECT_EQ(*io::MeshFormatFromPath(path), f.format);

    absl::StatusOr<io::TriangleMesh> from_memory = io::ReadMeshBytes(bytes, f.format, f.file);
    ASSERT_TRUE(from_memory.ok()) << f.file << ": " << from_memory.status();
    EXPECT_EQ(from_memory->vertices, from_file->vertices) << f.file;
    EXPECT_EQ(from_memory->triangles, from_file->triangles) << f.file;
    EXPECT_EQ(from_memory->face_colors, from_file->face_colors) << f.file;
  }
  // The format hint is case-insensitive.
  EXPECT_TRUE(io::ReadMeshBytes(ObjWithQuads(), "OBJ", "cube").ok());
}

TEST_F(MeshFiles, ColoursArePerFaceOrAveragedFromTheVertices) {
  absl::StatusOr<io::TriangleMesh> ascii =
      io::ReadMeshFile(Write("c.ply", AsciiPlyWithFaceColors()));
  ASSERT_TRUE(ascii.ok()) << ascii.status();
  ASSERT_EQ(ascii->face_colors.size(), 12u);
  // Each triangle has its quad's colour; the two triangles of a quad are its
  // corners split along a diagonal, so find each triangle's quad by its corners.
  for (size_t t = 0; t < 12; ++t) {
    std::set<std::array<double, 3>> tri;
    for (int i : ascii->triangles[t]) {
      const Vector3d& v = ascii->vertices[i];
      tri.insert({v.x(), v.y(), v.z()});
    }
    int quad = -1;
    for (int f = 0; f < 6; ++f) {
      std::set<std::array<double, 3>> q;
      for (int i : kQuads[f]) q.insert({Corner(i).x(), Corner(i).y(), Corner(i).z()});
      if (std::includes(q.begin(), q.end(), tri.begin(), tri.end())) quad = f;
    }
    ASSERT_GE(quad, 0);
    EXPECT_EQ(ascii->face_colors[t], kFaceColors[quad]) << "triangle " << t;
  }
  absl::StatusOr<io::TriangleMesh> binary =
      io::ReadMeshFile(Write("c_bin.ply", BinaryPlyWithVertexColors()));
  ASSERT_TRUE(binary.ok()) << binary.status();
  EXPECT_EQ(binary->face_colors, std::vector<uint32_t>(12, 0x336699));
  // No colours in the file: none in the mesh.
  EXPECT_TRUE(io::ReadMeshBytes(AsciiStl(), "stl", "cube.stl")->face_colors.empty());
}

// ------------------------------------------------------------ shared tools

const char* const kTools[] = {"Hammer", "Screwdriver", "Pliers", "Ruler", "C_Clamp"};

TEST(SharedMeshes, LoadClosedWithPlausibleDensities) {
  const auto dir = inertia::testing::SharedInertiaDir();
  if (!dir) GTEST_SKIP() << "../shared/data/inertia is absent";
  for (const char* tool : kTools) {
    SCOPED_TRACE(tool);
    absl::StatusOr<io::LoadedMesh> m = io::LoadMesh(Request(*dir + "/" + tool + ".mesh.json"));
    ASSERT_TRUE(m.ok()) << m.status();
    EXPECT_EQ(m->name, std::string(tool) + ".ply");
    EXPECT_EQ(m->format, "ply");
    EXPECT_EQ(fs::path(m->mesh_path), fs::path(*dir) / (std::string(tool) + ".ply"));
    EXPECT_EQ(m->placement.scale, 0.001);  // the CAD files are in millimetres
    const io::MeshCheck c = io::CheckMesh(m->mesh);
    EXPECT_TRUE(c.closed) << c.boundary_edges << " boundary, " << c.non_manifold_edges
                          << " non-manifold";
    EXPECT_TRUE(c.consistently_oriented) << c.inconsistent_edges;
    EXPECT_TRUE(io::RequireClosedSolid(c, m->name).ok()) << io::RequireClosedSolid(c, m->name);
    absl::StatusOr<inertia::InertiaTruth> truth =
        inertia::ReadTruthJsonFile(*dir + "/" + tool + ".truth.json");
    ASSERT_TRUE(truth.ok()) << truth.status();
    const double density = truth->params.mass / c.volume;  // kg/m^3
    EXPECT_GT(density, 500);
    EXPECT_LT(density, 20000);
    // The published CoM lies inside the hull of the mesh in the object frame.
    std::vector<Vector3d> points(m->mesh.vertices.begin(), m->mesh.vertices.end());
    absl::StatusOr<inertia::ConvexHull> hull = inertia::ComputeConvexHull(points);
    ASSERT_TRUE(hull.ok()) << hull.status();
    EXPECT_TRUE(hull->Contains(truth->params.com)) << truth->params.com.transpose();
  }
}

// -------------------------------------------------------------- descriptors

class Descriptors : public MeshFiles {
 protected:
  void SetUp() override {
    MeshFiles::SetUp();
    Write("cube.obj", ObjWithQuads());
  }
  // The error of reading a descriptor with this text.
  std::string Error(const std::string& json, std::string* path = nullptr) {
    const std::string p = Write("bad.mesh.json", json);
    if (path) *path = p;
    absl::StatusOr<io::MeshDescriptor> d = io::ReadMeshDescriptor(p);
    EXPECT_FALSE(d.ok()) << json;
    if (d.ok()) return "";
    EXPECT_EQ(d.status().code(), absl::StatusCode::kInvalidArgument);
    // Every message starts with the file.
    EXPECT_EQ(d.status().message().rfind(p, 0), 0u) << d.status();
    // Each is also what io::LoadMesh says.
    absl::StatusOr<io::LoadedMesh> loaded = io::LoadMesh(Request(p));
    EXPECT_FALSE(loaded.ok());
    if (!loaded.ok()) {
      EXPECT_EQ(loaded.status().message(), d.status().message());
    }
    return std::string(d.status().message());
  }
};

TEST_F(Descriptors, ReadsAllKeysAndDefaults) {
  const std::string p = Write("cube.mesh.json",
                              R"({"mesh": "cube.obj", "scale": 0.001,
                                  "object_in_mesh": {"position": [1, 2, 3], "quaternion": [0, 0, 0, 2]}})");
  absl::StatusOr<io::MeshDescriptor> d = io::ReadMeshDescriptor(p);
  ASSERT_TRUE(d.ok()) << d.status();
  EXPECT_EQ(fs::path(d->mesh_path), dir_ / "cube.obj");  // next to the descriptor
  EXPECT_EQ(d->placement.scale, 0.001);
  EXPECT_EQ(d->placement.position, Vector3d(1, 2, 3));
  EXPECT_EQ(d->placement.orientation.coeffs(), Eigen::Vector4d(0, 0, 2, 0));  // x, y, z, w

  const std::string q = Write("plain.mesh.json", R"({"mesh": "cube.obj"})");
  absl::StatusOr<io::MeshDescriptor> plain = io::ReadMeshDescriptor(q);
  ASSERT_TRUE(plain.ok()) << plain.status();
  EXPECT_EQ(plain->placement.scale, 1.0);
  EXPECT_EQ(plain->placement.position, Vector3d::Zero());
  EXPECT_TRUE(
      plain->placement.orientation.coeffs().isApprox(Eigen::Quaterniond::Identity().coeffs()));
}

TEST_F(Descriptors, ErrorsNameTheFileAndTheKey) {
  std::string e = Error(R"({"mesh": "cube.obj", "scales": 2})");
  EXPECT_TRUE(Has(e, "unknown key 'scales'")) << e;
  e = Error(R"({"mesh": "cube.obj", "object_in_mesh": {"rotation": [1, 0, 0, 0]}})");
  EXPECT_TRUE(Has(e, "unknown key 'object_in_mesh.rotation'")) << e;
  e = Error(R"({"scale": 0.001})");
  EXPECT_TRUE(Has(e, "missing key 'mesh'")) << e;
  e = Error(R"({"mesh": ""})");
  EXPECT_TRUE(Has(e, "'mesh' must be a non-empty string")) << e;
  for (const char* scale : {"0", "-0.001"}) {
    e = Error(absl::StrFormat(R"({"mesh": "cube.obj", "scale": %s})", scale));
    EXPECT_TRUE(Has(e, "scale: must be > 0")) << e;
  }
  e = Error(R"({"mesh": "cube.obj", "scale": "mm"})");
  EXPECT_TRUE(Has(e, "'scale' must be a number")) << e;
  e = Error(R"({"mesh": "cube.obj", "object_in_mesh": {"quaternion": [0, 0, 0, 0]}})");
  EXPECT_TRUE(Has(e, "object_in_mesh.quaternion: quaternion norm 0 is near zero")) << e;
  e = Error(R"({"mesh": "cube.obj", "object_in_mesh": {"position": [0.1, 0.2]}})");
  EXPECT_TRUE(Has(e, "'object_in_mesh.position' must be an array of 3 numbers")) << e;
  EXPECT_TRUE(Has(e, "got 2 elements")) << e;
  e = Error(R"({"mesh": "cube.obj", "object_in_mesh": {"position": [0.1, "y", 0.3]}})");
  EXPECT_TRUE(Has(e, "'object_in_mesh.position[1]' must be a number")) << e;
  e = Error(R"(["cube.obj"])");
  EXPECT_TRUE(Has(e, "expected a JSON object")) << e;

  // Malformed JSON: file:line:column of the offending token (the missing
  // ':' on line 3 is found at the number after "scale").
  std::string path;
  e = Error("{\n  \"mesh\": \"cube.obj\",\n  \"scale\" 0.001\n}\n", &path);
  std::smatch m;
  ASSERT_TRUE(std::regex_search(e, m, std::regex(":3:([0-9]+): JSON syntax error"))) << e;
  EXPECT_EQ(e.rfind(path + ":3:", 0), 0u) << e;
  const int column = std::stoi(m[1]);
  EXPECT_GE(column, 11) << e;  // the number "0.001" is columns 11-15
  EXPECT_LE(column, 15) << e;  // nlohmann reports the end of the token (15)

  // A descriptor that does not exist.
  absl::StatusOr<io::MeshDescriptor> missing =
      io::ReadMeshDescriptor((dir_ / "none.mesh.json").string());
  ASSERT_FALSE(missing.ok());
  EXPECT_TRUE(Has(std::string(missing.status().message()),
                  (dir_ / "none.mesh.json").string() + ": cannot open"))
      << missing.status();
}

TEST_F(Descriptors, LoadMeshOverridesReplaceTheDescriptorsValues) {
  // Mesh in mm; the object frame sits at (0, 0, 0.5) m, turned 90 degrees about z.
  const std::string p = Write("cube.mesh.json",
                              R"({"mesh": "cube.obj", "scale": 0.001,
                                  "object_in_mesh": {"position": [0, 0, 0.0005], "quaternion": [0.7071067811865476, 0, 0, 0.7071067811865476]}})");
  absl::StatusOr<io::LoadedMesh> m = io::LoadMesh(Request(p));
  ASSERT_TRUE(m.ok()) << m.status();
  EXPECT_EQ(m->name, "cube.obj");
  EXPECT_EQ(m->format, "obj");
  // Corner (1, 0, 0) mm -> R^T ((0.001, 0, 0) - (0, 0, 0.0005)) = (0, -0.001, -0.0005).
  auto image = [](const io::LoadedMesh& l, const Vector3d& corner) {
    for (size_t i = 0; i < l.mesh.vertices.size(); ++i) {
      // The loaded mesh keeps the file's vertex order; find the corner by the inverse map.
      const Vector3d back =
          (l.placement.orientation.toRotationMatrix() * l.mesh.vertices[i] + l.placement.position) /
          l.placement.scale;
      if ((back - corner).norm() < 1e-9) return l.mesh.vertices[i];
    }
    return Vector3d(Vector3d::Constant(std::numeric_limits<double>::quiet_NaN()));
  };
  EXPECT_LT((image(*m, Vector3d(1, 0, 0)) - Vector3d(0, -0.001, -0.0005)).norm(), 1e-15);
  EXPECT_NEAR(io::CheckMesh(m->mesh).volume, 1e-9, 1e-21);  // 1 mm^3, rotation keeps the sign

  // --mesh-scale replaces the descriptor's scale, keeps its pose.
  absl::StatusOr<io::LoadedMesh> s = io::LoadMesh(Request(p, 2.0));
  ASSERT_TRUE(s.ok()) << s.status();
  EXPECT_EQ(s->placement.scale, 2.0);
  EXPECT_EQ(s->placement.position, Vector3d(0, 0, 0.0005));
  EXPECT_LT((image(*s, Vector3d(1, 0, 0)) - Vector3d(0, -2, -0.0005)).norm(), 1e-12);
  EXPECT_NEAR(io::CheckMesh(s->mesh).volume, 8.0, 1e-12);

  // --mesh-pose replaces position and orientation, keeps the scale.
  io::MeshPlacement pose;
  pose.scale = 123;  // ignored
  pose.position = Vector3d(0.01, 0, 0);
  pose.orientation = Eigen::Quaterniond::Identity();
  absl::StatusOr<io::LoadedMesh> posed = io::LoadMesh(Request(p, std::nullopt, pose));
  ASSERT_TRUE(posed.ok()) << posed.status();
  EXPECT_EQ(posed->placement.scale, 0.001);
  EXPECT_EQ(posed->placement.position, Vector3d(0.01, 0, 0));
  EXPECT_LT((image(*posed, Vector3d(1, 0, 0)) - Vector3d(0.001 - 0.01, 0, 0)).norm(), 1e-15);

  // Without a descriptor the file is in the object frame, metres; overrides apply.
  absl::StatusOr<io::LoadedMesh> bare =
      io::LoadMesh(Request((dir_ / "cube.obj").string(), 0.5, std::nullopt));
  ASSERT_TRUE(bare.ok()) << bare.status();
  EXPECT_NEAR(io::CheckMesh(bare->mesh).volume, 0.125, 1e-15);

  // Bad overrides are errors naming the field.
  absl::StatusOr<io::LoadedMesh> zero = io::LoadMesh(Request(p, 0.0, std::nullopt));
  ASSERT_FALSE(zero.ok());
  EXPECT_TRUE(Has(std::string(zero.status().message()), "mesh.scale: must be > 0"))
      << zero.status();
  io::MeshPlacement no_rotation;
  no_rotation.orientation = Eigen::Quaterniond(0, 0, 0, 0);
  absl::StatusOr<io::LoadedMesh> bad_pose = io::LoadMesh(Request(p, std::nullopt, no_rotation));
  ASSERT_FALSE(bad_pose.ok());
  EXPECT_TRUE(Has(std::string(bad_pose.status().message()), "mesh.orientation"))
      << bad_pose.status();
}

// ---------------------------------------------------------------- placement

TEST(Placement, TransformMapsAVertexAsRTransposeOfScaledMinusPosition) {
  io::TriangleMesh m = Cube();
  m.face_colors.assign(12, 0x123456);
  for (Vector3d& v : m.vertices) v *= 1000;  // millimetres
  io::MeshPlacement pl;
  pl.scale = 0.001;
  pl.position = Vector3d(0.01, -0.02, 0.5);
  // 90 degrees about z, not normalised (norm 2).
  pl.orientation = Eigen::Quaterniond(std::sqrt(2.0), 0, 0, std::sqrt(2.0));
  ASSERT_TRUE(io::ValidatePlacement(pl).ok());
  const io::TriangleMesh out = io::TransformToObjectFrame(m, pl);
  // Corner 1 = (1000, 0, 0) mm: (1, 0, 0) m - p = (0.99, 0.02, -0.5); R^T turns
  // (x, y, z) into (y, -x, z).
  EXPECT_LT((out.vertices[1] - Vector3d(0.02, -0.99, -0.5)).norm(), 1e-15);
  // Every vertex, against the formula with a general rotation.
  pl.orientation = Eigen::Quaterniond(Eigen::AngleAxisd(0.7, Vector3d(1, 2, 3).normalized()));
  pl.orientation.coeffs() *= 3.0;
  const io::TriangleMesh general = io::TransformToObjectFrame(m, pl);
  const Eigen::Matrix3d R =
      Eigen::AngleAxisd(0.7, Vector3d(1, 2, 3).normalized()).toRotationMatrix();
  for (size_t i = 0; i < m.vertices.size(); ++i)
    EXPECT_LT((general.vertices[i] - R.transpose() * (0.001 * m.vertices[i] - pl.position)).norm(),
              1e-15);
  EXPECT_EQ(general.triangles, m.triangles);
  EXPECT_EQ(general.face_colors, m.face_colors);
  EXPECT_NEAR(io::CheckMesh(general).volume, 1.0, 1e-12);
}

TEST(Placement, ValidationNamesTheField) {
  io::MeshPlacement pl;
  pl.scale = -1;
  EXPECT_EQ(io::ValidatePlacement(pl, "mesh").message(), "mesh.scale: must be > 0 (got -1)");
  pl.scale = 1;
  pl.position = Vector3d(0, std::nan(""), 0);
  EXPECT_EQ(io::ValidatePlacement(pl, "m").message(), "m.position: not finite");
  pl.position.setZero();
  pl.orientation = Eigen::Quaterniond(1e-7, 0, 0, 0);
  EXPECT_TRUE(
      Has(std::string(io::ValidatePlacement(pl).message()), "mesh.orientation: quaternion norm"));
}

// ----------------------------------------------------------------- checking

TEST(CheckMesh, OpenBoxCountsItsBoundaryEdges) {
  io::TriangleMesh one = Cube();
  one.triangles.pop_back();  // one triangle missing: its three edges are used once
  io::MeshCheck c = io::CheckMesh(one);
  EXPECT_EQ(c.boundary_edges, 3);
  EXPECT_FALSE(c.closed);
  EXPECT_EQ(io::RequireClosedSolid(c, "box.stl").message(),
            "box.stl: 3 boundary edges: the mesh is not closed");

  io::TriangleMesh face = Cube();
  face.triangles.resize(10);  // a whole face missing: its four sides (the diagonal goes with it)
  c = io::CheckMesh(face);
  EXPECT_EQ(c.boundary_edges, 4);
  EXPECT_FALSE(c.closed);
  EXPECT_TRUE(c.consistently_oriented);
  EXPECT_EQ(io::RequireClosedSolid(c, "box.stl").message(),
            "box.stl: 4 boundary edges: the mesh is not closed");
}

TEST(CheckMesh, InvertedBoxMustBeFlipped) {
  io::TriangleMesh m = Cube();
  for (auto& t : m.triangles) std::swap(t[1], t[2]);
  const io::MeshCheck c = io::CheckMesh(m);
  EXPECT_TRUE(c.closed);
  EXPECT_TRUE(c.consistently_oriented);
  EXPECT_NEAR(c.volume, -1.0, 1e-12);
  const std::string e(io::RequireClosedSolid(c, "box.stl").message());
  EXPECT_TRUE(Has(e, "box.stl: volume -1 m^3 is negative")) << e;
  EXPECT_TRUE(Has(e, "flip the winding")) << e;
}

TEST(CheckMesh, FinOnAnEdgeIsNonManifold) {
  io::TriangleMesh m = Cube();
  // A triangle standing on the cube's edge 0-1, pointing away from it.
  m.vertices.emplace_back(0.5, -1, -1);
  m.triangles.push_back({0, 1, 8});
  const io::MeshCheck c = io::CheckMesh(m);
  EXPECT_EQ(c.non_manifold_edges, 1);  // edge 0-1, now used three times
  EXPECT_EQ(c.boundary_edges, 2);      // the fin's free sides
  EXPECT_FALSE(c.closed);
  const std::string e(io::RequireClosedSolid(c, "x.ply").message());
  EXPECT_EQ(e.rfind("x.ply: 1 non-manifold edges (shared by more than two triangles", 0), 0u) << e;
}

TEST(CheckMesh, OneFlippedTriangleIsInconsistent) {
  io::TriangleMesh m = Cube();
  std::swap(m.triangles[4][1], m.triangles[4][2]);
  const io::MeshCheck c = io::CheckMesh(m);
  EXPECT_TRUE(c.closed);  // every edge still has two triangles
  EXPECT_FALSE(c.consistently_oriented);
  EXPECT_EQ(c.inconsistent_edges, 3);
  EXPECT_EQ(io::RequireClosedSolid(c, "part.obj").message(),
            "part.obj: 3 edges are traversed twice in the same direction: the triangles are not "
            "consistently "
            "oriented");
}

TEST(CheckMesh, DegenerateFacesAreCounted) {
  io::TriangleMesh m = Cube();
  m.vertices.emplace_back(0.5, 0, 0);  // on the edge 0-1
  m.triangles.push_back({0, 8, 1});    // zero area
  const io::MeshCheck c = io::CheckMesh(m);
  EXPECT_EQ(c.degenerate_faces, 1);
  EXPECT_EQ(c.degenerate_area_fraction, 0.0);
  EXPECT_NEAR(c.volume, 1.0, 1e-12);
  EXPECT_TRUE(Has(std::string(io::ValidateMesh(m).message()), "mesh.triangles[12]: degenerate"));
  EXPECT_TRUE(io::ValidateMesh(Cube()).ok());
}

// ------------------------------------------------------------ reading errors

TEST_F(MeshFiles, ReadingErrorsNameTheFile) {
  const std::string dae = Write("cube.dae", ObjWithQuads());
  absl::StatusOr<io::TriangleMesh> r = io::ReadMeshFile(dae);
  ASSERT_FALSE(r.ok());
  EXPECT_EQ(r.status().message(),
            dae + ": unknown mesh format '.dae' (expected .stl, .obj or .ply)");
  absl::StatusOr<io::LoadedMesh> l = io::LoadMesh(Request(dae));
  ASSERT_FALSE(l.ok());
  EXPECT_TRUE(Has(std::string(l.status().message()), "unknown mesh format")) << l.status();
  r = io::ReadMeshBytes(ObjWithQuads(), "gltf", "memory");
  ASSERT_FALSE(r.ok());
  EXPECT_EQ(r.status().message(), "memory: unknown mesh format 'gltf' (expected stl, obj or ply)");
  // Found by the mesh fuzzer: a header cut short crashed assimp's PLY reader.
  r = io::ReadMeshBytes(std::string("ply\nformat binary_\0\0", 20), "ply", "cut.ply");
  ASSERT_FALSE(r.ok());
  EXPECT_EQ(r.status().message(), "cut.ply: PLY header line 2: binary bytes inside the header");
  r = io::ReadMeshBytes("ply\nformat ascii 1.0\nelement vertex 3\n", "ply", "short.ply");
  ASSERT_FALSE(r.ok());
  EXPECT_EQ(r.status().message(), "short.ply: not a PLY file: no 'end_header' line");
  r = io::ReadMeshBytes(
      "ply\nformat ascii 1.0\nelement vertex 1\nproperty floa0 z\nend_header\n0\n", "ply", "t.ply");
  ASSERT_FALSE(r.ok());
  EXPECT_EQ(r.status().message(), "t.ply: PLY header line 4: unexpected 'property floa0 z'");
  r = io::ReadMeshBytes("ply\nformat binary_middle_endian 1.0\nend_header\n", "ply", "odd.ply");
  ASSERT_FALSE(r.ok());
  EXPECT_EQ(r.status().message(),
            "odd.ply: PLY header line 2: unexpected 'format binary_middle_endian 1.0'");

  const std::string missing = (dir_ / "missing.ply").string();
  r = io::ReadMeshFile(missing);
  ASSERT_FALSE(r.ok());
  EXPECT_EQ(r.status().message().rfind(missing + ": cannot open", 0), 0u) << r.status();
  l = io::LoadMesh(Request(missing));
  ASSERT_FALSE(l.ok());
  EXPECT_EQ(l.status().message().rfind(missing + ": cannot open", 0), 0u) << l.status();

  // A descriptor pointing at a missing mesh names the mesh.
  const std::string desc = Write("gone.mesh.json", R"({"mesh": "gone.stl"})");
  l = io::LoadMesh(Request(desc));
  ASSERT_FALSE(l.ok());
  EXPECT_EQ(l.status().message().rfind((dir_ / "gone.stl").string() + ": cannot open", 0), 0u)
      << l.status();

  std::string garbage = "\x01\x02\x03 not a mesh at all \xff\xfe";
  for (const char* ext : {"stl", "obj", "ply"}) {
    const std::string path = Write(std::string("garbage.") + ext, garbage);
    r = io::ReadMeshFile(path);
    ASSERT_FALSE(r.ok()) << ext;
    EXPECT_EQ(r.status().code(), absl::StatusCode::kInvalidArgument);
    EXPECT_EQ(r.status().message().rfind(path + ": ", 0), 0u) << r.status();
  }
  const std::string empty = Write("empty.stl", "");
  r = io::ReadMeshFile(empty);
  ASSERT_FALSE(r.ok());
  EXPECT_EQ(r.status().message(), empty + ": empty file");
  // Files cut short (a broken download): never a solid. A PLY is refused
  // where its data ends before the header's counts (io checks PLY bodies
  // before assimp); assimp's STL and OBJ readers keep what they could read,
  // which the closed-solid check then refuses.
  for (const Format& f : kFormats) {
    const std::string bytes = f.bytes();
    for (size_t cut : {40, 100}) {
      SCOPED_TRACE(absl::StrFormat("%s cut by %d bytes", f.file, cut));
      r = io::ReadMeshBytes(bytes.substr(0, bytes.size() - cut), f.format, f.file);
      if (std::string(f.file) == "cube_binary.ply") {
        ASSERT_FALSE(r.ok());
        EXPECT_TRUE(Has(std::string(r.status().message()), "element 'face' item")) << r.status();
      }
      if (!r.ok()) {
        EXPECT_EQ(r.status().message().rfind(std::string(f.file) + ": ", 0), 0u) << r.status();
        continue;
      }
      EXPECT_FALSE(io::RequireClosedSolid(io::CheckMesh(*r), f.file).ok());
    }
  }
}

// -------------------------------------------------------------------- hulls

// The existing hull test (tests/inertia/metrics_test.cc) covers a cube with
// one interior point, containment, and a flat square; here: face count,
// many interior and surface points, the exact face planes, and the
// collinear/coincident/non-finite messages.
TEST(ConvexHull, CubeWithInteriorPointsHasSixFaces) {
  std::vector<Vector3d> pts;
  for (int i = 0; i < 8; ++i) pts.push_back(Corner(i));
  for (int i = 1; i < 4; ++i)
    for (int j = 1; j < 4; ++j)
      for (int k = 1; k < 4; ++k) pts.push_back(Vector3d(i, j, k) / 4);  // interior
  for (int f = 0; f < 3; ++f) {
    Vector3d c = Vector3d::Constant(0.5);
    c(f) = 0;
    pts.push_back(c);  // face centres: on the hull, not vertices of it
    c(f) = 1;
    pts.push_back(c);
  }
  absl::StatusOr<inertia::ConvexHull> h = inertia::ComputeConvexHull(pts);
  ASSERT_TRUE(h.ok()) << h.status();
  ASSERT_EQ(h->normals.size(), 6u);  // coplanar triangles merged into one face each
  EXPECT_EQ(h->vertices.size(), 8u);
  std::set<std::array<double, 3>> planes;
  for (size_t j = 0; j < 6; ++j) {
    EXPECT_NEAR(h->normals[j].norm(), 1.0, 1e-12);
    const Vector3d n = h->normals[j];
    Eigen::Index axis = 0;
    n.cwiseAbs().maxCoeff(&axis);
    EXPECT_NEAR(std::abs(n(axis)), 1.0, 1e-12);
    // x <= 1 (n = +e, d = 1) or -x <= 0 (n = -e, d = 0).
    EXPECT_NEAR(h->offsets[j], n(axis) > 0 ? 1.0 : 0.0, 1e-12);
    planes.insert({std::round(n.x()), std::round(n.y()), std::round(n.z())});
  }
  EXPECT_EQ(planes.size(), 6u);
  EXPECT_NEAR(h->size, std::sqrt(3.0), 1e-15);
  for (const Vector3d& p : pts) EXPECT_TRUE(h->Contains(p)) << p.transpose();
  EXPECT_TRUE(h->Contains(Vector3d(0.999, 0.001, 0.5)));
  for (int f = 0; f < 3; ++f) {
    Vector3d out = Vector3d::Constant(0.5);
    out(f) = 1.001;
    EXPECT_FALSE(h->Contains(out)) << out.transpose();
    EXPECT_NEAR(h->SignedDistanceBound(out), 0.001, 1e-12);
    out(f) = -0.001;
    EXPECT_FALSE(h->Contains(out)) << out.transpose();
  }
  EXPECT_NEAR(h->SignedDistanceBound(Vector3d::Constant(0.5)), -0.5, 1e-12);
  EXPECT_FALSE(h->Contains(Vector3d(1.1, 1.1, 1.1)));
}

TEST(ConvexHull, DegenerateSetsAreNamed) {
  auto message = [](const std::vector<Vector3d>& pts) {
    absl::StatusOr<inertia::ConvexHull> h = inertia::ComputeConvexHull(pts);
    EXPECT_FALSE(h.ok());
    return h.ok() ? std::string() : std::string(h.status().message());
  };
  // Coplanar: a tilted square grid with interior points (the existing test has a bare square).
  std::vector<Vector3d> plane;
  const Vector3d u = Vector3d(1, 1, 0).normalized(), v = Vector3d(0, 0, 1);
  for (int i = 0; i < 5; ++i)
    for (int j = 0; j < 5; ++j)
      plane.push_back(0.1 * i * u + 0.05 * j * v + Vector3d(0.3, -0.2, 0.1));
  EXPECT_EQ(message(plane),
            "hull: degenerate: all vertices are coplanar (a flat object has no volume)");
  std::vector<Vector3d> line;
  for (int i = 0; i < 6; ++i) line.push_back(Vector3d(1, 2, 3) * (0.01 * i) + Vector3d(0.1, 0, 0));
  EXPECT_EQ(message(line), "hull: degenerate: all vertices are collinear");
  EXPECT_EQ(message(std::vector<Vector3d>(5, Vector3d(1, 2, 3))), "hull: all vertices coincide");
  EXPECT_EQ(message({Vector3d(0, 0, 0), Vector3d(1, 0, 0), Vector3d(0, 1, 0)}),
            "hull: 3 vertices; at least 4 non-coplanar vertices are needed");
  std::vector<Vector3d> nan = {Vector3d(0, 0, 0), Vector3d(1, 0, 0), Vector3d(0, 1, 0),
                               Vector3d(0, 0, 1)};
  nan[2].y() = std::numeric_limits<double>::infinity();
  EXPECT_EQ(message(nan), "hull[2]: not finite");
  // A slab 1e-12 thick is flat for the hull (thickness below 1e-9 of its size).
  std::vector<Vector3d> slab = {Vector3d(0, 0, 0), Vector3d(1, 0, 0), Vector3d(0, 1, 0),
                                Vector3d(1, 1, 1e-12)};
  EXPECT_TRUE(Has(message(slab), "coplanar"));
}

}  // namespace
}  // namespace tactforce::estimator
