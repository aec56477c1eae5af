#include "scene/default_scene.hpp"

#include <cmath>
#include <numbers>

#include "common/units.hpp"
#include "scene/scene_builders.hpp"

namespace radar_emu::scene {

namespace detail {

void add_quad(Mesh& m, glm::vec3 a, glm::vec3 b, glm::vec3 c, glm::vec3 d, std::uint16_t mat) {
  // a b c d counter-clockwise seen from the side the normal points to.
  const auto base = static_cast<unsigned>(m.positions_m.size());
  m.positions_m.insert(m.positions_m.end(), {a, b, c, d});
  m.triangles.push_back({base, base + 1, base + 2});
  m.triangles.push_back({base, base + 2, base + 3});
  m.triangle_material.insert(m.triangle_material.end(), {mat, mat});
}

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

// Square trihedral corner reflector of edge a (three mutually perpendicular square plates, single
// sheets), corner at `corner`, symmetry axis (the direction of peak return) along `axis`.
// On axis its PO RCS is 12 pi a^4 / lambda^2 (physics.md, canonical targets), over a beam of
// some +-20 degrees.
void add_trihedral(Mesh& m, glm::dvec3 corner, glm::dvec3 axis, double a, std::uint16_t mat) {
  // Rotation taking the local octant's diagonal (1,1,1)/sqrt(3) onto `axis` (Rodrigues).
  const glm::dvec3 from = glm::normalize(glm::dvec3(1.0));
  const glm::dvec3 to = glm::normalize(axis);
  const glm::dvec3 k = glm::cross(from, to);
  const double s = glm::length(k), c = glm::dot(from, to);
  glm::dmat3 r(1.0);
  if (s > 1e-12) {
    const glm::dvec3 u = k / s;
    const glm::dmat3 kx(glm::dvec3(0, u.z, -u.y), glm::dvec3(-u.z, 0, u.x),
                        glm::dvec3(u.y, -u.x, 0));
    r = glm::dmat3(1.0) + s * kx + (1.0 - c) * kx * kx;
  }
  auto p = [&](double x, double y, double z) {
    return glm::vec3(corner + r * glm::dvec3(x, y, z));
  };
  add_quad(m, p(0, 0, 0), p(a, 0, 0), p(a, a, 0), p(0, a, 0), mat);  // floor, local normal +z
  add_quad(m, p(0, 0, 0), p(0, 0, a), p(a, 0, a), p(a, 0, 0), mat);  // wall, local normal +y
  add_quad(m, p(0, 0, 0), p(0, a, 0), p(0, a, a), p(0, 0, a), mat);  // wall, local normal +x
}

glm::dmat4 translation(const glm::dvec3& p) {
  glm::dmat4 t(1.0);
  t[3] = glm::dvec4(p, 1.0);
  return t;
}

void add_closed_loop_objects(SceneDescription& d, std::uint16_t metal, bool corner_reflectors,
                             const std::string& area) {
  using L = DefaultSceneLayout;
  const std::uint16_t kMetal = metal;
  auto object = [&](const char* name, const glm::dmat4& placement) {
    ObjectDesc o;
    o.name = name;
    o.world_from_body = placement;
    o.area = area;
    return o;
  };
  // Parked aircraft-sized object: fuselage east-west (12-sided prism, r 2 m, 32 m long, axis
  // 3.5 m above ground), wings north-south (30 m x 4 m x 0.4 m), tail fin at the east end. The
  // fin's root is sunk 0.2 m into the fuselage (whose flat top is at 3.5 + 2 sin 75 deg =
  // 5.43 m) so that no gap opens between them; its tip is at 11.3 m.
  ObjectDesc aircraft = object("parked_aircraft", translation(L::kParkedAircraft_m));
  add_prism_x(aircraft.mesh, -16.0f, 16.0f, {0.0f, 3.5f}, 2.0f, 12, kMetal);
  add_box(aircraft.mesh, {-2.0f, -15.0f, 3.3f}, {2.0f, 15.0f, 3.7f}, kMetal);
  add_box(aircraft.mesh, {11.0f, -0.2f, 5.3f}, {15.0f, 0.2f, 11.3f}, kMetal);
  // A trihedral on the fuselage top: a 32 m fuselage is bright (PO) only within 0.003 deg of
  // broadside at 94 GHz, and the approach sees it 1.3 deg off.
  if (corner_reflectors)
    add_trihedral(aircraft.mesh, {-6.0, 0.0, 5.5 + 0.5}, {0.0, -1.0, 0.06}, 0.5, kMetal);
  d.objects.push_back(std::move(aircraft));

  // Flat faces of boxes flash only within a few hundredths of a degree of normal incidence at
  // 94 GHz (PO), so each small object carries a 0.5 m square trihedral on its roof, aimed along
  // the approach (toward the south, 3 degrees up), as test ranges mount corner reflectors; the
  // corner sits one edge above the roof so that no plate dips into it.
  const glm::dvec3 approach(0.0, -1.0, 0.06);
  constexpr double kReflectorEdge_m = 0.5;
  ObjectDesc vehicle = object("parked_vehicle", translation(L::kParkedVehicle_m));
  add_box(vehicle.mesh, {-2.5f, -1.1f, 0.0f}, {2.5f, 1.1f, 2.2f}, kMetal);
  if (corner_reflectors)
    add_trihedral(vehicle.mesh, {0.0, 0.0, 2.2 + kReflectorEdge_m}, approach, kReflectorEdge_m,
                  kMetal);
  d.objects.push_back(std::move(vehicle));

  ObjectDesc mast = object("light_mast", translation(L::kLightMast_m));
  add_box(mast.mesh, {-0.5f, -0.5f, 0.0f}, {0.5f, 0.5f, 12.0f}, kMetal);
  add_box(mast.mesh, {-2.0f, -0.5f, 12.0f}, {2.0f, 0.5f, 13.0f}, kMetal);
  if (corner_reflectors)
    add_trihedral(mast.mesh, {0.0, 0.0, 13.0 + kReflectorEdge_m}, approach, kReflectorEdge_m,
                  kMetal);
  d.objects.push_back(std::move(mast));

  // Moving vehicle: 6 m x 2.5 m x 2.5 m, body origin at its bottom centre, northward at 15 m/s
  // on a taxiway west of the runway.
  ObjectDesc mover = object("moving_vehicle", glm::dmat4(1.0));
  mover.motion = LinearMotion{L::kMovingVehicleStart_m, L::kMovingVehicleVelocity_mps};
  add_box(mover.mesh, {-3.0f, -1.25f, 0.0f}, {3.0f, 1.25f, 2.5f}, kMetal);
  // Body frame: x along the velocity (north), so "toward the approach" is body -x.
  if (corner_reflectors)
    add_trihedral(mover.mesh, {0.0, 0.0, 2.5 + kReflectorEdge_m}, {-1.0, 0.0, 0.06},
                  kReflectorEdge_m, kMetal);
  d.objects.push_back(std::move(mover));
}

}  // namespace detail

SceneDescription default_scene() {
  using detail::add_quad;
  constexpr std::uint16_t kGrass = 0, kAsphalt = 1, kMetal = 2;
  using L = DefaultSceneLayout;
  SceneDescription d;
  d.materials = {{"grass", {0.25f, 0.45f, 0.15f}},
                 {"asphalt", {0.2f, 0.2f, 0.22f}},
                 {"metal", {0.75f, 0.75f, 0.8f}}};
  d.anchor = {common::radians(L::kAnchorLatitude_deg), common::radians(L::kAnchorLongitude_deg),
              L::kAnchorHeight_m};

  ObjectDesc ground{"ground", {}, glm::dmat4(1.0), std::nullopt};
  const auto gw = static_cast<float>(L::kGroundHalfWidth_m);
  const auto gs = static_cast<float>(L::kGroundSouth_m);
  const auto gn = static_cast<float>(L::kGroundNorth_m);
  add_quad(ground.mesh, {-gw, gs, 0}, {gw, gs, 0}, {gw, gn, 0}, {-gw, gn, 0}, kGrass);
  d.objects.push_back(std::move(ground));

  ObjectDesc runway{"runway", {}, glm::dmat4(1.0), std::nullopt};
  const auto rw = static_cast<float>(L::kRunwayWidth_m / 2.0);
  const auto rl = static_cast<float>(L::kRunwayLength_m);
  const auto rh = static_cast<float>(L::kRunwayHeight_m);
  add_quad(runway.mesh, {-rw, 0, rh}, {rw, 0, rh}, {rw, rl, rh}, {-rw, rl, rh}, kAsphalt);
  d.objects.push_back(std::move(runway));

  detail::add_closed_loop_objects(d, kMetal, true, "");
  return d;
}

}  // namespace radar_emu::scene
