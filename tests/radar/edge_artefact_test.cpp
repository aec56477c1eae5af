// The artefact hunt for edge diffraction (issue 30, item 2): plate, dihedral, both trihedrals,
// cylinder, sphere, cone and the vehicle swept densely in angle (0.1 deg steps near face
// normals and edge-on directions), both polarisations, edges on and off, against each target's
// physical maximum. Edges correct a result; they never create a lobe above what the target can
// return, and neighbouring angles never jump by more than the geometry explains.
//
//   maximum   the closed-form peak of physics.md where the target has one (plate 4 pi A^2 /
//             lambda^2, dihedral 8 pi a^2 b^2 / lambda^2, triangular trihedral 4 pi a^4 / (3
//             lambda^2) on its axis but 2 pi a^4 / lambda^2 at its largest (derived below),
//             square trihedral 12 pi a^4 / lambda^2, the cylinder's larger of
//             2 pi a L^2 / lambda and its end disc's 4 pi^3 a^4 / lambda^2, the sphere's Mie
//             value); for the cone and the vehicle the aperture bound 4 pi A^2 / lambda^2 with
//             A = sum over facets of area |n . d| (no return exceeds that of a flat plate as
//             large as everything the wave can meet, seen face on). Asserted: edges on never
//             above it by more than 1 dB (the margin).
//   jumps     S(theta) = sum_i a_i exp(j 2 k r_i . u(theta)): between neighbouring angles
//             |dS| <= |dtheta| (2 k r_max sum |a_i| + sum |a_i'|), with sum |a_i| <= k A /
//             sqrt(pi) (the aperture bound above, A at its largest over the step: at most the
//             larger end's plus the total facet area times the step) and sum |a_i'| <= 2 k
//             A_total / sqrt(pi) (each amplitude's own slope, a projected area or obliquity
//             factor; A_total every facet's area); r_max the bounding radius about the phase
//             reference. Asserted for edges on.
// The coarse version runs in CI (ctest); RADAR_EMU_EDGE_HUNT=full runs the dense one
// (scripts/edge-artefact-hunt.sh). Both print their worst cases. No random input.
#include <gtest/gtest.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdlib>
#include <iomanip>
#include <iostream>
#include <string>
#include <vector>

#include "radar/constants.hpp"
#include "radar/em/rcs.hpp"
#include "radar/reference/mie.hpp"
#include "scene/targets.hpp"

namespace radar_emu::radar {
namespace {

double deg(double d) {
  return d * kPi / 180.0;
}
double db(double x) {
  return 10.0 * std::log10(x);
}
bool full_hunt() {
  const char* v = std::getenv("RADAR_EMU_EDGE_HUNT");
  return v != nullptr && std::string(v) == "full";
}

// A closed right circular cone, apex up: base radius r at z = 0, apex at z = h, n segments.
scene::SceneDescription make_cone(double r, double h, int n) {
  scene::SceneDescription d;
  d.materials.push_back(scene::Material{});
  d.materials[0].name = "metal";
  scene::ObjectDesc o;
  o.name = "cone";
  scene::Mesh& m = o.mesh;
  m.positions_m.push_back({0.0f, 0.0f, static_cast<float>(h)});  // apex
  m.positions_m.push_back({0.0f, 0.0f, 0.0f});                   // base centre
  for (int i = 0; i < n; ++i) {
    const double a = 2.0 * kPi * i / n;
    m.positions_m.push_back(
        {static_cast<float>(r * std::cos(a)), static_cast<float>(r * std::sin(a)), 0.0f});
  }
  for (int i = 0; i < n; ++i) {
    const auto a = static_cast<unsigned>(2 + i), b = static_cast<unsigned>(2 + (i + 1) % n);
    m.triangles.push_back({a, b, 0u});  // side, outward (counter-clockwise from outside)
    m.triangles.push_back({b, a, 1u});  // base, facing -z
  }
  m.triangle_material.assign(m.triangles.size(), 0);
  d.objects.push_back(o);
  return d;
}

// One angle cut: phi fixed, theta over [lo, hi]; `special` angles (face normals, edge-on
// directions, in theta) are swept at `fine` within `halo` of them, elsewhere at `coarse`.
struct Cut {
  double phi_deg, lo_deg, hi_deg;
  std::vector<double> special_deg;
};

std::vector<double> thetas(const Cut& c, double fine, double halo, double coarse) {
  std::vector<double> t;
  for (double x = c.lo_deg + 0.5 * fine; x <= c.hi_deg + 1e-9; x += coarse)
    t.push_back(x);
  // The fine grid is offset by half a step from each special angle: exactly grazing incidence
  // on a sheet is a point where the double diffraction's uniform coefficient takes the mean of
  // its one-sided limits (edges.hpp); the sweep comes within fine / 2 of it from both sides.
  for (double s : c.special_deg) {
    for (double x = s - halo + 0.5 * fine; x <= s + halo + 1e-9; x += fine) {
      if (x >= c.lo_deg - 1e-9 && x <= c.hi_deg + 1e-9)
        t.push_back(x);
    }
  }
  std::sort(t.begin(), t.end());
  t.erase(
      std::unique(t.begin(), t.end(), [](double a, double b) { return std::abs(a - b) < 1e-6; }),
      t.end());
  return t;
}

struct Case {
  std::string name;
  scene::SceneDescription desc;
  double freq_hz;
  int bounces;
  double rays_per_wavelength;
  double max_m2;  // physical maximum; <= 0: the aperture bound
  std::vector<Cut> cuts;
  bool in_coarse;  // swept in the CI version
};

struct Worst {
  double over_max_db = -1e9;  // edges on above the maximum
  std::string over_where;
  double jump_ratio = 0.0;  // largest |dS| / bound
  std::string jump_where;
  double edges_minus_off_db = -1e9;  // largest on - off where off is within 20 dB of the maximum
  std::string gain_where;
};

double aperture_area_m2(const RcsEngine&, const scene::SceneDescription& d, const glm::dvec3& u) {
  double a = 0.0;
  for (const auto& o : d.objects) {
    const auto& m = o.mesh;
    for (const auto& t : m.triangles) {
      const glm::dvec3 p0(m.positions_m[t.x]), p1(m.positions_m[t.y]), p2(m.positions_m[t.z]);
      a += 0.5 * std::abs(glm::dot(glm::cross(p1 - p0, p2 - p0), u));
    }
  }
  return a;
}

Worst hunt(const Case& c, bool full) {
  const scene::Scene sc(c.desc);
  RcsConfig on;
  on.max_bounces = c.bounces;
  on.rays_per_wavelength = c.rays_per_wavelength;
  on.edges = true;
  RcsConfig off = on;
  off.edges = false;
  const RcsEngine e_on(sc, {SurfaceModel{}}, on), e_off(sc, {SurfaceModel{}}, off);
  const double lambda = kSpeedOfLight_mps / c.freq_hz, k = 2.0 * kPi / lambda;
  const double r_max = e_on.bounding_radius_m() + glm::length(e_on.bounding_centre_m());
  const double f[1] = {c.freq_hz};
  double total_area = 0.0;  // every facet's area
  for (const auto& o : c.desc.objects) {
    const auto& m = o.mesh;
    for (const auto& t : m.triangles) {
      const glm::dvec3 p0(m.positions_m[t.x]), p1(m.positions_m[t.y]), p2(m.positions_m[t.z]);
      total_area += 0.5 * glm::length(glm::cross(p1 - p0, p2 - p0));
    }
  }
  Worst w;
  for (const Cut& cut : c.cuts) {
    const std::vector<double> th = full ? thetas(cut, 0.1, 5.0, 0.5) : thetas(cut, 0.2, 1.0, 4.0);
    std::array<std::complex<double>, 2> prev{};
    double prev_t = 0.0, prev_area = 0.0;
    for (std::size_t i = 0; i < th.size(); ++i) {
      const Direction dir{deg(th[i]), deg(cut.phi_deg)};
      ScatteringMatrix s_on, s_off;
      RcsStats st;
      e_on.compute(dir, dir, f, std::span<ScatteringMatrix>(&s_on, 1), st);
      e_off.compute(dir, dir, f, std::span<ScatteringMatrix>(&s_off, 1), st);
      const double area = aperture_area_m2(e_on, c.desc, unit_vector(dir));
      const double bound_m2 = 4.0 * kPi * area * area / (lambda * lambda);
      const double max_m2 = c.max_m2 > 0.0 ? c.max_m2 : bound_m2;
      const std::array<std::complex<double>, 2> now{s_on.hh, s_on.vv};
      const std::array<std::complex<double>, 2> was{s_off.hh, s_off.vv};
      for (std::size_t p = 0; p < 2; ++p) {
        const std::string where = c.name + " phi " + std::to_string(cut.phi_deg) + " theta " +
                                  std::to_string(th[i]) + (p == 0 ? " HH" : " VV");
        const double over = dbsm(now[p]) - db(max_m2);
        if (over > w.over_max_db) {
          w.over_max_db = over;
          w.over_where = where;
        }
        if (dbsm(was[p]) > db(max_m2) - 20.0 &&
            dbsm(now[p]) - dbsm(was[p]) > w.edges_minus_off_db) {
          w.edges_minus_off_db = dbsm(now[p]) - dbsm(was[p]);
          w.gain_where = where;
        }
        if (i > 0) {
          const double dt = deg(th[i] - prev_t);
          // Over the step the aperture grows by at most total_area dt.
          const double a_step = std::max(area, prev_area) + total_area * dt;
          const double bound =
              (2.0 * k * r_max * a_step + 2.0 * total_area) * dt * k / std::sqrt(kPi);
          const double ratio = std::abs(now[p] - prev[p]) / bound;
          if (ratio > w.jump_ratio) {
            w.jump_ratio = ratio;
            w.jump_where = where;
          }
        }
      }
      prev = now;
      prev_t = th[i];
      prev_area = area;
    }
  }
  return w;
}

std::vector<Case> cases(bool full) {
  const double f = 10e9, lambda = kSpeedOfLight_mps / f;
  auto target = [](scene::TargetKind k, double a, double b, double c, double facet) {
    return scene::make_target({k, a, b, c, facet});
  };
  std::vector<Case> v;
  // Plate 0.3 x 0.2 m in z = 0: normal theta 0, edge-on theta 90.
  v.push_back({"plate",
               target(scene::TargetKind::kPlate, 0.3, 0.2, 1.0, 0.0),
               f,
               1,
               4.0,
               4.0 * kPi * std::pow(0.3 * 0.2, 2) / (lambda * lambda),
               {{0.0, 0.0, 90.0, {0.0, 90.0}}, {90.0, 0.0, 90.0, {0.0, 90.0}}},
               true});
  // Dihedral: fold along y (0.3 m), faces 0.2 m at +-45 deg from +z (normals at theta 45 in
  // phi 0 and 180, edge-on at theta 45 the other way).
  v.push_back({"dihedral",
               target(scene::TargetKind::kDihedral, 0.3, 0.2, 1.0, 0.0),
               f,
               2,
               4.0,
               8.0 * kPi * std::pow(0.3 * 0.2, 2) / (lambda * lambda),
               {{0.0, 0.0, 90.0, {0.0, 45.0, 90.0}}, {90.0, 0.0, 90.0, {0.0, 90.0}}},
               true});
  // Trihedrals in the positive octant: face normals x, y, z; phi 45 is the README's cut. The
  // triangular one returns more than on its axis in the planes of its faces: at phi 0, theta
  // 45 the faces x = 0 and z = 0 form a right dihedral whose slice at height y has two faces of
  // width a - y, all of whose rays return after two bounces (geometrical optics), so its
  // aperture is the integral of sqrt(2) (a - y) dy = a^2 / sqrt(2) against a^2 / sqrt(3) on the
  // axis: sigma = 4 pi (a^2 / sqrt(2))^2 / lambda^2 = 2 pi a^4 / lambda^2 (+1.76 dB).
  const double a3 = 0.3;
  v.push_back({"trihedral-tri",
               target(scene::TargetKind::kTrihedralTriangular, a3, 1.0, 1.0, 0.0),
               f,
               3,
               4.0,
               2.0 * kPi * std::pow(a3, 4) / (lambda * lambda),
               {{45.0, 0.0, 90.0, {0.0, 54.7356, 90.0}}, {0.0, 0.0, 90.0, {0.0, 90.0}}},
               true});
  v.push_back({"trihedral-square",
               target(scene::TargetKind::kTrihedralSquare, a3, 1.0, 1.0, 0.0),
               f,
               3,
               4.0,
               12.0 * kPi * std::pow(a3, 4) / (lambda * lambda),
               {{45.0, 0.0, 90.0, {0.0, 54.7356, 90.0}}, {0.0, 0.0, 90.0, {0.0, 90.0}}},
               true});
  // Cylinder radius 0.1 m, length 0.3 m along z (ka 21), facets lambda / 8: caps at theta 0 and
  // 180, broadside at 90.
  v.push_back({"cylinder",
               target(scene::TargetKind::kCylinder, 0.1, 0.3, 1.0, lambda / (full ? 8.0 : 4.0)),
               f,
               1,
               4.0,
               std::max(2.0 * kPi * 0.1 * 0.09 / lambda,
                        4.0 * std::pow(kPi, 3) * std::pow(0.1, 4) / (lambda * lambda)),
               {{0.0, 0.0, 180.0, {0.0, 90.0, 180.0}}},
               true});
  // Sphere radius 0.1 m (ka 21), facets lambda / 6: Mie + 1 dB is the bound (asserted + 1 dB).
  v.push_back({"sphere",
               target(scene::TargetKind::kSphere, 0.1, 1.0, 1.0, lambda / 6.0),
               f,
               1,
               4.0,
               mie_sphere_rcs_m2(0.1, 2.0 * kPi / lambda),
               {{0.0, 0.0, 180.0, {0.0, 90.0, 180.0}}},
               true});
  // Cone: base radius 0.1 m, height 0.3 m, 128 segments; base normal theta 180, a generator's
  // normal at theta 90 - atan(0.1 / 0.3) = 71.57, edge-on to a generator at 180 - 71.57 =
  // 108.43 (the generator seen along its length from below: theta 161.57 is the apex angle).
  v.push_back({"cone",
               make_cone(0.1, 0.3, 128),
               f,
               2,
               4.0,
               0.0,
               {{0.0, 0.0, 180.0, {0.0, 71.57, 90.0, 161.57, 180.0}}},
               true});
  // The vehicle (25k facets) at 3 GHz, 2 bounces, 1 ray per wavelength: elevation cut at the
  // bow (phi 0) through the glacis and the deck, and an azimuth-ish cut at theta 80.
  const scene::SceneDescription veh =
      scene::make_target({scene::TargetKind::kVehicle, 7.0, 3.5, 2.5, 0.0});
  v.push_back({"vehicle", veh, 3e9, 2, 1.0, 0.0,
               full
                   ? std::vector<Cut>{{0.0, 0.0, 90.0, {0.0, 90.0}}, {90.0, 0.0, 90.0, {0.0, 90.0}}}
                   : std::vector<Cut>{{90.0, 80.0, 90.0, {90.0}}},
               true});
  return v;
}

TEST(EdgeArtefacts, EdgesNeverCreateALobeOrAJump) {
  const bool full = full_hunt();
  std::cout << "edge artefact hunt (" << (full ? "full" : "coarse")
            << "; RADAR_EMU_EDGE_HUNT=full for the dense one)\n";
  double worst_over = -1e9, worst_jump = 0.0;
  std::string worst_over_where, worst_jump_where;
  for (const Case& c : cases(full)) {
    const auto t0 = std::chrono::steady_clock::now();
    const Worst w = hunt(c, full);
    const double secs =
        std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
    std::cout << std::fixed << std::setprecision(2) << std::setw(17) << c.name
              << ": edges on vs maximum " << w.over_max_db << " dB (" << w.over_where
              << "), largest jump " << w.jump_ratio << " of its bound (" << w.jump_where
              << "), edges on - off near the peak up to " << w.edges_minus_off_db << " dB ("
              << w.gain_where << "); " << secs << " s\n";
    EXPECT_LE(w.over_max_db, 1.0) << w.over_where;
    EXPECT_LE(w.jump_ratio, 1.0) << w.jump_where;
    if (w.over_max_db > worst_over) {
      worst_over = w.over_max_db;
      worst_over_where = w.over_where;
    }
    if (w.jump_ratio > worst_jump) {
      worst_jump = w.jump_ratio;
      worst_jump_where = w.jump_where;
    }
  }
  std::cout << "worst case: " << worst_over << " dB over the maximum at " << worst_over_where
            << "; largest jump " << worst_jump << " of its bound at " << worst_jump_where << "\n";
}

}  // namespace
}  // namespace radar_emu::radar

namespace radar_emu::radar {
namespace {

// Issue 30, acceptance: tessellated PEC cylinders and spheres, several tessellations, ka 10 to
// 40, edges on: within 0.2 dB of the closed form (cylinder broadside 2 pi a L^2 / lambda,
// physics.md) or of the faceted PO's own closed form and Mie (sphere), and no wedge on their
// smooth parts (wedge_weight 0 for every joint of the side, the caps and the sphere).
TEST(EdgeArtefacts, SmoothSurfacesHaveNoWedgeAndKeepTheirClosedForms) {
  const double f = 10e9, lambda = kSpeedOfLight_mps / f, k = 2.0 * kPi / lambda;
  RcsConfig config;
  config.max_bounces = 1;
  config.edges = true;
  double worst_cyl = 0.0, worst_sph = 0.0;
  for (double ka : {10.0, 21.0, 40.0}) {
    const double a = ka / k;
    for (double per_lambda : {4.0, 8.0, 16.0}) {
      if (!full_hunt() && per_lambda > 8.0)
        continue;  // the lambda / 16 meshes (up to 63 k facets) in the full hunt only
      // Cylinder of length 20 lambda, broadside; facets lambda / per_lambda. Its rims are real
      // right-angle wedges: their end diffraction, which the closed form leaves out, is about
      // 2 % of the amplitude at 6 lambda (VV +0.34 dB at ka 40) and falls as 1 / L.
      const double len = 20.0 * lambda;
      const scene::Scene sc(
          scene::make_target({scene::TargetKind::kCylinder, a, len, 1.0, lambda / per_lambda}));
      const RcsEngine e(sc, {SurfaceModel{}}, config);
      std::size_t smooth_wedges = 0, rims = 0;
      for (const WedgeEdge& w : e.edges()) {
        const bool rim =
            std::abs(std::abs(w.a_m.z) - 0.5 * len) < 1e-6 && std::abs(w.a_m.z - w.b_m.z) < 1e-6;
        rims += rim ? 1u : 0u;
        if (!rim && wedge_weight(w, lambda, config.edge_min_turn_rad) > 0.0)
          ++smooth_wedges;
      }
      ScatteringMatrix s;
      RcsStats st;
      const double fr[1] = {f};
      e.compute({kPi / 2, 0.3}, {kPi / 2, 0.3}, fr, std::span<ScatteringMatrix>(&s, 1), st);
      const double expected = db(2.0 * kPi * a * len * len / lambda);
      const double err = std::max(std::abs(dbsm(s.hh) - expected), std::abs(dbsm(s.vv) - expected));
      std::cout << "cylinder ka " << ka << ", facets lambda/" << per_lambda << ": "
                << e.edges().size() << " candidate joints, " << rims << " rim wedges, "
                << smooth_wedges << " wedges on the smooth parts; HH " << dbsm(s.hh) - expected
                << " dB, VV " << dbsm(s.vv) - expected << " dB off 2 pi a L^2 / lambda\n";
      EXPECT_EQ(smooth_wedges, 0u);
      EXPECT_LT(err, 0.2) << "cylinder ka " << ka << " lambda/" << per_lambda;
      worst_cyl = std::max(worst_cyl, err);
    }
    for (double per_lambda : {6.0, 8.0}) {
      if ((ka > 30.0 || !full_hunt()) && per_lambda > 6.0)
        continue;  // lambda / 8 in the full hunt (ka 40: 160 k facets, lambda / 6 only)
      const double facet_m = std::min(lambda / per_lambda, 2.0 * kPi * a / 96.0);
      const scene::Scene sc(scene::make_target({scene::TargetKind::kSphere, a, 1.0, 1.0, facet_m}));
      const RcsEngine e(sc, {SurfaceModel{}}, config);
      std::size_t wedges = 0;
      for (const WedgeEdge& w : e.edges())
        wedges += wedge_weight(w, lambda, config.edge_min_turn_rad) > 0.0 ? 1u : 0u;
      ScatteringMatrix s;
      RcsStats st;
      const double fr[1] = {f};
      e.compute({deg(37.0), deg(11.0)}, {deg(37.0), deg(11.0)}, fr,
                std::span<ScatteringMatrix>(&s, 1), st);
      const double po = db(po_sphere_rcs_m2(a, k)), mie = db(mie_sphere_rcs_m2(a, k));
      const double err = std::max(std::abs(dbsm(s.hh) - po), std::abs(dbsm(s.vv) - po));
      std::cout << "sphere ka " << ka << ", facets " << facet_m / lambda
                << " lambda: " << e.edges().size() << " candidate joints, " << wedges << " wedges, "
                << st.edges_used << " edge terms; HH " << dbsm(s.hh) - po
                << " dB off PO's closed form, " << dbsm(s.hh) - mie << " dB off Mie\n";
      EXPECT_EQ(wedges, 0u);
      EXPECT_EQ(st.edges_used, 0u);
      EXPECT_LT(err, 0.2) << "sphere ka " << ka;
      // PO against Mie: +-0.6 dB at ka 10-20, +-0.2 dB at 20-50 (physics.md; ka 21 still
      // ripples by 0.35 dB: the method's error, with or without edges).
      EXPECT_LT(std::abs(dbsm(s.hh) - mie), ka < 30.0 ? 0.6 : 0.25) << "sphere ka " << ka;
      worst_sph = std::max(worst_sph, err);
    }
  }
  std::cout << "worst: cylinder " << worst_cyl << " dB off its closed form, sphere " << worst_sph
            << " dB off PO's closed form (edges on)\n";
}

}  // namespace
}  // namespace radar_emu::radar
