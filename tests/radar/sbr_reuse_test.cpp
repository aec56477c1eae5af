// Static path reuse in the frame tracer (SbrConfig::reuse_static_paths, radar/em/sbr.hpp):
// kept paths re-evaluated for a still radar give back the traced returns; for a moving radar the
// right dihedral's double-bounce paths keep the image-method length to within Fermat's
// second-order bound, and the square trihedral keeps its closed-form RCS; every rule that calls
// for a new trace (aspect, antenna turn, spacing, a moving object near, the refresh) does, a slice
// at a time where it can (a slice past the limit alone; a grid one row off keeps its rows); kept
// targets' facets read their occlusion answers back.

#include <gtest/gtest.h>
#include <tbb/global_control.h>
#include <tbb/info.h>

#include <algorithm>
#include <cmath>
#include <complex>
#include <cstdio>
#include <iostream>
#include <numbers>
#include <vector>

#include "radar/em/sbr.hpp"
#include "scene/scene.hpp"
#include "tests/radar/sbr_shapes.hpp"

namespace sc = radar_emu::scene;
namespace rd = radar_emu::radar;
using radar_emu::test::dihedral;
using radar_emu::test::trihedral;

namespace {
constexpr double kC = 299792458.0;
constexpr double kPi = std::numbers::pi;

// A small plate (a x a, in the x-z plane) at `at`; moving at `velocity` when it is not zero.
sc::ObjectDesc plate(double a, glm::dvec3 at, glm::dvec3 velocity = glm::dvec3(0.0)) {
  sc::ObjectDesc o{"plate", {}, glm::dmat4(1.0), std::nullopt};
  const auto h = static_cast<float>(a / 2);
  o.mesh.positions_m = {{-h, 0, -h}, {h, 0, -h}, {h, 0, h}, {-h, 0, h}};
  o.mesh.triangles = {{0, 1, 2}, {0, 2, 3}};
  o.mesh.triangle_material = {0, 0};
  o.world_from_body[3] = glm::dvec4(at, 1.0);
  if (velocity != glm::dvec3(0.0))
    o.motion = sc::LinearMotion{at, velocity};
  return o;
}

sc::SceneDescription with(std::vector<sc::ObjectDesc> objects) {
  sc::SceneDescription d;
  d.materials = {{"metal", {}}};
  d.objects = std::move(objects);
  return d;
}

// Eight equal dihedrals side by side, 4 m apart along x (the refresh tests' scene).
sc::SceneDescription eight_dihedrals() {
  std::vector<sc::ObjectDesc> objects;
  for (int i = 0; i < 8; ++i)
    objects.push_back(dihedral(1.0, 0.5, {-14.0 + 4.0 * i, 0.0, 0.0}));
  return with(std::move(objects));
}

// The radar in the horizontal plane at `range` from the z axis, `phi_rad` clockwise (seen from
// above) from the -y axis, looking at the axis (antenna x toward it, z down).
rd::RadarPose pose_around(double range, double phi_rad) {
  rd::RadarPose p;
  const glm::dvec3 look(std::sin(phi_rad), std::cos(phi_rad), 0.0);
  p.position_m = -range * look;
  const glm::dvec3 down(0, 0, -1);
  p.world_from_antenna = glm::dmat3(look, glm::cross(down, look), down);
  return p;
}

// As pose_around, lifted by `elevation_rad` on the sphere of radius `range` (looking down at the
// origin, the antenna's y axis horizontal).
rd::RadarPose pose_above(double range, double phi_rad, double elevation_rad) {
  rd::RadarPose p;
  const glm::dvec3 look(std::sin(phi_rad) * std::cos(elevation_rad),
                        std::cos(phi_rad) * std::cos(elevation_rad), -std::sin(elevation_rad));
  p.position_m = -range * look;
  const glm::dvec3 right = glm::normalize(glm::cross(glm::dvec3(0, 0, -1), look));
  p.world_from_antenna = glm::dmat3(look, right, glm::cross(look, right));
  return p;
}

rd::SbrConfig config(double carrier_hz, double spacing_m) {
  rd::SbrConfig c;
  c.carrier_hz = carrier_hz;
  c.azimuth_min_rad = c.elevation_min_rad = -0.05;
  c.azimuth_max_rad = c.elevation_max_rad = 0.05;
  c.terrain_ray_spacing_rad = 0.05;
  c.terrain_rays = false;
  c.target_ray_spacing_m = spacing_m;
  c.max_rays_per_target = 20'000;
  c.max_range_m = 1e5;
  c.max_bounces = 3;
  c.target_ground_image = false;  // no ground here: the region is the box
  c.reuse_static_paths = true;
  return c;
}

// The aspect-change limit of a target of box diagonal extent_m (SbrConfig::reuse_static_paths).
double limit_rad(const rd::SbrConfig& c, double tube_m, double extent_m) {
  const double k = 2.0 * kPi * c.carrier_hz / kC;
  return std::min(0.5 * tube_m / extent_m, std::sqrt(c.reuse_max_phase_rad / (k * extent_m)));
}

struct Frame {
  std::vector<rd::Contribution> out;
  rd::TraceStats stats;
};

Frame trace(rd::SbrTracer& t, const rd::RadarPose& pose, const rd::TraceKnobs& knobs = {}) {
  Frame f;
  f.out.resize(t.max_contributions());
  f.out.resize(t.trace(pose, f.out, f.stats, knobs));
  return f;
}

// The coherent sum of the returns of `bounces` hits, phase referred to range r_ref.
std::complex<double> sum(const Frame& f, int bounces, double k, double r_ref) {
  std::complex<double> s{0.0, 0.0};
  for (const rd::Contribution& x : f.out) {
    if (x.bounces == bounces)
      s += x.amplitude * std::polar(1.0, 2.0 * k * r_ref);
  }
  return s;
}
}  // namespace

TEST(SbrReuse, AStillRadarGetsTheTracedReturnsBack) {
  const double f = 10e9;
  sc::Scene scene(with({trihedral(0.5)}));
  rd::SbrTracer tracer(scene, config(f, 0.02));
  const rd::RadarPose pose = pose_around(1000.0, 0.0);
  const Frame first = trace(tracer, pose);
  const Frame second = trace(tracer, pose);
  EXPECT_EQ(first.stats.reused_bundles, 0u);
  ASSERT_EQ(second.stats.reused_bundles, 1u);
  EXPECT_EQ(second.stats.rays, 0u);  // nothing traced again
  EXPECT_GT(second.stats.reused_contributions, 1000u);
  // The same returns in the same order (kept paths in ray order, then the facets): the end
  // segments are recomputed, so lengths and phases agree to rounding.
  ASSERT_EQ(first.out.size(), second.out.size());
  double peak = 0.0;
  for (const rd::Contribution& x : first.out)
    peak = std::max(peak, std::abs(x.amplitude));
  for (std::size_t i = 0; i < first.out.size(); ++i) {
    const rd::Contribution &a = first.out[i], &b = second.out[i];
    ASSERT_EQ(a.bounces, b.bounces) << i;
    ASSERT_EQ(a.object_id, b.object_id) << i;
    EXPECT_NEAR(a.range_m, b.range_m, 1e-9) << i;
    EXPECT_NEAR(std::abs(a.amplitude - b.amplitude), 0.0, 1e-8 * peak) << i;
    EXPECT_NEAR(a.azimuth_rad, b.azimuth_rad, 1e-12) << i;
    EXPECT_NEAR(a.elevation_rad, b.elevation_rad, 1e-12) << i;
    EXPECT_NEAR(a.radial_velocity_mps, b.radial_velocity_mps, 1e-12) << i;
  }
}

TEST(SbrReuse, KeptFacetsReadTheirShadowsBackInTheOrderAsked) {
  // A 1 m plate with a 0.3 m plate 2 m in front of it, off centre: the big plate is partly lit
  // (its facets cut into sub-triangles, each with its own visibility query). Its bundle keeps
  // its paths, and its facets' occlusion answers; a radar turned by a thousandth of the aspect
  // limit (no shadow boundary crosses a sample) gets every facet's light from them, no query
  // asked, and the bounce-1 returns a fresh trace computes at that pose, to rounding. Turned
  // past the limit, the facets ask the scene again.
  const double f = 10e9, rho = 1000.0, spacing = 0.05;
  sc::Scene scene(with({plate(1.0, {0.0, 0.0, 0.0}), plate(0.3, {0.4, -2.0, 0.0})}));
  const rd::SbrConfig c = config(f, spacing);
  rd::SbrConfig fresh_config = c;
  fresh_config.reuse_static_paths = false;
  const double limit = limit_rad(c, spacing, std::sqrt(2.0));
  const rd::RadarPose near = pose_around(rho, 1e-3 * limit);
  rd::SbrTracer reuse(scene, c), fresh(scene, fresh_config);
  const Frame first = trace(reuse, pose_around(rho, 0.0));
  const Frame kept = trace(reuse, near), traced = trace(fresh, near);
  EXPECT_GT(first.stats.facet_queries, 100u);
  EXPECT_GE(first.stats.partial_facets, 1u);
  ASSERT_EQ(kept.stats.reused_bundles, 2u);
  EXPECT_EQ(kept.stats.facet_queries, 0u);
  EXPECT_EQ(kept.stats.lit_facets, traced.stats.lit_facets);
  EXPECT_EQ(kept.stats.partial_facets, traced.stats.partial_facets);
  auto bounce1 = [](const Frame& fr) {
    std::vector<std::complex<double>> a;
    for (const rd::Contribution& x : fr.out) {
      if (x.bounces == 1)
        a.push_back(x.amplitude);
    }
    return a;
  };
  const std::vector<std::complex<double>> a = bounce1(kept), b = bounce1(traced);
  ASSERT_EQ(a.size(), b.size());
  ASSERT_GE(a.size(), 3u);
  for (std::size_t i = 0; i < a.size(); ++i)
    EXPECT_LE(std::abs(a[i] - b[i]), 1e-9 * std::abs(b[i])) << i;
  // Past both plates' limits (the small plate's is the larger).
  const Frame turned =
      trace(reuse, pose_around(rho, 1.5 * limit_rad(c, spacing, 0.3 * std::sqrt(2.0))));
  EXPECT_EQ(turned.stats.reused_bundles, 0u);
  EXPECT_GT(turned.stats.facet_queries, 100u);
}

TEST(SbrReuse, KeptDihedralPathsKeepTheImageLengthToSecondOrder) {
  // Right dihedral (fold on the z axis): every double-bounce path from a radar in the horizontal
  // plane at distance rho from the fold has the length of the straight line to the radar's image
  // through the fold, 2 rho (SbrCorner.DoubleBouncePathIsTheImageMethodLength), up to the
  // spherical wave's x^2 / rho. Kept paths re-evaluated for the radar turned by dtheta about the
  // fold keep their reflection points; the length is stationary in them (Fermat), so it is off
  // by the second order: at most D dtheta^2 of path (D the dihedral's extent), a quarter of it
  // at half the angle.
  const double f = 10e9, rho = 1000.0, a = 1.0, b = 0.5, spacing = 0.05;
  sc::Scene scene(with({dihedral(a, b)}));
  const rd::SbrConfig c = config(f, spacing);
  const double w = b / std::sqrt(2.0);
  const double extent = std::sqrt(4 * w * w + w * w + a * a);  // the box's diagonal
  const double limit = limit_rad(c, spacing, extent);
  // The worst range error of the kept double bounces beyond the traced ones' (the spherical
  // excess).
  auto worst_after = [&](double dtheta) {
    rd::SbrTracer tracer(scene, c);
    (void)trace(tracer, pose_around(rho, 0.0));
    const Frame kept = trace(tracer, pose_around(rho, dtheta));
    EXPECT_EQ(kept.stats.reused_bundles, 1u) << "limit " << limit << " rad";
    double worst = 0.0;
    std::size_t doubles = 0;
    for (const rd::Contribution& x : kept.out) {
      if (x.bounces != 2)
        continue;
      ++doubles;
      worst = std::max(worst, std::abs(x.range_m - rho));
    }
    EXPECT_GT(doubles, 50u);
    // The same pose traced: its worst is the spherical excess alone.
    rd::SbrConfig traced_config = c;
    traced_config.reuse_static_paths = false;
    rd::SbrTracer fresh(scene, traced_config);
    double spherical_m = 0.0;
    for (const rd::Contribution& x : trace(fresh, pose_around(rho, dtheta)).out) {
      if (x.bounces == 2)
        spherical_m = std::max(spherical_m, std::abs(x.range_m - rho));
    }
    return std::max(0.0, worst - spherical_m);
  };
  const double dtheta = 0.9 * limit;
  const double full = worst_after(dtheta), half = worst_after(0.5 * dtheta);
  const double bound_m = 0.5 * extent * dtheta * dtheta;  // half of D dtheta^2
  std::cout << "dtheta " << dtheta * 1e3 << " mrad: worst range error beyond the spherical "
            << full * 1e6 << " um (bound " << bound_m * 1e6 << " um), at half the angle "
            << half * 1e6 << " um\n";
  EXPECT_LE(full, bound_m);
  EXPECT_GT(full, 0.1 * bound_m);        // the kept points do matter at this angle
  EXPECT_NEAR(half / full, 0.25, 0.08);  // second order
}

TEST(SbrReuse, TrihedralKeepsItsClosedFormSeenFromAMovingRadar) {
  // Square trihedral on axis: sigma = 12 pi a^4 / lambda^2 (Knott, Shaeffer & Tuley, Radar
  // Cross Section, 2nd ed., table 6.1), flat within 0.01 dB over the few mrad here. The radar
  // moves around it in steps, each kept path re-evaluated until the aspect reaches its limit.
  // Each kept path's phase is within reuse_max_phase_rad of its traced value, so the coherent
  // sum is within 20 log10(1 / cos(phase)) dB (0.69 dB at pi / 8) of the traced one; here
  // it must also stay within the 0.5 dB of the closed form that the traced sum keeps
  // (SbrCorner.SquareTrihedralTripleBounceOnAxis).
  const double f = 10e9, lambda = kC / f, k = 2 * kPi / lambda, rho = 1000.0, a = 0.5;
  sc::Scene scene(with({trihedral(a)}));
  const rd::SbrConfig c = config(f, 0.02);
  rd::SbrTracer reuse(scene, c);
  rd::SbrConfig fresh_config = c;
  fresh_config.reuse_static_paths = false;
  rd::SbrTracer fresh(scene, fresh_config);
  const double expected_db = 10 * std::log10(12 * kPi * std::pow(a, 4) / (lambda * lambda));
  const double bound_db = 20 * std::log10(1.0 / std::cos(c.reuse_max_phase_rad));
  std::size_t reused = 0;
  for (int step = 0; step < 12; ++step) {
    const double phi = 1e-3 * step;
    const rd::RadarPose pose = pose_around(rho, phi);
    const Frame r = trace(reuse, pose), t = trace(fresh, pose);
    reused += r.stats.reused_bundles;
    const double reuse_db = 10 * std::log10(std::norm(sum(r, 3, k, rho)));
    const double fresh_db = 10 * std::log10(std::norm(sum(t, 3, k, rho)));
    std::cout << "phi " << phi * 1e3 << " mrad: kept " << reuse_db << " dBsm, traced " << fresh_db
              << ", closed form " << expected_db << (r.stats.reused_bundles ? " (kept)" : "")
              << "\n";
    EXPECT_NEAR(reuse_db, fresh_db, bound_db) << step;
    EXPECT_NEAR(reuse_db, expected_db, 0.5) << step;
  }
  EXPECT_GE(reused, 6u);  // most steps used kept paths
}

TEST(SbrReuse, EachRuleThatCallsForANewTraceDoes) {
  const double f = 10e9, rho = 1000.0, spacing = 0.05;
  const rd::SbrConfig c = config(f, spacing);
  const double w = 0.5 / std::sqrt(2.0);
  const double limit = limit_rad(c, spacing, std::sqrt(5 * w * w + 1.0));
  auto reused_after = [&](sc::Scene& scene, const rd::RadarPose& second,
                          const rd::TraceKnobs& knobs = {}) {
    rd::SbrTracer tracer(scene, c);
    (void)trace(tracer, pose_around(rho, 0.0));
    return trace(tracer, second, knobs).stats.reused_bundles;
  };
  sc::Scene still(with({dihedral(1.0, 0.5)}));
  // Within the aspect limit: kept; past it: traced.
  EXPECT_EQ(reused_after(still, pose_around(rho, 0.5 * limit)), 1u);
  EXPECT_EQ(reused_after(still, pose_around(rho, 1.5 * limit)), 0u);
  // The antenna rolled (its polarisation basis turned) past the limit: traced.
  rd::RadarPose rolled = pose_around(rho, 0.0);
  const double roll = 1.5 * limit;
  const glm::dvec3 right = rolled.world_from_antenna[1], down = rolled.world_from_antenna[2];
  rolled.world_from_antenna[1] = std::cos(roll) * right + std::sin(roll) * down;
  rolled.world_from_antenna[2] = -std::sin(roll) * right + std::cos(roll) * down;
  EXPECT_EQ(reused_after(still, rolled), 0u);
  // Another bundle spacing this frame (the governor's knob): traced.
  const std::vector<double> coarser = {2.0 * spacing};
  rd::TraceKnobs knobs;
  knobs.target_ray_spacing_m = coarser;
  EXPECT_EQ(reused_after(still, pose_around(rho, 0.0), knobs), 0u);
  // A moving object across the line of sight: traced; a moving one far off it: kept.
  sc::Scene crossing(with({dihedral(1.0, 0.5), plate(0.3, {0.0, -500.0, 0.0}, {1.0, 0.0, 0.0})}));
  EXPECT_EQ(reused_after(crossing, pose_around(rho, 0.0)), 0u);
  sc::Scene aside(with({dihedral(1.0, 0.5), plate(0.3, {300.0, -500.0, 0.0}, {1.0, 0.0, 0.0})}));
  EXPECT_EQ(reused_after(aside, pose_around(rho, 0.0)), 1u);
}

TEST(SbrReuse, TheRefreshTracesTheLongestKeptFirst) {
  // Eight equal dihedrals, reuse_refresh_frames = 4, a still radar: each frame traces again the
  // two longest kept (ceil(8 / 4) bundles' rays), so every bundle is traced every 4 frames and
  // the oldest kept paths in use are 3 frames old.
  const double f = 10e9, rho = 1000.0;
  sc::Scene scene(eight_dihedrals());
  rd::SbrConfig c = config(f, 0.05);
  c.reuse_refresh_frames = 4;
  c.reuse_refresh_slices = 1;  // whole bundles (TheRefreshGoesASliceAtATime: slices)
  rd::SbrTracer tracer(scene, c);
  const rd::RadarPose pose = pose_around(rho, 0.0);
  const Frame first = trace(tracer, pose);
  ASSERT_EQ(first.stats.target_bundles, 8u);
  const std::uint64_t rays_per_bundle = first.stats.rays / 8;
  for (int frame = 1; frame <= 12; ++frame) {
    const Frame x = trace(tracer, pose);
    EXPECT_EQ(x.stats.reused_bundles, 6u) << frame;
    EXPECT_EQ(x.stats.refreshed_bundles, 2u) << frame;
    EXPECT_NEAR(static_cast<double>(x.stats.rays), 2.0 * static_cast<double>(rays_per_bundle),
                0.02 * static_cast<double>(first.stats.rays))
        << frame;
    if (frame >= 4) {
      EXPECT_EQ(x.stats.reuse_max_age_frames, 3u) << frame;
    }
  }
}

TEST(SbrReuse, TheRefreshGoesASliceAtATime) {
  // One trihedral, a still radar, reuse_refresh_frames = 4 and 4 slices: after the first frame
  // each refresh traces one slice of the bundle's rows (about a quarter of its rays), the other
  // three slices' kept paths are re-evaluated, and every frame gives the first frame's returns
  // back: the slices' rows together are each row once (a row missed or counted twice changes
  // the count and the coherent sums). Over 8 frames each slice is traced about twice.
  const double f = 10e9;
  const double k = 2.0 * kPi * f / kC;
  sc::Scene scene(with({trihedral(0.5)}));
  rd::SbrConfig c = config(f, 0.02);
  c.reuse_refresh_frames = 4;
  c.reuse_refresh_slices = 4;
  rd::SbrTracer tracer(scene, c);
  const rd::RadarPose pose = pose_around(1000.0, 0.0);
  const Frame first = trace(tracer, pose);
  const auto all_rays = static_cast<double>(first.stats.rays);
  ASSERT_GT(all_rays, 1000.0);
  double traced = 0.0;
  for (int frame = 1; frame <= 8; ++frame) {
    const Frame x = trace(tracer, pose);
    EXPECT_EQ(x.stats.reused_bundles, 1u) << frame;
    EXPECT_LE(static_cast<double>(x.stats.rays), 0.3 * all_rays) << frame;
    // A slice with more than a quarter of the rays (the trihedral is narrower in its top and
    // bottom rows) waits a frame more for its credit.
    EXPECT_LE(x.stats.reuse_max_age_frames, 5u) << frame;
    traced += static_cast<double>(x.stats.rays);
    ASSERT_EQ(x.out.size(), first.out.size()) << frame;
    for (int bounces = 1; bounces <= 3; ++bounces) {
      const std::complex<double> a = sum(first, bounces, k, 1000.0), b = sum(x, bounces, k, 1000.0);
      EXPECT_LE(std::abs(a - b), 1e-9 * std::abs(a) + 1e-12) << frame << " " << bounces;
    }
  }
  EXPECT_NEAR(traced, 2.0 * all_rays, 0.3 * all_rays);
}

// The climb of the next three tests: a trihedral (a = 0.5 m, 10 GHz, spacing 0.02 m, 4 slices)
// traced once with the radar at 1 km level with it, then for `frames` frames climbing around it
// by 0.15 of limit_rad a frame, which is 0.22 of the tracer's own limit (its grid's tube is a
// little finer than the spacing). Every frame after the first re-evaluates kept paths, none in
// use past its limit, and its triple-bounce sum stays within reuse_max_phase_rad's bound
// (0.69 dB) of a fresh trace's of the same pose. Returns the first frame's rays and each later
// frame's.
struct Climb {
  double first_rays = 0.0;
  std::vector<double> rays;
};

Climb climb(int refresh_frames, bool mask, int frames) {
  const double f = 10e9, k = 2.0 * kPi * f / kC, rho = 1000.0, spacing = 0.02;
  sc::Scene scene(with({trihedral(0.5)}));
  rd::SbrConfig c = config(f, spacing);
  c.reuse_refresh_frames = refresh_frames;
  c.reuse_refresh_slices = 4;
  c.mask_target_rays = mask;
  rd::SbrConfig fresh_config = c;
  fresh_config.reuse_static_paths = false;
  rd::SbrTracer reuse(scene, c), fresh(scene, fresh_config);
  const double limit = limit_rad(c, spacing, std::sqrt(3.0) * 0.5);
  const double bound_db = 20 * std::log10(1.0 / std::cos(c.reuse_max_phase_rad));
  Climb out;
  out.first_rays = static_cast<double>(trace(reuse, pose_above(rho, 0.0, 0.0)).stats.rays);
  for (int frame = 1; frame <= frames; ++frame) {
    const rd::RadarPose pose = pose_above(rho, 0.0, 0.15 * limit * frame);
    const Frame r = trace(reuse, pose), t = trace(fresh, pose);
    out.rays.push_back(static_cast<double>(r.stats.rays));
    EXPECT_EQ(r.stats.reused_bundles, 1u) << frame;
    EXPECT_LE(r.stats.reuse_max_angle_fraction, 1.0) << frame;
    const double reuse_db = 10 * std::log10(std::norm(sum(r, 3, k, rho)));
    const double fresh_db = 10 * std::log10(std::norm(sum(t, 3, k, rho)));
    EXPECT_NEAR(reuse_db, fresh_db, bound_db) << frame;
  }
  return out;
}

TEST(SbrReuse, AKeptTargetKeepsItsRowsWhenItsGridAsksForOneMore) {
  // The climb with reuse_refresh_frames = 4 and every column of every row shot (rays = columns
  // x rows): over it the trihedral's box grows in elevation and a fresh grid gets another row
  // (40 x 40 rays at the start, 40 x 41 at the top). The bundle keeps the rows its slices were
  // traced with (one row off is within the slack), so its refresh still goes a slice at a
  // time: no frame after the first traces more than a third of its rays (a whole trace would).
  const int frames = 30;
  const Climb c = climb(4, false, frames);
  for (std::size_t i = 0; i < c.rays.size(); ++i)
    EXPECT_LE(c.rays[i], c.first_rays / 3.0) << i + 1;
  // The fresh grid at the top of the climb: one row more (a row is a few % of the rays).
  rd::SbrConfig fresh_config = config(10e9, 0.02);
  fresh_config.reuse_static_paths = false;
  fresh_config.mask_target_rays = false;
  sc::Scene scene(with({trihedral(0.5)}));
  rd::SbrTracer fresh(scene, fresh_config);
  const double limit = limit_rad(fresh_config, 0.02, std::sqrt(3.0) * 0.5);
  const auto top_rays =
      static_cast<double>(trace(fresh, pose_above(1000.0, 0.0, 0.15 * limit * frames)).stats.rays);
  std::cout << "rays at the start " << c.first_rays << ", at the top " << top_rays << "\n";
  EXPECT_GT(top_rays, c.first_rays);
  EXPECT_LT(top_rays, 1.1 * c.first_rays);
}

TEST(SbrReuse, ASlicePastTheAspectLimitIsTracedAlone) {
  // The climb with reuse_refresh_frames = 5: the refresh's credit traces a slice about every
  // frame and a quarter, so the longest kept slice passes the limit (5 frames x 0.22) before
  // its turn while the others are younger. That slice is traced again alone, the others kept:
  // no frame after the first traces more than a third of the rays (tracing the whole bundle
  // would put its slices back in step, to pass the limit together again).
  const Climb c = climb(5, true, 24);
  for (std::size_t i = 0; i < c.rays.size(); ++i)
    EXPECT_LE(c.rays[i], c.first_rays / 3.0) << i + 1;
}

TEST(SbrReuse, SlicesPastTheAspectLimitTogetherAreTracedWithoutTheOthers) {
  // The climb with reuse_refresh_frames = 8: the credit traces a slice about every other frame,
  // so after a whole trace the last two slices, traced in the same frame, pass the limit
  // together (5 frames x 0.22). Those two are traced again, the first two kept: no frame after
  // the first traces more than 60 % of the rays (the two are about half of them), none the
  // whole bundle.
  const Climb c = climb(8, true, 24);
  double most = 0.0;
  for (std::size_t i = 0; i < c.rays.size(); ++i) {
    EXPECT_LE(c.rays[i], 0.6 * c.first_rays) << i + 1;
    most = std::max(most, c.rays[i]);
  }
  EXPECT_GT(most, 0.4 * c.first_rays);  // two slices at once happened
}

TEST(SbrReuse, ATargetLeavingTheViewInElevationIsRefreshedASliceAtATime) {
  // The trihedral of ATargetLeavingTheViewKeepsItsPathsAndLeavesOutThoseThatHaveLeft at 30 m,
  // on the lower elevation edge of the view (the antenna pitched up by 0.05 rad), the radar
  // climbing 2 cm a frame (0.67 mrad, 0.06 of the aspect limit), so that the target leaves the
  // bottom of the view (from a half in view to a fifth over 12 frames), with
  // reuse_refresh_frames = 4. Its grid is its whole box's, of which the rows in view are shot
  // (bundle_for), so its slices stay put as the cut moves: it is refreshed a slice at a time,
  // never whole, its kept paths that leave the view are left out also in the frames that trace
  // a slice, and what it keeps gives the triple bounce of a fresh trace from each pose, to two
  // rows of tubes at the cut edge (by which slices traced from different poses and a fresh
  // grid can differ). Fails if a cut target is traced whole, if its grid is cut with the view
  // (its slices then move), or if a frame that traces a slice keeps the others' paths that
  // have left the view.
  const double f = 10e9, k = 2.0 * kPi * f / kC, rho = 30.0, spacing = 0.02, pitch = 0.05;
  rd::SbrConfig c = config(f, spacing);
  c.reuse_refresh_frames = 4;
  c.reuse_refresh_slices = 4;
  rd::SbrConfig fresh_config = c;
  fresh_config.reuse_static_paths = false;
  auto pose_at = [&](double h_m) {
    rd::RadarPose p;
    const glm::dvec3 look(0.0, std::cos(pitch), std::sin(pitch));
    const glm::dvec3 right = glm::normalize(glm::cross(glm::dvec3(0, 0, -1), look));
    p.position_m = {0.0, -rho, h_m};
    p.world_from_antenna = glm::dmat3(look, right, glm::cross(look, right));
    return p;
  };
  sc::Scene scene(with({trihedral(0.5)}));
  rd::SbrTracer kept(scene, c), fresh(scene, fresh_config);
  const Frame first = trace(kept, pose_at(0.0));
  ASSERT_EQ(first.stats.target_bundles, 1u);
  const auto first_rays = static_cast<double>(first.stats.rays);
  std::uint64_t left_view = 0;
  const double row = std::ceil(0.75 / spacing);  // the target's width over the spacing
  for (int frame = 1; frame <= 12; ++frame) {
    const rd::RadarPose pose = pose_at(0.02 * frame);
    const Frame r = trace(kept, pose), t = trace(fresh, pose);
    const double share = 2.0 * row / static_cast<double>(t.stats.rays);
    left_view += r.stats.kept_paths_left_view;
    const std::complex<double> s_kept = sum(r, 3, k, rho), s_traced = sum(t, 3, k, rho);
    std::printf("frame %d: rays %llu of %g, left %llu, triple %g vs %g, fresh rays %llu\n", frame,
                static_cast<unsigned long long>(r.stats.rays), first_rays,
                static_cast<unsigned long long>(r.stats.kept_paths_left_view), std::abs(s_kept),
                std::abs(s_traced), static_cast<unsigned long long>(t.stats.rays));
    EXPECT_EQ(r.stats.reused_bundles, 1u) << frame;
    EXPECT_LE(static_cast<double>(r.stats.rays), 0.55 * first_rays) << frame;
    EXPECT_NEAR(std::abs(s_kept), std::abs(s_traced), share * std::abs(s_traced)) << frame;
    EXPECT_LE(r.stats.reuse_max_angle_fraction, 1.0) << frame;
  }
  EXPECT_GT(left_view, 0u);
}

TEST(SbrReuse, FacetsTurningToTheRaysTraceTheBundleWholeAlsoWhenASliceWasDue) {
  // A dihedral (faces 1 m x 0.5 m, each two right triangles whose farthest vertex is rho =
  // 0.687 m from the centroid) at 10 GHz: its facets are integrated by the facet pass beyond
  // R_ff = 8 k rho^2 / pi (facet_in_far_field, 252 m) and left to the rays nearer. The radar
  // keeps its paths for n frames at 1.01 R_ff, then steps along its boresight to 0.99 R_ff: the
  // kept paths hold no bounce-1 return on the facets the rays now sample, so the reuse rule's
  // last condition (the same facets left to the rays) traces the bundle whole, also in a frame
  // where one of its 4 slices was due for refresh. That frame equals a tracer's without reuse
  // at that pose. Control: the same n frames then a step to 1.005 R_ff (no facet turns) refresh
  // one slice only, for some n; that is the frame the rule must not skip.
  const double f = 10e9;
  const double k = 2.0 * kPi * f / kC;
  const double rho =
      std::hypot(0.5 / 3.0, 2.0 / 3.0);  // to the vertex (0.5, 1) of (0, 0), (0.5, 0)
  const double r_ff = 8.0 * k * rho * rho / kPi;
  sc::Scene scene(with({dihedral(1.0, 0.5)}));
  rd::SbrConfig c = config(f, 0.05);
  c.reuse_refresh_frames = 4;
  c.reuse_refresh_slices = 4;
  rd::SbrConfig every_ray = c;
  every_ray.reuse_static_paths = false;
  auto energy = [](const Frame& x, int bounces) {
    double e = 0.0;
    for (const rd::Contribution& q : x.out)
      e += q.bounces == bounces ? std::norm(q.amplitude) : 0.0;
    return e;
  };
  int slice_frames = 0;
  for (int n = 1; n <= 4; ++n) {
    auto after = [&](double step_to) {
      rd::SbrTracer tracer(scene, c);
      for (int frame = 0; frame <= n; ++frame)
        (void)trace(tracer, pose_around(1.01 * r_ff, 0.0));
      return trace(tracer, pose_around(step_to, 0.0));
    };
    const Frame control = after(1.005 * r_ff);
    rd::SbrTracer fresh(scene, c);
    const auto all_rays =
        static_cast<double>(trace(fresh, pose_around(1.005 * r_ff, 0.0)).stats.rays);
    if (control.stats.rays > 0 && static_cast<double>(control.stats.rays) < 0.5 * all_rays)
      ++slice_frames;
    EXPECT_EQ(control.stats.reused_bundles, 1u) << n;
    const Frame x = after(0.99 * r_ff);
    rd::SbrTracer reference(scene, every_ray);
    const Frame ref = trace(reference, pose_around(0.99 * r_ff, 0.0));
    EXPECT_EQ(x.stats.reused_bundles, 0u) << n;
    EXPECT_EQ(x.stats.rays, ref.stats.rays) << n;
    ASSERT_EQ(x.out.size(), ref.out.size()) << n;
    for (int bounces = 1; bounces <= 3; ++bounces) {
      const std::complex<double> a = sum(ref, bounces, k, r_ff), b = sum(x, bounces, k, r_ff);
      EXPECT_LE(std::abs(a - b), 1e-9 * std::abs(a) + 1e-12) << n << " " << bounces;
      EXPECT_NEAR(energy(x, bounces), energy(ref, bounces), 1e-9 * energy(ref, bounces) + 1e-24)
          << n << " " << bounces;
    }
  }
  std::printf("R_ff %.1f m; frames where the control refreshed one slice: %d of 4\n", r_ff,
              slice_frames);
  EXPECT_GE(slice_frames, 1);
}

TEST(SbrReuse, ADeferredRefreshWaitsUntilAKeptBundleIsTwiceItsPeriodOld) {
  // The same eight dihedrals, reuse_refresh_frames = 4, once every bundle was traced (frame 0)
  // and each refreshed on its turn (frames 1-4). With TraceKnobs::defer_refresh every frame, the
  // refresh waits, the credit with it: nothing is traced while the oldest kept bundle is less
  // than 2 x 4 = 8 frames old; when it reaches 8, the refresh goes on (two bundles, the
  // credit's share of one frame), deferred or not. A frame without the knob right after
  // refreshes as usual.
  const double f = 10e9, rho = 1000.0;
  sc::Scene scene(eight_dihedrals());
  rd::SbrConfig c = config(f, 0.05);
  c.reuse_refresh_frames = 4;
  c.reuse_refresh_slices = 1;  // whole bundles (TheRefreshGoesASliceAtATime: slices)
  rd::SbrTracer tracer(scene, c);
  const rd::RadarPose pose = pose_around(rho, 0.0);
  for (int frame = 0; frame <= 4; ++frame)
    (void)trace(tracer, pose);
  rd::TraceKnobs defer;
  defer.defer_refresh = true;
  int waited = 0;
  for (;;) {
    const Frame x = trace(tracer, pose, defer);
    ASSERT_EQ(x.stats.refresh_deferred, 1u);
    if (x.stats.refreshed_bundles > 0) {
      EXPECT_EQ(x.stats.refreshed_bundles, 2u);
      break;
    }
    EXPECT_EQ(x.stats.rays, 0u) << waited;
    EXPECT_EQ(x.stats.reused_bundles, 8u) << waited;
    ++waited;
    ASSERT_LT(waited, 20);
  }
  // The oldest was refreshed at frame 1 (3 frames old at frame 4); it waits until 8 frames old.
  EXPECT_EQ(waited, 4);
  const Frame after = trace(tracer, pose);
  EXPECT_EQ(after.stats.refresh_deferred, 0u);
  EXPECT_EQ(after.stats.refreshed_bundles, 2u);
}

TEST(SbrReuse, KeptPathsDoNotDependOnTheThreads) {
  // A moving radar over eight dihedrals (traced, kept, refreshed in turn): every frame's returns
  // are bit-identical on one thread and on all of them.
  sc::Scene scene(eight_dihedrals());
  rd::SbrConfig c = config(10e9, 0.05);
  c.reuse_refresh_frames = 3;
  auto run = [&](std::size_t threads) {
    tbb::global_control limit(tbb::global_control::max_allowed_parallelism, threads);
    rd::SbrTracer tracer(scene, c);
    std::vector<Frame> frames;
    for (int frame = 0; frame < 6; ++frame)
      frames.push_back(trace(tracer, pose_around(1000.0, 2e-4 * frame)));
    return frames;
  };
  const std::vector<Frame> one = run(1), all = run(static_cast<std::size_t>(
                                             std::max(2, tbb::info::default_concurrency())));
  std::uint64_t reused = 0;
  for (std::size_t f = 0; f < one.size(); ++f) {
    reused += one[f].stats.reused_bundles;
    ASSERT_EQ(one[f].out.size(), all[f].out.size()) << f;
    for (std::size_t i = 0; i < one[f].out.size(); ++i) {
      const rd::Contribution &a = one[f].out[i], &b = all[f].out[i];
      ASSERT_EQ(a.amplitude, b.amplitude) << f << " " << i;
      ASSERT_EQ(a.range_m, b.range_m) << f << " " << i;
      ASSERT_EQ(a.azimuth_rad, b.azimuth_rad) << f << " " << i;
      ASSERT_EQ(a.radial_velocity_mps, b.radial_velocity_mps) << f << " " << i;
    }
  }
  EXPECT_GT(reused, 10u);
}

namespace {
// An a x a plate at `at`, cut into n x n squares of two triangles each, moving at `velocity`
// (LinearMotion, which turns body x along the horizontal velocity): the plate lies in the body
// y-z plane, so across a velocity along the world y axis it lies in the world x-z plane.
sc::ObjectDesc grid_plate(double a, int n, glm::dvec3 at, glm::dvec3 velocity) {
  sc::ObjectDesc o{"grid_plate", {}, glm::dmat4(1.0), std::nullopt};
  for (int i = 0; i <= n; ++i) {
    for (int j = 0; j <= n; ++j)
      o.mesh.positions_m.push_back({0.0F,
                                    static_cast<float>(a * (i / static_cast<double>(n) - 0.5)),
                                    static_cast<float>(a * (j / static_cast<double>(n) - 0.5))});
  }
  auto v = [&](int i, int j) { return static_cast<unsigned>(i * (n + 1) + j); };
  for (int i = 0; i < n; ++i) {
    for (int j = 0; j < n; ++j) {
      o.mesh.triangles.push_back({v(i, j), v(i + 1, j), v(i + 1, j + 1)});
      o.mesh.triangles.push_back({v(i, j), v(i + 1, j + 1), v(i, j + 1)});
    }
  }
  o.mesh.triangle_material.assign(o.mesh.triangles.size(), 0);
  o.world_from_body[3] = glm::dvec4(at, 1.0);
  o.motion = sc::LinearMotion{at, velocity};
  return o;
}

std::vector<std::complex<double>> bounce1(const Frame& fr) {
  std::vector<std::complex<double>> a;
  for (const rd::Contribution& x : fr.out) {
    if (x.bounces == 1)
      a.push_back(x.amplitude);
  }
  return a;
}

// The same facets lit and partly lit, and the same bounce-1 returns to 1e-9 (at least `min`).
void expect_same_bounce1(const Frame& a, const Frame& b, std::size_t min = 3) {
  EXPECT_EQ(a.stats.lit_facets, b.stats.lit_facets);
  EXPECT_EQ(a.stats.partial_facets, b.stats.partial_facets);
  const std::vector<std::complex<double>> x = bounce1(a), y = bounce1(b);
  ASSERT_EQ(x.size(), y.size());
  ASSERT_GE(x.size(), min);
  for (std::size_t i = 0; i < x.size(); ++i)
    EXPECT_LE(std::abs(x[i] - y[i]), 1e-9 * std::abs(y[i])) << i;
}
}  // namespace

TEST(SbrReuse, AMoversFacetsReadTheirShadowsBackWhileItsMotionStaysWithinHalfATube) {
  // A 1 m plate moving toward the radar along the line of sight, partly shadowed by a static
  // 0.3 m plate 2 m in front of it, off centre (its facets cut into sub-triangles, each with a
  // query). The mover's facets keep their occlusion answers (SbrTracer's facet memo of movers)
  // while its displacement plus D times its aspect change stays within half a ray tube. Moved
  // by 0.8 of half a tube along the line of sight (no aspect change), its facets read their
  // answers back, no query asked, and give the bounce-1 returns of a fresh trace at that time
  // to 1e-9; moved by 1.25 of it, they ask the scene again. Likewise a radar turned by 0.8 and
  // 1.25 of the aspect limit with the mover at rest (at 1e-3 of it, the fresh trace's returns).
  const double f = 10e9, rho = 1000.0, spacing = 0.05, speed = 0.01;
  auto scene_with = [&](std::vector<sc::ObjectDesc> more) {
    std::vector<sc::ObjectDesc> objects = {grid_plate(1.0, 1, {0.0, 0.0, 0.0}, {0.0, -speed, 0.0}),
                                           plate(0.3, {0.4, -2.0, 0.0})};
    for (sc::ObjectDesc& o : more)
      objects.push_back(std::move(o));
    return with(std::move(objects));
  };
  sc::Scene scene(scene_with({}));
  const rd::SbrConfig c = config(f, spacing);
  rd::SbrConfig fresh_config = c;
  fresh_config.reuse_static_paths = false;
  const double half_tube_m = 0.5 * spacing;
  // Records at t = 0, then traces at time t_s and pose `second`.
  auto second_frame = [&](sc::Scene& s, double t_s, const rd::RadarPose& second) {
    rd::SbrTracer tracer(s, c);
    s.set_time(0.0);
    const Frame first = trace(tracer, pose_around(rho, 0.0));
    EXPECT_GT(first.stats.facet_queries, 100u);
    EXPECT_GE(first.stats.partial_facets, 1u);
    EXPECT_EQ(first.stats.replayed_mover_facets, 0u);
    s.set_time(t_s);
    return trace(tracer, second);
  };
  auto fresh_frame = [&](sc::Scene& s, double t_s, const rd::RadarPose& pose) {
    rd::SbrTracer tracer(s, fresh_config);
    s.set_time(t_s);
    return trace(tracer, pose);
  };
  const rd::RadarPose ahead = pose_around(rho, 0.0);
  // Displacement: the mover's two facets (groups 0 and 1; frame 2's turn is group 2) read back.
  const double inside_s = 0.8 * half_tube_m / speed, past_s = 1.25 * half_tube_m / speed;
  const Frame moved = second_frame(scene, inside_s, ahead);
  EXPECT_EQ(moved.stats.replayed_mover_facets, 2u);
  EXPECT_EQ(moved.stats.facet_queries, 0u);
  expect_same_bounce1(moved, fresh_frame(scene, inside_s, ahead));
  const Frame moved_past = second_frame(scene, past_s, ahead);
  EXPECT_EQ(moved_past.stats.replayed_mover_facets, 0u);
  EXPECT_GT(moved_past.stats.facet_queries, 100u);
  // Aspect: the mover at rest (t = 0), the radar turned about it. The static plate's own limit
  // is the larger (its extent is smaller), so its facets read back at both.
  const double limit = limit_rad(c, spacing, std::sqrt(2.0));
  const rd::RadarPose barely = pose_around(rho, 1e-3 * limit);
  const Frame turned_barely = second_frame(scene, 0.0, barely);
  EXPECT_EQ(turned_barely.stats.replayed_mover_facets, 2u);
  EXPECT_EQ(turned_barely.stats.facet_queries, 0u);
  expect_same_bounce1(turned_barely, fresh_frame(scene, 0.0, barely));
  EXPECT_EQ(second_frame(scene, 0.0, pose_around(rho, 0.8 * limit)).stats.replayed_mover_facets,
            2u);
  const Frame turned_past = second_frame(scene, 0.0, pose_around(rho, 1.25 * limit));
  EXPECT_EQ(turned_past.stats.replayed_mover_facets, 0u);
  EXPECT_GT(turned_past.stats.facet_queries, 100u);
  // Another mover (a 0.3 m plate, its own facets read back: nothing moves near it) across the
  // line of sight: the big plate's facets ask again every frame; far off it: they read back.
  sc::Scene crossing(scene_with({plate(0.3, {0.0, -500.0, 0.0}, {1e-3, 0.0, 0.0})}));
  const Frame crossed = second_frame(crossing, 0.0, ahead);
  EXPECT_EQ(crossed.stats.replayed_mover_facets, 2u);
  EXPECT_GT(crossed.stats.facet_queries, 100u);
  sc::Scene aside(scene_with({plate(0.3, {300.0, -500.0, 0.0}, {1e-3, 0.0, 0.0})}));
  const Frame beside = second_frame(aside, 0.0, ahead);
  EXPECT_EQ(beside.stats.replayed_mover_facets, 2u);  // the other is out of the view
  EXPECT_EQ(beside.stats.facet_queries, 0u);
}

TEST(SbrReuse, AMoversFacetsAskTheSceneAgainOneGroupAFrame) {
  // A 4 x 4-square plate (32 facets, all lit) moving slowly toward the radar: the first frame
  // asks every facet's seven samples; each later frame asks again only the facets t of its turn,
  // t % 16 == frame % 16 (2 of 32), and reads the others back: 1/16 of the first frame's queries.
  const double f = 10e9, rho = 1000.0;
  sc::Scene scene(with({grid_plate(1.0, 4, {0.0, 0.0, 0.0}, {0.0, -1e-3, 0.0})}));
  rd::SbrTracer tracer(scene, config(f, 0.05));
  const rd::RadarPose pose = pose_around(rho, 0.0);
  scene.set_time(0.0);
  const Frame first = trace(tracer, pose);
  ASSERT_EQ(first.stats.lit_facets, 32u);
  EXPECT_EQ(first.stats.facet_queries, 32u * 7u);
  for (int frame = 1; frame <= 20; ++frame) {
    scene.set_time(0.01 * frame);
    const Frame x = trace(tracer, pose);
    EXPECT_EQ(x.stats.lit_facets, 32u) << frame;
    EXPECT_EQ(x.stats.facet_queries, first.stats.facet_queries / 16) << frame;
    EXPECT_EQ(x.stats.mover_facets, 32u) << frame;
    EXPECT_EQ(x.stats.replayed_mover_facets, 30u) << frame;
  }
}

TEST(SbrReuse, AMoversFacetsAskAgainWhenItHasTurnedPastTheLimit) {
  // A 1 m plate on a waypoint trajectory through a 90 degree turn of radius 5 cm at 1 m/s (body x
  // along the path: the plate turns with it). Recorded 1 cm into the turn, then traced 1 cm
  // later: it has moved 1 cm (0.4 of half a 5 cm tube) but turned by 0.2 rad, which moves its
  // edges by about 0.1 m and its self-shadowing by D phi: its facets ask the scene again. 10 um
  // later instead (a turn of 2e-4 rad, phi (D + r) = 0.4 mm), they read their answers back.
  const double f = 10e9, rho = 1000.0, spacing = 0.05, r = 0.05;
  sc::ObjectDesc mover = grid_plate(1.0, 1, {0.0, 0.0, 0.0}, {0.0, 1.0, 0.0});
  mover.motion.reset();
  mover.trajectory = sc::Trajectory{{{-1.0, 0.0, 0.0}, {0.0, 0.0, 0.0}, {0.0, 1.0, 0.0}}, 1.0, r};
  sc::Scene scene(with({mover}));
  const double into_turn_s = (1.0 - r) + 0.01;  // the turn starts r before the corner
  const rd::RadarPose pose = pose_around(rho, 0.0);
  auto second = [&](double dt_s) {
    rd::SbrTracer tracer(scene, config(f, spacing));
    scene.set_time(into_turn_s);
    const Frame first = trace(tracer, pose);
    EXPECT_EQ(first.stats.facet_queries, 14u);  // two facets lit whole: 7 samples each
    scene.set_time(into_turn_s + dt_s);
    return trace(tracer, pose);
  };
  const Frame turned = second(0.01);
  EXPECT_EQ(turned.stats.replayed_mover_facets, 0u);
  EXPECT_EQ(turned.stats.facet_queries, 14u);
  const Frame barely = second(1e-5);
  EXPECT_EQ(barely.stats.replayed_mover_facets, 2u);
  EXPECT_EQ(barely.stats.facet_queries, 0u);
}

TEST(SbrReuse, AMoversFacetsReadTheirOwnShadowsBackAndAskTheSceneWhenItHasMovedFurther) {
  // One mover of two parallel plates facing the radar: a 1 m back plate (a 4 x 4 grid, 32
  // facets) and a 0.3 m plate 0.5 m in front of it and off centre, which shadows part of it
  // (its own body). A static 0.3 m plate 2 m in front shadows another part (the scene). The
  // mover moves toward the radar along the line of sight by 1.25 of half a ray tube: the scene's
  // shadow on it has moved too far for its answers to be read back, but its own shadow has not
  // moved (its aspect is the same). Its facets outside this frame's turn read back which of
  // their samples its own body blocked and ask the rest of the scene for the others: fewer
  // queries than a fresh trace, and the fresh trace's bounce-1 returns to 1e-9. With the radar
  // also turned by 1.25 of the aspect limit, its own shadows have moved too: everything asked.
  const double f = 10e9, rho = 1000.0, spacing = 0.05, speed = 0.01;
  const double half_tube_m = 0.5 * spacing;
  sc::ObjectDesc mover{"two_plates", {}, glm::dmat4(1.0), std::nullopt};
  const int n = 4;
  for (int i = 0; i <= n; ++i)
    for (int j = 0; j <= n; ++j)
      mover.mesh.positions_m.push_back(
          {0.0F, static_cast<float>(i / double{n} - 0.5), static_cast<float>(j / double{n} - 0.5)});
  auto v = [&](int i, int j) { return static_cast<unsigned>(i * (n + 1) + j); };
  for (int i = 0; i < n; ++i) {
    for (int j = 0; j < n; ++j) {
      mover.mesh.triangles.push_back({v(i, j), v(i + 1, j), v(i + 1, j + 1)});
      mover.mesh.triangles.push_back({v(i, j), v(i + 1, j + 1), v(i, j + 1)});
    }
  }
  const auto base = static_cast<unsigned>(mover.mesh.positions_m.size());
  // Body x is along the motion (sc::LinearMotion), toward the radar: the plates' normal.
  for (const glm::vec3 c : {glm::vec3{0.5F, 0.1F, 0.1F}, glm::vec3{0.5F, 0.4F, 0.1F},
                            glm::vec3{0.5F, 0.4F, 0.4F}, glm::vec3{0.5F, 0.1F, 0.4F}})
    mover.mesh.positions_m.push_back(c);
  mover.mesh.triangles.push_back({base, base + 1, base + 2});
  mover.mesh.triangles.push_back({base, base + 2, base + 3});
  mover.mesh.triangle_material.assign(mover.mesh.triangles.size(), 0);
  mover.motion = sc::LinearMotion{glm::dvec3(0.0), {0.0, -speed, 0.0}};
  sc::Scene scene(with({mover, plate(0.3, {-0.25, -2.0, -0.2})}));
  const rd::SbrConfig c = config(f, spacing);
  rd::SbrConfig fresh_config = c;
  fresh_config.reuse_static_paths = false;
  const double moved_s = 1.25 * half_tube_m / speed;
  auto second_frame = [&](const rd::RadarPose& second, sc::Scene& s) {
    rd::SbrTracer tracer(s, c);
    s.set_time(0.0);
    const Frame first = trace(tracer, pose_around(rho, 0.0));
    EXPECT_EQ(first.stats.self_replayed_mover_facets, 0u);
    EXPECT_GE(first.stats.partial_facets, 2u);  // one shadow of each
    s.set_time(moved_s);
    return trace(tracer, second);
  };
  auto fresh_frame = [&](const rd::RadarPose& pose, sc::Scene& s) {
    rd::SbrTracer tracer(s, fresh_config);
    s.set_time(moved_s);
    return trace(tracer, pose);
  };
  const rd::RadarPose ahead = pose_around(rho, 0.0);
  const Frame moved = second_frame(ahead, scene), fresh = fresh_frame(ahead, scene);
  std::printf("moved: %llu of %llu facets read their own shadows back, %llu queries (fresh %llu)\n",
              static_cast<unsigned long long>(moved.stats.self_replayed_mover_facets),
              static_cast<unsigned long long>(moved.stats.mover_facets),
              static_cast<unsigned long long>(moved.stats.facet_queries),
              static_cast<unsigned long long>(fresh.stats.facet_queries));
  EXPECT_EQ(moved.stats.replayed_mover_facets, 0u);
  EXPECT_EQ(moved.stats.mover_facets, 34u);
  EXPECT_GE(moved.stats.self_replayed_mover_facets, 30u);  // all but this frame's turn
  EXPECT_LT(moved.stats.facet_queries, fresh.stats.facet_queries);
  expect_same_bounce1(moved, fresh, 20);
  // Turned past the aspect limit of the mover's region (its 1.03 m diagonal).
  const double limit = 0.5 * spacing / std::sqrt(1.0 + 0.25 + 1.0 / 16.0);
  const Frame turned = second_frame(pose_around(rho, 1.25 * limit), scene);
  EXPECT_EQ(turned.stats.self_replayed_mover_facets, 0u);
  EXPECT_EQ(turned.stats.replayed_mover_facets, 0u);
  // Another mover (a 0.3 m plate) across the line of sight, 500 m out, its shadow on the two
  // plates: their own shadows are still read back, and everything else is asked, the other
  // mover included (nothing is read back whole while it is near).
  sc::Scene crossing(
      with({mover, plate(0.3, {-0.25, -2.0, -0.2}), plate(0.3, {0.0, -500.0, 0.0}, {1e-3, 0, 0})}));
  const Frame crossed = second_frame(ahead, crossing), fresh_crossed = fresh_frame(ahead, crossing);
  EXPECT_GE(crossed.stats.self_replayed_mover_facets, 30u);
  EXPECT_LE(crossed.stats.replayed_mover_facets, 2u);  // the other plate's own two, at most
  expect_same_bounce1(crossed, fresh_crossed, 20);
}

TEST(SbrFacetPass, AFacetNoLongerThanTheSpacingAsksOneSample) {
  // A 1 m plate (two facets) seen face on, nothing in the way. The lighting rule (facet_light)
  // asks seven samples a facet; a partly lit facet is then cut into m x m sub-triangles, m its
  // longest edge over the spacing, rounded up. At a 2 m spacing m = 1: the facet is lit or dark
  // whole by its centroid's sample, the first of the seven, so it alone is asked (one query a
  // facet) and the returns are those of the centroid rule (TraceKnobs::facet_centroid_only). At
  // 0.3 m (m = 5) all seven are asked.
  sc::Scene scene(with({plate(1.0, glm::dvec3(0.0))}));
  const rd::RadarPose pose = pose_around(1000.0, 0.0);
  auto frame = [&](double spacing_m, bool centroid_only) {
    rd::SbrConfig c = config(10e9, spacing_m);
    c.reuse_static_paths = false;
    c.edges = false;
    rd::SbrTracer tracer(scene, c);
    rd::TraceKnobs knobs;
    knobs.facet_centroid_only = centroid_only;
    return trace(tracer, pose, knobs);
  };
  const Frame coarse = frame(2.0, false), centroid = frame(2.0, true), fine = frame(0.3, false);
  EXPECT_EQ(coarse.stats.facet_queries, 2u);
  EXPECT_EQ(fine.stats.facet_queries, 14u);
  ASSERT_EQ(coarse.out.size(), centroid.out.size());
  for (std::size_t i = 0; i < coarse.out.size(); ++i)
    EXPECT_EQ(coarse.out[i].amplitude, centroid.out[i].amplitude) << i;
  std::size_t facets = 0;
  for (const rd::Contribution& x : coarse.out)
    facets += x.bounces == 1 ? 1u : 0u;
  EXPECT_EQ(facets, 2u);
}

TEST(SbrReuse, ATargetLeavingTheViewKeepsItsPathsAndLeavesOutThoseThatHaveLeft) {
  // A trihedral (edge 0.5 m, 17 mrad wide at 30 m: its facets nearer than their plane-wave
  // range, so the rays light them, and none changes hands as it moves) straddling the field of
  // view's azimuth edge (-0.05 rad: the antenna turned by 0.05 rad), at 10 GHz with 2 cm tubes.
  // The radar then steps sideways so that the target leaves the view by 3.3 mrad (a fifth of
  // its width; the aspect change 0.3 of its limit): its paths are kept, the ones whose first hit
  // has left the view are left out, and what remains is what a trace from there gives, to the
  // one column of tubes at the cut edge by which the two grids' samplings can differ. Stepping
  // the other way brings more of it into view: traced.
  const double f = 10e9, k = 2.0 * kPi * f / kC, rho = 30.0, spacing = 0.02;
  const rd::SbrConfig c = config(f, spacing);
  const double yaw = 0.05;
  auto pose_at = [&](double x_m) {
    rd::RadarPose p;
    const glm::dvec3 look(std::sin(yaw), std::cos(yaw), 0.0), down(0, 0, -1);
    p.position_m = {x_m, -rho, 0.0};
    p.world_from_antenna = glm::dmat3(look, glm::cross(down, look), down);
    return p;
  };
  sc::Scene scene(with({trihedral(0.5)}));
  auto returns = [](const Frame& fr, int bounces) {
    return std::count_if(fr.out.begin(), fr.out.end(),
                         [&](const rd::Contribution& x) { return x.bounces == bounces; });
  };
  const double step_m = 0.1;  // 3.3 mrad at 30 m
  rd::SbrTracer kept(scene, c);
  const Frame first = trace(kept, pose_at(0.0));
  ASSERT_EQ(first.stats.target_bundles, 1u);
  const Frame second = trace(kept, pose_at(step_m));
  ASSERT_EQ(second.stats.reused_bundles, 1u);
  EXPECT_EQ(second.stats.rays, 0u);
  rd::SbrConfig fresh_config = c;
  fresh_config.reuse_static_paths = false;
  rd::SbrTracer fresh(scene, fresh_config);
  const Frame traced = trace(fresh, pose_at(step_m));
  const long n_first = returns(first, 3), n_kept = returns(second, 3),
             n_traced = returns(traced, 3);
  std::printf("triple-bounce returns: first %ld, kept %ld (%llu paths left out), traced %ld\n",
              n_first, n_kept, static_cast<unsigned long long>(second.stats.kept_paths_left_view),
              n_traced);
  // The step takes a fifth of the target out of view: without the pruning the kept paths would
  // be about a fifth more than the trace's.
  EXPECT_GT(second.stats.kept_paths_left_view, 0u);
  EXPECT_LT(n_kept, n_first);
  // One column of tubes: the target's height over the spacing, one return a tube.
  const long column = static_cast<long>(std::ceil(0.9 / spacing));
  EXPECT_LE(std::abs(n_kept - n_traced), column);
  // The triple bounce's coherent sum and power (the trihedral's response) within that column's
  // share of the visible returns.
  const std::complex<double> s_kept = sum(second, 3, k, rho), s_traced = sum(traced, 3, k, rho);
  const double share = static_cast<double>(column) / static_cast<double>(n_traced);
  std::printf("triple-bounce sum: kept %.4g, traced %.4g (column share %.3f)\n", std::abs(s_kept),
              std::abs(s_traced), share);
  EXPECT_NEAR(std::abs(s_kept), std::abs(s_traced), share * std::abs(s_traced));
  // Coming into view: traced.
  rd::SbrTracer entering(scene, c);
  (void)trace(entering, pose_at(0.0));
  EXPECT_EQ(trace(entering, pose_at(-step_m)).stats.reused_bundles, 0u);
}
