// SBR first pass against closed forms: PO flat plate (Knott, Shaeffer & Tuley, Radar Cross
// Section, 2nd ed., 2004; physics.md), its pattern off normal, the right dihedral's double
// bounce, Doppler of a moving plate, the image-method path length, ray-density convergence,
// determinism across thread counts, and diffuse terrain power.

#include "radar/em/sbr.hpp"

#include <gtest/gtest.h>
#include <tbb/global_control.h>

#include <cmath>
#include <complex>
#include <numbers>
#include <stdexcept>
#include <string>
#include <vector>

#include "radar/clutter/terrain.hpp"
#include "radar/em/surfaces.hpp"
#include "scene/scene.hpp"
#include "scene/targets.hpp"
#include "tests/radar/sbr_shapes.hpp"

namespace sc = radar_emu::scene;
namespace rd = radar_emu::radar;

namespace {
constexpr double kC = 299792458.0;
constexpr double kPi = std::numbers::pi;

// Square plate of side a in the x-z plane facing -y (toward a radar on the -y axis), rotated
// about the z axis by `tilt_rad` (monostatic aspect angle in the horizontal plane).
sc::ObjectDesc plate(double a, double tilt_rad, glm::dvec3 centre, const char* name = "plate") {
  sc::ObjectDesc o{name, {}, glm::dmat4(1.0), std::nullopt};
  const auto h = static_cast<float>(a / 2);
  o.mesh.positions_m = {{-h, 0, -h}, {h, 0, -h}, {h, 0, h}, {-h, 0, h}};
  o.mesh.triangles = {{0, 1, 2}, {0, 2, 3}};
  o.mesh.triangle_material = {0, 0};
  const double c = std::cos(tilt_rad), s = std::sin(tilt_rad);
  o.world_from_body[0] = glm::dvec4(c, s, 0, 0);
  o.world_from_body[1] = glm::dvec4(-s, c, 0, 0);
  o.world_from_body[3] = glm::dvec4(centre, 1.0);
  return o;
}

// The same plate tilted about the horizontal x axis (elevation aspect).
sc::ObjectDesc plate_el(double a, double tilt_rad, glm::dvec3 centre) {
  sc::ObjectDesc o = plate(a, 0.0, centre, "plate_el");
  const double c = std::cos(tilt_rad), s = std::sin(tilt_rad);
  o.world_from_body[0] = glm::dvec4(1, 0, 0, 0);
  o.world_from_body[1] = glm::dvec4(0, c, s, 0);
  o.world_from_body[2] = glm::dvec4(0, -s, c, 0);
  return o;
}

sc::SceneDescription with(std::vector<sc::ObjectDesc> objects) {
  sc::SceneDescription d;
  d.materials = {{"metal", {}}, {"grass", {}}};
  d.objects = std::move(objects);
  return d;
}

// Radar on the -y axis at `range`, boresight +y (antenna x = world y, antenna y (right) =
// world x... with z down: right = +x when looking along +y with up = +z).
rd::RadarPose pose_at(double range) {
  rd::RadarPose p;
  p.position_m = {0.0, -range, 0.0};
  p.world_from_antenna = glm::dmat3(glm::dvec3(0, 1, 0), glm::dvec3(1, 0, 0), glm::dvec3(0, 0, -1));
  return p;
}

rd::SbrConfig narrow(double carrier_hz, double half_fov_rad, double spacing_m) {
  rd::SbrConfig c;
  c.carrier_hz = carrier_hz;
  c.azimuth_min_rad = -half_fov_rad;
  c.azimuth_max_rad = half_fov_rad;
  c.elevation_min_rad = -half_fov_rad;
  c.elevation_max_rad = half_fov_rad;
  c.terrain_ray_spacing_rad = half_fov_rad;  // no terrain here: keep the coarse grid tiny
  c.target_ray_spacing_m = spacing_m;
  c.max_rays_per_target = 2'000'000;
  c.max_range_m = 1e5;
  c.max_bounces = 3;
  return c;
}

struct Sum {
  std::complex<double> total{0, 0};
  std::complex<double> by_bounces[4]{};
  std::size_t n = 0;
};

Sum coherent_sum(rd::SbrTracer& t, const rd::RadarPose& pose, double range_ref_m, double k) {
  std::vector<rd::Contribution> out(t.max_contributions());
  rd::TraceStats st;
  const std::size_t n = t.trace(pose, out, st);
  Sum s;
  s.n = n;
  // Refer phases to the target origin: multiply by e^{+j k 2 R_ref}.
  const std::complex<double> ref = std::polar(1.0, 2.0 * k * range_ref_m);
  for (std::size_t i = 0; i < n; ++i) {
    s.total += out[i].amplitude * ref;
    s.by_bounces[std::min<int>(out[i].bounces, 3)] += out[i].amplitude * ref;
  }
  return s;
}

double db(double x) {
  return 10.0 * std::log10(x);
}
}  // namespace

TEST(SbrPlate, NormalIncidenceMatchesPhysicalOptics) {
  // 1 m x 1 m plate at 10 GHz, radar 20 km away (far field: 2 D^2 / lambda = 67 m).
  const double f = 10e9, lambda = kC / f, k = 2 * kPi / lambda, a = 1.0, range = 20e3;
  sc::Scene scene(with({plate(a, 0.0, {0, 0, 0})}));
  rd::SbrTracer tracer(scene, narrow(f, 1e-3, 0.01));
  const Sum s = coherent_sum(tracer, pose_at(range), range, k);
  const double sigma = std::norm(s.total);
  const double expected = 4 * kPi * a * a * a * a / (lambda * lambda);  // 41.45 dBsm
  std::cout << "plate normal: " << db(sigma) << " dBsm, PO " << db(expected) << " dBsm\n";
  EXPECT_NEAR(db(sigma), db(expected), 0.5);
}

TEST(SbrPlate, PatternOffNormalFollowsPhysicalOptics) {
  // Monostatic PO pattern of a square plate rotated by theta about one edge direction:
  // sigma = (4 pi a^4 / lambda^2) cos^2(theta) sinc^2(k a sin theta) (physics.md; the phase
  // gradient across the plate is 2 k sin(theta), so the width integral is a sinc(k a sin theta)).
  const double f = 10e9, lambda = kC / f, k = 2 * kPi / lambda, a = 1.0, range = 20e3;
  for (double theta_deg : {1.0, 2.0, 3.0, 5.0, 8.0}) {
    const double th = theta_deg * kPi / 180.0;
    sc::Scene scene(with({plate(a, th, {0, 0, 0})}));
    rd::SbrTracer tracer(scene, narrow(f, 1e-3, 0.01));
    const Sum s = coherent_sum(tracer, pose_at(range), range, k);
    const double x = k * a * std::sin(th);
    const double expected =
        4 * kPi * std::pow(a, 4) / (lambda * lambda) * std::pow(std::cos(th) * std::sin(x) / x, 2);
    std::cout << "plate " << theta_deg << " deg: " << db(std::norm(s.total)) << " dBsm, PO "
              << db(expected) << " dBsm\n";
    EXPECT_NEAR(db(std::norm(s.total)), db(expected), 1.0) << theta_deg;
  }
}

TEST(SbrPlate, SidelobeConvergesWithTubeDensityAt94GHz) {
  // A 2.5 m plate tilted 3.1 deg in elevation seen from 4 km at 94 GHz: the geometry of a
  // vehicle's rear face on approach. The tube footprint integral makes the result independent of
  // the tube density (the monostatic phase is linear over a plane), so halving and quartering
  // the spacing changes nothing beyond 0.05 dB; and it stays within the near-field deviation
  // (2 D^2 / lambda = 3.9 km here) of the far-field PO value.
  const double f = 94e9, lambda = kC / f, k = 2 * kPi / lambda, a = 2.5, range = 4000;
  const double th = 3.1 * kPi / 180.0;
  const double x = k * a * std::sin(th);
  const double po =
      4 * kPi * std::pow(a, 4) / (lambda * lambda) * std::pow(std::cos(th) * std::sin(x) / x, 2);
  std::vector<double> results;
  for (double spacing : {0.25, 0.125, 0.0625}) {
    sc::Scene scene(with({plate_el(a, th, {0, 0, 0})}));
    rd::SbrTracer tracer(scene, narrow(f, 1e-3, spacing));
    results.push_back(db(std::norm(coherent_sum(tracer, pose_at(range), range, k).total)));
    std::cout << "spacing " << spacing << " m: " << results.back() << " dBsm (far-field PO "
              << db(po) << ")\n";
  }
  EXPECT_NEAR(results[1], results[0], 0.05);
  EXPECT_NEAR(results[2], results[1], 0.05);
  EXPECT_NEAR(results[2], db(po), 0.5);
}

using radar_emu::test::dihedral;
using radar_emu::test::trihedral;

TEST(SbrCorner, RightDihedralDoubleBounce) {
  // Broadside right dihedral: sigma = 8 pi a^2 b^2 / lambda^2 (physics.md), from the 2-bounce
  // paths; single bounces off each face at 45 deg are 40 dB down and not counted here.
  const double f = 10e9, lambda = kC / f, k = 2 * kPi / lambda, range = 20e3, a = 1.0, b = 0.5;
  sc::Scene scene(with({dihedral(a, b)}));
  rd::SbrTracer tracer(scene, narrow(f, 1e-3, 0.02));
  const Sum s = coherent_sum(tracer, pose_at(range), range, k);
  const double expected = 8 * kPi * a * a * b * b / (lambda * lambda);
  std::cout << "dihedral: " << db(std::norm(s.by_bounces[2])) << " dBsm, closed form "
            << db(expected) << "\n";
  EXPECT_NEAR(db(std::norm(s.by_bounces[2])), db(expected), 0.5);
  EXPECT_LT(std::norm(s.by_bounces[1]), 1e-3 * std::norm(s.by_bounces[2]));
}

TEST(SbrCorner, SquareTrihedralTripleBounceOnAxis) {
  // Square trihedral on its symmetry axis: sigma = 12 pi a^4 / lambda^2 (physics.md).
  const double f = 10e9, lambda = kC / f, k = 2 * kPi / lambda, range = 20e3, a = 0.5;
  sc::Scene scene(with({trihedral(a)}));
  rd::SbrTracer tracer(scene, narrow(f, 1e-3, 0.02));
  const Sum s = coherent_sum(tracer, pose_at(range), range, k);
  const double expected = 12 * kPi * std::pow(a, 4) / (lambda * lambda);
  std::cout << "trihedral: " << db(std::norm(s.by_bounces[3])) << " dBsm, closed form "
            << db(expected) << "\n";
  EXPECT_NEAR(db(std::norm(s.by_bounces[3])), db(expected), 0.5);
}

TEST(SbrCorner, DoubleBouncePathIsTheImageMethodLength) {
  // Law of reflection at every bounce: for a ray entering the dihedral parallel to its bisector
  // at lateral offset x, the unfolded path equals the straight path to the image of the radar
  // (two reflections in perpendicular planes = a point reflection through the fold axis), so
  // every 2-bounce contribution has range R exactly (the fold at the origin, radar at -R):
  // range = (R + |x| + |x| + R - 2|x|) / 2 = R for all rays.
  const double f = 10e9, range = 1000.0;
  sc::Scene scene(with({dihedral(1.0, 0.5)}));
  rd::SbrConfig c = narrow(f, 1e-3, 0.05);
  rd::SbrTracer tracer(scene, c);
  std::vector<rd::Contribution> out(tracer.max_contributions());
  rd::TraceStats st;
  const std::size_t n = tracer.trace(pose_at(range), out, st);
  std::size_t doubles = 0;
  for (std::size_t i = 0; i < n; ++i) {
    if (out[i].bounces != 2)
      continue;
    ++doubles;
    // Rays diverge from the radar (not exactly parallel): allow the spherical-wave excess,
    // at most x^2 / R ~ 0.35^2 / 1000 m.
    EXPECT_NEAR(out[i].range_m, range, 2e-4) << i;
  }
  EXPECT_GT(doubles, 50u);
}

TEST(Sbr, MovingPlateRadialVelocityIsItsVelocityAlongTheLineOfSight) {
  const double f = 10e9, range = 2000.0;
  sc::SceneDescription d = with({});
  sc::ObjectDesc p = plate(1.0, 0.0, {0, 0, 0});
  p.motion = sc::LinearMotion{{0, 0, 0}, {3.0, -40.0, 0.0}};  // closing at 40 m/s, 3 m/s across
  p.mesh.positions_m = {{-0.5f, 0, -0.5f}, {0.5f, 0, -0.5f}, {0.5f, 0, 0.5f}, {-0.5f, 0, 0.5f}};
  d.objects.push_back(p);
  sc::Scene scene(std::move(d));
  rd::SbrTracer tracer(scene, narrow(f, 1e-3, 0.05));
  rd::RadarPose pose = pose_at(range);
  pose.velocity_mps = {0.0, 10.0, 0.0};  // radar moving toward the plate at 10 m/s
  std::vector<rd::Contribution> out(tracer.max_contributions());
  rd::TraceStats st;
  const std::size_t n = tracer.trace(pose, out, st);
  ASSERT_GT(n, 0u);
  for (std::size_t i = 0; i < n; ++i) {
    const glm::dvec3 los = glm::normalize(glm::dvec3(0.0, range, 0.0));  // radar -> plate
    const double expected = glm::dot(glm::dvec3(3.0, -40.0, 0.0) - pose.velocity_mps, los);
    EXPECT_NEAR(out[i].radial_velocity_mps, expected, 0.01) << i;  // -50 m/s: closing
  }
}

TEST(Sbr, OutputIsIdenticalAcrossRunsAndThreadCounts) {
  const double f = 10e9, range = 500.0;
  sc::Scene scene(with({dihedral(1.0, 0.5), plate(0.5, 0.2, {2.0, 1.0, 0.0}, "p2")}));
  rd::SbrTracer tracer(scene, narrow(f, 5e-3, 0.02));
  std::vector<rd::Contribution> a(tracer.max_contributions()), b(a.size()), c(a.size());
  rd::TraceStats st;
  std::size_t na = 0, nb = 0, nc = 0;
  {
    tbb::global_control one(tbb::global_control::max_allowed_parallelism, 1);
    na = tracer.trace(pose_at(range), a, st);
  }
  {
    tbb::global_control two(tbb::global_control::max_allowed_parallelism, 2);
    nb = tracer.trace(pose_at(range), b, st);
    nc = tracer.trace(pose_at(range), c, st);
  }
  ASSERT_EQ(na, nb);
  ASSERT_EQ(nb, nc);
  ASSERT_GT(na, 100u);
  for (std::size_t i = 0; i < na; ++i) {
    ASSERT_EQ(a[i].amplitude, b[i].amplitude) << i;
    ASSERT_EQ(b[i].amplitude, c[i].amplitude) << i;
    ASSERT_EQ(a[i].range_m, b[i].range_m) << i;
  }
}

// The query log (bench_frame's BM_TraceRaw replays it against raw Embree): it changes no output,
// and its segments and shadow rays, asked again one by one of the scene, give the trace's own
// hit count and as many clear shadow rays as the trace kept later-bounce returns.
TEST(Sbr, QueryLogHoldsTheFramesQueriesAndChangesNothing) {
  const double f = 10e9, range = 500.0;
  sc::Scene scene(with({dihedral(1.0, 0.5), plate(0.5, 0.2, {2.0, 1.0, 0.0}, "p2")}));
  rd::SbrTracer tracer(scene, narrow(f, 5e-3, 0.02));
  std::vector<rd::Contribution> a(tracer.max_contributions()), b(a.size());
  rd::TraceStats sa, sb;
  const std::size_t na = tracer.trace(pose_at(range), a, sa);
  rd::QueryLog sizing;
  tracer.set_query_log(&sizing);
  (void)tracer.trace(pose_at(range), b, sb);
  std::vector<sc::Ray> intersects(sizing.n_intersects.load()),
      occlusions(sizing.n_occlusions.load());
  rd::QueryLog log;
  log.intersects = intersects;
  log.occlusions = occlusions;
  tracer.set_query_log(&log);
  sb = {};
  const std::size_t nb = tracer.trace(pose_at(range), b, sb);
  tracer.set_query_log(nullptr);
  ASSERT_EQ(na, nb);
  for (std::size_t i = 0; i < na; ++i) {
    ASSERT_EQ(a[i].amplitude, b[i].amplitude) << i;
    ASSERT_EQ(a[i].range_m, b[i].range_m) << i;
  }
  ASSERT_EQ(log.n_intersects.load(), intersects.size());
  ASSERT_EQ(log.n_occlusions.load(), occlusions.size());
  ASSERT_GT(intersects.size(), 100u);
  std::uint64_t hits = 0;
  for (const sc::Ray& r : intersects) {
    sc::Hit h;
    hits += scene.intersect(r, h) ? 1u : 0u;
  }
  EXPECT_EQ(hits, sb.hits);
  // Occlusion queries: bounce 1's facet samples (facet_queries) and one shadow ray per
  // later-bounce return that faced the radar; the clear ones are the kept returns.
  std::size_t later_returns = 0;
  for (std::size_t i = 0; i < nb; ++i)
    later_returns += b[i].bounces > 1 ? 1u : 0u;
  ASSERT_GE(occlusions.size(), sb.facet_queries);
  std::size_t clear_shadows = 0;
  for (std::size_t i = sb.facet_queries; i < occlusions.size(); ++i)
    clear_shadows += scene.occluded(occlusions[i]) ? 0u : 1u;
  EXPECT_GT(later_returns, 0u);
  EXPECT_EQ(clear_shadows, later_returns);
}

TEST(Sbr, NothingOutsideTheFieldOfView) {
  // A plate 10 m to the side at 100 m (5.7 deg) with a +-2 deg field of view: no rays, no returns.
  sc::Scene scene(with({plate(1.0, 0.0, {10.0, 0.0, 0.0})}));
  rd::SbrConfig c = narrow(10e9, 2.0 * kPi / 180.0, 0.05);
  c.terrain_ray_spacing_rad = 1e-3;
  rd::SbrTracer tracer(scene, c);
  std::vector<rd::Contribution> out(tracer.max_contributions());
  rd::TraceStats st;
  EXPECT_EQ(tracer.trace(pose_at(100.0), out, st), 0u);
  EXPECT_EQ(st.target_bundles, 0u);
}

namespace {
// Flat ground of one material 100 m below the radar (boresight horizontal), traced at 10 GHz.
std::vector<rd::Contribution> trace_flat_ground(const std::string& material, std::size_t& n) {
  sc::SceneDescription d;
  d.materials = {{material, {}}};
  sc::ObjectDesc g{"ground", {}, glm::dmat4(1.0), std::nullopt};
  g.mesh.positions_m = {
      {-5000, -5000, -100}, {5000, -5000, -100}, {5000, 5000, -100}, {-5000, 5000, -100}};
  g.mesh.triangles = {{0, 1, 2}, {0, 2, 3}};
  g.mesh.triangle_material = {0, 0};
  d.objects.push_back(g);
  sc::Scene scene(std::move(d));
  rd::SbrConfig c;
  c.carrier_hz = 10e9;
  c.azimuth_min_rad = -0.1;
  c.azimuth_max_rad = 0.1;
  c.elevation_min_rad = -0.4;
  c.elevation_max_rad = -0.1;
  c.terrain_ray_spacing_rad = 0.01;
  c.max_range_m = 1e4;
  rd::SbrTracer tracer(scene, c);
  std::vector<rd::Contribution> out(tracer.max_contributions());
  rd::TraceStats st;
  n = tracer.trace(pose_at(0.0), out, st);
  return out;
}
constexpr double kFlatDaz = 0.2 / 20, kFlatDel = 0.3 / 30;
}  // namespace

TEST(Sbr, ThePlaceholderSoilIsRefused) {
  // Issue 2's placeholder table (constant gamma) is gone: "soil" is no longer a material (the
  // catalogue's soils are soil_dry and soil_wet, named in the message; tests/radar/
  // surfaces_test.cpp checks the rest of the resolver).
  std::size_t n = 0;
  try {
    (void)trace_flat_ground("soil", n);
    ADD_FAILURE() << "a scene of \"soil\" was accepted";
  } catch (const std::invalid_argument& e) {
    const std::string what = e.what();
    EXPECT_NE(what.find("'soil' is unknown"), std::string::npos) << what;
    EXPECT_NE(what.find("soil_dry"), std::string::npos) << what;
    EXPECT_NE(what.find("soil_wet"), std::string::npos) << what;
  }
}

TEST(Sbr, CatalogueTerrainReturnsItsModelSigma0TimesTheFootprintArea) {
  // A terrain-catalogue material ("grass") takes sigma0 from issue 4's physical models: each ray's
  // sigma = sigma0_VV(theta_i) * footprint area, footprint = L^2 dOmega / cos(theta_i), with
  // cos(theta_i) = sin(-el) on flat ground. sigma0 is evaluated here directly with the model
  // (evaluate_sigma0, "total" = surface + volume), not through the tracer's interpolated table.
  namespace cl = radar_emu::radar::clutter;
  std::size_t n = 0;
  const auto out = trace_flat_ground("grass", n);
  ASSERT_EQ(n, 20u * 30u);
  const cl::SurfaceSpec spec = cl::resolve_surface(*cl::find_terrain_material("grass"), 10e9);
  double worst = 0.0;
  for (std::size_t i = 0; i < n; ++i) {
    const double el = out[i].elevation_rad, L = 100.0 / std::sin(-el);
    const double cos_i = std::sin(-el);
    const double sigma0 = cl::evaluate_sigma0(spec, cl::Sigma0Model::kTotal, 10e9,
                                              cl::Geometry::backscatter(std::acos(cos_i)))
                              .incoherent.vv;
    const double expected = sigma0 * L * L * std::cos(el) * kFlatDaz * kFlatDel / cos_i;
    worst = std::max(worst, std::abs(10.0 * std::log10(std::norm(out[i].amplitude) / expected)));
  }
  std::printf("  grass at 10 GHz, incidence %.1f-%.1f deg: worst |traced - model| %.2e dB\n",
              90.0 - 0.4 * 180.0 / kPi, 90.0 - 0.1 * 180.0 / kPi, worst);
  EXPECT_LT(worst,
            0.01);  // the table interpolates within 0.0002 dB (docs/validation_environment.md)
}

namespace {
// Radar at `range` in direction `dir` from the origin, looking back at it.
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
}  // namespace

TEST(SbrCanonicalTargets, GeneratedTargetsMatchClosedForms) {
  // The meshes `radar-emu scene target` writes, traced from their documented aspect.
  const double f = 10e9, lambda = kC / f, k = 2 * kPi / lambda, range = 20e3;
  struct Case {
    sc::TargetKind kind;
    double a, b;
    glm::dvec3 dir;
    int bounces;
    double sigma;
  };
  const double a4 = std::pow(0.5, 4);
  const Case cases[] = {
      {sc::TargetKind::kPlate, 1.0, 0.5, {0, 0, 1}, 1, 4 * kPi * 0.25 / (lambda * lambda)},
      {sc::TargetKind::kDihedral, 1.0, 0.5, {0, 0, 1}, 2, 8 * kPi * 0.25 / (lambda * lambda)},
      {sc::TargetKind::kTrihedralSquare, 0.5, 1, {1, 1, 1}, 3, 12 * kPi * a4 / (lambda * lambda)},
      {sc::TargetKind::kTrihedralTriangular,
       0.5,
       1,
       {1, 1, 1},
       3,
       4 * kPi * a4 / (3 * lambda * lambda)},
  };
  for (const Case& c : cases) {
    sc::Scene scene(sc::make_target({c.kind, c.a, c.b, 1.0, 0.0}));
    rd::SbrTracer tracer(scene, narrow(f, 0.02, 0.02));
    const Sum s = coherent_sum(tracer, looking_at_origin_from(c.dir, range), range, k);
    const double got = std::norm(s.by_bounces[c.bounces]);
    std::cout << sc::target_name(c.kind) << ": " << db(got) << " dBsm, closed form " << db(c.sigma)
              << "\n";
    EXPECT_NEAR(db(got), db(c.sigma), 0.5) << sc::target_name(c.kind);
  }
}
