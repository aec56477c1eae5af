// Offline RCS engine benchmarks (issue 3): a vehicle-like target of about 25,000 facets
// (scene::TargetKind::kVehicle, 7 x 3.5 x 2.5 m) at 35 GHz.
//   BM_VehicleRangeProfile/R   one range profile: 200 frequencies 34.5-35.5 GHz, 3 bounces, edges,
//                              R/2 ray tubes per wavelength (argument R = 2 x rays per wavelength)
//   BM_Vehicle361Angles/R      361 monostatic angles (phi 0..360 deg, theta 80 deg), one frequency
//                              (35 GHz), R/2 rays per wavelength
//   BM_VehicleProfileEdges/E   the range profile at 2 rays per wavelength without (E = 0) and with
//                              edge diffraction (radar/em/edges.hpp), first order and by way of a
//                              reflection (E = 1) and with the double diffraction of edge pairs
//                              too (E = 2, the default): the cost of edges
//   BM_SbrThroughput           compute() at one frequency: ray-tube segments per second, and
//   BM_EmbreeRawThroughput     raw Embree rtcIntersect1 bouncing the very same rays, side by side
// Convergence of the profile (doubling the rays) is reported as a counter of the profile
// benchmark: RMS dB change within 20 dB of the peak.
// Run: build/bench/bench_rcs --benchmark_repetitions=3 --benchmark_report_aggregates_only=true

#include <benchmark/benchmark.h>
#include <embree3/rtcore.h>
#include <tbb/parallel_for.h>

#include <atomic>
#include <cmath>
#include <cstring>
#include <vector>

#include "radar/constants.hpp"
#include "radar/em/rcs.hpp"
#include "radar/products/range_profile.hpp"
#include "scene/scene.hpp"
#include "scene/targets.hpp"

namespace radar = radar_emu::radar;
namespace scene = radar_emu::scene;

namespace {

constexpr double kPi = radar::kPi;
const radar::Direction kAspect{80.0 * kPi / 180.0, 30.0 * kPi / 180.0};

struct Vehicle {
  scene::SceneDescription desc =
      scene::make_target({scene::TargetKind::kVehicle, 7.0, 3.5, 2.5, 0.0});
  scene::Scene scene{desc};
};
Vehicle& vehicle() {
  static Vehicle v;
  return v;
}

std::vector<double> profile_freqs() {
  std::vector<double> f(200);
  for (std::size_t i = 0; i < f.size(); ++i)
    f[i] = 34.5e9 + 1e9 * static_cast<double>(i) / 199.0;
  return f;
}

std::vector<double> profile_db(const radar::RcsEngine& engine) {
  const std::vector<double> f = profile_freqs();
  std::vector<radar::ScatteringMatrix> s(f.size());
  radar::RcsStats stats;
  engine.compute(kAspect, kAspect, f, s, stats);
  std::vector<std::complex<double>> vv(f.size());
  for (std::size_t i = 0; i < f.size(); ++i)
    vv[i] = s[i].vv;
  const radar::RangeProfile p =
      radar::range_profile(vv, {f.front(), f[1] - f[0], f.size()}, radar::Window::kHann, 1);
  std::vector<double> db(p.amplitude_m.size());
  for (std::size_t i = 0; i < db.size(); ++i)
    db[i] = radar::dbsm(p.amplitude_m[i]);
  return db;
}

// RMS of the dB difference over the samples within 20 dB of the reference's peak.
double rms_change_db(const std::vector<double>& ref, const std::vector<double>& other) {
  double peak = -1e9;
  for (double v : ref)
    peak = std::max(peak, v);
  double sum = 0.0;
  std::size_t n = 0;
  for (std::size_t i = 0; i < ref.size(); ++i) {
    if (ref[i] < peak - 20.0)
      continue;
    sum += (ref[i] - other[i]) * (ref[i] - other[i]);
    ++n;
  }
  return n ? std::sqrt(sum / static_cast<double>(n)) : 0.0;
}

void BM_VehicleRangeProfile(benchmark::State& state) {
  Vehicle& v = vehicle();
  radar::RcsConfig config;
  config.max_bounces = 3;
  config.rays_per_wavelength = static_cast<double>(state.range(0)) / 2.0;
  config.edges = true;  // as the CLI's default (issue 30: the profile is timed with edges on)
  const radar::RcsEngine engine(v.scene, {radar::SurfaceModel{}}, config);
  const std::vector<double> f = profile_freqs();
  std::vector<radar::ScatteringMatrix> s(f.size());
  radar::RcsStats stats;
  for (auto _ : state) {
    stats = {};
    engine.compute(kAspect, kAspect, f, s, stats);
    benchmark::DoNotOptimize(s.data());
  }
  radar::RcsConfig doubled = config;
  doubled.rays_per_wavelength *= 2.0;
  const radar::RcsEngine finer(v.scene, {radar::SurfaceModel{}}, doubled);
  state.counters["facets"] = static_cast<double>(engine.facet_count());
  state.counters["rays"] = static_cast<double>(stats.rays);
  state.counters["paths"] = static_cast<double>(stats.paths);
  state.counters["rms_db_vs_2x_rays"] = rms_change_db(profile_db(finer), profile_db(engine));
}
BENCHMARK(BM_VehicleRangeProfile)
    ->Arg(2)
    ->Arg(4)
    ->Arg(8)
    ->Unit(benchmark::kMillisecond)
    ->UseRealTime();

void BM_VehicleProfileEdges(benchmark::State& state) {
  Vehicle& v = vehicle();
  radar::RcsConfig config;
  config.max_bounces = 3;
  config.rays_per_wavelength = 2.0;
  config.edges = state.range(0) != 0;
  config.edge_order = state.range(0) == 2 ? 2 : 1;
  const radar::RcsEngine engine(v.scene, {radar::SurfaceModel{}}, config);
  const std::vector<double> f = profile_freqs();
  std::vector<radar::ScatteringMatrix> s(f.size());
  radar::RcsStats stats;
  for (auto _ : state) {
    stats = {};
    engine.compute(kAspect, kAspect, f, s, stats);
    benchmark::DoNotOptimize(s.data());
  }
  state.counters["edges"] = static_cast<double>(engine.edges().size());
  state.counters["edges_used"] = static_cast<double>(stats.edges_used);
  state.counters["edge_pairs"] = static_cast<double>(engine.edge_pairs().size());
  state.counters["edges_double"] = static_cast<double>(stats.edges_double);
  state.counters["edges_reflected"] = static_cast<double>(stats.edges_reflected);
  state.counters["rays"] = static_cast<double>(stats.rays);
}
BENCHMARK(BM_VehicleProfileEdges)
    ->Arg(0)
    ->Arg(1)
    ->Arg(2)
    ->Unit(benchmark::kMillisecond)
    ->UseRealTime();

// The directions side by side, one TBB task each (as the CLI's sweep does them, in waves:
// tools/rcs.cpp, sweep_rcs); each call is parallel inside too.
std::vector<double> pattern_db(const radar::RcsEngine& engine) {
  std::vector<double> db(361);
  tbb::parallel_for(std::size_t{0}, db.size(), [&](std::size_t i) {
    const double f[1] = {35e9};
    radar::ScatteringMatrix s;
    radar::RcsStats stats;
    const radar::Direction d{80.0 * kPi / 180.0, static_cast<double>(i) * kPi / 180.0};
    engine.compute(d, d, f, std::span<radar::ScatteringMatrix>(&s, 1), stats);
    db[i] = radar::dbsm(s.vv);
  });
  return db;
}

void BM_Vehicle361Angles(benchmark::State& state) {
  Vehicle& v = vehicle();
  radar::RcsConfig config;
  config.max_bounces = 3;
  config.rays_per_wavelength = static_cast<double>(state.range(0)) / 2.0;
  const radar::RcsEngine engine(v.scene, {radar::SurfaceModel{}}, config);
  std::vector<double> db;
  for (auto _ : state) {
    db = pattern_db(engine);
    benchmark::DoNotOptimize(db.data());
  }
  // Convergence over the pattern: RMS dB change when the rays double, over the angles within
  // 20 dB of the pattern's peak (deep nulls excluded).
  radar::RcsConfig doubled = config;
  doubled.rays_per_wavelength *= 2.0;
  state.counters["rms_db_vs_2x_rays"] =
      rms_change_db(pattern_db(radar::RcsEngine(v.scene, {radar::SurfaceModel{}}, doubled)), db);
}
BENCHMARK(BM_Vehicle361Angles)
    ->Arg(1)
    ->Arg(2)
    ->Unit(benchmark::kMillisecond)
    ->UseRealTime()
    ->Iterations(1);

constexpr double kThroughputRaysPerWavelength = 2.0;

void BM_SbrThroughput(benchmark::State& state) {
  Vehicle& v = vehicle();
  radar::RcsConfig config;
  config.max_bounces = 3;
  config.rays_per_wavelength = kThroughputRaysPerWavelength;
  const radar::RcsEngine engine(v.scene, {radar::SurfaceModel{}}, config);
  const double f[1] = {35e9};
  radar::ScatteringMatrix s;
  radar::RcsStats stats;
  for (auto _ : state) {
    stats = {};
    engine.compute(kAspect, kAspect, f, std::span<radar::ScatteringMatrix>(&s, 1), stats);
    benchmark::DoNotOptimize(s);
  }
  state.counters["segments"] = static_cast<double>(stats.segments);
  state.counters["Msegments_per_s"] = benchmark::Counter(
      static_cast<double>(stats.segments) * 1e-6, benchmark::Counter::kIsIterationInvariantRate);
}
BENCHMARK(BM_SbrThroughput)->Unit(benchmark::kMillisecond)->UseRealTime();

// The same grid of rays, bounced up to 3 times by raw Embree (rtcIntersect1, geometric normal,
// mirror reflection) and nothing else: the ceiling the SBR tracer is measured against.
void BM_EmbreeRawThroughput(benchmark::State& state) {
  Vehicle& v = vehicle();
  radar::RcsConfig config;
  config.rays_per_wavelength = kThroughputRaysPerWavelength;
  const radar::RcsEngine engine(v.scene, {radar::SurfaceModel{}}, config);
  const radar::RayGrid grid = engine.ray_grid(kAspect, 35e9);
  RTCDevice device = rtcNewDevice(nullptr);
  RTCScene rs = rtcNewScene(device);
  const scene::Mesh& mesh = v.desc.objects[0].mesh;
  RTCGeometry geom = rtcNewGeometry(device, RTC_GEOMETRY_TYPE_TRIANGLE);
  // glm::vec3 and glm::uvec3 are three packed 4-byte values: Embree's FLOAT3 / UINT3 layouts.
  std::memcpy(rtcSetNewGeometryBuffer(geom, RTC_BUFFER_TYPE_VERTEX, 0, RTC_FORMAT_FLOAT3,
                                      sizeof(glm::vec3), mesh.positions_m.size()),
              mesh.positions_m.data(), mesh.positions_m.size() * sizeof(glm::vec3));
  std::memcpy(rtcSetNewGeometryBuffer(geom, RTC_BUFFER_TYPE_INDEX, 0, RTC_FORMAT_UINT3,
                                      sizeof(glm::uvec3), mesh.triangles.size()),
              mesh.triangles.data(), mesh.triangles.size() * sizeof(glm::uvec3));
  rtcCommitGeometry(geom);
  rtcAttachGeometry(rs, geom);
  rtcReleaseGeometry(geom);
  rtcCommitScene(rs);
  std::atomic<std::uint64_t> segments{0};
  const float eps = static_cast<float>(1e-5 * engine.bounding_radius_m());
  for (auto _ : state) {
    segments = 0;
    tbb::parallel_for(std::uint64_t{0}, grid.rows, [&](std::uint64_t row) {
      RTCIntersectContext ctx;
      std::uint64_t local = 0;
      for (std::uint64_t col = 0; col < grid.cols; ++col) {
        const glm::dvec3 o = grid.origin_m + static_cast<double>(row) * grid.dv_m +
                             static_cast<double>(col) * grid.du_m;
        glm::vec3 org(o), dir(grid.direction);
        float tnear = 0.0f;
        for (int bounce = 0; bounce < 3; ++bounce) {
          rtcInitIntersectContext(&ctx);
          RTCRayHit rh{};
          rh.ray.org_x = org.x;
          rh.ray.org_y = org.y;
          rh.ray.org_z = org.z;
          rh.ray.dir_x = dir.x;
          rh.ray.dir_y = dir.y;
          rh.ray.dir_z = dir.z;
          rh.ray.tnear = tnear;
          rh.ray.tfar = 1e30f;
          rh.ray.mask = 0xFFFFFFFFu;
          rh.hit.geomID = RTC_INVALID_GEOMETRY_ID;
          ++local;
          rtcIntersect1(rs, &ctx, &rh);
          if (rh.hit.geomID == RTC_INVALID_GEOMETRY_ID)
            break;
          const glm::vec3 n = glm::normalize(glm::vec3(rh.hit.Ng_x, rh.hit.Ng_y, rh.hit.Ng_z));
          org += rh.ray.tfar * dir;
          dir = dir - 2.0f * glm::dot(n, dir) * n;
          tnear = eps;
        }
      }
      segments += local;
    });
    benchmark::DoNotOptimize(segments.load());
  }
  state.counters["segments"] = static_cast<double>(segments.load());
  state.counters["Msegments_per_s"] = benchmark::Counter(
      static_cast<double>(segments.load()) * 1e-6, benchmark::Counter::kIsIterationInvariantRate);
  rtcReleaseScene(rs);
  rtcReleaseDevice(device);
}
BENCHMARK(BM_EmbreeRawThroughput)->Unit(benchmark::kMillisecond)->UseRealTime();

}  // namespace

BENCHMARK_MAIN();
