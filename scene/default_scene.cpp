#include "scene/default_scene.hpp"

#include <cmath>
#include <numbers>

namespace radar_emu::scene {

namespace {

constexpr std::uint16_t kGrass = 0, kAsphalt = 1, kMetal = 2;

// Anchor of the default scene: the runway threshold (a made-up airport in southern France).
constexpr double kAnchorLatitude_deg = 43.6;
constexpr double kAnchorLongitude_deg = 1.4;
constexpr double kAnchorHeight_m = 150.0;

void add_quad(Mesh& m, glm::vec3 a, glm::vec3 b, glm::vec3 c, glm::vec3 d, std::uint16_t mat) {
  // a b c d counter-clockwise seen from the side the normal points to.
  const auto base = static_cast<unsigned>(m.positions_m.size());
  m.positions_m.insert(m.positions_m.end(), {a, b, c, d});
  m.triangles.push_back({base, base + 1, base + 2});
  m.triangles.push_back({base, base + 2, base + 3});
  m.triangle_material.insert(m.triangle_material.end(), {mat, mat});
}

// Axis-aligned box, outward normals.
void add_box(Mesh& m, glm::vec3 lo, glm::vec3 hi, std::uint16_t mat) {
  const glm::vec3 p000 = lo, p111 = hi;
  const glm::vec3 p100{hi.x, lo.y, lo.z}, p010{lo.x, hi.y, lo.z}, p001{lo.x, lo.y, hi.z};
  const glm::vec3 p110{hi.x, hi.y, lo.z}, p101{hi.x, lo.y, hi.z}, p011{lo.x, hi.y, hi.z};
  add_quad(m, p000, p010, p110, p100, mat);  // -z
  add_quad(m, p001, p101, p111, p011, mat);  // +z
  add_quad(m, p000, p100, p101, p001, mat);  // -y
  add_quad(m, p010, p011, p111, p110, mat);  // +y
  add_quad(m, p000, p001, p011, p010, mat);  // -x
  add_quad(m, p100, p110, p111, p101, mat);  // +x
}

// Closed prism of `sides` faces along x from x0 to x1, axis at (y, z) = centre, outward normals.
void add_prism_x(Mesh& m, float x0, float x1, glm::vec2 centre, float radius, int sides,
                 std::uint16_t mat) {
  const double step = 2.0 * std::numbers::pi / sides;
  auto ring = [&](int i, float x) {
    // Start half a step below the horizontal so that two faces point exactly sideways (+-y).
    const double a = (i + 0.5) * step;
    return glm::vec3(x, centre.x + radius * static_cast<float>(std::cos(a)),
                     centre.y + radius * static_cast<float>(std::sin(a)));
  };
  for (int i = 0; i < sides; ++i) {
    add_quad(m, ring(i, x0), ring(i + 1, x0), ring(i + 1, x1), ring(i, x1), mat);
  }
  for (int i = 1; i + 1 < sides; ++i) {  // end caps as fans
    const auto base = static_cast<unsigned>(m.positions_m.size());
    m.positions_m.insert(m.positions_m.end(), {ring(0, x0), ring(i + 1, x0), ring(i, x0)});
    m.triangles.push_back({base, base + 1, base + 2});
    m.triangle_material.push_back(mat);
    const auto b2 = static_cast<unsigned>(m.positions_m.size());
    m.positions_m.insert(m.positions_m.end(), {ring(0, x1), ring(i, x1), ring(i + 1, x1)});
    m.triangles.push_back({b2, b2 + 1, b2 + 2});
    m.triangle_material.push_back(mat);
  }
}

glm::dmat4 translation(double x, double y, double z) {
  glm::dmat4 t(1.0);
  t[3] = glm::dvec4(x, y, z, 1.0);
  return t;
}

}  // namespace

SceneDescription default_scene() {
  using L = DefaultSceneLayout;
  SceneDescription d;
  d.materials = {{"grass", {0.25f, 0.45f, 0.15f}},
                 {"asphalt", {0.2f, 0.2f, 0.22f}},
                 {"metal", {0.75f, 0.75f, 0.8f}}};
  const double deg = std::numbers::pi / 180.0;
  d.anchor = {kAnchorLatitude_deg * deg, kAnchorLongitude_deg * deg, kAnchorHeight_m};

  ObjectDesc ground{"ground", {}, glm::dmat4(1.0), std::nullopt};
  const auto gw = static_cast<float>(L::kGroundHalfWidth_m);
  const auto gs = static_cast<float>(L::kGroundSouth_m);
  const auto gn = static_cast<float>(L::kGroundNorth_m);
  add_quad(ground.mesh, {-gw, gs, 0}, {gw, gs, 0}, {gw, gn, 0}, {-gw, gn, 0}, kGrass);
  d.objects.push_back(std::move(ground));

  ObjectDesc runway{"runway", {}, glm::dmat4(1.0), std::nullopt};
  const auto rw = static_cast<float>(L::kRunwayWidth_m / 2.0);
  const auto rl = static_cast<float>(L::kRunwayLength_m);
  add_quad(runway.mesh, {-rw, 0, 0.05f}, {rw, 0, 0.05f}, {rw, rl, 0.05f}, {-rw, rl, 0.05f},
           kAsphalt);
  d.objects.push_back(std::move(runway));

  // Parked aircraft-sized object: fuselage east-west (12-sided prism, r 2 m, 32 m long, axis
  // 3.5 m above ground), wings north-south (30 m x 4 m x 0.4 m), tail fin at the east end.
  ObjectDesc aircraft{"parked_aircraft", {}, translation(110.0, 700.0, 0.0), std::nullopt};
  add_prism_x(aircraft.mesh, -16.0f, 16.0f, {0.0f, 3.5f}, 2.0f, 12, kMetal);
  add_box(aircraft.mesh, {-2.0f, -15.0f, 3.3f}, {2.0f, 15.0f, 3.7f}, kMetal);
  add_box(aircraft.mesh, {11.0f, -0.2f, 5.5f}, {15.0f, 0.2f, 11.5f}, kMetal);
  d.objects.push_back(std::move(aircraft));

  ObjectDesc vehicle{"parked_vehicle", {}, translation(-70.0, 400.0, 0.0), std::nullopt};
  add_box(vehicle.mesh, {-2.5f, -1.1f, 0.0f}, {2.5f, 1.1f, 2.2f}, kMetal);
  d.objects.push_back(std::move(vehicle));

  ObjectDesc mast{"light_mast", {}, translation(60.0, 250.0, 0.0), std::nullopt};
  add_box(mast.mesh, {-0.5f, -0.5f, 0.0f}, {0.5f, 0.5f, 12.0f}, kMetal);
  add_box(mast.mesh, {-2.0f, -0.5f, 12.0f}, {2.0f, 0.5f, 13.0f}, kMetal);
  d.objects.push_back(std::move(mast));

  // Moving vehicle: 6 m x 2.5 m x 2.5 m, body origin at its bottom centre, northward at 15 m/s
  // on a taxiway west of the runway.
  ObjectDesc mover{
      "moving_vehicle", {}, glm::dmat4(1.0), LinearMotion{{-120.0, 200.0, 0.0}, {0.0, 15.0, 0.0}}};
  add_box(mover.mesh, {-3.0f, -1.25f, 0.0f}, {3.0f, 1.25f, 2.5f}, kMetal);
  d.objects.push_back(std::move(mover));
  return d;
}

}  // namespace radar_emu::scene
