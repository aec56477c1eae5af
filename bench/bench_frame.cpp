// Frame-path benchmarks on the default scenario: each stage alone, and whole frames.
// Run: build/bench/bench_frame --benchmark_repetitions=5 --benchmark_report_aggregates_only=true

#include <benchmark/benchmark.h>
#include <embree3/rtcore.h>
#include <tbb/global_control.h>
#include <tbb/parallel_invoke.h>

#include <algorithm>
#include <cmath>
#include <complex>
#include <cstdint>
#include <cstring>
#include <ctime>
#include <limits>
#include <map>
#include <memory>
#include <optional>
#include <span>
#include <string>
#include <vector>

#include "loop/closed_loop.hpp"
#include "loop/scenario.hpp"
#include "radar/em/sbr.hpp"
#include "radar/products/terrain_returns.hpp"
#include "radar/sensor/capture_storage.hpp"
#include "radar/sensor/noise.hpp"
#include "radar/sensor/sensor.hpp"
#include "scene/airport_gen.hpp"
#include "scene/default_scene.hpp"
#include "scene/scene.hpp"

namespace loop = radar_emu::loop;
namespace radar = radar_emu::radar;

namespace {

// The default scenario with the tracer's terrain rays ([radar] terrain = "rays"): the frame the
// fixture's benchmarks (BM_Trace, BM_Sensor, BM_SensorCapture, ...) measured before the terrain
// engine became the default, so that their history in docs/performance.md stays comparable
// (without it they would trace no terrain at all: the engine is not part of the fixture).
// BM_TraceTerrain and BM_TerrainCompute compare the two ways.
loop::Scenario rays_scenario() {
  loop::Scenario s = loop::parse_scenario(loop::default_scenario_toml(), "<default scenario>");
  s.terrain_engine = false;
  s.sbr.terrain_rays = true;
  s.sbr.reuse_static_paths = false;  // every iteration traces its frame whole, as it did then
  return s;
}

struct Fixture {
  explicit Fixture(radar_emu::scene::SceneDescription d) : scene(std::move(d)) { init(); }
  Fixture() : Fixture(radar_emu::scene::default_scene()) {}
  loop::Scenario s = rays_scenario();
  radar_emu::scene::Scene scene;
  radar::SbrTracer tracer{scene, s.sbr};
  radar::Sensor sensor{s.sensor};
  std::vector<radar::Contribution> contributions =
      std::vector<radar::Contribution>(tracer.max_contributions());
  std::vector<radar::Detection> detections = std::vector<radar::Detection>(s.sensor.max_detections);
  radar::RadarPose pose;
  void init() { pose = loop::scripted_pose(s); }
};

Fixture& fixture() {
  static Fixture f;
  return f;
}

// The generated airport the default scenario flies to (issue 7: hangars, terminal,
// approach-light stations, parked transports, service vehicles; 40 metallic objects against the
// runway scene's 4), seen from the same pose.
Fixture& airport_fixture() {
  static Fixture f(radar_emu::scene::generate_airport({}));
  return f;
}

// Argument 0: the runway scene (scene/default_scene.hpp); 1: the generated airport.
void BM_Trace(benchmark::State& state) {
  Fixture& f = state.range(0) == 0 ? fixture() : airport_fixture();
  std::size_t n = 0;
  radar::TraceStats stats;
  for (auto _ : state) {
    stats = {};
    n = f.tracer.trace(f.pose, f.contributions, stats);
    benchmark::DoNotOptimize(n);
  }
  state.counters["rays"] = static_cast<double>(stats.rays);
  state.counters["bundles"] = static_cast<double>(stats.target_bundles);
  state.counters["coarsened"] = static_cast<double>(stats.coarsened_bundles);
  state.counters["contributions"] = static_cast<double>(n);
  state.counters["lit_facets"] = static_cast<double>(stats.lit_facets);
  state.counters["partial_facets"] = static_cast<double>(stats.partial_facets);
  state.counters["facet_queries"] = static_cast<double>(stats.facet_queries);
  state.counters["Mrays_per_s"] = benchmark::Counter(static_cast<double>(stats.rays) * 1e-6,
                                                     benchmark::Counter::kIsIterationInvariantRate);
}
BENCHMARK(BM_Trace)->Arg(0)->Arg(1)->Unit(benchmark::kMillisecond)->UseRealTime();

// The airport frame with first-order edge currents only (argument 1) and with the double
// diffraction of edge pairs (2, the default; radar/em/edges.hpp): its cost in the loop.
void BM_TraceEdgeOrder(benchmark::State& state) {
  Fixture& f = airport_fixture();
  radar::SbrConfig c = f.s.sbr;
  c.edge_order = static_cast<int>(state.range(0));
  radar::SbrTracer tracer(f.scene, c);
  std::vector<radar::Contribution> out(tracer.max_contributions());
  radar::TraceStats stats;
  std::size_t n = 0;
  for (auto _ : state) {
    stats = {};
    n = tracer.trace(f.pose, out, stats);
    benchmark::DoNotOptimize(n);
  }
  state.counters["edges_used"] = static_cast<double>(stats.edges_used);
  state.counters["edges_double"] = static_cast<double>(stats.edges_double);
  state.counters["contributions"] = static_cast<double>(n);
}
BENCHMARK(BM_TraceEdgeOrder)->Arg(1)->Arg(2)->Unit(benchmark::kMillisecond)->UseRealTime();

// The same frame at several target-bundle densities (argument: spacing in mm), side by side:
// cost against the accuracy the tests measure (tests/radar: a trihedral converges to within
// 0.2 dB of 12 pi a^4 / lambda^2 at 25 tubes per edge, a flat plate at any density).
void BM_TraceTargetSpacing(benchmark::State& state) {
  Fixture& f = fixture();
  radar::SbrConfig c = f.s.sbr;
  c.target_ray_spacing_m = static_cast<double>(state.range(0)) * 1e-3;
  radar::SbrTracer tracer(f.scene, c);
  std::vector<radar::Contribution> out(tracer.max_contributions());
  radar::TraceStats stats;
  for (auto _ : state) {
    stats = {};
    benchmark::DoNotOptimize(tracer.trace(f.pose, out, stats));
  }
  state.counters["rays"] = static_cast<double>(stats.rays);
  state.counters["Mrays_per_s"] = benchmark::Counter(static_cast<double>(stats.rays) * 1e-6,
                                                     benchmark::Counter::kIsIterationInvariantRate);
}
BENCHMARK(BM_TraceTargetSpacing)
    ->Arg(250)
    ->Arg(100)
    ->Arg(50)
    ->Unit(benchmark::kMillisecond)
    ->UseRealTime();

// What a fidelity governor pays to budget a frame before tracing it: plan() over the airport's
// objects (no ray is shot).
void BM_TracePlan(benchmark::State& state) {
  Fixture& f = state.range(0) == 0 ? fixture() : airport_fixture();
  std::vector<std::size_t> per_object(f.scene.objects().size());
  radar::TracePlan p;
  for (auto _ : state) {
    p = f.tracer.plan(f.pose, {}, per_object);
    benchmark::DoNotOptimize(p);
  }
  state.counters["rays"] = static_cast<double>(p.rays());
  state.counters["bundles"] = static_cast<double>(p.target_bundles);
}
BENCHMARK(BM_TracePlan)->Arg(0)->Arg(1)->Unit(benchmark::kMicrosecond);

// The sensor on the traced runway frame. Argument 0: noise-only cells drawn (the default);
// 1: every cell synthesised (SensorConfig::synthesise_every_cell, the reference): the ratio of
// the two is what drawing the noise cells saves.
void BM_Sensor(benchmark::State& state) {
  Fixture& f = fixture();
  radar::TraceStats ts;
  const std::size_t n = f.tracer.trace(f.pose, f.contributions, ts);
  radar::SensorConfig c = f.s.sensor;
  c.synthesise_every_cell = state.range(0) == 1;
  radar::Sensor sensor(c);
  radar::SensorStats ss;
  for (auto _ : state) {
    ss = {};
    benchmark::DoNotOptimize(sensor.process(
        std::span<const radar::Contribution>(f.contributions.data(), n), f.detections, ss));
  }
  state.counters["contributions"] = static_cast<double>(n);
  state.counters["cells_synthesised"] = static_cast<double>(ss.cells_synthesised);
  state.counters["merged"] = static_cast<double>(ss.merged_returns);
}
BENCHMARK(BM_Sensor)->Arg(0)->Arg(1)->Unit(benchmark::kMillisecond)->UseRealTime();

// Data cubes out (`run --cube`, docs/cube.md): storage for one captured frame, as
// loop/outputs/cube_writer.cpp allocates a slot.
struct CaptureStorage : radar::CaptureStorage {
  explicit CaptureStorage(const radar::Sensor& sensor)
      : radar::CaptureStorage(sensor.capture_shape(), 256, std::size_t{1} << 17),
        raw(sensor.capture_shape().raw_values()),
        workspace(sensor.make_raw_workspace()) {}
  std::vector<std::complex<float>> raw;
  std::unique_ptr<radar::Sensor::RawWorkspace> workspace;
};

// The frame path's share of a captured frame, on one thread (so that CPU time counts all the
// work): the traced runway frame through the sensor (argument 0, 1) or traced and sensed (2, 3),
// without (0, 2) and with (1, 3) a capture armed. The sensor then copies its synthesised cells,
// drawn false alarms and returns into the slot; the rest is the writer's (BM_CubeCompletion).
void BM_SensorCapture(benchmark::State& state) {
  const tbb::global_control one(tbb::global_control::max_allowed_parallelism, 1);
  Fixture& f = fixture();
  radar::TraceStats ts;
  std::size_t n = f.tracer.trace(f.pose, f.contributions, ts);
  radar::Sensor sensor(f.s.sensor);
  CaptureStorage storage(sensor);
  radar::SensorStats ss;
  const bool capture = state.range(0) % 2 == 1, trace = state.range(0) >= 2;
  for (auto _ : state) {
    ss = {};
    if (trace) {
      ts = {};
      n = f.tracer.trace(f.pose, f.contributions, ts);
    }
    if (capture)
      sensor.capture_next(&storage.capture);
    benchmark::DoNotOptimize(sensor.process(
        std::span<const radar::Contribution>(f.contributions.data(), n), f.detections, ss));
  }
  state.counters["returns_captured"] = static_cast<double>(storage.capture.return_count);
}
BENCHMARK(BM_SensorCapture)->DenseRange(0, 3)->Unit(benchmark::kMillisecond);

// The cube writer's work for one captured frame, off the frame path (its own thread; measured
// here on one thread): the image completed (0) and the raw samples synthesised (1), on the
// traced runway frame.
void BM_CubeCompletion(benchmark::State& state) {
  const tbb::global_control one(tbb::global_control::max_allowed_parallelism, 1);
  Fixture& f = fixture();
  radar::TraceStats ts;
  const std::size_t n = f.tracer.trace(f.pose, f.contributions, ts);
  radar::Sensor sensor(f.s.sensor);
  CaptureStorage storage(sensor);
  radar::SensorStats ss;
  sensor.capture_next(&storage.capture);
  (void)sensor.process(std::span<const radar::Contribution>(f.contributions.data(), n),
                       f.detections, ss);
  for (auto _ : state) {
    if (state.range(0) == 0)
      sensor.complete_image(storage.capture);
    else
      sensor.synthesise_raw(storage.capture, storage.raw, *storage.workspace);
    benchmark::DoNotOptimize(storage.raw.data());
  }
  state.counters["returns"] = static_cast<double>(storage.capture.return_count);
}
BENCHMARK(BM_CubeCompletion)->Arg(0)->Arg(1)->Unit(benchmark::kMillisecond);

// Whole default-scenario frames without (0) and with (1) `--cube` on every frame (20 frames an
// iteration, the file in /tmp): p50 of the frame stage (the frame path, copies included; the
// wait for a free slot is between frames) and the run's wall time per frame (waits included: on
// the simulated clock the loop waits for the writer).
void BM_FrameCube(benchmark::State& state) {
  loop::Scenario s = loop::parse_scenario(loop::default_scenario_toml(), "<default scenario>");
  s.frames = 20;
  loop::RunOptions o;
  if (state.range(0) == 1) {
    o.cube_file = "/tmp/radar_emu_bench_cube.h5";
    o.cube_first_frame = 0;
    o.cube_last_frame = s.frames - 1;
  }
  loop::RunResult r;
  for (auto _ : state) {
    state.PauseTiming();
    loop::ClosedLoop loop(s, o);
    state.ResumeTiming();
    r = loop.run();
  }
  const auto& frame = r.stages[static_cast<std::size_t>(radar_emu::timing::Stage::kFrame)];
  const auto& sensor = r.stages[static_cast<std::size_t>(radar_emu::timing::Stage::kSensor)];
  state.counters["frame_p50_ms"] = frame.p50_s * 1e3;
  state.counters["sensor_p50_ms"] = sensor.p50_s * 1e3;
  state.counters["wall_ms_per_frame"] = r.wall_time_s * 1e3 / static_cast<double>(r.frames);
}
BENCHMARK(BM_FrameCube)
    ->Arg(0)
    ->Arg(1)
    ->Iterations(2)
    ->Unit(benchmark::kMillisecond)
    ->UseRealTime();

// Sensor time against the number of returns (the default scenario's sensor, 16 beams x 1502 x 32
// cells): N point returns of random phase spread over the field of view, the swath and +-10 m/s
// (fixed seed), and N = 0, a frame with nothing in view (goal: 1 ms or less).
void BM_SensorReturns(benchmark::State& state) {
  Fixture& f = fixture();
  const auto n = static_cast<std::size_t>(state.range(0));
  std::vector<radar::Contribution> in(n);
  radar::NoiseRng rng(20261124);
  const radar::SensorConfig& c = f.s.sensor;
  const double r0 = radar::first_range_m(c.processing.waveform);
  for (radar::Contribution& r : in) {
    r.range_m = r0 + (c.max_range_m - r0) * rng.uniform();
    r.amplitude = std::polar(0.1, 6.283185307179586 * rng.uniform());
    r.radial_velocity_mps = 20.0 * (rng.uniform() - 0.5);
    r.azimuth_rad = f.s.sbr.azimuth_min_rad +
                    (f.s.sbr.azimuth_max_rad - f.s.sbr.azimuth_min_rad) * rng.uniform();
    r.elevation_rad = f.s.sbr.elevation_min_rad +
                      (f.s.sbr.elevation_max_rad - f.s.sbr.elevation_min_rad) * rng.uniform();
  }
  radar::SensorStats ss;
  for (auto _ : state) {
    ss = {};
    benchmark::DoNotOptimize(f.sensor.process(in, f.detections, ss));
  }
  state.counters["returns"] = static_cast<double>(n);
  state.counters["cells_synthesised"] = static_cast<double>(ss.cells_synthesised);
}
BENCHMARK(BM_SensorReturns)
    ->Arg(0)
    ->Arg(10)
    ->Arg(100)
    ->Arg(1000)
    ->Arg(10000)
    ->Arg(100000)
    ->Unit(benchmark::kMillisecond)
    ->UseRealTime();

// The sensor on the default closed loop's own frame (issue 29: "the sensor's synthesis within
// 5 ms"): the default scenario as `radar-emu run` flies it ([radar] terrain = "engine"): the
// tracer's returns (no terrain rays) followed by the terrain engine's cells, one diffuse return
// per lit range-azimuth cell, traced once at the scenario's first pose (argument 1 = 0) or 5 s
// into the flight (1), or examples/terrain_movers.toml's frame at its first pose (2: the terrain
// database, most of its returns its buildings' paths). Argument 0: threads (0: as many as TBB
// runs, 1: one, so that the CPU time of the benchmark's thread is the sensor's whole work however
// loaded the machine).
struct LoopFrame {
  loop::Scenario s;
  radar_emu::scene::Scene scene{loop::scene_description(s)};
  std::vector<radar::Contribution> contributions;
  std::size_t coherent = 0;
  LoopFrame(loop::Scenario scenario, double t_s) : s(std::move(scenario)) {
    scene.set_time(t_s);
    const radar::RadarPose pose = loop::scripted_pose(s, t_s);
    radar::SbrConfig cfg = s.sbr;
    cfg.terrain_rays = false;
    radar::SbrTracer tracer(scene, cfg);
    radar::TerrainReturns terrain(scene, tracer, loop::terrain_returns_config(s));
    const std::size_t cap = tracer.max_contributions();
    contributions.resize(cap + terrain.max_returns());
    radar::TraceStats ts;
    radar::clutter::TerrainStats es;
    std::uint64_t dropped = 0;
    const std::span<radar::Contribution> all(contributions);
    const std::size_t n = tracer.trace(pose, all.first(cap), ts);
    const std::size_t m = terrain.compute(pose, all.subspan(cap), es, dropped);
    std::copy_n(all.begin() + static_cast<std::ptrdiff_t>(cap), m,
                all.begin() + static_cast<std::ptrdiff_t>(n));
    contributions.resize(n + m);
    for (const radar::Contribution& c : contributions)
      coherent += c.coherent ? 1u : 0u;
  }
};

void BM_SensorLoopFrame(benchmark::State& state) {
  static LoopFrame frames[] = {
      LoopFrame(loop::parse_scenario(loop::default_scenario_toml(), "<default scenario>"), 0.0),
      LoopFrame(loop::parse_scenario(loop::default_scenario_toml(), "<default scenario>"), 5.0),
      LoopFrame(loop::load_scenario(std::string(RADAR_EMU_EXAMPLES_DIR) + "/terrain_movers.toml"),
                0.0)};
  const LoopFrame& f = frames[state.range(1)];
  std::optional<tbb::global_control> serial;
  if (state.range(0) == 1)
    serial.emplace(tbb::global_control::max_allowed_parallelism, 1);
  radar::Sensor sensor(f.s.sensor);
  std::vector<radar::Detection> detections(f.s.sensor.max_detections);
  radar::SensorStats ss;
  for (auto _ : state) {
    ss = {};
    benchmark::DoNotOptimize(sensor.process(f.contributions, detections, ss));
  }
  state.counters["returns"] = static_cast<double>(f.contributions.size());
  state.counters["coherent"] = static_cast<double>(f.coherent);
  state.counters["cells_synthesised"] = static_cast<double>(ss.cells_synthesised);
  state.counters["detections"] = static_cast<double>(ss.detections);
  state.SetLabel(serial ? "1 thread" : "all threads");
}
BENCHMARK(BM_SensorLoopFrame)
    ->ArgsProduct({{0, 1}, {0, 1, 2}})
    ->Unit(benchmark::kMillisecond)
    ->UseRealTime();

// Terrain clutter on the same frame, two ways (issue 28 item 2, issue 29's first lever): the
// trace with the tracer's terrain rays (argument 1 = 0, [radar] terrain = "rays") against the
// trace without them plus the terrain engine's cells (1, terrain = "engine": shadows by the
// horizon sweep; 4: by one occlusion query per patch; 5: as 1 in columns of 0.25 deg, a quarter
// beamwidth, instead of the scenario's 0.5; 3: no shadows; 2: no terrain; 6: as 1 but the engine
// after the trace instead of beside it), all from the scenario's first pose. The engine runs
// beside the tracer's trace (tbb::parallel_invoke, as the loop runs them) except in mode 6.
// Argument 0: the default scenario (0) or examples/terrain_movers.toml (1, the 207k-polygon
// terrain). Counters: the rays shot, the returns handed to the sensor, the engine's patches
// (evaluated, lit); trace_ms and engine_ms, the wall time of the tracer's trace and of the engine's
// compute per frame; engine_cpu_ms, the CPU time of all the process's threads during the engine's
// compute (TBB's workers waiting for work included) in mode 6, else the CPU time of the thread that
// ran compute() (its whole work with one thread); cpu_all_ms, the CPU time of all the process's
// threads per frame (TBB's waiting workers included).
void BM_TraceTerrain(benchmark::State& state) {
  struct Case {
    loop::Scenario s;
    radar_emu::scene::Scene scene;
    radar::RadarPose pose;
    explicit Case(loop::Scenario sc) : s(std::move(sc)), scene(loop::scene_description(s)) {
      scene.set_time(0.0);
      pose = loop::scripted_pose(s);
    }
  };
  static Case cases[] = {
      Case(loop::parse_scenario(loop::default_scenario_toml(), "<default scenario>")),
      Case(loop::load_scenario(std::string(RADAR_EMU_EXAMPLES_DIR) + "/terrain_movers.toml"))};
  Case& c = cases[state.range(0)];
  const long mode = state.range(1);
  // Argument 2 = 1: one thread (TBB limited to it), so that the CPU time of the benchmark's
  // thread is the frame's whole work, however loaded the machine (no spinning workers counted).
  std::optional<tbb::global_control> serial;
  if (state.range(2) == 1)
    serial.emplace(tbb::global_control::max_allowed_parallelism, 1);
  const bool engine = mode == 1 || mode == 3 || mode == 4 || mode == 5 || mode == 6;
  radar::SbrConfig cfg = c.s.sbr;
  cfg.terrain_rays = mode == 0;
  cfg.reuse_static_paths = false;  // one frame traced whole, every iteration
  radar::SbrTracer tracer(c.scene, cfg);
  std::optional<radar::TerrainReturns> terrain;
  radar::TerrainReturnsConfig tc = loop::terrain_returns_config(c.s);
  tc.shadowing = mode != 3;
  tc.horizon = mode != 4;
  if (mode == 5)
    tc.azimuth_cell_rad = 0.25 * 3.14159265358979323846 / 180.0;  // the former 0.25 deg columns
  if (engine)
    terrain.emplace(c.scene, tracer, tc);
  const std::size_t cap = tracer.max_contributions();
  std::vector<radar::Contribution> out(cap + (terrain ? terrain->max_returns() : 0));
  radar::TraceStats ts;
  radar::clutter::TerrainStats es;
  std::uint64_t dropped = 0;
  std::size_t n = 0;
  // The engine's share: the CPU time of every thread of the process while compute() runs (one
  // thread: that thread's), and the wall time of compute() and of the tracer's trace().
  double engine_cpu_s = 0.0, engine_wall_s = 0.0, trace_wall_s = 0.0;
  auto clock_s = [](clockid_t id) {
    timespec t{};
    clock_gettime(id, &t);
    return static_cast<double>(t.tv_sec) + 1e-9 * static_cast<double>(t.tv_nsec);
  };
  const std::span<radar::Contribution> all(out);
  auto trace = [&] {
    const double w0 = clock_s(CLOCK_MONOTONIC);
    n = tracer.trace(c.pose, terrain ? all.first(cap) : all, ts);
    trace_wall_s += clock_s(CLOCK_MONOTONIC) - w0;
  };
  std::size_t m = 0;
  auto cells = [&] {
    const double w0 = clock_s(CLOCK_MONOTONIC);
    const double t0 = clock_s(mode == 6 ? CLOCK_PROCESS_CPUTIME_ID : CLOCK_THREAD_CPUTIME_ID);
    m = terrain->compute(c.pose, all.subspan(cap), es, dropped);
    engine_cpu_s += clock_s(mode == 6 ? CLOCK_PROCESS_CPUTIME_ID : CLOCK_THREAD_CPUTIME_ID) - t0;
    engine_wall_s += clock_s(CLOCK_MONOTONIC) - w0;
  };
  const double process_cpu0_s = clock_s(CLOCK_PROCESS_CPUTIME_ID);
  for (auto _ : state) {
    ts = {};
    es = {};
    if (!terrain) {
      trace();
    } else {
      if (mode == 6) {
        trace();
        cells();
      } else {
        tbb::parallel_invoke(trace, cells);
      }
      std::copy_n(all.begin() + static_cast<std::ptrdiff_t>(cap), m,
                  all.begin() + static_cast<std::ptrdiff_t>(n));
      n += m;
    }
    benchmark::DoNotOptimize(n);
  }
  const double per_iteration_ms =
      1e3 / static_cast<double>(std::max<benchmark::IterationCount>(1, state.iterations()));
  state.counters["engine_cpu_ms"] = engine_cpu_s * per_iteration_ms;
  state.counters["cpu_all_ms"] =
      (clock_s(CLOCK_PROCESS_CPUTIME_ID) - process_cpu0_s) * per_iteration_ms;
  state.counters["engine_ms"] = engine_wall_s * per_iteration_ms;
  state.counters["trace_ms"] = trace_wall_s * per_iteration_ms;
  state.counters["rays"] = static_cast<double>(ts.rays);
  state.counters["returns"] = static_cast<double>(n);
  state.counters["patches"] = static_cast<double>(es.patches);
  state.counters["patches_lit"] = static_cast<double>(es.patches_lit);
  state.counters["facets"] = terrain ? static_cast<double>(terrain->engine().facets().size()) : 0.0;
  state.counters["facets_considered"] = static_cast<double>(es.facets_considered);
  state.counters["horizon_patches"] = static_cast<double>(es.horizon_patches);
  state.counters["queries"] = static_cast<double>(es.occlusion_queries);
  static constexpr const char* kModes[] = {", rays",
                                           ", engine",
                                           ", no terrain",
                                           ", engine without shadowing",
                                           ", engine, a ray per patch",
                                           ", engine, 0.25 deg columns",
                                           ", engine after the trace"};
  state.SetLabel(std::string(state.range(0) == 0 ? "default" : "terrain_movers") + kModes[mode] +
                 (serial ? ", 1 thread" : ""));
}
BENCHMARK(BM_TraceTerrain)
    ->ArgsProduct({{0, 1}, {0, 1, 2, 3, 4, 5, 6}, {0, 1}})
    ->Unit(benchmark::kMillisecond)
    ->UseRealTime();

// The terrain engine at the fidelity governor's levels (issue 29, "a scene heavier than the
// machine"): examples/terrain_movers.toml's first pose, the engine alone (no rays), one thread,
// TerrainReturns::compute at level L's terrain knob (patch scale 2^(L/4), loop/governor.hpp), then
// the scenario's sensor on those returns alone. Argument: L. Counters (per frame, the thread's CPU
// time): engine_ms, sensor_ms, patches, horizon_samples, returns (the lit cells), columns and bins
// of the cell grid the engine used at that level.
void BM_TerrainLevel(benchmark::State& state) {
  struct Case {
    loop::Scenario s =
        loop::load_scenario(std::string(RADAR_EMU_EXAMPLES_DIR) + "/terrain_movers.toml");
    radar_emu::scene::Scene scene{loop::scene_description(s)};
    radar::RadarPose pose;
    std::optional<radar::SbrTracer> tracer;
    std::optional<radar::TerrainReturns> terrain;
    std::optional<radar::Sensor> sensor;
    Case() {
      scene.set_time(0.0);
      pose = loop::scripted_pose(s);
      radar::SbrConfig cfg = s.sbr;
      cfg.terrain_rays = false;
      tracer.emplace(scene, cfg);
      terrain.emplace(scene, *tracer, loop::terrain_returns_config(s));
      radar::SensorConfig sc = s.sensor;
      sc.max_contributions = terrain->max_returns();
      sensor.emplace(sc);
    }
  };
  static Case c;
  const tbb::global_control serial(tbb::global_control::max_allowed_parallelism, 1);
  const double scale = std::pow(2.0, 0.25 * static_cast<double>(state.range(0)));
  std::vector<radar::Contribution> out(c.terrain->max_returns());
  std::vector<radar::Detection> detections(c.s.sensor.max_detections);
  auto cpu_s = [] {
    timespec t{};
    clock_gettime(CLOCK_THREAD_CPUTIME_ID, &t);
    return static_cast<double>(t.tv_sec) + 1e-9 * static_cast<double>(t.tv_nsec);
  };
  radar::clutter::TerrainStats es;
  radar::SensorStats ss;
  std::uint64_t dropped = 0;
  std::size_t n = 0;
  double engine_s = 0.0, sensor_s = 0.0;
  for (auto _ : state) {
    es = {};
    ss = {};
    const double t0 = cpu_s();
    n = c.terrain->compute(c.pose, out, es, dropped, scale);
    const double t1 = cpu_s();
    benchmark::DoNotOptimize(
        c.sensor->process(std::span<const radar::Contribution>(out.data(), n), detections, ss));
    sensor_s += cpu_s() - t1;
    engine_s += t1 - t0;
  }
  const double per_ms =
      1e3 / static_cast<double>(std::max<benchmark::IterationCount>(1, state.iterations()));
  state.counters["engine_ms"] = engine_s * per_ms;
  state.counters["sensor_ms"] = sensor_s * per_ms;
  state.counters["patches"] = static_cast<double>(es.patches);
  state.counters["horizon_samples"] = static_cast<double>(es.horizon_patches);
  state.counters["returns"] = static_cast<double>(n);
  state.counters["dropped"] = static_cast<double>(dropped);
}
BENCHMARK(BM_TerrainLevel)
    ->Arg(0)
    ->Arg(4)
    ->Arg(8)
    ->Arg(12)
    ->Arg(16)
    ->Unit(benchmark::kMillisecond)
    ->UseRealTime();

// The tracer against raw Embree on the same frame's rays (issue 29, item 1: "the tracer at >= 50 %
// of the raw Embree rate on the same frame's rays"). The frame of BM_TraceTerrain/0/M/1 (the
// default scenario's first pose, argument M = 0: with the terrain grid, 2: without it) is traced
// once with a radar::QueryLog, which records every scene query the tracer makes: the rays'
// segments (closest hit) and its occlusion queries (bounce 1's facet samples, the edges' probes,
// the later bounces' shadow rays). Raw: those queries replayed by rtcIntersect1 / rtcOccluded1
// alone through one Embree BVH of the same world triangles (every object at the scene's time 0,
// each terrain tile at its active level), built as the scene builds its own (robust mode, high
// quality: scene::embree_build()), with nothing else: no refit in double, no per-object
// transform, no physics. Each iteration runs the whole trace and then the raw replay, one thread,
// and times both by the thread's CPU clock, so the two share the machine's state and load.
// Counters: trace_ms, raw_ms (CPU per frame), fraction = raw_ms / trace_ms (the tracer's rate as a
// fraction of the raw rate on the same rays), the queries replayed, and raw_hits against the
// tracer's hits (the same rays: close, not equal, as the tracer's BVHs are split by object).
// The same replay through Embree's default build (fast mode, not watertight): raw_fast_ms,
// fraction_fast, and fast_differs, the queries it answers differently from the robust BVH (the
// reason the scene pays for robust mode). Until stop 45 the yardstick was that fast build.
void BM_TraceRaw(benchmark::State& state) {
  namespace scene = radar_emu::scene;
  static loop::Scenario s =
      loop::parse_scenario(loop::default_scenario_toml(), "<default scenario>");
  static scene::Scene world(loop::scene_description(s));
  world.set_time(0.0);
  const radar::RadarPose pose = loop::scripted_pose(s);
  tbb::global_control serial(tbb::global_control::max_allowed_parallelism, 1);
  radar::SbrConfig cfg = s.sbr;
  cfg.terrain_rays = state.range(0) == 0;
  cfg.reuse_static_paths = false;  // the frame traced whole, every iteration
  radar::SbrTracer tracer(world, cfg);
  std::vector<radar::Contribution> out(tracer.max_contributions());
  // Record the frame's queries (twice: the first pass sizes the log).
  radar::TraceStats ts;
  std::vector<scene::Ray> intersects, occlusions;
  {
    radar::QueryLog sizing;
    tracer.set_query_log(&sizing);
    (void)tracer.trace(pose, out, ts);
    intersects.resize(sizing.n_intersects.load());
    occlusions.resize(sizing.n_occlusions.load());
    radar::QueryLog log;
    log.intersects = intersects;
    log.occlusions = occlusions;
    tracer.set_query_log(&log);
    ts = {};
    (void)tracer.trace(pose, out, ts);
    tracer.set_query_log(nullptr);
    // The first trace fills the tracer's memos, so this one, like the timed ones, asks fewer
    // queries than the sizing pass counted: the replay is this trace's queries only.
    intersects.resize(std::min(intersects.size(), log.n_intersects.load()));
    occlusions.resize(std::min(occlusions.size(), log.n_occlusions.load()));
  }
  // One flat Embree BVH of the world triangles the queries can meet, built as the scene builds
  // its BVHs (scene::embree_build(): robust mode, high quality): `rs`, the yardstick. Beside it
  // the same triangles in Embree's default build (fast mode, medium quality): `fast`, timed too,
  // with a count of the queries it answers differently (fast_differs).
  const scene::SceneDescription& desc = world.description();
  std::map<std::int32_t, std::vector<std::uint8_t>> levels;  // LOD group -> its levels, sorted
  for (const scene::ObjectDesc& o : desc.objects) {
    if (o.lod_group >= 0)
      levels[o.lod_group].push_back(o.lod_level);
  }
  for (auto& [g, l] : levels)
    std::sort(l.begin(), l.end());
  RTCDevice device = rtcNewDevice(nullptr);
  RTCScene rs = rtcNewScene(device);
  const scene::EmbreeBuild build = scene::embree_build();
  rtcSetSceneFlags(rs, static_cast<RTCSceneFlags>(build.scene_flags));
  rtcSetSceneBuildQuality(rs, static_cast<RTCBuildQuality>(build.build_quality));
  RTCScene fast = rtcNewScene(device);
  for (std::uint32_t id = 0; id < desc.objects.size(); ++id) {
    const scene::ObjectDesc& o = desc.objects[id];
    if (o.lod_group >= 0) {
      const int active = world.active_lod_level(o.lod_group);
      if (active < 0 || levels[o.lod_group][static_cast<std::size_t>(active)] != o.lod_level)
        continue;
    }
    const glm::dmat4 x = world.world_from_body(id);
    RTCGeometry geom = rtcNewGeometry(device, RTC_GEOMETRY_TYPE_TRIANGLE);
    auto* v = static_cast<float*>(rtcSetNewGeometryBuffer(geom, RTC_BUFFER_TYPE_VERTEX, 0,
                                                          RTC_FORMAT_FLOAT3, 3 * sizeof(float),
                                                          o.mesh.positions_m.size()));
    for (std::size_t i = 0; i < o.mesh.positions_m.size(); ++i) {
      const glm::dvec3 p(x * glm::dvec4(glm::dvec3(o.mesh.positions_m[i]), 1.0));
      v[3 * i] = static_cast<float>(p.x);
      v[3 * i + 1] = static_cast<float>(p.y);
      v[3 * i + 2] = static_cast<float>(p.z);
    }
    // glm::uvec3 is three packed 4-byte values: Embree's UINT3 layout.
    std::memcpy(rtcSetNewGeometryBuffer(geom, RTC_BUFFER_TYPE_INDEX, 0, RTC_FORMAT_UINT3,
                                        sizeof(glm::uvec3), o.mesh.triangles.size()),
                o.mesh.triangles.data(), o.mesh.triangles.size() * sizeof(glm::uvec3));
    rtcCommitGeometry(geom);
    rtcAttachGeometry(rs, geom);
    rtcAttachGeometry(fast, geom);
    rtcReleaseGeometry(geom);
  }
  rtcCommitScene(rs);
  rtcCommitScene(fast);
  auto to_rtc = [](const scene::Ray& r) {
    RTCRay e{};
    e.org_x = static_cast<float>(r.origin_m.x);
    e.org_y = static_cast<float>(r.origin_m.y);
    e.org_z = static_cast<float>(r.origin_m.z);
    e.dir_x = static_cast<float>(r.direction.x);
    e.dir_y = static_cast<float>(r.direction.y);
    e.dir_z = static_cast<float>(r.direction.z);
    e.tnear = static_cast<float>(r.t_near_m);
    e.tfar =
        r.t_far_m >= 3e38 ? std::numeric_limits<float>::infinity() : static_cast<float>(r.t_far_m);
    e.mask = 0xFFFFFFFFu;
    return e;
  };
  auto cpu_s = [] {
    timespec t{};
    clock_gettime(CLOCK_THREAD_CPUTIME_ID, &t);
    return static_cast<double>(t.tv_sec) + 1e-9 * static_cast<double>(t.tv_nsec);
  };
  // The queries as Embree takes them, converted once outside the timing: the replay is Embree
  // alone (each query copied from its prepared struct, rows whole, as the scene's to_embree
  // stores them).
  std::vector<RTCRayHit> prepared_intersects(intersects.size());
  for (std::size_t i = 0; i < intersects.size(); ++i) {
    RTCRayHit& rh = prepared_intersects[i];
    rh = RTCRayHit{};
    rh.ray = to_rtc(intersects[i]);
    rh.hit.geomID = RTC_INVALID_GEOMETRY_ID;
    rh.hit.instID[0] = RTC_INVALID_GEOMETRY_ID;
  }
  std::vector<RTCRay> prepared_occlusions(occlusions.size());
  for (std::size_t i = 0; i < occlusions.size(); ++i)
    prepared_occlusions[i] = to_rtc(occlusions[i]);
  // The fast build's answers against the yardstick's: a hit against a miss, a different
  // triangle more than 1 mm nearer or farther (the same triangle is the same answer: the scene
  // refits its distance in double; a different one at the same distance, the same surface), or
  // a different occlusion.
  std::uint64_t fast_differs = 0;
  {
    RTCIntersectContext ctx;
    rtcInitIntersectContext(&ctx);
    for (const RTCRayHit& prepared : prepared_intersects) {
      RTCRayHit a = prepared, b = prepared;
      rtcIntersect1(rs, &ctx, &a);
      rtcIntersect1(fast, &ctx, &b);
      const bool hit_a = a.hit.geomID != RTC_INVALID_GEOMETRY_ID;
      const bool hit_b = b.hit.geomID != RTC_INVALID_GEOMETRY_ID;
      const bool other_triangle =
          hit_a && (a.hit.geomID != b.hit.geomID || a.hit.primID != b.hit.primID);
      fast_differs +=
          hit_a != hit_b || (other_triangle && std::abs(a.ray.tfar - b.ray.tfar) > 1e-3f);
    }
    for (const RTCRay& prepared : prepared_occlusions) {
      RTCRay a = prepared, b = prepared;
      rtcOccluded1(rs, &ctx, &a);
      rtcOccluded1(fast, &ctx, &b);
      fast_differs += (a.tfar < 0.0f) != (b.tfar < 0.0f);
    }
  }
  auto replay = [&](RTCScene scene, std::uint64_t& hits, std::uint64_t& blocked) {
    hits = 0;
    blocked = 0;
    RTCIntersectContext ctx;
    rtcInitIntersectContext(&ctx);
    for (const RTCRayHit& prepared : prepared_intersects) {
      RTCRayHit rh = prepared;
      rtcIntersect1(scene, &ctx, &rh);
      hits += rh.hit.geomID != RTC_INVALID_GEOMETRY_ID ? 1u : 0u;
    }
    for (const RTCRay& prepared : prepared_occlusions) {
      RTCRay ray = prepared;
      rtcOccluded1(scene, &ctx, &ray);
      blocked += ray.tfar < 0.0f ? 1u : 0u;
    }
  };
  double trace_s = 0.0, raw_s = 0.0, fast_s = 0.0;
  std::uint64_t raw_hits = 0, raw_blocked = 0, fast_hits = 0, fast_blocked = 0;
  for (auto _ : state) {
    ts = {};
    const double t0 = cpu_s();
    benchmark::DoNotOptimize(tracer.trace(pose, out, ts));
    const double t1 = cpu_s();
    replay(rs, raw_hits, raw_blocked);
    const double t2 = cpu_s();
    replay(fast, fast_hits, fast_blocked);
    fast_s += cpu_s() - t2;
    raw_s += t2 - t1;
    trace_s += t1 - t0;
  }
  rtcReleaseScene(fast);
  rtcReleaseScene(rs);
  rtcReleaseDevice(device);
  const double per_iteration_ms =
      1e3 / static_cast<double>(std::max<benchmark::IterationCount>(1, state.iterations()));
  state.counters["trace_ms"] = trace_s * per_iteration_ms;
  state.counters["raw_ms"] = raw_s * per_iteration_ms;
  state.counters["fraction"] = trace_s > 0.0 ? raw_s / trace_s : 0.0;
  state.counters["raw_fast_ms"] = fast_s * per_iteration_ms;
  state.counters["fraction_fast"] = trace_s > 0.0 ? fast_s / trace_s : 0.0;
  state.counters["fast_differs"] = static_cast<double>(fast_differs);
  state.counters["rays"] = static_cast<double>(ts.rays);
  state.counters["intersects"] = static_cast<double>(intersects.size());
  state.counters["occlusions"] = static_cast<double>(occlusions.size());
  state.counters["hits"] = static_cast<double>(ts.hits);
  state.counters["raw_hits"] = static_cast<double>(raw_hits);
  state.counters["raw_blocked"] = static_cast<double>(raw_blocked);
  state.SetLabel(state.range(0) == 0 ? "default, rays, 1 thread" : "default, no terrain, 1 thread");
}
BENCHMARK(BM_TraceRaw)->Arg(0)->Arg(2)->Unit(benchmark::kMillisecond);

// The terrain engine's cells alone (TerrainReturns::compute, the loop's configuration) from the
// scenario's first pose, as in BM_TraceTerrain's engine rows. Argument 0: the default scenario
// (0) or examples/terrain_movers.toml (1); argument 1: TBB threads (0: all). Counters: cpu_ms,
// the CPU time of all the process's threads per compute (one thread: the work itself).
void BM_TerrainCompute(benchmark::State& state) {
  std::optional<tbb::global_control> threads;
  if (state.range(1) > 0)
    threads.emplace(tbb::global_control::max_allowed_parallelism,
                    static_cast<std::size_t>(state.range(1)));
  loop::Scenario s =
      state.range(0) == 0
          ? loop::parse_scenario(loop::default_scenario_toml(), "<default scenario>")
          : loop::load_scenario(std::string(RADAR_EMU_EXAMPLES_DIR) + "/terrain_movers.toml");
  radar_emu::scene::Scene scene(loop::scene_description(s));
  scene.set_time(0.0);
  const radar::RadarPose pose = loop::scripted_pose(s);
  radar::SbrConfig cfg = s.sbr;
  cfg.terrain_rays = false;
  radar::SbrTracer tracer(scene, cfg);
  radar::TerrainReturns terrain(scene, tracer, loop::terrain_returns_config(s));
  std::vector<radar::Contribution> out(terrain.max_returns());
  radar::clutter::TerrainStats es;
  std::uint64_t dropped = 0;
  std::size_t n = 0;
  timespec t0{}, t1{};
  clock_gettime(CLOCK_PROCESS_CPUTIME_ID, &t0);
  for (auto _ : state) {
    es = {};
    n = terrain.compute(pose, out, es, dropped);
    benchmark::DoNotOptimize(n);
  }
  clock_gettime(CLOCK_PROCESS_CPUTIME_ID, &t1);
  state.counters["cpu_ms"] =
      (1e3 * static_cast<double>(t1.tv_sec - t0.tv_sec) +
       1e-6 * static_cast<double>(t1.tv_nsec - t0.tv_nsec)) /
      static_cast<double>(std::max<benchmark::IterationCount>(1, state.iterations()));
  double power_m2 = 0.0;  // the returns' total mean power: the same cells give the same sum
  for (std::size_t i = 0; i < n; ++i)
    power_m2 += std::norm(out[i].amplitude);
  state.counters["returns"] = static_cast<double>(n);
  state.counters["power_m2"] = power_m2;
  state.counters["patches"] = static_cast<double>(es.patches);
  state.counters["patches_lit"] = static_cast<double>(es.patches_lit);
  state.counters["queries"] = static_cast<double>(es.occlusion_queries);
  state.counters["facets_considered"] = static_cast<double>(es.facets_considered);
}
BENCHMARK(BM_TerrainCompute)
    ->ArgsProduct({{0, 1}, {1, 2}})
    ->Unit(benchmark::kMillisecond)
    ->UseRealTime();

void BM_SceneSetTime(benchmark::State& state) {
  Fixture& f = fixture();
  double t = 0.0;
  for (auto _ : state) {
    f.scene.set_time(t);
    t += 0.05;
  }
}
BENCHMARK(BM_SceneSetTime)->Unit(benchmark::kMicrosecond);

// Whole closed-loop frames (bus in, trace, sensor, bus out), 50 frames per iteration.
void BM_ClosedLoop50Frames(benchmark::State& state) {
  loop::Scenario s = loop::parse_scenario(loop::default_scenario_toml(), "<default scenario>");
  s.frames = 50;
  for (auto _ : state) {
    state.PauseTiming();
    loop::ClosedLoop loop(s, {});
    state.ResumeTiming();
    benchmark::DoNotOptimize(loop.run());
  }
  state.counters["frames_per_s"] =
      benchmark::Counter(50.0, benchmark::Counter::kIsIterationInvariantRate);
}
BENCHMARK(BM_ClosedLoop50Frames)->Unit(benchmark::kMillisecond)->UseRealTime();

// Whole closed-loop runs of `s`, one an iteration (the loop built outside the timing): the last
// run's result, and the counter cpu_all_ms, the CPU time of all the process's threads a frame.
loop::RunResult timed_runs(const loop::Scenario& s, benchmark::State& state) {
  loop::RunResult r;
  double cpu_s = 0.0;
  for (auto _ : state) {
    state.PauseTiming();
    loop::ClosedLoop loop(s, {});
    timespec t0{}, t1{};
    clock_gettime(CLOCK_PROCESS_CPUTIME_ID, &t0);
    state.ResumeTiming();
    r = loop.run();
    clock_gettime(CLOCK_PROCESS_CPUTIME_ID, &t1);
    cpu_s += static_cast<double>(t1.tv_sec - t0.tv_sec) +
             1e-9 * static_cast<double>(t1.tv_nsec - t0.tv_nsec);
  }
  const double frames =
      static_cast<double>(s.frames) *
      static_cast<double>(std::max<benchmark::IterationCount>(1, state.iterations()));
  state.counters["cpu_all_ms"] = 1e3 * cpu_s / frames;
  return r;
}

// Whole closed-loop frames with terrain clutter both ways (issue 28): the scenario's first 20
// frames, [governor] off, terrain rays (argument 1 = 0) or the engine's cells (1) beside the
// trace. Argument 0: the default scenario (0) or examples/terrain_movers.toml (1). Counters:
// cpu_all_ms, the CPU time of all the process's threads per frame (the frame's work on every
// core); trace_p50_ms and sensor_p50_ms, the stages' medians.
void BM_ClosedLoopTerrain(benchmark::State& state) {
  loop::Scenario s =
      state.range(0) == 0
          ? loop::parse_scenario(loop::default_scenario_toml(), "<default scenario>")
          : loop::load_scenario(std::string(RADAR_EMU_EXAMPLES_DIR) + "/terrain_movers.toml");
  s.frames = 20;
  s.governor.enabled = false;
  s.terrain_engine = state.range(1) == 1;
  s.sbr.terrain_rays = !s.terrain_engine;
  const loop::RunResult r = timed_runs(s, state);
  state.counters["trace_p50_ms"] =
      1e3 * r.stages[static_cast<std::size_t>(radar_emu::timing::Stage::kTrace)].p50_s;
  state.counters["sensor_p50_ms"] =
      1e3 * r.stages[static_cast<std::size_t>(radar_emu::timing::Stage::kSensor)].p50_s;
  state.SetLabel(std::string(state.range(0) == 0 ? "default" : "terrain_movers") +
                 (s.terrain_engine ? ", engine" : ", rays"));
}
BENCHMARK(BM_ClosedLoopTerrain)
    ->ArgsProduct({{0, 1}, {0, 1}})
    ->Iterations(1)
    ->Unit(benchmark::kMillisecond)
    ->UseRealTime();

// The frame budget (issue 15): whole closed-loop runs of a scenario as fast as possible (the
// governor in its reproducible model mode), the frame time's percentiles as fractions of the
// frame period. Argument 0: the default scenario; 1: examples/ev_radar_94ghz.toml (10 Hz);
// 2: examples/terrain_movers.toml (the 207k-polygon terrain, three moving targets). Goals:
// p99 / budget <= 0.5 (default), <= 0.8 (the others).
void BM_FrameBudget(benchmark::State& state) {
  static constexpr const char* kFiles[] = {nullptr, "ev_radar_94ghz.toml", "terrain_movers.toml"};
  const char* file = kFiles[state.range(0)];
  loop::Scenario s = file == nullptr
                         ? loop::parse_scenario(loop::default_scenario_toml(), "<default scenario>")
                         : loop::load_scenario(std::string(RADAR_EMU_EXAMPLES_DIR) + "/" + file);
  s.frames = 100;
  loop::RunResult r;
  for (auto _ : state) {
    state.PauseTiming();
    loop::ClosedLoop loop(s, {});
    state.ResumeTiming();
    r = loop.run();
  }
  const double budget_ms = 1e3 / s.rate_hz;
  const auto& frame = r.stages[static_cast<std::size_t>(radar_emu::timing::Stage::kFrame)];
  state.counters["budget_ms"] = budget_ms;
  state.counters["p50_ms"] = frame.p50_s * 1e3;
  state.counters["p99_ms"] = frame.p99_s * 1e3;
  state.counters["p50_over_budget"] = frame.p50_s * 1e3 / budget_ms;
  state.counters["p99_over_budget"] = frame.p99_s * 1e3 / budget_ms;
  state.counters["over_budget"] = static_cast<double>(r.frames_over_budget);
  state.counters["degraded"] = static_cast<double>(r.governor.frames_degraded);
  state.counters["max_level"] = r.governor.max_level;
  state.SetLabel(s.name.substr(0, 40));
}
BENCHMARK(BM_FrameBudget)
    ->DenseRange(0, 2)
    ->Iterations(1)
    ->Unit(benchmark::kMillisecond)
    ->UseRealTime();

// Issue 29's acceptance frame: whole closed-loop runs at full physics ([governor] off: level 0
// every frame), the frame's and the stages' p50 / p99 [ms] (stage times of the loop's own clock),
// and cpu_all_ms, the CPU time of all the process's threads per frame. Argument 0: the default
// scenario (0, 200 frames: its whole flight) or examples/terrain_movers.toml (1, its first 60
// frames); argument 1: [radar] reuse_static_paths off (0) or as the scenario has it (1). The
// first frame traces every bundle (nothing is kept yet): it is in the percentiles.
void BM_FrameLevel0(benchmark::State& state) {
  loop::Scenario s =
      state.range(0) == 0
          ? loop::parse_scenario(loop::default_scenario_toml(), "<default scenario>")
          : loop::load_scenario(std::string(RADAR_EMU_EXAMPLES_DIR) + "/terrain_movers.toml");
  s.frames = state.range(0) == 0 ? 200 : 60;
  s.governor.enabled = false;
  if (state.range(1) == 0)
    s.sbr.reuse_static_paths = false;
  const loop::RunResult r = timed_runs(s, state);
  using radar_emu::timing::Stage;
  auto stage = [&](Stage st) { return r.stages[static_cast<std::size_t>(st)]; };
  state.counters["frame_p50_ms"] = 1e3 * stage(Stage::kFrame).p50_s;
  state.counters["frame_p99_ms"] = 1e3 * stage(Stage::kFrame).p99_s;
  state.counters["trace_p50_ms"] = 1e3 * stage(Stage::kTrace).p50_s;
  state.counters["trace_p99_ms"] = 1e3 * stage(Stage::kTrace).p99_s;
  state.counters["sensor_p50_ms"] = 1e3 * stage(Stage::kSensor).p50_s;
  state.counters["sensor_p99_ms"] = 1e3 * stage(Stage::kSensor).p99_s;
  const auto frames = static_cast<double>(r.frames);
  state.counters["rays"] = static_cast<double>(r.trace.rays) / frames;
  state.counters["reused_rays"] = static_cast<double>(r.trace.reused_rays) / frames;
  state.SetLabel(std::string(state.range(0) == 0 ? "default" : "terrain_movers") +
                 (s.sbr.reuse_static_paths ? ", static paths reused" : ", every ray traced"));
}
BENCHMARK(BM_FrameLevel0)
    ->ArgsProduct({{0, 1}, {0, 1}})
    ->Iterations(1)
    ->Unit(benchmark::kMillisecond)
    ->UseRealTime();

}  // namespace

BENCHMARK_MAIN();
