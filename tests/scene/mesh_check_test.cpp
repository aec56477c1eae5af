// Mesh checks at load: degenerate triangles reported with file, triangle and line and dropped;
// open and non-manifold surfaces reported; a file of nothing but degenerate triangles refused.
#include "scene/mesh_check.hpp"

#include <gtest/gtest.h>

#include <array>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <limits>
#include <stdexcept>
#include <string>
#include <vector>

#include "scene/gltf.hpp"
#include "scene/mesh_io.hpp"
#include "scene/targets.hpp"

namespace sc = radar_emu::scene;
namespace fs = std::filesystem;

namespace {

fs::path tmp(const std::string& name) {
  const fs::path dir = fs::path(::testing::TempDir()) / "mesh_check";
  fs::create_directories(dir);
  return dir / name;
}

bool any_contains(const std::vector<std::string>& v, const std::string& needle) {
  for (const std::string& s : v) {
    if (s.find(needle) != std::string::npos)
      return true;
  }
  return false;
}

TEST(MeshCheck, ClosedOpenAndNonManifold) {
  // A closed box (every edge shared by two triangles once welded) and an open plate (4 edges).
  const sc::Mesh box = sc::make_target({sc::TargetKind::kBox, 1, 2, 3, 0.5}).objects[0].mesh;
  const sc::MeshCheck cb = sc::check_mesh(box);
  EXPECT_TRUE(cb.closed());
  EXPECT_TRUE(cb.degenerate.empty());
  const sc::Mesh plate = sc::make_target({sc::TargetKind::kPlate, 1, 1, 1, 0}).objects[0].mesh;
  EXPECT_EQ(sc::check_mesh(plate).boundary_edges, 4u);
  // Three triangles on one edge: non-manifold.
  sc::Mesh fan;
  fan.positions_m = {{0, 0, 0}, {1, 0, 0}, {0, 1, 0}, {0, -1, 0}, {0, 0, 1}};
  fan.triangles = {{0, 1, 2}, {1, 0, 3}, {0, 1, 4}};
  fan.triangle_material = {0, 0, 0};
  EXPECT_EQ(sc::check_mesh(fan).non_manifold_edges, 1u);
  // Degenerate: repeated index, collinear vertices, index out of range.
  sc::Mesh bad = fan;
  bad.triangles = {{0, 1, 2}, {0, 0, 1}, {0, 1, 1}};
  bad.positions_m.push_back({2, 0, 0});  // collinear with 0 and 1
  bad.triangles.push_back({0, 1, 5});
  bad.triangles.push_back({0, 1, 99});
  bad.triangle_material.assign(bad.triangles.size(), 0);
  EXPECT_EQ(sc::check_mesh(bad).degenerate, (std::vector<std::size_t>{1, 2, 3, 4}));
}

TEST(MeshCheck, NonFiniteVerticesAreDegenerateNotUndefinedBehaviour) {
  // Found by fuzzing (tests/fuzz/regressions/obj/): an infinite vertex made the weld quantum
  // NaN and its conversion to an integer key undefined. The loaders now refuse such vertices;
  // the check itself stays defined (this runs under UBSan, label "sanitize").
  sc::Mesh m;
  m.positions_m = {{0, 0, 0}, {1, 0, 0}, {0, 1, 0}, {0, std::numeric_limits<float>::infinity(), 1}};
  m.triangles = {{0, 1, 2}, {0, 1, 3}};
  m.triangle_material = {0, 0};
  const sc::MeshCheck c = sc::check_mesh(m);
  EXPECT_EQ(c.degenerate, (std::vector<std::size_t>{1}));
}

TEST(MeshCheck, TJunctionsCloseASeamTessellatedDifferentlyOnEachSide) {
  // A tetrahedron-like closed surface whose edge (0,1) is split at its midpoint on one side only:
  // the long edge has no partner, its two halves have none either, yet the surface is closed.
  sc::Mesh m;
  m.positions_m = {{0, 0, 0}, {2, 0, 0}, {1, 2, 0}, {1, 1, 2}, {1, 0, 0}};
  m.triangles = {{0, 2, 1}, {0, 4, 3}, {4, 1, 3}, {1, 2, 3}, {2, 0, 3}};
  m.triangle_material.assign(m.triangles.size(), 0);
  EXPECT_TRUE(sc::check_mesh(m).closed()) << sc::check_mesh(m).boundary_edges;
  // Removing one face opens it again: its three edges are boundary.
  m.triangles.pop_back();
  m.triangle_material.pop_back();
  EXPECT_EQ(sc::check_mesh(m).boundary_edges, 3u);
  // The generated vehicle (parts tessellated at different densities) is closed.
  EXPECT_TRUE(
      sc::check_mesh(sc::make_target({sc::TargetKind::kVehicle, 7, 3.5, 2.5, 0}).objects[0].mesh)
          .closed());
}

TEST(MeshCheck, WeldsByDistanceNotByGridCell) {
  // The cube [0, 1]^3 as a soup whose corner at the origin sits at x = h, half a weld tolerance
  // (1e-7 of the extent, scene/mesh/topology.hpp) from x = 0, one copy of it a float step
  // (7e-15 m) nearer. The check used to round positions to cells of the tolerance, which split
  // this pair across a cell boundary: 4 boundary edges reported on a closed box. The one weld
  // rule is a distance and welds it.
  const double tolerance = 1e-7 * std::sqrt(3.0);
  // h: the least float at or above half the tolerance; h_minus the float below it.
  float h = static_cast<float>(0.5 * tolerance);
  while (static_cast<double>(h) < 0.5 * tolerance)
    h = std::nextafter(h, 1.0f);
  while (static_cast<double>(std::nextafter(h, 0.0f)) >= 0.5 * tolerance)
    h = std::nextafter(h, 0.0f);
  const float h_minus = std::nextafter(h, 0.0f);
  ASSERT_LT(static_cast<double>(h - h_minus), 1e-12);
  const std::array<glm::vec3, 8> corner{
      {{h, 0, 0}, {1, 0, 0}, {0, 1, 0}, {1, 1, 0}, {0, 0, 1}, {1, 0, 1}, {0, 1, 1}, {1, 1, 1}}};
  const std::array<std::array<unsigned, 4>, 6> faces{
      {{0, 2, 3, 1}, {4, 5, 7, 6}, {0, 1, 5, 4}, {2, 6, 7, 3}, {0, 4, 6, 2}, {1, 3, 7, 5}}};
  sc::Mesh m;
  bool moved = false;
  for (const auto& f : faces) {
    for (const std::array<unsigned, 3> tri :
         {std::array<unsigned, 3>{f[0], f[1], f[2]}, std::array<unsigned, 3>{f[0], f[2], f[3]}}) {
      const auto base = static_cast<unsigned>(m.positions_m.size());
      for (unsigned c : tri) {
        glm::vec3 p = corner[c];
        if (c == 0 && !moved) {
          p.x = h_minus;
          moved = true;
        }
        m.positions_m.push_back(p);
      }
      m.triangles.push_back({base, base + 1, base + 2});
      m.triangle_material.push_back(0);
    }
  }
  const sc::MeshCheck c = sc::check_mesh(m);
  EXPECT_EQ(c.boundary_edges, 0u);
  EXPECT_TRUE(c.closed());
}

TEST(MeshCheck, InconsistentWindingIsNotClosedAsForTheTracer) {
  // A box with one triangle wound the wrong way: every edge has two triangles, but three of them
  // run it the same way. The tracer's closed parts (sbr_core.hpp) take such a part as open; the
  // check used to call it closed. Now it counts and reports the edges.
  sc::Mesh box = sc::make_target({sc::TargetKind::kBox, 1, 2, 3, 0}).objects[0].mesh;
  std::swap(box.triangles[3].y, box.triangles[3].z);
  const sc::MeshCheck c = sc::check_mesh(box);
  EXPECT_EQ(c.boundary_edges, 0u);
  EXPECT_EQ(c.inconsistent_edges, 3u);
  EXPECT_FALSE(c.closed());
  const std::vector<std::string> w = sc::clean_loaded_mesh(box, "box.obj");
  EXPECT_TRUE(any_contains(w, "box.obj: 3 edges between triangles wound inconsistently"))
      << (w.empty() ? "" : w[0]);
}

TEST(MeshCheck, ObjDegenerateTriangleIsReportedWithFileTriangleAndLineThenDropped) {
  const fs::path p = tmp("degenerate.obj");
  std::ofstream(p) << "v 0 0 0\nv 1 0 0\nv 0 1 0\nv 2 0 0\n"
                   << "f 1 2 3\n"   // line 5: triangle 0, fine
                   << "f 1 2 4\n";  // line 6: triangle 1, collinear
  std::vector<std::string> warnings;
  const sc::SceneDescription d = sc::load_mesh_file(p, {}, &warnings);
  EXPECT_EQ(d.objects[0].mesh.triangles.size(), 1u);
  EXPECT_TRUE(any_contains(warnings, p.string() + ": triangle 1 (line 6) is degenerate"))
      << (warnings.empty() ? "" : warnings[0]);
  EXPECT_TRUE(any_contains(warnings, "open mesh: 3 boundary edges"));
  // Without a warnings vector the load still succeeds silently.
  EXPECT_EQ(sc::load_mesh_file(p).objects[0].mesh.triangles.size(), 1u);
}

TEST(MeshCheck, ManyDegenerateTrianglesAreSummarised) {
  const fs::path p = tmp("many.obj");
  {
    std::ofstream f(p);
    f << "v 0 0 0\nv 1 0 0\nv 0 1 0\nv 2 0 0\nf 1 2 3\n";
    for (int i = 0; i < 15; ++i)
      f << "f 1 2 4\n";
  }
  std::vector<std::string> warnings;
  (void)sc::load_mesh_file(p, {}, &warnings);
  EXPECT_TRUE(any_contains(warnings, "... and 5 more degenerate triangles dropped"));
}

TEST(MeshCheck, OnlyDegenerateTrianglesIsAnErrorNamingTheFile) {
  const fs::path p = tmp("flat.obj");
  std::ofstream(p) << "v 0 0 0\nv 1 0 0\nv 2 0 0\nf 1 2 3\n";
  try {
    (void)sc::load_mesh_file(p);
    FAIL() << "expected an error";
  } catch (const std::runtime_error& e) {
    EXPECT_NE(std::string(e.what()).find(p.string()), std::string::npos) << e.what();
    EXPECT_NE(std::string(e.what()).find("degenerate"), std::string::npos) << e.what();
  }
}

TEST(MeshCheck, BinaryStlIsWeldedSoAClosedBoxIsClosed) {
  const sc::SceneDescription box = sc::make_target({sc::TargetKind::kBox, 1, 1, 1, 0});
  const fs::path p = tmp("box.stl");
  sc::write_mesh_file(box.objects[0].mesh, box.materials, p);
  std::vector<std::string> warnings;
  const sc::SceneDescription d = sc::load_mesh_file(p, {}, &warnings);
  EXPECT_TRUE(sc::check_mesh(d.objects[0].mesh).closed());
  EXPECT_TRUE(warnings.empty()) << warnings[0];
}

TEST(MeshCheck, GltfOpenMeshWarnsWithTheNode) {
  const sc::SceneDescription plate = sc::make_target({sc::TargetKind::kPlate, 1, 1, 1, 0});
  const fs::path p = tmp("plate.glb");
  sc::write_gltf(plate, p);
  std::vector<std::string> warnings;
  (void)sc::load_gltf(p, &warnings);
  EXPECT_TRUE(any_contains(warnings, p.string() + ": node plate: open mesh: 4 boundary edges"))
      << (warnings.empty() ? "" : warnings[0]);
}

}  // namespace
