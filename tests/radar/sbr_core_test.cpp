// One scattering core for the frame tracer and the RCS engine (radar/em/sbr_core.hpp):
//   - the closed loop's tracer (spherical waves from the antenna) against the offline RCS engine
//     (plane waves) for the same target, aspect and polarisation, in the far field: a plate, a
//     dihedral and the 25k-facet vehicle;
//   - a PEC plate standing on an asphalt plane: the target-ground double bounce at the range the
//     image method gives, with the amplitude of a dihedral one face of which reflects with the
//     Fresnel coefficient of asphalt (Knott, Shaeffer & Tuley, Radar Cross Section, 2nd ed., 2004,
//     ch. 5 / physics.md: right dihedral sigma = 8 pi a^2 b^2 / lambda^2);
//   - the law of reflection and the Fresnel magnitudes at every bounce off a dielectric, against
//     the closed forms of Balanis, Advanced Engineering Electromagnetics, 2nd ed., 2012, sec. 5.3;
//   - the governor's per-frame knobs and plan().

#include <gtest/gtest.h>
#include <tbb/global_control.h>

#include <algorithm>
#include <cmath>
#include <complex>
#include <functional>
#include <glm/gtc/matrix_transform.hpp>
#include <iostream>
#include <limits>
#include <mutex>
#include <numbers>
#include <random>
#include <vector>

#include "common/polarisation.hpp"
#include "radar/clutter/terrain.hpp"
#include "radar/em/rcs.hpp"
#include "radar/em/sbr.hpp"
#include "radar/em/surfaces.hpp"
#include "scene/mesh/topology.hpp"
#include "scene/mesh_check.hpp"
#include "scene/scene.hpp"
#include "scene/targets.hpp"

namespace sc = radar_emu::scene;
namespace rd = radar_emu::radar;

namespace {
constexpr double kC = 299792458.0;
constexpr double kPi = std::numbers::pi;
constexpr double kF = 10e9;

double db(double x) {
  return 10.0 * std::log10(x);
}

// Radar at `range` in direction `dir` from the origin, looking at it; antenna "up" = +z (or +y
// when looking vertically).
rd::RadarPose looking_at_origin_from(glm::dvec3 dir, double range) {
  dir = glm::normalize(dir);
  rd::RadarPose p;
  p.position_m = dir * range;
  const glm::dvec3 x = -dir;
  const glm::dvec3 up = std::abs(x.z) > 0.99 ? glm::dvec3(0, 1, 0) : glm::dvec3(0, 0, 1);
  const glm::dvec3 y = glm::normalize(glm::cross(x, up));
  p.world_from_antenna = glm::dmat3(x, y, glm::cross(x, y));
  return p;
}

// The RCS engine's direction of the same radar.
rd::Direction rcs_direction(glm::dvec3 dir) {
  dir = glm::normalize(dir);
  return {std::acos(dir.z), std::atan2(dir.y, dir.x)};
}

// The RCS engine's scattering matrix (basis V = theta-hat, H = phi-hat of `dir`) in the tracer's
// channel `pol` (SbrConfig::polarisation: V = the antenna's up projected perpendicular to the
// ray d = -dir, H = V x d): S_pq = sum_ij (p . e_i) (q . e_j) S_ij, receive p, transmit q.
std::complex<double> in_tracer_channel(const rd::ScatteringMatrix& s, const rd::RadarPose& pose,
                                       glm::dvec3 dir, rd::Polarisation pol) {
  dir = glm::normalize(dir);
  const glm::dvec3 d = -dir, up = -pose.world_from_antenna[2];
  const glm::dvec3 v = glm::normalize(up - glm::dot(up, d) * d);
  const glm::dvec3 h = glm::normalize(glm::cross(v, d));
  const rd::Direction rd_dir = rcs_direction(dir);
  const glm::dvec3 th = rd::theta_hat(rd_dir), ph = rd::phi_hat(rd_dir);
  const bool rx_h = pol == rd::Polarisation::kHH || pol == rd::Polarisation::kHV;
  const bool tx_h = pol == rd::Polarisation::kHH || pol == rd::Polarisation::kVH;
  const glm::dvec3 p = rx_h ? h : v, q = tx_h ? h : v;
  const double pv = glm::dot(p, th), pw = glm::dot(p, ph), qv = glm::dot(q, th),
               qw = glm::dot(q, ph);
  return pv * qv * s.vv + pv * qw * s.vh + pw * qv * s.hv + pw * qw * s.hh;
}

rd::SbrConfig narrow(double half_fov_rad, double spacing_m, rd::Polarisation pol) {
  rd::SbrConfig c;
  c.carrier_hz = kF;
  c.azimuth_min_rad = -half_fov_rad;
  c.azimuth_max_rad = half_fov_rad;
  c.elevation_min_rad = -half_fov_rad;
  c.elevation_max_rad = half_fov_rad;
  c.terrain_ray_spacing_rad = half_fov_rad;  // 2 x 2 terrain rays
  c.target_ray_spacing_m = spacing_m;
  c.max_rays_per_target = 4'000'000;
  c.max_range_m = 1e5;  // raised: the default would do, but nothing should end early
  c.max_bounces = 3;
  c.polarisation = pol;
  return c;
}

std::vector<rd::Contribution> trace(rd::SbrTracer& t, const rd::RadarPose& pose,
                                    const rd::TraceKnobs& knobs = {},
                                    rd::TraceStats* stats = nullptr) {
  std::vector<rd::Contribution> out(t.max_contributions());
  rd::TraceStats st;
  out.resize(t.trace(pose, out, stats != nullptr ? *stats : st, knobs));
  return out;
}

// Coherent sum of the returns referred to the target origin: the tracer's amplitude has no
// range term (the sensor applies 1/R^2), only the path phase exp(-j k L); multiplying by
// exp(+j k 2R), R = |radar - origin|, refers it to the origin as the RCS engine does.
std::complex<double> referred_sum(const std::vector<rd::Contribution>& out, double range_m,
                                  int bounces = 0) {
  const double k = 2 * kPi * kF / kC;
  std::complex<double> s{0, 0};
  for (const rd::Contribution& c : out) {
    if (c.coherent && (bounces == 0 || c.bounces == bounces))
      s += c.amplitude;
  }
  return s * std::polar(1.0, 2.0 * k * range_m);
}

// Balanis 2012, sec. 5.3 (eqs. 5-24 and 5-33 written for non-magnetic media, eps = eps_2/eps_1):
// Gamma_perp = (cos t - sqrt(eps - sin^2 t)) / (cos t + sqrt(eps - sin^2 t)),
// Gamma_par = (eps cos t - sqrt(eps - sin^2 t)) / (eps cos t + sqrt(eps - sin^2 t)) in the sign
// convention of E_r along e_par_r = e_perp x d_r (at normal incidence Gamma_par = Gamma_perp
// up to the basis flip); only magnitudes are compared.
double fresnel_perp(std::complex<double> eps, double theta) {
  const double c = std::cos(theta), s2 = std::sin(theta) * std::sin(theta);
  const std::complex<double> r = std::sqrt(eps - s2);
  return std::abs((c - r) / (c + r));
}
double fresnel_par(std::complex<double> eps, double theta) {
  const double c = std::cos(theta), s2 = std::sin(theta) * std::sin(theta);
  const std::complex<double> r = std::sqrt(eps - s2);
  return std::abs((eps * c - r) / (eps * c + r));
}

using radar_emu::common::polarisation_name;
}  // namespace

TEST(SbrLoopVsRcs, PlateAndDihedralMatchTheRcsEngine) {
  // Far field: D <= 0.36 m, 2 D^2 / lambda = 8.6 m << R = 200 m; the residual two-way phase
  // curvature k r^2 / R over the target is < 0.04 rad (amplitude effect < 1e-3 dB). The tracer's
  // bundle spacing is 2 mm at 200 m (lambda / 15), the RCS engine's 10 tubes per wavelength.
  const double range = 200.0;
  struct Case {
    sc::TargetSpec spec;
    glm::dvec3 dir;
    double roll_rad;  // target turned about z (the line of sight of the first cases)
  };
  const Case cases[] = {
      {{sc::TargetKind::kPlate, 0.25, 0.2, 1.0, 0.0}, {0, 0, 1}, 0.0},
      {{sc::TargetKind::kPlate, 0.25, 0.2, 1.0, 0.0}, {0.02, 0.01, 1}, 0.0},
      {{sc::TargetKind::kDihedral, 0.3, 0.2, 1.0, 0.0}, {0, 0, 1}, 0.0},
      {{sc::TargetKind::kDihedral, 0.3, 0.2, 1.0, 0.0}, {0.15, 0.01, 1}, 0.0},
      // Rolled 30 deg: all four channels are strong (HV = VH by reciprocity).
      {{sc::TargetKind::kDihedral, 0.3, 0.2, 1.0, 0.0}, {0, 0, 1}, kPi / 6},
  };
  rd::RcsConfig rc;
  rc.max_bounces = 3;
  rc.rays_per_wavelength = 10.0;
  double worst_db = 0.0, worst_deg = 0.0;
  for (const Case& c : cases) {
    sc::SceneDescription desc = sc::make_target(c.spec);
    const double cr = std::cos(c.roll_rad), sr = std::sin(c.roll_rad);
    desc.objects[0].world_from_body[0] = glm::dvec4(cr, sr, 0, 0);
    desc.objects[0].world_from_body[1] = glm::dvec4(-sr, cr, 0, 0);
    sc::Scene scene(std::move(desc));
    const rd::RcsEngine engine(scene, {rd::SurfaceModel{}}, rc);
    const rd::Direction dir = rcs_direction(c.dir);
    rd::ScatteringMatrix s;
    rd::RcsStats rs;
    const double f[1] = {kF};
    engine.compute(dir, dir, f, std::span<rd::ScatteringMatrix>(&s, 1), rs);
    for (rd::Polarisation pol : {rd::Polarisation::kHH, rd::Polarisation::kVV,
                                 rd::Polarisation::kHV, rd::Polarisation::kVH}) {
      if (c.roll_rad == 0.0 && (pol == rd::Polarisation::kHV || pol == rd::Polarisation::kVH))
        continue;  // cross-polar nulls: compared on the rolled dihedral
      rd::SbrTracer tracer(scene, narrow(0.01, 0.0015, pol));
      const rd::RadarPose pose = looking_at_origin_from(c.dir, range);
      const std::complex<double> loop = referred_sum(trace(tracer, pose), range);
      const std::complex<double> ref = in_tracer_channel(s, pose, c.dir, pol);
      const double d_db = db(std::norm(loop)) - db(std::norm(ref));
      const double d_deg = std::arg(loop / ref) * 180.0 / kPi;
      std::cout << sc::target_name(c.spec.kind) << " " << polarisation_name(pol) << ": loop "
                << db(std::norm(loop)) << " dBsm, RCS engine " << db(std::norm(ref))
                << " dBsm, difference " << d_db << " dB, " << d_deg << " deg\n";
      worst_db = std::max(worst_db, std::abs(d_db));
      worst_deg = std::max(worst_deg, std::abs(d_deg));
      EXPECT_LT(std::abs(d_db), 0.05)
          << sc::target_name(c.spec.kind) << " " << polarisation_name(pol);
      // Same phase too (same reference point; the residual is the spherical-wave curvature).
      EXPECT_LT(std::abs(d_deg), 3.0)
          << sc::target_name(c.spec.kind) << " " << polarisation_name(pol);
    }
  }
  std::cout << "worst |loop - RCS|: " << worst_db << " dB, " << worst_deg << " deg\n";
}

TEST(SbrLoopVsRcs, EdgeDiffractionOfAPlateMatchesTheRcsEngine) {
  // The same plate away from normal incidence, where PO alone is its sinc sidelobes and the
  // edges' fringe currents (radar/em/edges.hpp) change the return by dB: with edges on in both
  // engines the loop's per-edge spherical-wave contributions must sum to the RCS engine's plane-
  // wave result (R = 200 m: the phase curvature over the 0.32 m plate is < 0.02 rad).
  const double range = 200.0;
  const sc::TargetSpec plate{sc::TargetKind::kPlate, 0.25, 0.2, 1.0, 0.0};
  const glm::dvec3 dirs[] = {{0.0, 0.0, 1.0},  {0.2, 0.0, 1.0}, {0.6, 0.0, 1.0},
                             {0.0, 0.45, 1.0}, {0.3, 0.3, 1.0}, {1.0, 0.05, 0.6}};
  rd::RcsConfig rc;
  rc.max_bounces = 3;
  rc.rays_per_wavelength = 10.0;
  rc.edges = true;
  double worst_db = 0.0, largest_edge_effect_db = 0.0;
  for (const glm::dvec3& dir_v : dirs) {
    sc::Scene scene(sc::make_target(plate));
    const rd::RcsEngine engine(scene, {rd::SurfaceModel{}}, rc);
    const rd::Direction dir = rcs_direction(dir_v);
    rd::ScatteringMatrix s;
    rd::RcsStats rs;
    const double f[1] = {kF};
    engine.compute(dir, dir, f, std::span<rd::ScatteringMatrix>(&s, 1), rs);
    for (rd::Polarisation pol : {rd::Polarisation::kHH, rd::Polarisation::kVV}) {
      rd::SbrConfig cfg = narrow(0.01, 0.0015, pol);
      cfg.edges = true;
      rd::SbrTracer with_edges(scene, cfg);
      cfg.edges = false;
      rd::SbrTracer without(scene, cfg);
      const rd::RadarPose pose = looking_at_origin_from(dir_v, range);
      rd::TraceStats st;
      const std::complex<double> loop = referred_sum(trace(with_edges, pose, {}, &st), range);
      const std::complex<double> po = referred_sum(trace(without, pose), range);
      const std::complex<double> ref = in_tracer_channel(s, pose, dir_v, pol);
      const double d_db = db(std::norm(loop)) - db(std::norm(ref));
      const double edge_db = db(std::norm(loop)) - db(std::norm(po));
      std::cout << "plate toward (" << dir_v.x << ", " << dir_v.y << ", " << dir_v.z << ") "
                << polarisation_name(pol) << ": loop " << db(std::norm(loop)) << " dBsm ("
                << st.edges_used << " edges; PO alone " << db(std::norm(po)) << "), RCS engine "
                << db(std::norm(ref)) << " dBsm, difference " << d_db << " dB\n";
      EXPECT_EQ(st.edges_used, rs.edges_used) << "the same edges radiate in both engines";
      EXPECT_LT(std::abs(d_db), 0.05) << polarisation_name(pol);
      worst_db = std::max(worst_db, std::abs(d_db));
      largest_edge_effect_db = std::max(largest_edge_effect_db, std::abs(edge_db));
    }
  }
  std::cout << "worst |loop - RCS| with edges: " << worst_db << " dB; largest edge effect "
            << largest_edge_effect_db << " dB\n";
  EXPECT_GT(largest_edge_effect_db, 3.0) << "the cases must be ones where edges matter";
}

TEST(SbrKnobs, CentroidOnlyLightingIsOneQueryAFacetAndExactOnAnOpenFacet) {
  // TraceKnobs::facet_centroid_only: a plate seen in the clear is lit whole either way, so the
  // return is the same (the exact facet integral), with one occlusion query per facet instead
  // of seven.
  sc::Scene scene(sc::make_target({sc::TargetKind::kPlate, 0.25, 0.2, 1.0, 0.0}));
  rd::SbrTracer tracer(scene, narrow(0.01, 0.0015, rd::Polarisation::kVV));
  const rd::RadarPose pose = looking_at_origin_from({0.1, 0.05, 1.0}, 200.0);
  rd::TraceStats seven, one;
  rd::TraceKnobs k;
  const std::complex<double> a = referred_sum(trace(tracer, pose, k, &seven), 200.0, 1);
  k.facet_centroid_only = true;
  const std::complex<double> b = referred_sum(trace(tracer, pose, k, &one), 200.0, 1);
  EXPECT_EQ(seven.lit_facets, 2u);
  EXPECT_EQ(one.lit_facets, 2u);
  EXPECT_EQ(seven.facet_queries, 14u);
  EXPECT_EQ(one.facet_queries, 2u);
  EXPECT_NEAR(std::abs(a - b), 0.0, 1e-12 * std::abs(a));
}

TEST(SbrLoopVsRcs, VehicleMatchesTheRcsEngineInTheFarField) {
  // The 25k-facet vehicle (7 x 3.5 x 2.5 m) alone in the loop at 10 GHz, broadside (radar on +y,
  // level): bounce 1 is the same lighting rule in both engines (sbr_core.hpp, FacetLight: exact
  // PO over wholly lit facets, over the lit sub-triangles of partly lit ones, resolved to the
  // ray spacing), bounces 2 and 3 their ray tubes: 1 cm (lambda / 3) in both.
  // The loop's spherical wave departs from the far field by the quadratic phase k r^2 / R over
  // the target (2 D^2 / lambda = 4.2 km here): 0.04 dB at 80 km, falling as 1 / R. Traced at
  // R and 2 R (40 and 80 km), S(R) = S_inf + c / R extrapolates to S_inf = 2 S(2R) - S(R)
  // (Richardson); a third range (160 km) checks the 1 / R law itself.
  const double th = kPi / 2, ph = kPi / 2;
  const glm::dvec3 dir(std::sin(th) * std::cos(ph), std::sin(th) * std::sin(ph), std::cos(th));
  sc::Scene scene(sc::make_target({sc::TargetKind::kVehicle, 7.0, 3.5, 2.5, 0.0}));
  rd::RcsConfig rc;
  rc.max_bounces = 3;
  rc.rays_per_wavelength = kC / kF / 0.01;  // 1 cm tubes, as the loop's bundle
  const rd::RcsEngine engine(scene, {rd::SurfaceModel{}}, rc);
  rd::ScatteringMatrix s;
  rd::RcsStats rs;
  const double f[1] = {kF};
  engine.compute(rcs_direction(dir), rcs_direction(dir), f, std::span<rd::ScatteringMatrix>(&s, 1),
                 rs);
  std::cout << "vehicle (" << engine.facet_count() << " facets), RCS engine: " << rs.facets_lit
            << " lit, " << rs.facets_partial << " partly lit facets, " << rs.paths
            << " multi-bounce footprints\n";
  EXPECT_GT(rs.facets_partial, 100u);  // the rule's partial branch is exercised
  for (rd::Polarisation pol : {rd::Polarisation::kHH, rd::Polarisation::kVV}) {
    rd::SbrConfig c = narrow(0.01, 0.01, pol);
    c.max_range_m = 4e5;
    c.max_rays_per_target = 400'000;
    rd::SbrTracer tracer(scene, c);
    const double ranges[3] = {40e3, 80e3, 160e3};
    std::complex<double> at[3];
    std::complex<double> ref;
    for (int i = 0; i < 3; ++i) {
      const rd::RadarPose pose = looking_at_origin_from(dir, ranges[i]);
      rd::TraceStats ts;
      at[i] = referred_sum(trace(tracer, pose, {}, &ts), ranges[i]);
      ref = in_tracer_channel(s, pose, dir, pol);
      std::cout << "  " << polarisation_name(pol) << " at " << ranges[i] / 1e3 << " km: loop "
                << db(std::norm(at[i])) << " dBsm (" << ts.lit_facets << " lit, "
                << ts.partial_facets << " partly lit facets, " << ts.rays << " rays), "
                << db(std::norm(at[i])) - db(std::norm(ref)) << " dB from the RCS engine\n";
    }
    const std::complex<double> far = 2.0 * at[1] - at[0];
    const double d_db = db(std::norm(far)) - db(std::norm(ref));
    const double d_deg = std::arg(far / ref) * 180.0 / kPi;
    std::cout << "vehicle " << polarisation_name(pol) << ": loop extrapolated to the far field "
              << db(std::norm(far)) << " dBsm, RCS engine " << db(std::norm(ref))
              << " dBsm, difference " << d_db << " dB, " << d_deg << " deg\n";
    EXPECT_LT(std::abs(d_db), 0.05) << polarisation_name(pol);
    EXPECT_LT(std::abs(d_deg), 1.0) << polarisation_name(pol);
    // The 1 / R law: at 4 R the loop sits halfway between S(2R) and S_inf.
    EXPECT_LT(std::abs(at[2] - 0.5 * (far + at[1])), 0.002 * std::abs(far))
        << polarisation_name(pol);
  }
}

// sin_cos (the returns' phase and footprint sincs) against libm's sin and cos: within 2.3e-16
// absolute over the tracer's phases (two-way paths to 12 km at 94 GHz: 2.4e7 rad) and beyond,
// at multiples of pi/2 and next to them (the quadrant boundaries), and libm itself for arguments
// past its reduction's range and for non-finite ones. Fixed seed 20261128.
TEST(SbrCore, SinCosMatchesLibm) {
  std::mt19937_64 rng(20261128);
  double worst = 0.0;
  auto check = [&](double x) {
    const rd::SinCos sc = rd::sin_cos(x);
    worst = std::max({worst, std::abs(sc.sin - std::sin(x)), std::abs(sc.cos - std::cos(x))});
  };
  for (const double limit : {1.0, 1e3, 1e6, 2.5e7, 1e9}) {
    std::uniform_real_distribution<double> u(-limit, limit);
    for (int i = 0; i < 200000; ++i)
      check(u(rng));
  }
  for (int n = -2000; n <= 2000; ++n) {
    const double x = n * (std::numbers::pi / 2.0);
    check(x);
    check(std::nextafter(x, 1e300));
    check(std::nextafter(x, -1e300));
    check(x * 1e4);
  }
  EXPECT_LE(worst, 2.3e-16);
  EXPECT_EQ(rd::sin_cos(0.0).sin, 0.0);
  EXPECT_EQ(rd::sin_cos(0.0).cos, 1.0);
  EXPECT_EQ(rd::sin_cos(1e12).sin, std::sin(1e12));  // beyond the reduction: libm
  EXPECT_TRUE(std::isnan(rd::sin_cos(std::numeric_limits<double>::quiet_NaN()).sin));
  EXPECT_TRUE(std::isnan(rd::sin_cos(std::numeric_limits<double>::infinity()).cos));
}

TEST(SbrCore, ClosedPartsAndTheirWinding) {
  // The closed parts both engines take (scene::closed_part_winding over the one topology):
  // every triangle of the box (its faces' vertices repeated per face, welded) is on a closed,
  // outward-wound part; the box wound the other way is inward; sheets (plate, dihedral) and a
  // box with one triangle missing are open.
  auto winding = [](const sc::SceneDescription& d) {
    return sc::closed_part_winding(
        sc::build_topology(d.objects[0].mesh.positions_m, d.objects[0].mesh.triangles));
  };
  auto count = [](const std::vector<std::int8_t>& w, int v) {
    return static_cast<std::size_t>(std::count(w.begin(), w.end(), static_cast<std::int8_t>(v)));
  };
  sc::SceneDescription box = sc::make_target({sc::TargetKind::kBox, 0.3, 0.2, 0.1, 0.05});
  const auto wb = winding(box);
  EXPECT_EQ(count(wb, 1), wb.size());
  sc::SceneDescription inverted = box;
  for (glm::uvec3& t : inverted.objects[0].mesh.triangles)
    std::swap(t.y, t.z);
  const auto wi = winding(inverted);
  EXPECT_EQ(count(wi, -1), wi.size());
  sc::SceneDescription holed = box;
  holed.objects[0].mesh.triangles.pop_back();
  const auto wh = winding(holed);
  EXPECT_EQ(count(wh, 0), wh.size());
  for (sc::TargetKind k : {sc::TargetKind::kPlate, sc::TargetKind::kDihedral}) {
    const auto w = winding(sc::make_target({k, 0.3, 0.2, 1.0, 0.0}));
    EXPECT_EQ(count(w, 0), w.size()) << sc::target_name(k);
  }
  // The vehicle: its parts are outward-wound, but some meet their caps at T-junctions (open
  // edges), so only part of it qualifies; none is found inward.
  const auto wv = winding(sc::make_target({sc::TargetKind::kVehicle, 7.0, 3.5, 2.5, 0.0}));
  std::cout << "vehicle: " << count(wv, 1) << " of " << wv.size()
            << " triangles on closed outward-wound parts\n";
  EXPECT_GT(count(wv, 1), wv.size() / 4);
  EXPECT_EQ(count(wv, -1), 0u);
}

TEST(SbrCore, ClosedPartsAgreeWithTheMeshCheckOnNearCoincidentVertices) {
  // The generated sphere's seam (phi = 2 pi lands about 1e-17 m off phi = 0) and south pole (one
  // point per longitude) are cracks far under float resolution. The mesh check welded them and
  // called the sphere closed; the tracer welded exact positions only and found all 960 triangles
  // on open parts, so the bounce-1 shortcut for closed parts never applied. One weld rule now:
  // closed for both.
  auto winding = [](const sc::Mesh& m) {
    return sc::closed_part_winding(sc::build_topology(m.positions_m, m.triangles));
  };
  auto count = [](const std::vector<std::int8_t>& w, int v) {
    return static_cast<std::size_t>(std::count(w.begin(), w.end(), static_cast<std::int8_t>(v)));
  };
  const sc::Mesh sphere =
      sc::make_target({sc::TargetKind::kSphere, 0.1, 1.0, 1.0, 0.0}).objects[0].mesh;
  EXPECT_TRUE(sc::check_mesh(sphere).closed());
  const auto ws = winding(sphere);
  EXPECT_EQ(count(ws, 1), ws.size());
  // A box with a corner at the origin reached twice, 1e-9 m apart (3e-9 of its extent): the
  // check called it closed, the tracer open. 1e-3 m apart: open for both.
  for (const double gap_m : {1e-9, 1e-3}) {
    sc::Mesh box = sc::make_target({sc::TargetKind::kBox, 0.3, 0.2, 0.1, 0.0}).objects[0].mesh;
    const glm::vec3 corner = box.positions_m[box.triangles[0].x];
    for (glm::vec3& p : box.positions_m)
      p -= corner;  // exact: each coordinate is corner's or its opposite's
    box.positions_m.push_back(glm::vec3(static_cast<float>(gap_m), 0.0f, 0.0f));
    box.triangles[0].x = static_cast<unsigned>(box.positions_m.size() - 1);
    const bool welded = gap_m < 1e-6;
    EXPECT_EQ(sc::check_mesh(box).closed(), welded) << gap_m;
    const auto wb = winding(box);
    EXPECT_EQ(count(wb, welded ? 1 : 0), wb.size()) << gap_m;
  }
}

namespace {
// A PEC plate of width a (y) and height b (z) standing at x = 0 on an asphalt square at z = 0,
// facing -x, and a radar at grazing angle psi on the -x side.
sc::SceneDescription plate_on_asphalt(double a, double b, double ground_half_m) {
  sc::SceneDescription d;
  d.materials = {{"metal", {}}, {"asphalt", {}}};
  sc::ObjectDesc plate{"plate", {}, glm::dmat4(1.0), std::nullopt};
  const auto ha = static_cast<float>(a / 2), fb = static_cast<float>(b);
  plate.mesh.positions_m = {{0, -ha, 0}, {0, ha, 0}, {0, ha, fb}, {0, -ha, fb}};
  plate.mesh.triangles = {{0, 1, 2}, {0, 2, 3}};
  plate.mesh.triangle_material = {0, 0};
  sc::ObjectDesc ground{"ground", {}, glm::dmat4(1.0), std::nullopt};
  const auto g = static_cast<float>(ground_half_m);
  ground.mesh.positions_m = {{-g, -g, 0}, {g, -g, 0}, {g, g, 0}, {-g, g, 0}};
  ground.mesh.triangles = {{0, 1, 2}, {0, 2, 3}};
  ground.mesh.triangle_material = {1, 1};
  d.objects = {plate, ground};
  return d;
}
}  // namespace

TEST(SbrGround, PlateOnAsphaltDoubleBounceIsTheDielectricDihedral) {
  // Radar at 45 deg grazing: the plate (a x b) and the ground in front of it form a right
  // dihedral whose ground face reflects with Fresnel's coefficient at 45 deg incidence. Both
  // orders (plate -> ground, ground -> plate) retro-reflect over the plate's projected area
  // a b cos 45 each and arrive in phase (image method), so sigma = 4 pi (2 a b cos 45)^2 |R|^2 /
  // lambda^2 = 8 pi a^2 b^2 |R|^2 / lambda^2: Knott's right dihedral times |R|^2 of the one
  // dielectric face; H is perpendicular to the plane of incidence (R_perp), V parallel (R_par).
  // Tolerance 0.15 dB: the closed form is geometrical optics over the aperture, the traced value
  // adds the PO edge terms of the finite plate's footprints (the PEC dihedral in sbr_test.cpp is
  // within 0.01 dB of it) and the spherical-wave curvature at R = 200 m (< 0.04 rad).
  const double a = 0.3, b = 0.2, range = 200.0, lambda = kC / kF, psi = kPi / 4;
  sc::Scene scene(plate_on_asphalt(a, b, 30.0));
  const glm::dvec3 dir(-std::cos(psi), 0.0, std::sin(psi));
  const rd::RadarPose pose = looking_at_origin_from(dir, range);
  const std::complex<double> eps =
      radar_emu::radar::clutter::permittivity(*rd::clutter::find_terrain_material("asphalt"), kF);
  // Image method: the path via a ground point equals the distance from the radar's image below
  // the ground to the plate point; for the plate's base centre (origin) half the path is
  // (|radar - O| + |image - O|) / 2 = R; points up to 0.36 m away shift it by < r^2 / R.
  const glm::dvec3 image(pose.position_m.x, pose.position_m.y, -pose.position_m.z);
  const double image_range = 0.5 * (glm::length(pose.position_m) + glm::length(image));
  for (rd::Polarisation pol : {rd::Polarisation::kHH, rd::Polarisation::kVV}) {
    rd::SbrTracer tracer(scene, narrow(0.01, 0.002, pol));
    rd::TraceStats stats;
    const auto out = trace(tracer, pose, {}, &stats);
    std::size_t doubles = 0, ground_last = 0;
    for (const rd::Contribution& c : out) {
      if (!c.coherent || c.bounces != 2)
        continue;
      ++doubles;
      EXPECT_EQ(c.object_id, 0u);  // the plate owns both orders (radar/em/sbr.hpp)
      ground_last += c.radiated_by_owner ? 0 : 1;
      EXPECT_NEAR(c.range_m, image_range, 1e-3);
    }
    EXPECT_GT(doubles, 1000u);
    // Both orders are present: radar -> plate -> ground (radiating from the ground) and
    // radar -> ground -> plate, about half each.
    EXPECT_GT(ground_last, doubles / 4);
    EXPECT_LT(ground_last, 3 * doubles / 4);
    EXPECT_GT(stats.dielectric_reflections, 1000u);
    const double r = pol == rd::Polarisation::kHH ? fresnel_perp(eps, psi) : fresnel_par(eps, psi);
    const double expected = 8 * kPi * a * a * b * b * r * r / (lambda * lambda);
    const double got = std::norm(referred_sum(out, range, 2));
    std::cout << "plate on asphalt (eps " << eps << ") " << polarisation_name(pol)
              << ": double bounce " << db(got) << " dBsm, dielectric dihedral " << db(expected)
              << " dBsm (|R| " << r << "), difference " << db(got) - db(expected) << " dB\n";
    EXPECT_NEAR(db(got), db(expected), 0.15) << polarisation_name(pol);
  }
}

TEST(SbrGround, LawOfReflectionAndFresnelMagnitudeAtEveryDielectricBounce) {
  // The shared core's GO step, seen through the RCS engine's bounce hook, on the plate-on-asphalt
  // scene from several grazing angles in the x-z plane: that plane is the plane of incidence at
  // every bounce (ground normal z, plate normal x), so the V-transmit field stays parallel to it
  // and the H-transmit field perpendicular, and at each bounce off the asphalt
  // |E_after| / |E_before| = |Gamma_par| (V) and |Gamma_perp| (H) of Balanis sec. 5.3 at that
  // bounce's incidence angle; off the plate (PEC) |E| is unchanged.
  sc::Scene scene(plate_on_asphalt(0.3, 0.2, 1.0));
  const std::complex<double> eps =
      radar_emu::radar::clutter::permittivity(*rd::clutter::find_terrain_material("asphalt"), kF);
  std::vector<rd::SurfaceModel> surfaces;
  const rd::SurfaceSet set =
      rd::resolve_surfaces(scene.materials(), {kF, rd::Polarisation::kVV, {}});
  for (const rd::Surface& s : set.surfaces)
    surfaces.push_back(s.specular);
  ASSERT_EQ(surfaces[1].kind, rd::SurfaceModel::Kind::kDielectric);
  EXPECT_EQ(surfaces[1].relative_permittivity, eps);
  rd::RcsConfig config;
  config.max_bounces = 4;
  config.rays_per_wavelength = 2.0;
  const rd::RcsEngine engine(scene, surfaces, config);
  std::mutex mutex;
  std::size_t dielectric = 0;
  double worst_angle = 0, worst_plane = 0, worst_v = 0, worst_h = 0;
  const std::function<void(const rd::BounceEvent&)> check = [&](const rd::BounceEvent& e) {
    const double cos_i = -glm::dot(e.incident, e.normal);
    const double theta = std::acos(std::clamp(cos_i, 0.0, 1.0));
    std::lock_guard<std::mutex> lock(mutex);
    worst_angle = std::max(worst_angle, std::abs(glm::dot(e.reflected, e.normal) - cos_i));
    worst_plane =
        std::max(worst_plane, std::abs(glm::dot(glm::cross(e.incident, e.normal), e.reflected)));
    if (e.pec || e.field_before < 1e-6 || e.field_h_before < 1e-6)
      return;
    ++dielectric;
    worst_v = std::max(worst_v, std::abs(e.field_after / e.field_before - fresnel_par(eps, theta)));
    worst_h =
        std::max(worst_h, std::abs(e.field_h_after / e.field_h_before - fresnel_perp(eps, theta)));
  };
  for (double psi_deg : {20.0, 45.0, 60.0}) {
    const double psi = psi_deg * kPi / 180.0;
    rd::ScatteringMatrix s;
    rd::RcsStats stats;
    const double f[1] = {kF};
    const rd::Direction dir{kPi / 2 - psi, kPi};  // radar on the -x side
    engine.compute(dir, dir, f, std::span<rd::ScatteringMatrix>(&s, 1), stats, &check);
  }
  std::cout << dielectric << " dielectric bounces: worst |cos i - cos r| " << worst_angle
            << ", out of plane " << worst_plane << ", | |E_r|/|E_i| - |Gamma| | V " << worst_v
            << " H " << worst_h << "\n";
  EXPECT_GT(dielectric, 100u);
  EXPECT_LT(worst_angle, 1e-12);
  EXPECT_LT(worst_plane, 1e-12);
  EXPECT_LT(worst_v, 1e-9);
  EXPECT_LT(worst_h, 1e-9);
}

TEST(SbrKnobs, PlanCountsWhatTraceShootsAndKnobsScaleIt) {
  const double range = 200.0;
  sc::Scene scene(plate_on_asphalt(0.3, 0.2, 30.0));
  rd::SbrConfig c = narrow(0.02, 0.004, rd::Polarisation::kVV);
  c.terrain_ray_spacing_rad = 0.001;  // 40 x 40 terrain rays
  rd::SbrTracer tracer(scene, c);
  const rd::RadarPose pose = looking_at_origin_from({-1, 0, 1}, range);
  std::vector<std::size_t> per_object(2, 99);
  const rd::TracePlan p = tracer.plan(pose, {}, per_object);
  EXPECT_EQ(p.terrain_rays, 40u * 40u);
  EXPECT_EQ(p.target_bundles, 1u);
  EXPECT_EQ(per_object[1], 0u);  // the ground has no bundle
  EXPECT_EQ(per_object[0], p.target_rays);
  EXPECT_EQ(p.max_bounces, 3);
  rd::TraceStats st;
  const auto all = trace(tracer, pose, {}, &st);
  EXPECT_EQ(st.rays, p.rays());
  EXPECT_EQ(st.knob_fallbacks, 0u);

  // Coarser terrain, fewer bounces, a coarser bundle for object 0.
  const double spacing[1] = {0.008};
  rd::TraceKnobs k;
  k.terrain_spacing_scale = 2.0;
  k.max_bounces = 1;
  k.target_ray_spacing_m = spacing;
  const rd::TracePlan q = tracer.plan(pose, k);
  EXPECT_EQ(q.terrain_rays, 20u * 20u);
  EXPECT_EQ(q.max_bounces, 1);
  EXPECT_NEAR(static_cast<double>(q.target_rays), static_cast<double>(p.target_rays) / 4.0,
              0.1 * static_cast<double>(p.target_rays) / 4.0);
  rd::TraceStats sk;
  const auto some = trace(tracer, pose, k, &sk);
  EXPECT_EQ(sk.rays, q.rays());
  for (const rd::Contribution& ct : some)
    EXPECT_EQ(ct.bounces, 1);

  // Invalid knobs fall back to the configuration, counted.
  rd::TraceKnobs bad;
  bad.terrain_spacing_scale = 0.5;
  bad.max_bounces = 7;
  const double bad_spacing[1] = {-1.0};
  bad.target_ray_spacing_m = bad_spacing;
  rd::TraceStats sb;
  const auto same = trace(tracer, pose, bad, &sb);
  EXPECT_EQ(sb.knob_fallbacks, 3u);
  EXPECT_EQ(sb.rays, p.rays());
  ASSERT_EQ(same.size(), all.size());
  for (std::size_t i = 0; i < all.size(); ++i)
    EXPECT_EQ(same[i].amplitude, all[i].amplitude) << i;
}

namespace {

TEST(SbrLoopVsRcs, EdgeTermsAreBitIdenticalWhateverTheThreading) {
  // Boxes and plates (edges and edge pairs: first order and double diffraction) among two
  // non-conducting grounds, traced with every worker thread and with one: the same contributions,
  // bit for bit, in the same order, frame after frame (the frame path's determinism, which replay
  // and the Python loop parity rely on).
  sc::SceneDescription d = sc::make_target({sc::TargetKind::kBox, 0.8, 0.5, 0.4, 0.0});
  for (int i = 0; i < 6; ++i) {
    sc::SceneDescription more = sc::make_target(
        {i % 2 == 0 ? sc::TargetKind::kPlate : sc::TargetKind::kBox, 0.6, 0.4, 0.3, 0.0});
    more.objects[0].name = "t" + std::to_string(i);
    more.objects[0].world_from_body =
        glm::translate(glm::dmat4(1.0), glm::dvec3(1.5 * (i - 3), 0.7 * (i % 3), 0.2 * i));
    d.objects.push_back(more.objects[0]);
  }
  // Non-conducting objects (no edges, no pairs) before and among the targets.
  d.materials.push_back({"asphalt", {}});
  sc::ObjectDesc ground{"ground", {}, glm::dmat4(1.0), std::nullopt};
  ground.mesh.positions_m = {{-6, -6, -1}, {6, -6, -1}, {6, 6, -1}, {-6, 6, -1}};
  ground.mesh.triangles = {{0, 1, 2}, {0, 2, 3}};
  const auto asphalt = static_cast<std::uint16_t>(d.materials.size() - 1);
  ground.mesh.triangle_material = {asphalt, asphalt};
  d.objects.insert(d.objects.begin(), ground);
  ground.name = "ground2";
  ground.world_from_body = glm::translate(glm::dmat4(1.0), glm::dvec3(0.0, 0.0, -0.5));
  d.objects.insert(d.objects.begin() + 3, ground);
  const sc::Scene scene(d);
  rd::SbrConfig c = narrow(0.1, 0.2, rd::Polarisation::kVV);
  c.max_rays_per_target = 100'000;  // keeps the contribution buffer (one per trace) small
  c.edges = true;
  rd::SbrTracer tracer(scene, c);
  // The targets alone: the same edge and edge-pair terms (the grounds have none).
  sc::SceneDescription targets_only = d;
  targets_only.objects.erase(targets_only.objects.begin() + 3);
  targets_only.objects.erase(targets_only.objects.begin());
  const sc::Scene bare(targets_only);
  rd::SbrTracer bare_tracer(bare, c);
  for (const glm::dvec3 dir : {glm::dvec3(0.3, 0.2, 1.0), glm::dvec3(1.0, 0.4, 0.5)}) {
    const rd::RadarPose pose = looking_at_origin_from(dir, 100.0);
    rd::TraceStats st1;
    std::vector<rd::Contribution> one;
    {
      tbb::global_control serial(tbb::global_control::max_allowed_parallelism, 1);
      one = trace(tracer, pose, {}, &st1);
    }
    ASSERT_GT(st1.edges_double, 0u);
    rd::TraceStats st_bare;
    (void)trace(bare_tracer, pose, {}, &st_bare);
    EXPECT_EQ(st1.edges_used, st_bare.edges_used);
    EXPECT_EQ(st1.edges_double, st_bare.edges_double);
    for (int rep = 0; rep < 5; ++rep) {
      rd::TraceStats st;
      const std::vector<rd::Contribution> many = trace(tracer, pose, {}, &st);
      ASSERT_EQ(many.size(), one.size());
      EXPECT_EQ(st.edges_double, st1.edges_double);
      for (std::size_t i = 0; i < one.size(); ++i) {
        ASSERT_EQ(many[i].amplitude, one[i].amplitude) << "contribution " << i << " rep " << rep;
        ASSERT_EQ(many[i].range_m, one[i].range_m) << i;
      }
    }
  }
}

}  // namespace

namespace {
// A metal bar (length x w x w, along its body x, in `segments` boxes end to end, as a power
// line's) on `world_from_body`, over the asphalt ground of plate_on_asphalt (a 0-size plate
// there: the ground alone).
sc::SceneDescription bar_over_asphalt(double length_m, double w_m, const glm::dmat4& xf,
                                      int segments) {
  sc::SceneDescription d = plate_on_asphalt(0.0, 0.0, 200.0);
  sc::ObjectDesc bar{"bar", {}, xf, std::nullopt};
  const auto r = static_cast<float>(w_m / 2);
  for (int s = 0; s < segments; ++s) {
    const auto x0 = static_cast<float>(length_m * (s / double(segments) - 0.5));
    const auto x1 = static_cast<float>(length_m * ((s + 1) / double(segments) - 0.5));
    const auto base = static_cast<unsigned>(bar.mesh.positions_m.size());
    for (int k = 0; k < 8; ++k)
      bar.mesh.positions_m.emplace_back((k & 1) ? x1 : x0, (k & 2) ? r : -r, (k & 4) ? r : -r);
    for (const glm::uvec3 t : {glm::uvec3{0, 2, 3},
                               {0, 3, 1},
                               {4, 5, 7},
                               {4, 7, 6},
                               {0, 1, 5},
                               {0, 5, 4},
                               {2, 6, 7},
                               {2, 7, 3},
                               {0, 4, 6},
                               {0, 6, 2},
                               {1, 3, 7},
                               {1, 7, 5}})
      bar.mesh.triangles.push_back(t + base);
  }
  bar.mesh.triangle_material.assign(bar.mesh.triangles.size(), 0);
  d.objects[0] = bar;  // in place of the plate
  return d;
}

// The returns of one frame with SbrConfig::mask_target_rays on and off, and the stats.
struct MaskPair {
  std::vector<rd::Contribution> on, off;
  rd::TraceStats on_stats, off_stats;
};
MaskPair trace_masked_and_not(const sc::Scene& scene, const rd::SbrConfig& base,
                              const rd::RadarPose& pose) {
  MaskPair p;
  rd::SbrConfig c = base;
  c.mask_target_rays = true;
  rd::SbrTracer on(scene, c);
  p.on = trace(on, pose, {}, &p.on_stats);
  c.mask_target_rays = false;
  rd::SbrTracer off(scene, c);
  p.off = trace(off, pose, {}, &p.off_stats);
  return p;
}

void expect_same_returns(const MaskPair& p) {
  ASSERT_EQ(p.on.size(), p.off.size());
  for (std::size_t i = 0; i < p.on.size(); ++i) {
    const rd::Contribution &a = p.on[i], &b = p.off[i];
    ASSERT_EQ(a.amplitude, b.amplitude) << i;
    ASSERT_EQ(a.range_m, b.range_m) << i;
    ASSERT_EQ(a.azimuth_rad, b.azimuth_rad) << i;
    ASSERT_EQ(a.elevation_rad, b.elevation_rad) << i;
    ASSERT_EQ(a.bounces, b.bounces) << i;
  }
}
}  // namespace

TEST(SbrMask, ABarOverTheGroundKeepsEveryReturnFromFarFewerRays) {
  // A 40 m bar, 0.2 m thick, 6 m above asphalt, turned 40 deg in azimuth and sloping 5 deg:
  // its box (and the box's image) is mostly empty. Masked to where its parts and their image in
  // the ground below project, the bundle shoots the same rays there and none elsewhere, so
  // every return, the bar-ground double bounces included (their rays aim at the bar's image
  // in the ground, 6 m below its base's plane), is the unmasked trace's, bit for bit.
  const glm::dmat4 xf =
      glm::rotate(glm::rotate(glm::translate(glm::dmat4(1.0), glm::dvec3(0.0, 0.0, 6.0)),
                              40.0 * kPi / 180.0, glm::dvec3(0.0, 0.0, 1.0)),
                  5.0 * kPi / 180.0, glm::dvec3(0.0, 1.0, 0.0));
  sc::Scene scene(bar_over_asphalt(40.0, 0.2, xf, 10));
  const rd::RadarPose pose = looking_at_origin_from({-1.0, 0.2, 0.5}, 150.0);
  const MaskPair p = trace_masked_and_not(scene, narrow(0.3, 0.1, rd::Polarisation::kHH), pose);
  std::size_t doubles = 0;
  for (const rd::Contribution& x : p.off)
    doubles += x.coherent && x.bounces == 2 ? 1u : 0u;
  std::cout << "bar over asphalt: " << p.off_stats.rays << " rays unmasked, " << p.on_stats.rays
            << " masked (" << p.on_stats.masked_rays << " left out), " << p.off.size()
            << " returns, " << doubles << " double bounces\n";
  EXPECT_GT(doubles, 10u);
  EXPECT_LT(2 * p.on_stats.rays, p.off_stats.rays);
  EXPECT_EQ(p.on_stats.rays + p.on_stats.masked_rays, p.off_stats.rays);
  expect_same_returns(p);
}

TEST(SbrMask, ABarReachingBehindTheAntennaKeepsEveryReturn) {
  // A 120 m bar along x (one box: each of its facets runs its whole length), 5 m above the
  // ground, the radar 30 m up over its middle looking along it 25 deg down: half the bar is
  // behind the antenna plane, so its bundle spans the whole field of view, and so does every
  // part of it. The mask halves the parts that reach behind until each half is in front or out
  // of the field of view; the returns are the unmasked trace's, bit for bit.
  const glm::dmat4 xf = glm::translate(glm::dmat4(1.0), glm::dvec3(0.0, 0.0, 5.0));
  sc::Scene scene(bar_over_asphalt(120.0, 0.3, xf, 1));
  rd::RadarPose pose;
  pose.position_m = {0.0, -6.0, 30.0};
  const double dip = 25.0 * kPi / 180.0;
  const glm::dvec3 x(std::cos(dip), 0.0, -std::sin(dip)), y(0.0, 1.0, 0.0);
  pose.world_from_antenna = glm::dmat3(x, y, glm::cross(x, y));
  const MaskPair p = trace_masked_and_not(scene, narrow(0.3, 0.1, rd::Polarisation::kHH), pose);
  std::cout << "bar behind the antenna: " << p.off_stats.rays << " rays unmasked, "
            << p.on_stats.rays << " masked, " << p.off.size() << " returns\n";
  EXPECT_GT(p.off.size(), 100u);
  EXPECT_LT(2 * p.on_stats.rays, p.off_stats.rays);
  expect_same_returns(p);
}
