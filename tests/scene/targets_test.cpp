// Canonical targets against closed-form areas and volumes (divergence theorem), orientation
// conventions, and OBJ/STL round trips and broken files.

#include "scene/targets.hpp"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <iostream>
#include <numbers>
#include <stdexcept>

#include "scene/mesh_io.hpp"
#include "scene/scene.hpp"

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

TEST(Targets, VehicleIsTheTwentyFiveThousandFacetBenchmarkTarget) {
  const sc::Mesh v = target(sc::TargetKind::kVehicle, 7.0, 3.5, 2.5);
  std::cout << "vehicle: " << v.triangles.size() << " triangles, " << area(v) << " m^2\n";
  EXPECT_GE(v.triangles.size(), 24000u);
  EXPECT_LE(v.triangles.size(), 26000u);
  // Overall dimensions: length a (gun included), width b, height c; wheels on z = 0 within
  // the sagitta of their facets.
  glm::dvec3 lo(1e9), hi(-1e9);
  double longest = 0.0, smallest = 1e9;
  for (const auto& t : v.triangles) {
    const glm::dvec3 p0(v.positions_m[t.x]), p1(v.positions_m[t.y]), p2(v.positions_m[t.z]);
    for (const glm::dvec3& p : {p0, p1, p2}) {
      lo = glm::min(lo, p);
      hi = glm::max(hi, p);
    }
    longest = std::max({longest, glm::length(p1 - p0), glm::length(p2 - p1), glm::length(p0 - p2)});
    smallest = std::min(smallest, 0.5 * glm::length(glm::cross(p1 - p0, p2 - p0)));
  }
  EXPECT_NEAR(lo.x, -3.5, 1e-6);
  EXPECT_NEAR(hi.x, 3.5, 1e-6);
  EXPECT_NEAR(lo.y, -1.75, 1e-6);
  EXPECT_NEAR(hi.y, 1.75, 1e-6);
  EXPECT_NEAR(lo.z, 0.0, 0.01);
  EXPECT_NEAR(hi.z, 2.5, 1e-6);
  EXPECT_GT(smallest, 1e-6);  // no degenerate facet
  // The default facet size bounds every edge (split quads: their diagonal, sqrt(2) larger).
  EXPECT_LE(longest, std::sqrt(2.0) * 7.0 / 58.0 * (1 + 1e-6));
  // A finer facet size is respected and refines.
  const sc::Mesh fine = target(sc::TargetKind::kVehicle, 7.0, 3.5, 2.5, 0.08);
  EXPECT_GT(fine.triangles.size(), v.triangles.size());
  for (const auto& t : fine.triangles) {
    const glm::dvec3 p0(fine.positions_m[t.x]), p1(fine.positions_m[t.y]),
        p2(fine.positions_m[t.z]);
    ASSERT_LE(std::max({glm::length(p1 - p0), glm::length(p2 - p1), glm::length(p0 - p2)}),
              std::sqrt(2.0) * 0.08 * (1 + 1e-6));
  }
  // Deterministic.
  const sc::Mesh again = target(sc::TargetKind::kVehicle, 7.0, 3.5, 2.5);
  ASSERT_EQ(again.positions_m.size(), v.positions_m.size());
  EXPECT_EQ(std::memcmp(again.positions_m.data(), v.positions_m.data(),
                        v.positions_m.size() * sizeof(glm::vec3)),
            0);
  // Wound outward: every surface a ray from outside meets first faces that ray (grids of rays
  // from 26 directions around the vehicle).
  const sc::Scene scene(sc::make_target({sc::TargetKind::kVehicle, 7.0, 3.5, 2.5, 0.0}));
  std::size_t hits = 0, inward = 0;
  for (int dx = -1; dx <= 1; ++dx) {
    for (int dy = -1; dy <= 1; ++dy) {
      for (int dz = -1; dz <= 1; ++dz) {
        if (dx == 0 && dy == 0 && dz == 0)
          continue;
        const glm::dvec3 d = -glm::normalize(glm::dvec3(dx, dy, dz) + glm::dvec3(0.01, 0.02, 0.03));
        const glm::dvec3 e1 = glm::normalize(glm::cross(d, glm::dvec3(0.3, 0.5, 0.8)));
        const glm::dvec3 e2 = glm::cross(d, e1);
        for (int i = -40; i <= 40; ++i) {
          for (int j = -40; j <= 40; ++j) {
            sc::Ray ray;
            ray.origin_m = glm::dvec3(0, 0, 1.2) - 20.0 * d + 0.1 * i * e1 + 0.1 * j * e2;
            ray.direction = d;
            sc::Hit h;
            if (!scene.intersect(ray, h))
              continue;
            ++hits;
            inward += glm::dot(h.normal, d) > 0.0;
          }
        }
      }
    }
  }
  EXPECT_GT(hits, 10000u);
  EXPECT_EQ(inward, 0u);
}

TEST(Targets, NamesAndBadDimensions) {
  EXPECT_EQ(sc::target_kind_from_name("trihedral-tri"), sc::TargetKind::kTrihedralTriangular);
  EXPECT_FALSE(sc::target_kind_from_name("cone").has_value());
  EXPECT_EQ(sc::target_names(),
            "plate|dihedral|trihedral-square|trihedral-tri|sphere|cylinder|box|vehicle");
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
