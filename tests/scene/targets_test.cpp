// Canonical targets against closed-form areas and volumes (divergence theorem), orientation
// conventions, and OBJ/STL round trips and broken files.

#include "scene/targets.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <filesystem>
#include <fstream>
#include <numbers>
#include <stdexcept>

#include "scene/mesh_io.hpp"

namespace sc = radar_emu::scene;
namespace fs = std::filesystem;
constexpr double kPi = std::numbers::pi;

namespace {
double area(const sc::Mesh& m) {
  double s = 0;
  for (const auto& t : m.triangles) {
    s += 0.5 * glm::length(glm::cross(glm::dvec3(m.positions_m[t.y] - m.positions_m[t.x]),
                                      glm::dvec3(m.positions_m[t.z] - m.positions_m[t.x])));
  }
  return s;
}
// Signed volume, (1/6) sum a . (b x c): positive when the closed surface is wound outward.
double volume(const sc::Mesh& m) {
  double v = 0;
  for (const auto& t : m.triangles) {
    v += glm::dot(glm::dvec3(m.positions_m[t.x]),
                  glm::cross(glm::dvec3(m.positions_m[t.y]), glm::dvec3(m.positions_m[t.z])));
  }
  return v / 6.0;
}
glm::dvec3 normal(const sc::Mesh& m, std::size_t i) {
  const auto& t = m.triangles[i];
  return glm::normalize(glm::cross(glm::dvec3(m.positions_m[t.y] - m.positions_m[t.x]),
                                   glm::dvec3(m.positions_m[t.z] - m.positions_m[t.x])));
}
sc::Mesh target(sc::TargetKind k, double a, double b = 1, double c = 1, double f = 0) {
  return sc::make_target({k, a, b, c, f}).objects.at(0).mesh;
}
fs::path tmp(const std::string& n) {
  const fs::path d = fs::temp_directory_path() / "radar_emu_targets_test";
  fs::create_directories(d);
  return d / n;
}
}  // namespace

TEST(Targets, FlatTargetsHaveTheirExactAreaAndFacing) {
  const sc::Mesh plate = target(sc::TargetKind::kPlate, 2.0, 0.5, 1, 0.1);
  EXPECT_NEAR(area(plate), 1.0, 1e-6);
  EXPECT_EQ(plate.triangles.size(), 2u * 20u * 5u);  // 0.1 m facets
  for (std::size_t i = 0; i < plate.triangles.size(); ++i)
    EXPECT_NEAR(normal(plate, i).z, 1.0, 1e-6);
  const sc::Mesh dihedral = target(sc::TargetKind::kDihedral, 1.0, 0.5);
  EXPECT_NEAR(area(dihedral), 1.0, 1e-6);
  // Faces at +-45 deg, each facing the other (interior normals (+-1, 0, 1)/sqrt 2).
  EXPECT_NEAR(normal(dihedral, 0).z, std::sqrt(0.5), 1e-6);
  EXPECT_NEAR(normal(dihedral, 0).x, std::sqrt(0.5), 1e-6);
  EXPECT_NEAR(normal(dihedral, dihedral.triangles.size() - 1).x, -std::sqrt(0.5), 1e-6);
  EXPECT_NEAR(area(target(sc::TargetKind::kTrihedralSquare, 0.3, 1, 1, 0.05)), 3 * 0.09, 1e-6);
  EXPECT_NEAR(area(target(sc::TargetKind::kTrihedralTriangular, 0.3, 1, 1, 0.05)), 1.5 * 0.09,
              1e-6);
  // Trihedral plates face into the positive octant.
  const sc::Mesh tri = target(sc::TargetKind::kTrihedralTriangular, 1.0);
  for (std::size_t i = 0; i < tri.triangles.size(); ++i) {
    const glm::dvec3 n = normal(tri, i);
    EXPECT_NEAR(n.x + n.y + n.z, 1.0, 1e-6);  // one of +x, +y, +z
  }
}

TEST(Targets, ClosedTargetsAreWoundOutwardWithTheirVolume) {
  const sc::Mesh box = target(sc::TargetKind::kBox, 1.0, 2.0, 3.0, 0.5);
  EXPECT_NEAR(volume(box), 6.0, 1e-5);
  EXPECT_NEAR(area(box), 2 * (2 + 3 + 6), 1e-5);
  // Faceted sphere and cylinder converge to the closed forms (facets 1/100 of the radius).
  const double r = 1.0;
  const sc::Mesh sphere = target(sc::TargetKind::kSphere, r, 1, 1, 0.01);
  EXPECT_NEAR(area(sphere) / (4 * kPi * r * r), 1.0, 1e-3);
  EXPECT_NEAR(volume(sphere) / (4.0 / 3.0 * kPi * r * r * r), 1.0, 1e-3);
  const sc::Mesh cyl = target(sc::TargetKind::kCylinder, 0.5, 2.0, 1, 0.01);
  EXPECT_NEAR(volume(cyl) / (kPi * 0.25 * 2.0), 1.0, 1e-3);
  EXPECT_NEAR(area(cyl) / (2 * kPi * 0.5 * 2.0 + 2 * kPi * 0.25), 1.0, 1e-3);
  // Coarse default sphere (32 around): inscribed polyhedron, a few percent under.
  const double coarse = volume(target(sc::TargetKind::kSphere, r)) / (4.0 / 3.0 * kPi);
  EXPECT_LT(coarse, 1.0);
  EXPECT_GT(coarse, 0.95);
}

TEST(Targets, NamesAndBadDimensions) {
  EXPECT_EQ(sc::target_kind_from_name("trihedral-tri"), sc::TargetKind::kTrihedralTriangular);
  EXPECT_FALSE(sc::target_kind_from_name("cone").has_value());
  EXPECT_EQ(sc::target_names(),
            "plate|dihedral|trihedral-square|trihedral-tri|sphere|cylinder|box");
  EXPECT_THROW(sc::make_target({sc::TargetKind::kPlate, -1.0, 1, 1, 0}), std::invalid_argument);
  EXPECT_THROW(sc::make_target({sc::TargetKind::kBox, 1, std::nan(""), 1, 0}),
               std::invalid_argument);
  EXPECT_THROW(sc::make_target({sc::TargetKind::kBox, 1, 1, 1, -0.1}), std::invalid_argument);
}

TEST(MeshFiles, ObjAndStlRoundTrip) {
  const sc::SceneDescription d = sc::make_target({sc::TargetKind::kCylinder, 0.5, 2.0, 1, 0.2});
  const sc::Mesh& m = d.objects[0].mesh;
  for (const char* name : {"cyl.obj", "cyl.stl"}) {
    sc::write_mesh_file(m, d.materials, tmp(name));
    const sc::SceneDescription r = sc::load_mesh_file(tmp(name));
    ASSERT_EQ(r.objects.size(), 1u);
    EXPECT_EQ(r.objects[0].name, "cyl");
    ASSERT_EQ(r.objects[0].mesh.triangles.size(), m.triangles.size()) << name;
    EXPECT_NEAR(area(r.objects[0].mesh), area(m), 1e-5) << name;
    EXPECT_NEAR(volume(r.objects[0].mesh), volume(m), 1e-5) << name;
    EXPECT_EQ(r.materials[0].name, "metal");
  }
  // Unit scaling: the same file read as millimetres is 1000 times smaller.
  const sc::SceneDescription mm = sc::load_mesh_file(tmp("cyl.stl"), {0.001, "metal"});
  EXPECT_NEAR(area(mm.objects[0].mesh), area(m) * 1e-6, 1e-9);
}

TEST(MeshFiles, HandWrittenFilesLoad) {
  {
    std::ofstream(tmp("quad.obj")) << "# quad\nv 0 0 0\nv 1 0 0\nv 1 1 0\nv 0 1 0\n"
                                   << "usemtl asphalt\nf 1/1/1 2/2/1 3/3/1 4/4/1\nf -4 -2 -1\n";
    const sc::SceneDescription d = sc::load_mesh_file(tmp("quad.obj"));
    ASSERT_EQ(d.objects[0].mesh.triangles.size(), 3u);  // quad fan (2) + 1 relative-index face
    EXPECT_EQ(d.materials[0].name, "asphalt");
    EXPECT_EQ(d.objects[0].mesh.triangles[2], glm::uvec3(0, 2, 3));
  }
  {
    std::ofstream(tmp("tri.stl")) << "solid t\nfacet normal 0 0 1\nouter loop\nvertex 0 0 0\n"
                                  << "vertex 2 0 0\nvertex 0 2 0\nendloop\nendfacet\nendsolid t\n";
    const sc::SceneDescription d = sc::load_mesh_file(tmp("tri.stl"));
    ASSERT_EQ(d.objects[0].mesh.triangles.size(), 1u);
    EXPECT_NEAR(area(d.objects[0].mesh), 2.0, 1e-12);
  }
}

TEST(MeshFiles, BrokenFilesNameFileLineAndProblem) {
  auto error_of = [](const fs::path& p) {
    try {
      (void)sc::load_mesh_file(p);
    } catch (const std::runtime_error& e) {
      return std::string(e.what());
    }
    return std::string();
  };
  std::ofstream(tmp("badidx.obj")) << "v 0 0 0\nv 1 0 0\nf 1 2 3\n";
  EXPECT_NE(error_of(tmp("badidx.obj")).find("badidx.obj:3: vertex index 3 out of range"),
            std::string::npos)
      << error_of(tmp("badidx.obj"));
  std::ofstream(tmp("badnum.obj")) << "v 0 zero 0\n";
  EXPECT_NE(error_of(tmp("badnum.obj")).find("badnum.obj:1:"), std::string::npos);
  std::ofstream(tmp("empty.obj")) << "# nothing\n";
  EXPECT_NE(error_of(tmp("empty.obj")).find("no triangles"), std::string::npos);
  {
    // Binary STL whose size disagrees with its count (truncated).
    std::ofstream out(tmp("trunc.stl"), std::ios::binary);
    std::string header(80, ' ');
    out << header;
    const char count[4] = {5, 0, 0, 0};
    out.write(count, 4);
    out << std::string(60, '\0');
  }
  EXPECT_NE(error_of(tmp("trunc.stl")).find("does not match its triangle count 5"),
            std::string::npos)
      << error_of(tmp("trunc.stl"));
  std::ofstream(tmp("x.ply")) << "ply\n";
  EXPECT_NE(error_of(tmp("x.ply")).find("unknown mesh format"), std::string::npos);
  EXPECT_NE(error_of(tmp("missing.obj")).find("missing.obj: no such file"), std::string::npos);
}
