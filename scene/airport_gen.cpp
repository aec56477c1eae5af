#include "scene/airport_gen.hpp"

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdio>
#include <numbers>
#include <stdexcept>
#include <string>
#include <vector>

#include "common/units.hpp"
#include "scene/default_scene.hpp"
#include "scene/scene_builders.hpp"
#include "scene/targets.hpp"

namespace radar_emu::scene {

namespace {

using detail::add_box;
using detail::add_quad;
using L = DefaultSceneLayout;

constexpr std::uint16_t kGrass = 0, kAsphalt = 1, kConcrete = 2, kMetal = 3;
constexpr double kPaveZ_m = L::kRunwayHeight_m;  // every pavement, 5 cm over the grass

// SplitMix64 (Steele, Lea & Flood, "Fast splittable pseudorandom number generators", OOPSLA
// 2014): the same sequence on every platform, unlike <random>'s distributions.
class SplitMix64 {
 public:
  explicit SplitMix64(std::uint64_t seed) : state_(seed) {}
  std::uint64_t next() {
    std::uint64_t z = (state_ += 0x9E3779B97F4A7C15ull);
    z = (z ^ (z >> 30)) * 0xBF58476D1CE4E5B9ull;
    z = (z ^ (z >> 27)) * 0x94D049BB133111EBull;
    return z ^ (z >> 31);
  }
  /// Uniform in [lo, hi) from the top 53 bits.
  double uniform(double lo, double hi) {
    return lo + (hi - lo) * static_cast<double>(next() >> 11) * 0x1.0p-53;
  }

 private:
  std::uint64_t state_;
};

struct Rect {
  double x0, x1, y0, y1;
};

// Horizontal rectangle at the pavement height, facing up.
void add_pavement(Mesh& m, const Rect& r, std::uint16_t mat) {
  const auto z = static_cast<float>(kPaveZ_m);
  const auto x0 = static_cast<float>(r.x0), x1 = static_cast<float>(r.x1);
  const auto y0 = static_cast<float>(r.y0), y1 = static_cast<float>(r.y1);
  add_quad(m, {x0, y0, z}, {x1, y0, z}, {x1, y1, z}, {x0, y1, z}, mat);
}

void add_box_d(Mesh& m, glm::dvec3 lo, glm::dvec3 hi, std::uint16_t mat) {
  add_box(m, glm::vec3(lo), glm::vec3(hi), mat);
}

// The painted markings of one runway end, in "distance from this end" coordinates (x across,
// d along the runway from the threshold); see airport_gen.hpp for the figures and their source.
void end_markings(std::vector<Rect>& out) {
  for (int k = 0; k < 6; ++k) {  // threshold stripes
    const double x0 = 1.8 + 3.6 * k;
    out.push_back({x0, x0 + 1.8, 6.0, 36.0});
    out.push_back({-x0 - 1.8, -x0, 6.0, 36.0});
  }
  out.push_back({9.0, 19.0, 400.0, 460.0});  // aiming point
  out.push_back({-19.0, -9.0, 400.0, 460.0});
  const std::array<std::pair<double, int>, 6> tdz{
      {{150.0, 3}, {300.0, 3}, {600.0, 2}, {750.0, 2}, {900.0, 1}, {1050.0, 1}}};
  for (const auto& [d, stripes] : tdz) {
    for (int k = 0; k < stripes; ++k) {
      const double x0 = 9.0 + 3.3 * k;
      out.push_back({x0, x0 + 1.8, d, d + 22.5});
      out.push_back({-x0 - 1.8, -x0, d, d + 22.5});
    }
  }
}

// Runway surface partitioned into asphalt and marking ("concrete") rectangles that tile
// [-w/2, w/2] x [0, length] exactly: strips between consecutive marking edges along y, each
// split across at the markings covering it.
Mesh runway_mesh() {
  const double half = L::kRunwayWidth_m / 2.0, len = L::kRunwayLength_m;
  std::vector<Rect> marks;
  std::vector<Rect> end;
  end_markings(end);
  for (const Rect& r : end) {
    marks.push_back(r);
    marks.push_back({r.x0, r.x1, len - r.y1, len - r.y0});  // the opposite end, mirrored
  }
  for (double y = 60.0; y + 30.0 <= len - 60.0 + 1e-9; y += 50.0)
    marks.push_back({-0.45, 0.45, y, y + 30.0});    // centreline dashes
  marks.push_back({-half, -half + 0.9, 0.0, len});  // side stripes
  marks.push_back({half - 0.9, half, 0.0, len});
  std::vector<double> ys{0.0, len};
  for (const Rect& r : marks) {
    ys.push_back(r.y0);
    ys.push_back(r.y1);
  }
  std::sort(ys.begin(), ys.end());
  ys.erase(std::unique(ys.begin(), ys.end()), ys.end());
  Mesh m;
  std::vector<Rect> across;
  for (std::size_t i = 0; i + 1 < ys.size(); ++i) {
    const double y0 = ys[i], y1 = ys[i + 1], mid = 0.5 * (y0 + y1);
    across.clear();
    for (const Rect& r : marks) {
      if (r.y0 < mid && mid < r.y1)
        across.push_back(r);
    }
    std::sort(across.begin(), across.end(),
              [](const Rect& a, const Rect& b) { return a.x0 < b.x0; });
    double x = -half;
    for (const Rect& r : across) {
      if (r.x0 > x)
        add_pavement(m, {x, r.x0, y0, y1}, kAsphalt);
      add_pavement(m, {r.x0, r.x1, y0, y1}, kConcrete);
      x = r.x1;
    }
    if (x < half)
      add_pavement(m, {x, half, y0, y1}, kAsphalt);
  }
  return m;
}

// Gabled building: walls [lo, hi] and a roof prism (eaves `eave` beyond the walls, ridge along
// y, `rise` above the wall tops).
void add_gabled(Mesh& m, glm::dvec3 lo, glm::dvec3 hi, double rise, double eave,
                std::uint16_t mat) {
  add_box_d(m, lo, hi, mat);
  const auto x0 = static_cast<float>(lo.x - eave), x1 = static_cast<float>(hi.x + eave);
  const auto xm = static_cast<float>(0.5 * (lo.x + hi.x));
  const auto y0 = static_cast<float>(lo.y - eave), y1 = static_cast<float>(hi.y + eave);
  const auto z0 = static_cast<float>(hi.z), z1 = static_cast<float>(hi.z + rise);
  add_quad(m, {x0, y0, z0}, {x0, y1, z0}, {x1, y1, z0}, {x1, y0, z0}, mat);  // soffit, -z
  add_quad(m, {x1, y0, z0}, {x1, y1, z0}, {xm, y1, z1}, {xm, y0, z1}, mat);  // east slope
  add_quad(m, {x0, y1, z0}, {x0, y0, z0}, {xm, y0, z1}, {xm, y1, z1}, mat);  // west slope
  const auto base = static_cast<unsigned>(m.positions_m.size());
  m.positions_m.insert(m.positions_m.end(), {{x0, y0, z0},
                                             {x1, y0, z0},
                                             {xm, y0, z1},  // south
                                             {x1, y1, z0},
                                             {x0, y1, z0},
                                             {xm, y1, z1}});  // north
  m.triangles.push_back({base, base + 1, base + 2});
  m.triangles.push_back({base + 3, base + 4, base + 5});
  m.triangle_material.insert(m.triangle_material.end(), {mat, mat});
}

// world_from_body: rotation by `heading` (counter-clockwise from east, about z) then
// translation.
glm::dmat4 placement(glm::dvec3 position_m, double heading_rad) {
  glm::dmat4 t = detail::translation(position_m);
  const double c = std::cos(heading_rad), s = std::sin(heading_rad);
  t[0] = glm::dvec4(c, s, 0.0, 0.0);
  t[1] = glm::dvec4(-s, c, 0.0, 0.0);
  return t;
}

ObjectDesc object(std::string name) {
  ObjectDesc o;
  o.name = std::move(name);
  o.area = "airport";
  return o;
}

// A target mesh with its material ("metal") remapped to the airport's.
Mesh target_mesh(TargetKind kind, double a, double b, double c) {
  Mesh m = make_target({kind, a, b, c, 0.0}).objects.at(0).mesh;
  m.triangle_material.assign(m.triangles.size(), kMetal);
  return m;
}

}  // namespace

SceneDescription generate_airport(const AirportSpec& spec) {
  if (spec.parked_transports < 0 || spec.parked_transports > 6) {
    throw std::invalid_argument("airport: parked_transports must be in 0..6 (got " +
                                std::to_string(spec.parked_transports) + ")");
  }
  SplitMix64 rng(spec.seed);
  SceneDescription d;
  d.materials = {{"grass", {0.25f, 0.45f, 0.15f}},
                 {"asphalt", {0.2f, 0.2f, 0.22f}},
                 {"concrete", {0.72f, 0.72f, 0.7f}},
                 {"metal", {0.75f, 0.75f, 0.8f}}};
  d.anchor = {common::radians(L::kAnchorLatitude_deg), common::radians(L::kAnchorLongitude_deg),
              L::kAnchorHeight_m};

  ObjectDesc ground = object("ground");
  const auto gw = static_cast<float>(L::kGroundHalfWidth_m);
  const auto gs = static_cast<float>(L::kGroundSouth_m);
  const auto gn = static_cast<float>(L::kGroundNorth_m);
  add_quad(ground.mesh, {-gw, gs, 0}, {gw, gs, 0}, {gw, gn, 0}, {-gw, gn, 0}, kGrass);
  d.objects.push_back(std::move(ground));

  ObjectDesc runway = object("runway");
  runway.mesh = runway_mesh();
  d.objects.push_back(std::move(runway));

  // Taxiways (23 m wide) and aprons: rectangles that touch but never overlap each other or the
  // runway (x [-22.5, 22.5]).
  ObjectDesc taxiways = object("taxiways");
  for (const Rect& r : {Rect{-131.5, -108.5, 0.0, 3000.0},  // parallel taxiway (moving vehicle)
                        Rect{-108.5, -22.5, 0.0, 23.0}, Rect{-108.5, -22.5, 1000.0, 1023.0},
                        Rect{-108.5, -22.5, 1900.0, 1923.0}, Rect{-108.5, -22.5, 2977.0, 3000.0},
                        Rect{22.5, 150.0, 1188.5, 1211.5},  // to the main apron
                        Rect{22.5, 85.0, 688.5, 711.5}}) {  // to the remote stand
    add_pavement(taxiways.mesh, r, kAsphalt);
  }
  d.objects.push_back(std::move(taxiways));
  ObjectDesc aprons = object("aprons");
  for (const Rect& r : {Rect{150.0, 470.0, 950.0, 1450.0},        // main apron
                        Rect{85.0, 135.0, 670.0, 730.0},          // remote stand (parked_aircraft)
                        Rect{-270.0, -131.5, 1450.0, 1800.0},     // hangar apron
                        Rect{-215.0, -185.0, 1285.0, 1315.0}}) {  // helipad
    add_pavement(aprons.mesh, r, kConcrete);
  }
  d.objects.push_back(std::move(aprons));

  if (spec.approach_lights) {
    // Category I approach lights (ICAO Annex 14 Vol. I, 5.3.4): barrettes every 30 m on the
    // extended centreline to 900 m, the 30 m crossbar at 300 m. One object per light station
    // ("approach_light_030" .. "_900"): the SBR tracer gives each metallic object a ray bundle
    // over its angular extent, and one object spanning 900 m along the line of sight would be
    // a bundle of mostly empty rays.
    constexpr double kMastTop_m = 1.8, kBarTop_m = 2.1, kHalf_m = 0.15;
    for (int k = 1; k <= 30; ++k) {
      char name[32];
      std::snprintf(name, sizeof name, "approach_light_%03d", 30 * k);
      ObjectDesc station = object(name);
      auto mast = [&](double x, double y) {
        add_box_d(station.mesh, {x - kHalf_m, y - kHalf_m, 0.0},
                  {x + kHalf_m, y + kHalf_m, kMastTop_m}, kMetal);
      };
      const double y = -30.0 * k;
      mast(0.0, y);
      const double half_bar = k == 10 ? 15.0 : 2.0;  // the crossbar includes the barrette
      add_box_d(station.mesh, {-half_bar, y - kHalf_m, kMastTop_m},
                {half_bar, y + kHalf_m, kBarTop_m}, kMetal);
      if (k == 10) {
        for (double x : {-14.0, -7.0, 7.0, 14.0})
          mast(x, y);
      }
      d.objects.push_back(std::move(station));
    }
  }

  // Terminal east of the main apron, with a roof slab, and the control tower behind it.
  ObjectDesc terminal = object("terminal");
  add_box_d(terminal.mesh, {475.0, 980.0, 0.0}, {515.0, 1420.0, 14.0}, kConcrete);
  add_box_d(terminal.mesh, {474.0, 979.0, 14.0}, {516.0, 1421.0, 15.0}, kConcrete);
  add_box_d(terminal.mesh, {541.5, 1196.5, 0.0}, {548.5, 1203.5, 32.0}, kConcrete);
  add_box_d(terminal.mesh, {540.0, 1195.0, 32.0}, {550.0, 1205.0, 37.0}, kConcrete);
  add_box_d(terminal.mesh, {539.5, 1194.5, 37.0}, {550.5, 1205.5, 37.5}, kConcrete);
  d.objects.push_back(std::move(terminal));

  // Hangars west of the parallel taxiway, doors (east walls) on the hangar apron's edge.
  double y = 1460.0;
  for (int k = 1; k <= 3; ++k) {
    const double depth = rng.uniform(50.0, 70.0), width = rng.uniform(60.0, 75.0);
    const double wall = rng.uniform(14.0, 20.0), rise = rng.uniform(4.0, 6.0);
    ObjectDesc hangar = object("hangar_" + std::to_string(k));
    add_gabled(hangar.mesh, {-270.0 - depth, y, 0.0}, {-270.0, y + width, wall}, rise, 0.5,
               kConcrete);
    d.objects.push_back(std::move(hangar));
    y += width + 12.0;
  }

  // Transport aircraft at `parked_transports` of the six gates, nose east toward the terminal.
  std::vector<int> gates{0, 1, 2, 3, 4, 5};
  for (std::size_t i = 0; i + 1 < gates.size(); ++i) {  // Fisher-Yates shuffle
    const std::size_t j = i + static_cast<std::size_t>(rng.next() % (gates.size() - i));
    std::swap(gates[i], gates[j]);
  }
  gates.resize(static_cast<std::size_t>(spec.parked_transports));
  std::sort(gates.begin(), gates.end());
  constexpr double kLength_m = 37.57, kSpan_m = 35.8, kHeight_m = 11.76;  // A320
  for (std::size_t i = 0; i < gates.size(); ++i) {
    const int gate = gates[i];
    const glm::dvec3 at(475.0 - 7.0 - kLength_m / 2 + rng.uniform(-1.0, 1.0),
                        1010.0 + 80.0 * gate + rng.uniform(-1.0, 1.0), 0.0);
    ObjectDesc aircraft = object("transport_" + std::to_string(i + 1));
    aircraft.mesh = target_mesh(TargetKind::kTransportAircraft, kLength_m, kSpan_m, kHeight_m);
    aircraft.world_from_body = placement(at, common::radians(rng.uniform(-2.0, 2.0)));
    d.objects.push_back(std::move(aircraft));
  }
  if (spec.service_vehicles) {
    // Between gates (gate centres 80 m apart, wings 36 m): y 1050 + 80 k +- 10 m.
    ObjectDesc truck = object("service_truck");
    truck.mesh = target_mesh(TargetKind::kTruck, 8.0, 2.5, 3.4);
    truck.world_from_body =
        placement({rng.uniform(380.0, 440.0), 1130.0 + rng.uniform(-10.0, 10.0), 0.0},
                  rng.uniform(0.0, 2.0 * std::numbers::pi));
    d.objects.push_back(std::move(truck));
    ObjectDesc jeep = object("service_jeep");
    jeep.mesh = target_mesh(TargetKind::kJeep, 4.0, 1.8, 1.9);
    jeep.world_from_body =
        placement({rng.uniform(380.0, 440.0), 1290.0 + rng.uniform(-10.0, 10.0), 0.0},
                  rng.uniform(0.0, 2.0 * std::numbers::pi));
    d.objects.push_back(std::move(jeep));
  }
  if (spec.helicopter) {
    ObjectDesc heli = object("helicopter");
    heli.mesh = target_mesh(TargetKind::kHelicopter, 12.7, 14.6, 4.4);
    heli.world_from_body =
        placement({-200.0, 1300.0, 0.0}, rng.uniform(0.0, 2.0 * std::numbers::pi));
    d.objects.push_back(std::move(heli));
  }

  // The default scene's closed-loop objects, unchanged.
  detail::add_closed_loop_objects(d, kMetal, spec.corner_reflectors, "airport");
  return d;
}

}  // namespace radar_emu::scene
