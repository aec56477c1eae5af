// Canonical targets against closed-form areas and volumes (divergence theorem), orientation
// conventions, and OBJ/STL round trips and broken files.

#include "scene/targets.hpp"

#include <gtest/gtest.h>

#include <algorithm>
#include <array>
#include <cctype>
#include <cmath>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <iostream>
#include <map>
#include <numbers>
#include <stdexcept>
#include <tuple>
#include <vector>

#include "scene/gltf.hpp"
#include "scene/mesh_check.hpp"
#include "scene/mesh_io.hpp"
#include "scene/scene.hpp"
#include "tests/scene/mesh_parts.hpp"

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

// ---- Vehicles and aircraft (truck, jeep, helicopter, transport_aircraft) ----
// Their part lists and proportions are documented in scene/targets.cpp; the volumes below are
// the closed forms of those parts: boxes, prisms of polygonal profiles (shoelace area times
// width), regular n-gon prisms ((n/2) r^2 sin(2 pi/n) times length), pyramids (A h / 3) and
// frustums of similar sections (h/3 (A0 + A1 + sqrt(A0 A1)), exact for any polyhedron whose
// vertices lie in two parallel planes with similar, parallel-sided sections). The parts are
// separately closed surfaces, so the divergence-theorem volume of the whole mesh is the sum of
// the parts' volumes whether or not they interpenetrate.

namespace {

double ngon_area(int n, double ru, double rv) {
  return 0.5 * n * ru * rv * std::sin(2.0 * kPi / n);
}
double shoelace(const std::vector<glm::dvec2>& p) {
  double s = 0.0;
  for (std::size_t i = 0; i < p.size(); ++i)
    s += p[i].x * p[(i + 1) % p.size()].y - p[(i + 1) % p.size()].x * p[i].y;
  return 0.5 * std::abs(s);
}
double frustum(double h, double a0, double a1) {
  return h / 3.0 * (a0 + a1 + std::sqrt(a0 * a1));
}

using radar_emu::test::closed_and_consistent;

// Signed volumes of the connected parts (triangles sharing a vertex position).
std::vector<double> part_volumes(const sc::Mesh& m) {
  std::vector<double> out;
  for (const auto& part : radar_emu::test::mesh_parts(m))
    out.push_back(radar_emu::test::signed_volume(m, part));
  return out;
}

void bounds(const sc::Mesh& m, glm::dvec3& lo, glm::dvec3& hi) {
  lo = glm::dvec3(1e300);
  hi = glm::dvec3(-1e300);
  for (const glm::vec3& p : m.positions_m) {
    lo = glm::min(lo, glm::dvec3(p));
    hi = glm::max(hi, glm::dvec3(p));
  }
}

double longest_edge(const sc::Mesh& m) {
  double longest = 0.0;
  for (const auto& t : m.triangles) {
    const glm::dvec3 p0(m.positions_m[t.x]), p1(m.positions_m[t.y]), p2(m.positions_m[t.z]);
    longest = std::max({longest, glm::length(p1 - p0), glm::length(p2 - p1), glm::length(p0 - p2)});
  }
  return longest;
}

double truck_volume(double a, double b, double c) {
  const double wheels = 6 * ngon_area(16, 0.15 * c, 0.15 * c) * 0.14 * b;
  const double chassis = 0.93 * a * 0.66 * b * 0.10 * c;
  const double cab = shoelace({{0.24 * a, 0.22 * c},
                               {0.5 * a, 0.22 * c},
                               {0.5 * a, 0.55 * c},
                               {0.44 * a, 0.78 * c},
                               {0.24 * a, 0.78 * c}}) *
                     b;
  const double cargo = 0.71 * a * b * 0.71 * c;
  return wheels + chassis + cab + cargo;
}

double jeep_volume(double a, double b, double c) {
  const double wheels = 4 * ngon_area(16, 0.19 * c, 0.19 * c) * 0.14 * b;
  const double hull = shoelace({{-0.5 * a, 0.2 * c},
                                {0.44 * a, 0.2 * c},
                                {0.5 * a, 0.3 * c},
                                {0.5 * a, 0.52 * c},
                                {-0.5 * a, 0.55 * c}}) *
                      0.86 * b;
  const double cabin =
      shoelace({{-0.45 * a, 0.5 * c}, {0.12 * a, 0.5 * c}, {0.02 * a, c}, {-0.45 * a, c}}) * 0.84 *
      b;
  return wheels + hull + cabin;
}

double helicopter_volume(double a, double b, double c) {
  const double zf = 0.38 * c;
  auto ell = [&](double s) { return ngon_area(16, s * 0.08 * a, s * 0.22 * c); };
  const double fuselage = ell(0.6) * 0.08 * a / 3 + frustum(0.12 * a, ell(0.6), ell(1.0)) +
                          ell(1.0) * 0.42 * a + frustum(0.1 * a, ell(1.0), ell(0.4)) +
                          ell(0.4) * 0.03 * a / 3;
  const double boom =
      frustum(0.29 * a, ngon_area(12, 0.045 * c, 0.045 * c), ngon_area(12, 0.025 * c, 0.025 * c));
  const double fin = shoelace({{-0.5 * a, 0.45 * c},
                               {-0.43 * a, 0.45 * c},
                               {-0.46 * a, 0.85 * c},
                               {-0.5 * a, 0.85 * c}}) *
                     0.016 * a;
  const double stabiliser = 0.05 * a * 0.2 * a * 0.03 * c;
  const double tail_rotor = ngon_area(16, 0.08 * a, 0.08 * a) * 0.004 * a;
  const double mast = ngon_area(12, 0.025 * a, 0.025 * a) * (0.93 * c - zf - 0.15 * c);
  const double hub = 0.08 * a * 0.08 * a * 0.12 * c;
  const double blades = b * 0.035 * b * 0.012 * c;
  const double skids = 2 * ngon_area(12, 0.008 * a, 0.008 * a) * 0.45 * a;
  const double struts = 4 * 0.01 * a * 0.01 * a * (0.33 * c - 0.004 * a);
  return fuselage + boom + fin + stabiliser + tail_rotor + mast + hub + blades + skids + struts;
}

double transport_aircraft_volume(double a, double b, double c) {
  const double r = 0.053 * a, zf = 0.3 * c;
  auto ring = [&](double s) { return ngon_area(32, s * r, s * r); };
  const double fuselage = ring(0.55) * 0.07 * a / 3 + frustum(0.1 * a, ring(0.55), ring(1.0)) +
                          ring(1.0) * 0.53 * a + frustum(0.23 * a, ring(1.0), ring(0.35)) +
                          ring(0.35) * 0.07 * a / 3;
  // Hexagonal aerofoil of thickness ratio tau: area 0.675 tau chord^2; a tapered surface of
  // span s is a frustum: s A_root (1 + t + t^2) / 3.
  auto surface = [](double span, double chord, double tau, double taper) {
    return span * 0.675 * tau * chord * chord * (1 + taper + taper * taper) / 3.0;
  };
  const double wing = surface(b, 0.19 * a, 0.12, 0.24);
  const double tailplane = surface(0.34 * b, 0.1 * a, 0.10, 0.33);
  const double fin = surface(c - (zf + 0.4 * r), 0.17 * a, 0.10, 0.35);
  const double re = 0.031 * a;
  auto eng = [&](double s) { return ngon_area(24, s * re, s * re); };
  const double nacelles =
      2 * (frustum(0.04 * a, eng(0.9), eng(1.0)) + frustum(0.07 * a, eng(1.0), eng(0.7)));
  const double pylons = 2 * 0.08 * a * 0.008 * a * 0.35 * re;
  const double nose_gear =
      ngon_area(12, 0.035 * c, 0.035 * c) * 0.016 * a + 0.008 * a * 0.006 * a * (zf - 0.035 * c);
  const double main_gear = 2 * (ngon_area(16, 0.05 * c, 0.05 * c) * 0.02 * b +
                                0.012 * a * 0.008 * a * (zf - 0.55 * r - 0.05 * c));
  return fuselage + wing + tailplane + fin + nacelles + pylons + nose_gear + main_gear;
}

struct VehicleCase {
  sc::TargetKind kind;
  double a, b, c;
  double volume_m3;
};

}  // namespace

TEST(Targets, VehiclesAndAircraftAreClosedOutwardWithTheirPartsVolumesAndBounds) {
  const VehicleCase cases[] = {
      {sc::TargetKind::kTruck, 8.0, 2.5, 3.4, truck_volume(8.0, 2.5, 3.4)},
      {sc::TargetKind::kJeep, 4.0, 1.8, 1.9, jeep_volume(4.0, 1.8, 1.9)},
      {sc::TargetKind::kHelicopter, 12.7, 14.6, 4.4, helicopter_volume(12.7, 14.6, 4.4)},
      {sc::TargetKind::kTransportAircraft, 37.57, 35.8, 11.76,
       transport_aircraft_volume(37.57, 35.8, 11.76)},  // A320
      {sc::TargetKind::kTransportAircraft, 29.8, 40.4, 11.7,
       transport_aircraft_volume(29.8, 40.4, 11.7)},  // C-130 size
  };
  for (const VehicleCase& k : cases) {
    const std::string name(sc::target_name(k.kind));
    const sc::SceneDescription d = sc::make_target({k.kind, k.a, k.b, k.c, 0.0});
    ASSERT_EQ(d.objects.size(), 1u);
    EXPECT_EQ(d.objects[0].name, name);
    ASSERT_EQ(d.materials.size(), 1u);
    EXPECT_EQ(d.materials[0].name, "metal");
    const sc::Mesh& m = d.objects[0].mesh;
    std::cout << name << " " << k.a << " x " << k.b << " x " << k.c << " m: " << m.triangles.size()
              << " triangles, volume " << volume(m) << " m^3 (parts, closed form " << k.volume_m3
              << ")\n";
    EXPECT_EQ(m.triangle_material.size(), m.triangles.size());
    // Closed: by directed edges (each paired with its reverse) and by the loader's check.
    EXPECT_TRUE(closed_and_consistent(m)) << name;
    const sc::MeshCheck check = sc::check_mesh(m);
    EXPECT_TRUE(check.closed()) << name << ": " << check.boundary_edges << " boundary, "
                                << check.non_manifold_edges << " non-manifold";
    EXPECT_TRUE(check.degenerate.empty()) << name;
    // Outward: every part encloses a positive volume; together the parts' closed forms.
    for (double v : part_volumes(m))
      EXPECT_GT(v, 0.0) << name;
    EXPECT_NEAR(volume(m), k.volume_m3, 1e-5 * k.volume_m3) << name;
    // Overall dimensions as specified: x [-a/2, a/2], y [-b/2, b/2], z [0, c].
    glm::dvec3 lo, hi;
    bounds(m, lo, hi);
    const double tol = 1e-5 * k.a;
    EXPECT_NEAR(lo.x, -k.a / 2, tol) << name;
    EXPECT_NEAR(hi.x, k.a / 2, tol) << name;
    EXPECT_NEAR(lo.y, -k.b / 2, tol) << name;
    EXPECT_NEAR(hi.y, k.b / 2, tol) << name;
    EXPECT_NEAR(lo.z, 0.0, tol) << name;
    EXPECT_NEAR(hi.z, k.c, tol) << name;
    EXPECT_GT(m.triangles.size(), 100u) << name;
    EXPECT_LT(m.triangles.size(), 5000u) << name;
  }
}

TEST(Targets, VehiclesAndAircraftHonourTheFacetSize) {
  // Flat-faced parts keep their volume exactly when refined; round parts gain sides (closer to
  // the circle), so the aircraft's volume grows a little toward its circular-section value.
  for (const auto kind : {sc::TargetKind::kTruck, sc::TargetKind::kJeep,
                          sc::TargetKind::kHelicopter, sc::TargetKind::kTransportAircraft}) {
    const bool aircraft = kind == sc::TargetKind::kTransportAircraft;
    const double a = aircraft ? 37.57 : 8.0, b = aircraft ? 35.8 : 2.5, c = aircraft ? 11.76 : 3.4;
    const double f = aircraft ? 1.0 : 0.35;
    const sc::Mesh coarse = target(kind, a, b, c, 0.0);
    const sc::Mesh fine = target(kind, a, b, c, f);
    const std::string name(sc::target_name(kind));
    std::cout << name << " facet " << f << " m: " << fine.triangles.size() << " triangles\n";
    EXPECT_GT(fine.triangles.size(), coarse.triangles.size()) << name;
    EXPECT_LE(longest_edge(fine), std::sqrt(2.0) * f * (1 + 1e-5)) << name;
    EXPECT_TRUE(closed_and_consistent(fine)) << name;
    EXPECT_TRUE(sc::check_mesh(fine).degenerate.empty()) << name;
    for (double v : part_volumes(fine))
      EXPECT_GT(v, 0.0) << name;
    EXPECT_GE(volume(fine), volume(coarse) * (1 - 1e-5)) << name;
    EXPECT_LE(volume(fine), volume(coarse) * 1.02) << name;
  }
}

// Issue 32: `scene target` and [[target]] read one table of sizes. The vehicles and aircraft
// default to the example sizes of scene/targets.hpp (a truck is 8 x 2.5 x 3.4 m, not the
// 1 x 1 x 1 m `scene target truck` used to write), and the mesh made at that size spans exactly
// x [-a/2, a/2], y [-b/2, b/2], z [0, c]; the canonical shapes have no default.
TEST(Targets, OneTableOfDefaultSizesAndTheMeshesHaveThem) {
  const std::map<sc::TargetKind, std::array<double, 3>> examples{
      {sc::TargetKind::kVehicle, {7.0, 3.5, 2.5}},
      {sc::TargetKind::kTruck, {8.0, 2.5, 3.4}},
      {sc::TargetKind::kJeep, {4.0, 1.8, 1.9}},
      {sc::TargetKind::kHelicopter, {12.7, 14.6, 4.4}},
      {sc::TargetKind::kTransportAircraft, {37.6, 35.8, 11.8}}};
  for (const auto& [kind, size] : examples) {
    const sc::TargetKindSize k = sc::target_kind_size(kind);
    ASSERT_TRUE(k.default_m.has_value()) << sc::target_name(kind);
    EXPECT_EQ(*k.default_m, size) << sc::target_name(kind);
    EXPECT_EQ(k.dims, 3);
    if (kind == sc::TargetKind::kVehicle)
      continue;  // its gun and cupola: bounds checked in the benchmark-target test
    const sc::SceneDescription d = sc::make_target({kind, size[0], size[1], size[2], 0.0});
    glm::dvec3 lo(1e9), hi(-1e9);
    for (const glm::vec3& p : d.objects[0].mesh.positions_m) {
      lo = glm::min(lo, glm::dvec3(p));
      hi = glm::max(hi, glm::dvec3(p));
    }
    EXPECT_NEAR(hi.x - lo.x, size[0], 1e-3) << sc::target_name(kind);
    EXPECT_NEAR(hi.y - lo.y, size[1], 1e-3) << sc::target_name(kind);
    EXPECT_NEAR(hi.z - lo.z, size[2], 1e-3) << sc::target_name(kind);
  }
  for (const sc::TargetKind kind :
       {sc::TargetKind::kPlate, sc::TargetKind::kDihedral, sc::TargetKind::kTrihedralSquare,
        sc::TargetKind::kTrihedralTriangular, sc::TargetKind::kSphere, sc::TargetKind::kCylinder,
        sc::TargetKind::kBox})
    EXPECT_FALSE(sc::target_kind_size(kind).default_m.has_value()) << sc::target_name(kind);
  EXPECT_EQ(sc::target_kind_size(sc::TargetKind::kSphere).dims, 1);
  EXPECT_EQ(sc::target_kind_size(sc::TargetKind::kPlate).dims, 2);
  EXPECT_EQ(sc::target_size_text({sc::TargetKind::kTruck, 8.0, 2.5, 3.4, 0.0}),
            "truck 8 x 2.5 x 3.4 m [length, width, height]");
  EXPECT_EQ(sc::target_size_text({sc::TargetKind::kSphere, 0.05, 1.0, 1.0, 0.0}),
            "sphere 0.05 m [radius]");
}

TEST(Targets, NamesAndBadDimensions) {
  EXPECT_EQ(sc::target_kind_from_name("trihedral-tri"), sc::TargetKind::kTrihedralTriangular);
  EXPECT_FALSE(sc::target_kind_from_name("cone").has_value());
  EXPECT_EQ(sc::target_names(),
            "plate|dihedral|trihedral-square|trihedral-tri|sphere|cylinder|box|vehicle|truck|jeep|"
            "helicopter|transport_aircraft");
  for (const char* n : {"truck", "jeep", "helicopter", "transport_aircraft"}) {
    ASSERT_TRUE(sc::target_kind_from_name(n).has_value()) << n;
    EXPECT_EQ(sc::target_name(*sc::target_kind_from_name(n)), n);
  }
  EXPECT_THROW((void)sc::make_target({sc::TargetKind::kPlate, -1.0, 1, 1, 0}),
               std::invalid_argument);
  EXPECT_THROW((void)sc::make_target({sc::TargetKind::kBox, 1, std::nan(""), 1, 0}),
               std::invalid_argument);
  EXPECT_THROW((void)sc::make_target({sc::TargetKind::kBox, 1, 1, 1, -0.1}), std::invalid_argument);
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

// The extension picks the format whatever its case: "BOX.GLB" is glTF (binary: its magic
// "glTF", glTF 2.0 spec 4.4.3), "BOX.OBJ" the text mesh; each reads back with the box's area.
TEST(MeshFiles, WriteTargetFilePicksTheFormatByExtensionInAnyCase) {
  const sc::TargetSpec spec{sc::TargetKind::kBox, 1.0, 2.0, 3.0, 0.0};
  const double box_area_m2 = 2.0 * (1.0 * 2.0 + 2.0 * 3.0 + 1.0 * 3.0);
  for (const char* name : {"BOX.GLB", "box.Gltf", "BOX.OBJ", "box.stl"}) {
    const std::size_t written = sc::write_target_file(spec, tmp(name));
    const std::string lower = [&] {
      std::string s(name);
      for (char& c : s)
        c = static_cast<char>(std::tolower(static_cast<unsigned char>(c)));
      return s;
    }();
    const bool gltf = lower.ends_with(".glb") || lower.ends_with(".gltf");
    if (lower.ends_with(".glb")) {
      std::ifstream f(tmp(name), std::ios::binary);
      char magic[4] = {};
      f.read(magic, 4);
      EXPECT_EQ(std::string(magic, 4), "glTF") << name;
    }
    const sc::SceneDescription r = gltf ? sc::load_gltf(tmp(name)) : sc::load_mesh_file(tmp(name));
    ASSERT_EQ(r.objects.size(), 1u) << name;
    EXPECT_EQ(r.objects[0].mesh.triangles.size(), written) << name;
    EXPECT_NEAR(area(r.objects[0].mesh), box_area_m2, 1e-6) << name;
  }
  // A format nobody writes is refused before the file is opened: no empty file left behind.
  fs::remove(tmp("box.ply"));
  EXPECT_THROW((void)sc::write_target_file(spec, tmp("box.ply")), std::runtime_error);
  EXPECT_FALSE(fs::exists(tmp("box.ply")));
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

// The estimate that `scene target` refuses a mesh by (--max-triangles): exact where the count is
// a closed form of the divisions, within a factor of 2 for the lofted kinds at the example sizes
// of targets.hpp; an absurd facet size is a huge estimate (infinity at worst), never an integer
// that wrapped round to a small one.
TEST(Targets, TriangleEstimateMatchesTheMeshes) {
  for (sc::TargetKind k :
       {sc::TargetKind::kPlate, sc::TargetKind::kDihedral, sc::TargetKind::kTrihedralSquare,
        sc::TargetKind::kTrihedralTriangular, sc::TargetKind::kSphere, sc::TargetKind::kCylinder,
        sc::TargetKind::kBox}) {
    for (double f : {0.0, 0.3, 0.07}) {
      const sc::TargetSpec spec{k, 1.3, 0.9, 0.6, f};
      const double n = static_cast<double>(sc::make_target(spec).objects[0].mesh.triangles.size());
      EXPECT_EQ(sc::target_triangle_estimate(spec), n) << sc::target_name(k) << " facet " << f;
    }
  }
  const std::vector<std::tuple<sc::TargetKind, double, double, double>> lofted{
      {sc::TargetKind::kVehicle, 7.0, 3.5, 2.5},
      {sc::TargetKind::kTruck, 8.0, 2.5, 3.4},
      {sc::TargetKind::kJeep, 4.0, 1.8, 1.9},
      {sc::TargetKind::kHelicopter, 12.7, 14.6, 4.4},
      {sc::TargetKind::kTransportAircraft, 37.6, 35.8, 11.8}};
  for (const auto& [k, a, b, c] : lofted) {
    for (double f : {0.0, 0.5, 0.2, 0.1}) {
      const sc::TargetSpec spec{k, a, b, c, f};
      const double n = static_cast<double>(sc::make_target(spec).objects[0].mesh.triangles.size());
      const double e = sc::target_triangle_estimate(spec);
      EXPECT_GT(e, 0.5 * n) << sc::target_name(k) << " facet " << f;
      EXPECT_LT(e, 2.0 * n) << sc::target_name(k) << " facet " << f;
    }
  }
  // Sphere of radius 1 m at 0.1 mm: 62832 around x 31416 rings (2 per cell but the poles).
  const double huge = sc::target_triangle_estimate({sc::TargetKind::kSphere, 1.0, 1.0, 1.0, 1e-4});
  EXPECT_DOUBLE_EQ(huge, 62832.0 * (2.0 * 31416.0 - 2.0));
  EXPECT_GT(sc::target_triangle_estimate({sc::TargetKind::kBox, 1, 1, 1, 1e-300}), 1e300);
}
