// Scene database benchmarks (issue 7): loading and building the terrain database, moving targets
// on trajectories, the per-frame view (culling + LOD), and ray throughput with and without it.
// Run: build/bench/bench_scene --benchmark_repetitions=3 --benchmark_report_aggregates_only=true
// Goals: load + build of the ~200k-triangle .glb under 2 s and 500 MB peak resident memory;
// set_time under 1 ms for all movers.

#include <benchmark/benchmark.h>
#include <unistd.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <memory>
#include <numbers>
#include <random>
#include <string>
#include <vector>

#include "common/units.hpp"
#include "scene/gltf.hpp"
#include "scene/scene.hpp"
#include "scene/terrain_gen.hpp"
#include "scene/trajectory.hpp"

namespace common = radar_emu::common;
namespace sc = radar_emu::scene;
namespace fs = std::filesystem;

namespace {

// Resident-set figures of this process from /proc/self/status [bytes]: VmHWM (peak) or VmRSS.
double status_bytes(const char* key) {
  std::ifstream in("/proc/self/status");
  std::string line;
  const std::string k = std::string(key) + ":";
  while (std::getline(in, line)) {
    if (line.rfind(k, 0) == 0)
      return 1024.0 * std::stod(line.substr(k.size()));  // "VmHWM:   123456 kB"
  }
  return 0.0;
}

// Resets the peak resident set (VmHWM) to the current one (Linux >= 4.0, proc(5) clear_refs).
void reset_peak_rss() {
  std::ofstream("/proc/self/clear_refs") << "5";
}

struct Files {
  fs::path dir = fs::temp_directory_path() / ("radar_emu_bench_scene_" + std::to_string(getpid()));
  fs::path full = dir / "terrain_lod.glb";     // every level and the surround
  fs::path level0 = dir / "terrain_lod0.glb";  // level 0 and objects outside LOD groups
  std::size_t full_triangles = 0, level0_triangles = 0;
  Files() {
    fs::create_directories(dir);
    sc::SceneDescription d = sc::generate_terrain({});
    for (const auto& o : d.objects)
      full_triangles += o.mesh.triangles.size();
    sc::write_gltf(d, full);
    std::erase_if(d.objects, [](const sc::ObjectDesc& o) { return o.lod_level > 0; });
    for (const auto& o : d.objects)
      level0_triangles += o.mesh.triangles.size();
    sc::write_gltf(d, level0);
  }
  ~Files() {
    std::error_code ec;
    fs::remove_all(dir, ec);
  }
};

Files& files() {
  static Files f;
  return f;
}

// (a) load_gltf + BVH build. Counters: triangles, file size, peak resident memory of the
// process during the iteration and its growth over the resident set before it.
void load_and_build(benchmark::State& state, const fs::path& path, std::size_t triangles) {
  double peak = 0.0, growth = 0.0;
  for (auto _ : state) {
    reset_peak_rss();
    const double before = status_bytes("VmRSS");
    auto scene = std::make_unique<sc::Scene>(sc::load_gltf(path));
    benchmark::DoNotOptimize(scene->triangle_count());
    peak = std::max(peak, status_bytes("VmHWM"));
    growth = std::max(growth, status_bytes("VmHWM") - before);
    state.PauseTiming();
    scene.reset();
    state.ResumeTiming();
  }
  state.counters["triangles"] = static_cast<double>(triangles);
  state.counters["file_MB"] = static_cast<double>(fs::file_size(path)) * 1e-6;
  state.counters["peak_rss_MB"] = peak * 1e-6;
  state.counters["rss_growth_MB"] = growth * 1e-6;
}

void BM_LoadAndBuildLevel0Glb(benchmark::State& state) {
  load_and_build(state, files().level0, files().level0_triangles);
}
BENCHMARK(BM_LoadAndBuildLevel0Glb)->Unit(benchmark::kMillisecond)->UseRealTime()->Iterations(3);

void BM_LoadAndBuildAllLevelsGlb(benchmark::State& state) {
  load_and_build(state, files().full, files().full_triangles);
}
BENCHMARK(BM_LoadAndBuildAllLevelsGlb)->Unit(benchmark::kMillisecond)->UseRealTime()->Iterations(3);

// (a') load_gltf + BVH build of any .glb named by RADAR_EMU_BENCH_GLB (registered only then):
// scripts/bench-geodata-import.sh compares an imported database with the generated one above
// in one run.
const bool kFileBenchmark = [] {
  const char* path = std::getenv("RADAR_EMU_BENCH_GLB");
  if (path == nullptr || *path == '\0')
    return false;
  std::size_t triangles = 0;
  for (const auto& o : sc::load_gltf(path).objects)
    triangles += o.mesh.triangles.size();
  benchmark::RegisterBenchmark("BM_LoadAndBuildGlbFile",
                               [file = fs::path(path), triangles](benchmark::State& state) {
                                 load_and_build(state, file, triangles);
                               })
      ->Unit(benchmark::kMillisecond)
      ->UseRealTime()
      ->Iterations(3);
  return true;
}();

// (b) set_time with N movers on looping trajectories (8 waypoints, 40 m turns), each a 12-
// triangle box, over a static ground.
sc::SceneDescription movers(int n) {
  sc::SceneDescription d;
  d.materials = {{"grass", {}}, {"metal", {}}};
  sc::ObjectDesc ground;
  ground.name = "ground";
  ground.mesh.positions_m = {{-10000, -10000, 0}, {10000, -10000, 0}, {0, 10000, 0}};
  ground.mesh.triangles = {{0, 1, 2}};
  ground.mesh.triangle_material = {0};
  d.objects.push_back(ground);
  std::mt19937 rng(7);
  std::uniform_real_distribution<double> u(-1.0, 1.0);
  for (int i = 0; i < n; ++i) {
    sc::ObjectDesc o;
    o.name = "mover_" + std::to_string(i);
    const float lo[3] = {-3, -1, 0}, hi[3] = {3, 1, 2};
    for (int c = 0; c < 8; ++c)
      o.mesh.positions_m.emplace_back((c & 1) ? hi[0] : lo[0], (c & 2) ? hi[1] : lo[1],
                                      (c & 4) ? hi[2] : lo[2]);
    o.mesh.triangles = {{0, 2, 1}, {1, 2, 3}, {4, 5, 6}, {5, 7, 6}, {0, 1, 4}, {1, 5, 4},
                        {2, 6, 3}, {3, 6, 7}, {0, 4, 2}, {2, 4, 6}, {1, 3, 5}, {3, 7, 5}};
    o.mesh.triangle_material.assign(12, 1);
    sc::Trajectory t;
    const glm::dvec3 c(3000.0 * u(rng), 3000.0 * u(rng), 0.0);
    for (int k = 0; k < 8; ++k) {
      const double a = 2.0 * std::numbers::pi * k / 8.0;
      t.waypoints_m.push_back(c + glm::dvec3((400.0 + 100.0 * u(rng)) * std::cos(a),
                                             (400.0 + 100.0 * u(rng)) * std::sin(a), 0.0));
    }
    t.speed_mps = 10.0 + 5.0 * u(rng);
    t.turn_radius_m = 40.0;
    t.loop = true;
    o.trajectory = t;
    d.objects.push_back(o);
  }
  return d;
}

void BM_SetTimeTrajectories(benchmark::State& state) {
  const auto n = static_cast<int>(state.range(0));
  sc::Scene s(movers(n));
  double t = 0.0;
  for (auto _ : state) {
    t += 0.05;
    s.set_time(t);
    benchmark::ClobberMemory();
  }
  state.counters["movers"] = n;
  // Seconds per mover per call (printed with its SI prefix, e.g. "80n" = 80 ns).
  state.counters["per_mover_s"] =
      benchmark::Counter(static_cast<double>(n), benchmark::Counter::kIsIterationInvariantRate |
                                                     benchmark::Counter::kInvert);
}
BENCHMARK(BM_SetTimeTrajectories)->Arg(1)->Arg(10)->Arg(100)->Arg(1000)->Arg(10000);

// The generated database, built once, and a radar 4 km south of the centre at 300 m looking
// north, 3 deg down, over a 30 x 10 deg field to 6 km (examples/ev_radar_94ghz.toml's field).
struct Database {
  sc::Scene lod{sc::generate_terrain({})};
  sc::Scene level0{[] {
    sc::SceneDescription d = sc::generate_terrain({});
    std::erase_if(d.objects, [](const sc::ObjectDesc& o) { return o.lod_level > 0; });
    return d;
  }()};
  sc::ViewVolume view;
  Database() {
    view.position_m = {0.0, -4000.0, 300.0};
    const double dep = common::radians(3.0);
    const glm::dvec3 x(0.0, std::cos(dep), -std::sin(dep));  // boresight north, 3 deg down
    const glm::dvec3 y(1.0, 0.0, 0.0);                       // right = east
    view.world_from_antenna = glm::dmat3(x, y, glm::cross(x, y));
    view.azimuth_min_rad = common::radians(-15.0);
    view.azimuth_max_rad = common::radians(15.0);
    view.elevation_min_rad = common::radians(-5.0);
    view.elevation_max_rad = common::radians(5.0);
    view.max_range_m = 6000.0;
    view.range_cell_m = 3.0;
    view.angular_cell_rad =
        common::radians(0.15) * 10.0;  // beam 1.5 deg: coarser levels from ~800 m
  }
};

Database& database() {
  static Database d;
  return d;
}

// (c) set_view on the database (140 tiles x 3 levels, a few thousand other objects).
void BM_SetView(benchmark::State& state) {
  Database& d = database();
  sc::ViewVolume v = d.view;
  int i = 0;
  for (auto _ : state) {
    v.position_m.y = d.view.position_m.y + 0.1 * (i++ % 100);  // the radar moves a little
    d.lod.set_view(v);
    benchmark::ClobberMemory();
  }
  d.lod.set_view(d.view);
  const sc::ViewStats& st = d.lod.view_stats();
  state.counters["objects"] = static_cast<double>(d.lod.objects().size());
  state.counters["tiles_in_view"] = st.lod_groups_in_view;
  state.counters["tiles_culled"] = st.lod_groups_culled;
  state.counters["tiles_lod0"] = st.lod_groups_at_level[0];
  state.counters["tiles_lod1"] = st.lod_groups_at_level[1];
  state.counters["tiles_lod2"] = st.lod_groups_at_level[2];
  state.counters["tri_active"] = static_cast<double>(st.triangles_active);
  state.counters["tri_in_view"] = static_cast<double>(st.triangles_in_view);
  state.counters["tri_total"] = static_cast<double>(st.triangles_total);
  d.lod.clear_view();
}
BENCHMARK(BM_SetView)->Unit(benchmark::kMicrosecond);

// (d) Ray throughput (one thread): a 300 x 100 grid over the field of view, first hits only.
// Arg 0: level-0-only scene, no view (the reference); 1: all levels, default view (level 0
// active: the filter's cost); 2: all levels with set_view (culling + coarser far tiles).
void BM_Rays(benchmark::State& state) {
  Database& d = database();
  const int mode = static_cast<int>(state.range(0));
  sc::Scene& s = mode == 0 ? d.level0 : d.lod;
  if (mode == 2)
    s.set_view(d.view);
  else
    d.lod.clear_view();
  const sc::ViewVolume& v = d.view;
  constexpr int kAz = 300, kEl = 100;
  std::vector<sc::Ray> rays;
  for (int j = 0; j < kEl; ++j) {
    for (int i = 0; i < kAz; ++i) {
      const double az =
          v.azimuth_min_rad + (v.azimuth_max_rad - v.azimuth_min_rad) * (i + 0.5) / kAz;
      const double el =
          v.elevation_min_rad + (v.elevation_max_rad - v.elevation_min_rad) * (j + 0.5) / kEl;
      sc::Ray r;
      r.origin_m = v.position_m;
      r.direction = v.world_from_antenna * glm::dvec3(std::cos(el) * std::cos(az),
                                                      std::cos(el) * std::sin(az), -std::sin(el));
      r.t_far_m = v.max_range_m;
      rays.push_back(r);
    }
  }
  std::size_t hits = 0;
  for (auto _ : state) {
    hits = 0;
    sc::Hit h;
    for (const sc::Ray& r : rays)
      hits += s.intersect(r, h) ? 1u : 0u;
    benchmark::DoNotOptimize(hits);
  }
  state.counters["hits"] = static_cast<double>(hits);
  state.counters["Mrays_per_s"] = benchmark::Counter(static_cast<double>(rays.size()) * 1e-6,
                                                     benchmark::Counter::kIsIterationInvariantRate);
  d.lod.clear_view();
}
BENCHMARK(BM_Rays)->Arg(0)->Arg(1)->Arg(2)->Unit(benchmark::kMillisecond)->UseRealTime();

}  // namespace

BENCHMARK_MAIN();
