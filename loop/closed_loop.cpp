#include "loop/closed_loop.hpp"

#include <tbb/parallel_invoke.h>
#include <unistd.h>

#include <algorithm>
#include <atomic>
#include <cerrno>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <ctime>
#include <limits>
#include <nlohmann/json.hpp>
#include <numbers>
#include <optional>
#include <stdexcept>

#include "common/units.hpp"
#include "io/modbus.hpp"
#include "io/modbus_map.hpp"
#include "loop/accounting.hpp"
#include "loop/bus_backends.hpp"
#include "loop/bus_side.hpp"
#include "loop/outputs/output_stream.hpp"
#include "loop/outputs/run_plots.hpp"
#include "loop/ownship.hpp"
#include "loop/ownship_source.hpp"
#include "loop/peers.hpp"
#include "loop/scene_import.hpp"
#include "radar/clutter/terrain_engine.hpp"
#include "radar/em/surfaces.hpp"
#include "radar/propagation/itu.hpp"
#include "radar/propagation/path.hpp"
#include "scene/airport_gen.hpp"
#include "scene/default_scene.hpp"
#include "scene/geo.hpp"
#include "scene/gltf.hpp"
#include "scene/scene.hpp"
#include "scene/terrain_gen.hpp"
#include "sim_bus/fault_injector.hpp"
#include "timing/clock.hpp"
#include "timing/scheduler.hpp"

namespace radar_emu::loop {

namespace {

// Output paths, checked before any other setup (the scene can take seconds to build): the
// output directory is created, the trace-event file created empty. Throws with the path.
struct OutputPaths {
  explicit OutputPaths(const RunOptions& o) {
    std::error_code ec;
    if (!o.out_dir.empty()) {
      std::filesystem::create_directories(o.out_dir, ec);
      if (ec || !std::filesystem::is_directory(o.out_dir)) {
        throw std::runtime_error(o.out_dir.string() + ": cannot create the output directory" +
                                 (ec ? ": " + ec.message() : std::string()));
      }
    }
    if (!o.trace_events_file.empty()) {
      const std::filesystem::path& p = o.trace_events_file;
      if (p.has_parent_path())
        std::filesystem::create_directories(p.parent_path(), ec);
      trace_events = std::fopen(p.c_str(), "wb");
      if (trace_events == nullptr) {
        throw std::runtime_error(p.string() + ": cannot open for writing: " + std::strerror(errno));
      }
    }
  }
  ~OutputPaths() {
    if (trace_events != nullptr)
      std::fclose(trace_events);
  }
  OutputPaths(const OutputPaths&) = delete;
  OutputPaths& operator=(const OutputPaths&) = delete;
  std::FILE* trace_events = nullptr;  ///< --trace-events, open from setup to the end
};

io::icd::Detection to_icd(const radar::Detection& d) noexcept {
  io::icd::Detection o;
  o.range_m = d.range_m;
  o.azimuth_deg = common::degrees(d.azimuth_rad);
  o.elevation_deg = common::degrees(d.elevation_rad);
  o.radial_velocity_mps = d.radial_velocity_mps;
  o.snr_db = 10.0 * std::log10(d.snr);
  o.rcs_dbsm = 10.0 * std::log10(d.rcs_m2);
  // Carried by the CAN FD lists only (docs/icd/detections.md).
  o.range_std_m = d.range_std_m;
  o.azimuth_std_deg = common::degrees(d.azimuth_std_rad);
  o.elevation_std_deg = common::degrees(d.elevation_std_rad);
  o.radial_velocity_std_mps = d.velocity_std_mps;
  o.range_ambiguous = d.range_ambiguous;
  o.velocity_ambiguous = d.velocity_ambiguous;
  return o;
}

// The scenario's sensor, sized for every contribution the tracer can produce.
radar::SensorConfig sensor_config(const Scenario& s, std::size_t max_contributions) {
  radar::SensorConfig c = s.sensor;
  // Up to 2^18 a frame (the default traces 43 k; the tracer's worst case, 2.5 M, would cost the
  // sensor 260 MB of per-return state); beyond it returns are counted as dropped_input.
  c.max_contributions = std::clamp<std::size_t>(max_contributions, 1, 1u << 18);
  return c;
}

// The scenario's governor with its mode resolved: "auto" learns from the measured stage times
// only when frames are paced on the wall clock (elsewhere the run must be reproducible).
GovernorConfig governor_config(const Scenario& s, const RunOptions& o) {
  GovernorConfig g = s.governor;
  if (g.mode == GovernorConfig::Mode::kAuto)
    g.mode = o.realtime ? GovernorConfig::Mode::kMeasured : GovernorConfig::Mode::kModel;
  return g;
}

// Setup refuses a run of no frames (after the scene, tracer and sensor are built, as always).
const Scenario& require_frames(const Scenario& s) {
  if (s.frames == 0)
    throw std::runtime_error("scenario: frames must be >= 1");
  return s;
}

// Frames one detection list takes on the bus (classic or FD).
std::size_t list_frames(const Scenario& s) {
  return s.can_fd ? io::icd::frames_for_fd(s.sensor.max_detections)
                  : io::icd::frames_for(s.sensor.max_detections);
}

// Input frames one radar frame can receive (sizes the input log): the INS schedule, doubled
// for duplicates, plus a babbling node's rate.
std::uint64_t input_frames_per_frame(const Scenario& s) {
  double per_s = (3.0 * s.attitude_rate_hz + 8.0 * s.navigation_rate_hz) *
                 (1.0 + s.link_faults.duplicate_probability);
  if (s.babbling_node)
    per_s += s.babble.rate_hz * (1.0 + s.link_faults.duplicate_probability);
  return static_cast<std::uint64_t>(std::ceil(per_s / s.rate_hz)) + 12;
}

// The scenario's link faults acting on the register transport: a lost frame is a lost
// transaction, a stale INS a frozen register image (sim_bus/fault_injector.hpp). None in a
// replay.
sim_bus::RegisterFaultConfig register_faults(const Scenario& s, bool replay) {
  sim_bus::RegisterFaultConfig rf;
  if (!replay) {
    rf.timeout_probability = s.link_faults.drop_probability;
    rf.corrupt_probability = s.link_faults.corrupt_probability;
    rf.corrupt_max_bits = s.link_faults.corrupt_max_bits;
    if (s.stale_sender) {
      rf.frozen_start_s = s.stale.start_s;
      rf.frozen_end_s = s.stale.end_s;
    }
    rf.seed = s.link_faults.seed;
  }
  rf.epoch_ns = s.epoch_unix_ns;
  return rf;
}

// [weather]: the one-way specific attenuation at the carrier, built once from the ITU-R
// models (radar/propagation/path.hpp sums P.676 gases, P.838 rain and P.840 fog), rain at the
// tilt of the scenario's polarisation (rain_tilt_rad()).
WeatherFigures weather_figures(const Scenario& s) {
  const WeatherSpec& w = s.weather;
  WeatherFigures out;
  if (!w.enabled)
    return out;
  const double f = s.sbr.carrier_hz;
  const radar::Atmosphere air{w.pressure_hpa, w.temperature_k, w.humidity_gm3};
  const double tilt_rad = rain_tilt_rad(s.sbr.polarisation);
  try {
    radar::MediumSpec medium;
    medium.name = w.condition;
    medium.atmosphere = air;
    medium.rain_mm_per_h = w.rain_mm_per_h;
    medium.liquid_water_gm3 = w.fog_water_gm3;
    const radar::PathAttenuation path(f, tilt_rad, std::span(&medium, 1));
    out.total_db_per_m = path.specific_db_per_m(0);
    out.gas_db_per_km = radar::gaseous_specific_attenuation(f, air).total_db_per_km();
    out.rain_db_per_km =
        radar::rain_specific_attenuation_db_per_km(f, w.rain_mm_per_h, 0.0, tilt_rad);
    if (w.fog_water_gm3 > 0.0) {
      out.fog_db_per_km =
          radar::cloud_fog_specific_attenuation_db_per_km(f, w.fog_water_gm3, w.temperature_k);
    }
  } catch (const std::invalid_argument& e) {
    throw std::runtime_error("scenario: [weather] at carrier_hz " + std::to_string(f) + ": " +
                             e.what());
  }
  return out;
}

// The streamed outputs (loop/outputs/output_stream.hpp): real-time runs drop what the writer
// cannot take in time (counted); simulated-clock runs wait for it between frames.
std::unique_ptr<OutputStream> open_output_stream(const Scenario& s, const RunOptions& o,
                                                 const scene::Scene& scene,
                                                 std::span<const std::uint32_t> truth_objects) {
  OutputStreamConfig c;
  c.dir = o.out_dir;
  c.scenario = &s;
  c.frames_planned = s.frames;
  for (const auto& obj : scene.description().objects)
    c.object_names.push_back(obj.name);
  c.truth_objects.assign(truth_objects.begin(), truth_objects.end());
  c.max_detections = s.sensor.max_detections;
  c.bus_frames_per_frame = static_cast<std::size_t>(input_frames_per_frame(s)) + list_frames(s);
  c.wait_when_full = !o.realtime;
  c.wake_latency = o.realtime;
  return std::make_unique<OutputStream>(std::move(c));
}

// The cube file (loop/outputs/cube_writer.hpp): checked and created now. Real-time runs drop
// the frames the writer has no slot for (counted); simulated-clock runs wait for it.
std::unique_ptr<CubeWriter> open_cube_writer(const Scenario& s, const RunOptions& o,
                                             const radar::Sensor& sensor) {
  CubeWriterConfig c;
  c.file = o.cube_file;
  c.first_frame = o.cube_first_frame;
  c.last_frame = o.cube_last_frame;
  c.file_source = o.cube_file_source;
  c.frames_source = o.cube_frames_source;
  c.run_frames = s.frames;
  c.sensor = &sensor;
  c.scenario_name = s.name;
  c.wait_when_full = !o.realtime;
  return std::make_unique<CubeWriter>(std::move(c));
}

// The live view (loop/outputs/live_view.hpp): binds its server now, so that a bad address or a
// port in use is an error before the run.
std::unique_ptr<LiveView> open_live_view(const Scenario& s, const RunOptions& o,
                                         const scene::Scene& scene, std::size_t max_truth) {
  LiveViewConfig c;
  c.serve = o.serve;
  c.scenario = &s;
  for (const auto& obj : scene.description().objects)
    c.object_names.push_back(obj.name);
  c.max_detections = s.sensor.max_detections;
  c.max_truth = std::max<std::size_t>(max_truth, 1);
  return std::make_unique<LiveView>(std::move(c));
}

// Ground truth covers the objects with a conducting material (the tracer's targets); pure
// terrain (ground, pavement, grass) is left out of truth.json.
std::vector<std::uint32_t> truth_objects(const scene::Scene& scene,
                                         const radar::SbrTracer& tracer) {
  std::vector<std::uint32_t> ids;
  for (std::size_t i = 0; i < scene.description().objects.size(); ++i) {
    if (tracer.is_target(static_cast<std::uint32_t>(i)))
      ids.push_back(static_cast<std::uint32_t>(i));
  }
  return ids;
}

// The association gate of the outcome per target (loop/outcome.hpp): the sensor's resolution
// cells and ambiguity intervals.
AssociationGate association_gate(const Scenario& s, const radar::Sensor& sensor) {
  AssociationGate g;
  g.range_cell_m = radar::range_resolution_m(s.sensor.processing.waveform);
  g.azimuth_cell_rad = sensor.antenna().sum_beamwidth_az_rad();
  g.elevation_cell_rad = sensor.antenna().sum_beamwidth_el_rad();
  g.unambiguous_range_m = sensor.unambiguous_range_m();
  g.unambiguous_velocity_mps = sensor.unambiguous_velocity_mps();
  return g;
}

// Setup: a [[target]] that never enters the beam over the planned run gets a warning. The
// check flies the scripted ownship (the scenario's [ownship] straight line and attitude in the
// anchor's ENU frame) against each target's scripted trajectory (Scene::set_time: transforms
// only), at every frame time, or at kSamples times evenly spread over a longer run; in the beam
// means what truth.json means (objects_in_view). A run whose ownship comes from elsewhere (a
// real bus, a replay, an external Modbus source, Python) flies what it is given: the summary's
// per-target table says what it saw. Leaves the scene at time 0.
void warn_targets_never_in_beam(const Scenario& s, scene::Scene& scene,
                                std::vector<std::string>& warnings) {
  const std::size_t n_objects = scene.objects().size();
  if (s.targets.empty() || s.targets.size() > n_objects || s.frames == 0)
    return;
  const std::size_t first = n_objects - s.targets.size();  // appended in table order
  std::vector<std::uint32_t> ids;
  for (std::size_t k = first; k < n_objects; ++k)
    ids.push_back(static_cast<std::uint32_t>(k));
  std::vector<bool> seen(ids.size(), false);
  std::vector<ObjectTruth> in_view(ids.size());
  constexpr std::uint64_t kSamples = 100'000;
  const std::uint64_t samples = std::min<std::uint64_t>(s.frames, kSamples);
  const double duration_s = static_cast<double>(s.frames - 1) / s.rate_hz;
  radar::RadarPose pose;
  pose.world_from_antenna =
      enu_from_body(s.ownship_heading_rad, s.ownship_pitch_rad, s.ownship_roll_rad) *
      body_from_antenna(s.antenna_depression_rad);
  pose.velocity_mps = s.ownship_velocity_enu_mps;
  std::size_t unseen = ids.size();
  for (std::uint64_t k = 0; k < samples && unseen > 0; ++k) {
    const double t_s =
        samples > 1 ? duration_s * static_cast<double>(k) / static_cast<double>(samples - 1) : 0.0;
    scene.set_time(t_s);
    pose.position_m = s.ownship_start_enu_m + s.ownship_velocity_enu_mps * t_s;
    const std::size_t n = objects_in_view(pose, scene.objects(), ids, s.sbr, in_view);
    for (std::size_t j = 0; j < n; ++j) {
      const std::size_t idx = in_view[j].object_id - first;
      if (!seen[idx]) {
        seen[idx] = true;
        --unseen;
      }
    }
  }
  scene.set_time(0.0);
  for (std::size_t i = 0; i < ids.size(); ++i) {
    if (seen[i])
      continue;
    const scene::TargetPlacement& t = s.targets[i];
    warnings.push_back((t.context.empty() ? "[[target]]" : t.context) + " '" + t.name +
                       "' never enters the beam over the planned run (" + std::to_string(s.frames) +
                       " frames along the scripted [ownship] flight): it will not be seen");
  }
}

// ---- the loop's parts (each built once from the scenario) ----

// The scene database, its anchor's ENU frame, and the objects ground truth covers.
struct SceneSide {
  explicit SceneSide(const Scenario& s)
      : scene(scene_description(s, &import)), enu(scene.anchor()) {}
  scene::geodata::ImportReport import;  ///< [scene.import]'s report (before `scene`: filled by it)
  scene::Scene scene;
  scene::wgs84::EnuFrame enu;
  std::vector<std::uint32_t> truth_objects;  ///< objects truth.json covers
  std::vector<ObjectTruth> frame_truth;      ///< the current frame's objects in view
  std::vector<double> frame_size_m;          ///< their sizes (half the box diagonal) [m]
};

// The SBR tracer, the terrain engine's cells ([radar] terrain = "engine"), their contribution
// buffer (the tracer's returns, then the cells') and the path loss every return takes. A scene
// with no terrain (metal alone) has no terrain clutter: the engine is left out, and no_terrain
// says why (a setup warning).
struct TracerSide {
  TracerSide(const scene::Scene& scene, const Scenario& s) : tracer(scene, s.sbr) {
    if (s.terrain_engine) {
      try {
        terrain.emplace(scene, tracer, terrain_returns_config(s));
      } catch (const radar::clutter::NoTerrain& e) {
        no_terrain = std::string(e.what()) + ": no terrain clutter";
      }
    }
    contributions.resize(tracer.max_contributions() + (terrain ? terrain->max_returns() : 0));
    // Static path reuse: the static targets' paths traced once at setup, from the scenario's
    // scripted start (frame 0's pose on the software bus), so that the first frame re-evaluates
    // them instead of tracing every bundle within its period; a first pose elsewhere (a real
    // bus) is traced in its frame as usual.
    if (s.sbr.reuse_static_paths) {
      radar::TraceStats setup;
      primed_contributions = tracer.trace(
          scripted_pose(s, 0.0), std::span(contributions).first(tracer.max_contributions()), setup);
      primed_rays = setup.rays + setup.reused_rays;
      primed = true;
    }
  }
  /// The engine's part of `contributions`: after the tracer's max_contributions(), its bound.
  [[nodiscard]] std::span<radar::Contribution> engine_part() noexcept {
    return std::span(contributions).subspan(tracer.max_contributions());
  }
  /// Moves the engine's first `m` returns down behind the tracer's first `n`: n + m returns.
  std::size_t append_engine(std::size_t n, std::size_t m) noexcept {
    const std::span<radar::Contribution> engine = engine_part();
    std::copy_n(engine.begin(), m, contributions.begin() + static_cast<std::ptrdiff_t>(n));
    return n + m;
  }
  radar::SbrTracer tracer;
  std::optional<radar::TerrainReturns> terrain;
  std::string no_terrain;  ///< why the engine was left out; empty when it runs
  std::vector<radar::Contribution> contributions;
  WeatherFigures weather;  ///< [weather] one-way; all 0: free space
  /// The frame traced at setup (static path reuse): its returns, at the start of
  /// `contributions` until the first frame, and the rays it traced or kept.
  bool primed = false;
  std::size_t primed_contributions = 0;
  std::uint64_t primed_rays = 0;
};

// The sensor and its detection buffers (the sensor's view and the ICD's).
struct SensorSide {
  SensorSide(const Scenario& s, const TracerSide& tracer)
      : sensor(sensor_config(s, tracer.contributions.size())),
        detections(s.sensor.max_detections),
        icd_detections(s.sensor.max_detections) {}
  radar::Sensor sensor;
  std::vector<radar::Detection> detections;
  std::vector<io::icd::Detection> icd_detections;
};

// What one frame's stages hand each other (on the stack: nothing allocated).
struct Frame {
  timing::Tick tick{};
  std::int64_t start_wall_ns = 0;   ///< wall clock when the frame began [ns]
  std::int64_t since_start_ns = 0;  ///< its deadline since the run's first [ns]
  std::int64_t bus_now_ns = 0;      ///< bus time of the deadline [ns]
  double t_s = 0.0;                 ///< scenario time [s]
  radar::RadarPose pose{};
  bool valid = false;                          ///< a fresh ownship state (or the caller's)
  const GovernorDecision* decision = nullptr;  ///< null: nothing traced
  std::uint64_t rays_before = 0, cells_before = 0, truncated_before = 0, merged_before = 0;
  std::uint64_t under_floor_before = 0;
  std::uint64_t terrain_patches = 0, terrain_returns = 0;  ///< the engine's, this frame
  std::uint64_t terrain_facets = 0;                        ///< the facets cut into its patches
  std::uint64_t kept_returns = 0, cells_synthesised = 0;   ///< this frame's (FrameRecord)
  std::uint64_t target_facets = 0;                         ///< this frame's (FrameRecord)
  std::uint64_t merged_returns = 0;                        ///< this frame's (FrameRecord)
  std::size_t contributions = 0, detections = 0, truth = 0;
  FrameRecord record{};
};

}  // namespace

double rain_tilt_rad(radar::Polarisation polarisation) noexcept {
  switch (polarisation) {
    case radar::Polarisation::kHH:
      return 0.0;
    case radar::Polarisation::kVV:
      return std::numbers::pi / 2.0;
    default:
      return std::numbers::pi / 4.0;  // one way H, the other V
  }
}

scene::SceneDescription scene_database(const SceneSource& s,
                                       scene::geodata::ImportReport* import_report) {
  if (s.import) {
    scene::geodata::ImportReport report;
    scene::SceneDescription d = import_scene(*s.import, report);
    if (import_report != nullptr)
      *import_report = std::move(report);
    return d;
  }
  if (!s.file.empty())
    return scene::load_gltf(s.file);
  if (s.builtin == "airport") {
    scene::AirportSpec spec;
    spec.seed = s.seed;
    spec.corner_reflectors = s.corner_reflectors;
    return scene::generate_airport(spec);
  }
  if (s.builtin == "terrain") {
    scene::TerrainSpec spec;
    spec.seed = s.seed;
    return scene::generate_terrain(spec);
  }
  return scene::default_scene();  // read_scene_source() accepts only these built-ins
}

scene::SceneDescription scene_description(const Scenario& s,
                                          scene::geodata::ImportReport* import_report) {
  scene::SceneDescription d = scene_database(
      {s.scene_builtin, s.scene_seed, s.scene_corner_reflectors, s.scene_file, s.scene_import},
      import_report);
  // [[target]] tables: appended after the database's own objects, in table order. A mesh
  // file's own material names must be radar materials too (a [[target]] material was checked
  // when the scenario was read).
  const std::size_t first_target = d.objects.size();
  scene::add_targets(d, s.targets);
  for (std::size_t i = first_target; i < d.objects.size(); ++i) {
    std::vector<bool> used(d.materials.size(), false);
    for (std::uint16_t k : d.objects[i].mesh.triangle_material)
      used[k] = true;
    for (std::size_t k = 0; k < used.size(); ++k) {
      if (!used[k])
        continue;
      if (!radar::is_surface_material(d.materials[k].name)) {
        throw std::runtime_error(
            s.targets[i - first_target].context + ": mesh_file material '" + d.materials[k].name +
            "' is not a radar material (known: " + radar::surface_material_names() +
            "); set material = \"NAME\" in the table");
      }
    }
  }
  return d;
}

struct ClosedLoop::Impl {
  // Setup, in order (each step may throw with context; nothing after it is built then).
  Impl(const Scenario& s, const RunOptions& o)
      : paths(o),
        scenario(s),
        options(o),
        scene(s),
        tracer(scene.scene, s),
        sensor(s, tracer),
        governor(governor_config(s, o), scene.scene, tracer.tracer, sensor.sensor, 1.0 / s.rate_hz),
        bus(require_frames(s), o.replay, list_frames(s)),
        peers(scenario, scene.enu, bus, o.replay, options.replay_input,
              std::min<std::uint64_t>(s.frames, o.record_frames_max)),
        ownship(bus.decoder()),
        accounting(s, o.record_frames_max, o.timing_frames_max, !o.trace_events_file.empty()) {
    bus.open_can(scenario, o.can, o.nav_modbus, o.realtime, o.replay, warnings);
    choose_ownship_source();
    if (!o.modbus_server.empty())
      bus.open_table_server(o.modbus_server, s.sensor.max_detections);
    tracer.weather = weather_figures(s);
    scene.truth_objects = truth_objects(scene.scene, tracer.tracer);
    scene.frame_truth.resize(scene.truth_objects.size());
    scene.frame_size_m.resize(scene.truth_objects.size());
    outcome.emplace(association_gate(s, sensor.sensor), scene.truth_objects,
                    s.sensor.max_detections, scene.truth_objects.size());
    warn_targets_never_in_beam(s, scene.scene, warnings);
    if (!tracer.no_terrain.empty())
      warnings.push_back(tracer.no_terrain);
    if (tracer.terrain)  // the governor predicts the engine's returns as its cells merge
      governor.set_terrain_cells(tracer.terrain->coarsening());
    if (tracer.primed)
      prime_governor();
    if (!scene.scene.incomplete().empty()) {  // a `scene import` stopped early
      warnings.push_back((s.scene_file.empty() ? std::string("the scene") : s.scene_file.string()) +
                         ": an incomplete scene database (" + scene.scene.incomplete() + ")");
    }
    if (!o.out_dir.empty())
      outputs.stream = open_output_stream(scenario, o, scene.scene, scene.truth_objects);
    if (!o.serve.empty())
      outputs.view = open_live_view(scenario, o, scene.scene, scene.frame_truth.size());
    if (!o.cube_file.empty())
      cube = open_cube_writer(scenario, o, sensor.sensor);
  }

  // The ownship source, once: CANaerospace (the default), the register map played on the
  // loopback bank, or an external Modbus server. A real bus silences the scripted peers.
  void choose_ownship_source() {
    const io::modbus::NavMapConfig nav_map{};
    if (options.nav_modbus == "sim") {
      RegisterBankSource& source =
          ownship.emplace<RegisterBankSource>(nav_map, register_faults(scenario, options.replay));
      peers.play_navigation(source.bank(), nav_map, scenario.navigation_rate_hz);
    } else if (!options.nav_modbus.empty()) {
      ownship.emplace<PollerSource>(options.nav_modbus, nav_map, bus.bus_from_monotonic_ns);
    }
    if (bus.hardware() || ownship.external())
      peers.silence();
  }

  // The governor's first prediction from the frame traced at setup (TracerSide): that frame's
  // returns through the terrain engine and the sensor once, their counts observed as a frame's
  // (no times: a setup frame's wall time says nothing of the loop's; measured mode learns from
  // the first frame). Without it the first frame is predicted from the whole image synthesised
  // and half a return a ray (FidelityGovernor's start), far above a frame's cost: the first
  // frame degrades, and its lost kept paths then hold the run there. The sensor's noise frame
  // and the engine's sigma0 record are set back, so the run draws and reports what it would
  // have.
  void prime_governor() {
    const radar::RadarPose pose = scripted_pose(scenario, 0.0);
    std::size_t n = tracer.primed_contributions;
    std::uint64_t patches = 0, facets = 0, terrain_returns = 0;
    if (tracer.terrain) {
      radar::clutter::TerrainStats ts;
      std::uint64_t dropped = 0;
      terrain_returns = tracer.terrain->compute(pose, tracer.engine_part(), ts, dropped);
      n = tracer.append_engine(n, terrain_returns);
      patches = ts.patches;
      facets = ts.facets_considered;
      tracer.terrain->forget_sigma0_use();
    }
    radar::SensorStats ss;
    const std::uint64_t noise_frame = sensor.sensor.noise_frame();
    (void)sensor.sensor.process(std::span(tracer.contributions).first(n), sensor.detections, ss);
    sensor.sensor.set_noise_frame(noise_frame);
    const double untimed = std::numeric_limits<double>::quiet_NaN();
    governor.observe(untimed, untimed, tracer.primed_rays, n, ss.cells_synthesised, patches,
                     terrain_returns, facets, ss.merged_returns + ss.returns_under_floor);
  }

  // ---- the frame's stages (ClosedLoop::step), each timed but wait_or_stop ----
  bool wait_or_stop(Frame& f);
  void read(Frame& f, const OwnshipInput* given);
  void update_scene(Frame& f);
  void trace(Frame& f);
  void sense(Frame& f);
  void send(Frame& f);
  bool stop_requested(RunResult& r) const;

  OutputPaths paths;  ///< first: checked before the rest of the setup
  Scenario scenario;
  RunOptions options;
  SceneSide scene;
  TracerSide tracer;
  SensorSide sensor;
  FidelityGovernor governor;
  BusSide bus;
  Peers peers;
  OwnshipSource ownship;
  Accounting accounting;
  RunOutputs outputs;
  std::optional<OutcomeTally> outcome;  ///< built once the truth objects are known
  std::unique_ptr<CubeWriter> cube;     ///< RunOptions::cube_file; stopped before the sensor goes
  std::vector<std::string> warnings;    ///< from backend setup and the beam check
};

// A stop request ends the run at a frame boundary: before the wait, or after it (a real-time
// run may sleep a period in between).
bool ClosedLoop::Impl::stop_requested(RunResult& r) const {
  const int sig = options.stop ? options.stop->load(std::memory_order_relaxed) : 0;
  if (sig != 0) {
    r.interrupted = true;
    r.stop_signal = sig;
  }
  return sig != 0;
}

// Waits for the frame's deadline (false: the run is over or stopped); the frame's times.
bool ClosedLoop::Impl::wait_or_stop(Frame& f) {
  RunState& rs = accounting.run();
  if (rs.done >= scenario.frames || stop_requested(rs.r))
    return false;
  if (outputs.stream)
    outputs.stream->wait_for_room();  // simulated clock only: the writer keeps up
  f.tick = rs.scheduler->wait_next();
  if (stop_requested(rs.r))
    return false;
  if (cube)  // a frame of the cube's range: the sensor copies its cells into a free slot
    sensor.sensor.capture_next(cube->begin_frame(f.tick.period_index));
  f.start_wall_ns = rs.wall.now_ns();
  accounting.profiler.set_frame(rs.done);
  f.since_start_ns = f.tick.deadline_ns - rs.start_ns;
  f.t_s = static_cast<double>(f.since_start_ns) * 1e-9;
  f.bus_now_ns = scenario.epoch_unix_ns + f.since_start_ns;
  if (options.realtime)
    accounting.profiler.record(timing::Stage::kWakeLatency, f.tick.wake_ns - f.tick.deadline_ns);
  return true;
}

// Input: the bus read, logged and decoded; the ownship state from its source (or the caller's).
void ClosedLoop::Impl::read(Frame& f, const OwnshipInput* given) {
  RunState& rs = accounting.run();
  RunResult& r = rs.r;
  timing::ScopedStage stage(accounting.profiler, rs.wall, timing::Stage::kInput);
  bus.receive(f.bus_now_ns, outputs.stream.get(), r);
  const io::canas::OwnshipState& st = ownship.read(f.bus_now_ns);
  f.valid = radar_pose_from_state(st, f.bus_now_ns, rs.timeout_ns, scene.enu,
                                  scenario.antenna_depression_rad, f.pose);
  if (given != nullptr) {
    // A stepped frame with the caller's state (step()): it replaces the bus's, in the
    // scenario's [ownship] conventions (anchor ENU, body attitude, the mount depression).
    f.pose.position_m = given->position_enu_m;
    f.pose.velocity_mps = given->velocity_enu_mps;
    f.pose.world_from_antenna =
        enu_from_body(given->heading_rad, given->pitch_rad, given->roll_rad) *
        body_from_antenna(scenario.antenna_depression_rad);
    f.valid = true;
  }
  for (std::size_t k = 0; k < io::canas::kFieldCount; ++k) {
    const auto field = static_cast<io::canas::Field>(k);
    if (st[field].received)
      r.field_age_max_s[k] = std::max(r.field_age_max_s[k], st.age_s(field, f.bus_now_ns));
    if (!st.fresh(field, f.bus_now_ns, rs.timeout_ns))
      ++r.field_stale_frames[k];
  }
}

// Scene update: moving objects to frame time; the view the radar sees.
void ClosedLoop::Impl::update_scene(Frame& f) {
  RunState& rs = accounting.run();
  RunResult& r = rs.r;
  const Scenario& s = scenario;
  timing::ScopedStage stage(accounting.profiler, rs.wall, timing::Stage::kSceneUpdate);
  scene.scene.set_time(f.t_s);
  if (!f.valid)
    return;
  // Model no more than the radar sees: terrain tiles outside the beam are dropped, the
  // others take the coarsest level of detail whose facets stay within a resolution cell.
  scene::ViewVolume view;
  view.position_m = f.pose.position_m;
  view.world_from_antenna = f.pose.world_from_antenna;
  view.azimuth_min_rad = s.sbr.azimuth_min_rad;
  view.azimuth_max_rad = s.sbr.azimuth_max_rad;
  view.elevation_min_rad = s.sbr.elevation_min_rad;
  view.elevation_max_rad = s.sbr.elevation_max_rad;
  view.max_range_m = s.sbr.max_range_m;
  view.range_cell_m = radar::range_resolution_m(s.sensor.processing.waveform);
  view.angular_cell_rad = s.sbr.terrain_ray_spacing_rad;
  scene.scene.set_view(view);
  const scene::ViewStats& vs = scene.scene.view_stats();
  r.view.lod_groups_culled += vs.lod_groups_culled;
  r.view.lod_groups_in_view += vs.lod_groups_in_view;
  r.view.triangles_active += vs.triangles_active;
  for (std::size_t k = 0; k < r.view.lod_groups_at_level.size(); ++k)
    r.view.lod_groups_at_level[k] += vs.lod_groups_at_level[k];
  ++r.view.frames;
}

// Trace: the governor sets the fidelity, then shoot and bounce; the path loss of [weather].
void ClosedLoop::Impl::trace(Frame& f) {
  RunState& rs = accounting.run();
  RunResult& r = rs.r;
  f.rays_before = r.trace.rays + r.trace.reused_rays;
  const std::uint64_t kept_before = r.trace.reused_contributions;
  const std::uint64_t target_facets_before = r.trace.target_facets;
  f.cells_before = r.sensor.cells_synthesised;
  timing::ScopedStage stage(accounting.profiler, rs.wall, timing::Stage::kTrace);
  if (f.valid) {
    f.decision = &governor.decide(f.pose);
    if (tracer.terrain) {
      // Terrain clutter per cell from the engine, at the same time as the tracer's rays (both on
      // TBB: the engine's slices fill the cores the trace leaves idle and the other way round),
      // each into its own part of the buffer (the tracer's holds max_contributions(), its
      // bound); the engine's returns then move down behind the tracer's. Same returns in the same
      // order as one after the other.
      const std::size_t cap = tracer.tracer.max_contributions();
      const std::uint64_t patches_before = r.terrain.patches;
      const std::uint64_t facets_before = r.terrain.facets_considered;
      tbb::parallel_invoke(
          [&] {
            f.contributions = tracer.tracer.trace(
                f.pose, std::span(tracer.contributions).first(cap), r.trace, f.decision->knobs);
          },
          [&] {
            // The governor's terrain knob coarsens the engine's patches as the terrain rays,
            // and from level 4 on merges its cells (fewer returns for the sensor).
            f.terrain_returns =
                tracer.terrain->compute(f.pose, tracer.engine_part(), r.terrain, r.terrain_dropped,
                                        f.decision->knobs.terrain_spacing_scale);
          });
      f.terrain_patches = r.terrain.patches - patches_before;
      f.terrain_facets = r.terrain.facets_considered - facets_before;
      f.contributions = tracer.append_engine(f.contributions, f.terrain_returns);
    } else {
      f.contributions =
          tracer.tracer.trace(f.pose, tracer.contributions, r.trace, f.decision->knobs);  // adds
    }
  }
  f.kept_returns = r.trace.reused_contributions - kept_before;
  f.target_facets = r.trace.target_facets - target_facets_before;
  // [weather]: every return loses the two-way attenuation of its path (diffuse ones too).
  radar::apply_two_way_loss(std::span(tracer.contributions.data(), f.contributions),
                            tracer.weather.total_db_per_m);
}

// Sensor: cells, CFAR, detections; then the governor learns the frame's cost (untimed).
void ClosedLoop::Impl::sense(Frame& f) {
  RunState& rs = accounting.run();
  RunResult& r = rs.r;
  f.truncated_before = r.sensor.truncated;
  f.merged_before = r.sensor.merged_returns;
  f.under_floor_before = r.sensor.returns_under_floor;
  {
    timing::ScopedStage stage(accounting.profiler, rs.wall, timing::Stage::kSensor);
    if (f.valid) {
      f.detections = sensor.sensor.process(std::span(tracer.contributions.data(), f.contributions),
                                           sensor.detections, r.sensor);  // accumulates
    }
  }
  const GovernorDecision* d = f.decision;
  if (f.valid) {
    const timing::StageProfiler& p = accounting.profiler;
    f.cells_synthesised = r.sensor.cells_synthesised - f.cells_before;
    f.merged_returns = r.sensor.merged_returns - f.merged_before;
    governor.observe(static_cast<double>(p.last_ns(timing::Stage::kTrace)) * 1e-6,
                     static_cast<double>(p.last_ns(timing::Stage::kSensor)) * 1e-6,
                     r.trace.rays + r.trace.reused_rays - f.rays_before, f.contributions,
                     f.cells_synthesised, f.terrain_patches, f.terrain_returns, f.terrain_facets,
                     f.merged_returns + (r.sensor.returns_under_floor - f.under_floor_before));
    ++r.governor.level_frames[static_cast<std::size_t>(d->level)];
    r.governor.frames_degraded += d->degraded ? 1 : 0;
    r.governor.frames_predicted_late += d->over_deadline ? 1 : 0;
    r.governor.max_level = std::max(r.governor.max_level, d->level);
  }
  if (r.governor.per_frame_level.size() < r.governor.per_frame_level.capacity()) {
    // Every frame, valid or not (-1: no state, nothing traced), up to kGovernorFramesKept.
    r.governor.per_frame_level.push_back(static_cast<std::int8_t>(d != nullptr ? d->level : -1));
    r.governor.per_frame_predicted_ms.push_back(d != nullptr ? static_cast<float>(d->predicted_ms)
                                                             : 0.0f);
  }
}

// Output: the ICD list on the bus (and the Modbus table), the frame's truth and its record.
void ClosedLoop::Impl::send(Frame& f) {
  RunState& rs = accounting.run();
  RunResult& r = rs.r;
  const Scenario& s = scenario;
  const GovernorDecision* d = f.decision;
  timing::ScopedStage stage(accounting.profiler, rs.wall, timing::Stage::kOutput);
  for (std::size_t i = 0; i < f.detections; ++i)
    sensor.icd_detections[i] = to_icd(sensor.detections[i]);
  io::icd::Header h;
  h.frame_counter = rs.frame_counter++;
  h.time_ms = static_cast<std::uint32_t>(f.since_start_ns / 1'000'000);
  if (!f.valid)
    h.status |= io::icd::status::kOwnshipInvalid;
  if (f.tick.late)
    h.status |= io::icd::status::kOverrun;
  if (r.sensor.truncated > f.truncated_before)
    h.status |= io::icd::status::kTruncated;
  if (d != nullptr && d->degraded)
    h.status |= io::icd::status::kDegraded;
  // A stale state sends an empty list flagged OWNSHIP_INVALID, or nothing ("silent").
  const bool send_list = f.valid || !s.stale_output_silent;
  const io::icd::EncodeResult enc =
      bus.send(h, std::span(sensor.icd_detections.data(), f.detections), send_list, s.can_fd,
               f.bus_now_ns, outputs.stream.get(), r);
  // Ground truth: each target whose box centre is inside the field of view and range.
  f.truth = f.valid ? objects_in_view(f.pose, scene.scene.objects(), scene.truth_objects, s.sbr,
                                      scene.frame_truth)
                    : 0;
  // The outcome per target: the detections associated with the objects in the beam.
  if (f.valid) {
    const std::span<const scene::ObjectState> states = scene.scene.objects();
    for (std::size_t j = 0; j < f.truth; ++j) {
      const scene::ObjectState& o = states[scene.frame_truth[j].object_id];
      scene.frame_size_m[j] = 0.5 * glm::length(o.bounds_max_m - o.bounds_min_m);
    }
    outcome->frame(std::span(scene.frame_truth.data(), f.truth),
                   std::span(scene.frame_size_m.data(), f.truth),
                   std::span(sensor.detections.data(), f.detections));
  }
  FrameRecord& rec = f.record;
  rec.frame_index = f.tick.period_index;
  rec.time_s = f.t_s;
  rec.header = h;
  rec.header.detection_count = static_cast<std::uint8_t>(enc.encoded);
  rec.detection_count = static_cast<std::uint32_t>(f.detections);
  rec.truth_count = static_cast<std::uint32_t>(f.truth);
  rec.late = f.tick.late;
  rec.sent = send_list;
  rec.ownship_valid = f.valid;
  rec.ownship_enu_m = f.valid ? f.pose.position_m : glm::dvec3(0.0);
  rec.governor_level = d != nullptr ? d->level : 0;
  rec.governor_predicted_ms = d != nullptr ? d->predicted_ms : 0.0;
  rec.governor_error_db = d != nullptr ? d->estimated_snr_error_db : 0.0;
  rec.rays = d != nullptr ? d->rays : 0;
  rec.governor_predicted_trace_ms = d != nullptr ? d->predicted_trace_ms : 0.0;
  rec.governor_predicted_sensor_ms = d != nullptr ? d->predicted_sensor_ms : 0.0;
  rec.kept_returns = f.kept_returns;
  rec.returns = f.valid ? f.contributions : 0;
  rec.cells_synthesised = f.cells_synthesised;
  rec.terrain_patches = f.terrain_patches;
  rec.terrain_facets = f.terrain_facets;
  rec.target_facets = f.target_facets;
  rec.terrain_returns = f.valid ? f.terrain_returns : 0;
  rec.merged_returns = f.merged_returns;
}

ClosedLoop::ClosedLoop(const Scenario& scenario, const RunOptions& options)
    : impl_(std::make_unique<Impl>(scenario, options)) {}

ClosedLoop::~ClosedLoop() = default;

const Scenario& ClosedLoop::scenario() const noexcept {
  return impl_->scenario;
}

std::string ClosedLoop::live_view_address() const {
  return impl_->outputs.view ? impl_->outputs.view->address() : std::string();
}

bool ClosedLoop::wait_for_viewer(double timeout_s) const {
  return impl_->outputs.view &&
         impl_->outputs.view->wait_for_client(timeout_s, impl_->options.stop);
}

std::optional<LiveViewCounters> ClosedLoop::live_view_counters() const {
  if (!impl_->outputs.view)
    return std::nullopt;
  return impl_->outputs.view->counters();
}

void choose_cube(const Scenario& s, const std::string& file, const std::string& frames,
                 RunOptions& o, std::string_view file_option, std::string_view frames_option) {
  o.cube_file = s.cube_file;
  o.cube_first_frame = s.cube_first_frame;
  o.cube_last_frame = s.cube_last_frame;
  o.cube_file_source = s.cube_source.empty() ? std::string(file_option) : s.cube_source + "cube";
  // Both from the scenario: the file's name is in the message once (before the file's key).
  o.cube_frames_source =
      s.cube_source.empty() ? std::string(frames_option) : "[output] cube_frames";
  if (!file.empty()) {
    const std::string ext = std::filesystem::path(file).extension().string();
    if (ext != ".h5" && ext != ".hdf5") {
      throw std::runtime_error(std::string(file_option) + " " + file +
                               ": not an HDF5 file name (.h5 or .hdf5; docs/cube.md)");
    }
    o.cube_file = file;
    o.cube_file_source = std::string(file_option);
    if (!s.cube_source.empty())
      o.cube_frames_source = s.cube_source + "cube_frames";
  }
  if (frames.empty())
    return;
  if (o.cube_file.empty()) {
    throw std::runtime_error(std::string(frames_option) + " " + frames + ": needs a cube file (" +
                             std::string(file_option) +
                             " FILE.h5, or the scenario's [output] "
                             "cube)");
  }
  const std::string error = parse_cube_frames(frames, o.cube_first_frame, o.cube_last_frame);
  if (!error.empty())
    throw std::runtime_error(std::string(frames_option) + " " + error);
  o.cube_frames_source = std::string(frames_option);
}

std::optional<CubeCounters> ClosedLoop::cube_counters() const {
  if (!impl_->cube)
    return std::nullopt;
  return impl_->cube->counters();
}

std::string ClosedLoop::modbus_server_address() const {
  const io::modbus::ModbusServer* server = impl_->bus.table_server();
  return server != nullptr ? server->address() : std::string();
}

std::string ClosedLoop::nav_source_failure() const {
  return impl_->ownship.failure();
}

const std::vector<std::string>& ClosedLoop::setup_warnings() const noexcept {
  return impl_->warnings;
}

void ClosedLoop::begin() {
  Impl& m = *impl_;
  m.accounting.begin(m.scenario, m.options.realtime, m.options.rt, m.scene.truth_objects.size());
  if (m.bus.hardware() || m.ownship.external()) {
    // A real bus: bus time is Unix time (CLOCK_REALTIME, as SocketCAN's and gs_usb's stamps),
    // taken once here and carried on by the monotonic clock.
    const RunState& rs = m.accounting.run();
    timespec rt{};
    clock_gettime(CLOCK_REALTIME, &rt);
    const std::int64_t realtime_now_ns =
        static_cast<std::int64_t>(rt.tv_sec) * 1'000'000'000LL + rt.tv_nsec;
    m.scenario.epoch_unix_ns = realtime_now_ns + (rs.start_ns - rs.wall.now_ns());
    m.bus.bus_from_monotonic_ns.store(m.scenario.epoch_unix_ns - rs.start_ns);
  }
}

bool ClosedLoop::step(FrameOutput& out, const OwnshipInput* ownship) {
  Impl& m = *impl_;
  if (!m.accounting.begun())
    begin();
  RunState& rs = m.accounting.run();
  if (rs.finished)
    return false;
  Frame f;
  if (!m.wait_or_stop(f))
    return false;
  // Peers on the software bus act first: the INS publishes what is due by now, or, in a
  // replay, the recorded frames the radar had received by now.
  m.peers.publish_until(f.t_s, f.bus_now_ns, rs.done, rs.r);
  m.read(f, ownship);
  m.update_scene(f);
  m.trace(f);
  m.sense(f);
  m.send(f);
  if (m.cube) {  // the captured frame to the cube's writer (loop/outputs/cube_writer.hpp)
    m.sensor.sensor.capture_next(nullptr);
    m.cube->end_frame(f.record,
                      std::span<const radar::Detection>(m.sensor.detections.data(), f.detections));
  }
  FrameProducts products;
  products.detections =
      std::span<const io::icd::Detection>(m.sensor.icd_detections.data(), f.detections);
  products.sensor_detections =
      std::span<const radar::Detection>(m.sensor.detections.data(), f.detections);
  products.truth = std::span<const ObjectTruth>(m.scene.frame_truth.data(), f.truth);
  products.velocity_mps = f.valid ? f.pose.velocity_mps : glm::dvec3(0.0);
  products.outcome = m.outcome->so_far();
  m.accounting.frame(f.record, f.start_wall_ns, products, m.outputs);
  // The avionics under test read what the radar sent.
  m.peers.poll_avionics();
  out.record = f.record;
  out.detections = products.detections;
  out.sensor_detections = products.sensor_detections;
  out.truth = products.truth;
  out.association = f.valid ? m.outcome->association() : std::span<const int>();
  if (m.options.progress)
    m.options.progress(rs.done, m.scenario.frames);
  return true;
}

RunResult ClosedLoop::finish() {
  Impl& m = *impl_;
  if (!m.accounting.begun())
    begin();
  RunState& rs = m.accounting.run();
  if (rs.finished)
    throw std::logic_error("ClosedLoop: finish() called twice");
  rs.finished = true;
  if (m.outputs.view)
    m.outputs.view->end();
  if (m.cube)
    m.cube->finish();
  RunResult& r = rs.r;
  m.accounting.finish(r);
  r.outcome = m.outcome->totals();
  r.decoder = m.bus.decoder().counters();
  r.link_faults = m.bus.link().counters();
  r.bus_rx_overflows = m.bus.rx_overflows();
  r.record_overflows = m.outputs.stream ? m.outputs.stream->bus_frames_dropped() : 0;
  m.peers.count(r);
  return std::move(r);
}

RunResult ClosedLoop::run() {
  begin();
  FrameOutput frame;
  while (step(frame))
    continue;
  return finish();
}

OutputCounters ClosedLoop::output_counters() const {
  return impl_->outputs.stream ? impl_->outputs.stream->counters() : OutputCounters{};
}

RunReport ClosedLoop::report(const RunResult& result) const {
  const Impl& m = *impl_;
  RunReport p;
  p.scenario = &m.scenario;
  p.result = &result;
  p.realtime = m.options.realtime;
  p.replay = m.options.replay;
  p.replay_log_frames = m.options.replay_input.size();
  p.can = m.bus.can_spec().text;
  p.nav_modbus = m.options.nav_modbus;
  p.modbus_server_address = modbus_server_address();
  if (const io::CanEndpoint* can = m.bus.hardware_can())
    p.can_backend_json = can_backend_report_json(*can);
  p.nav = m.ownship.report();
  if (const io::modbus::ModbusServer* server = m.bus.table_server())
    p.modbus_server_json = modbus_server_report_json(server->address(), server->counters());
  p.timing_frames_kept = m.accounting.profiler.capacity_frames();
  p.trace_events_file = m.options.trace_events_file;
  p.trace_events = m.accounting.profiler.events().size();
  const scene::Scene& sc = m.scene.scene;
  p.scene.objects = sc.objects().size();
  p.scene.triangles = sc.triangle_count();
  p.scene.lod_tiles = sc.view_stats().lod_groups;
  if (m.scenario.scene_import) {
    const scene::geodata::ImportReport& ir = m.scene.import;
    p.scene.import = {ir.vertical,
                      ir.anchor_height_m,
                      ir.anchor_undulation_m,
                      ir.dem_holes_filled,
                      ir.unknown_class_cells,
                      ir.osm_broken_ways,
                      ir.osm_outside,
                      ir.seconds};
  }
  p.weather = m.tracer.weather;
  if (m.tracer.terrain) {  // issue 28: the engine's flagged sigma0 values, the whole run
    const radar::TerrainReturns& t = *m.tracer.terrain;
    const std::span<const radar::clutter::Sigma0Use> use = t.sigma0_use();
    p.sigma0_tracked = true;
    p.sigma0_flags = radar::clutter::sigma0_use_flags(use);
    p.sigma0_lines = radar::clutter::sigma0_use_lines(
        use, radar::clutter::sigma0_row_names(t.engine().materials()), m.scenario.sbr.carrier_hz);
    p.sigma0_patch_fraction = radar::clutter::sigma0_use_patch_fraction(use);
    p.sigma0_power_fraction = radar::clutter::sigma0_use_power_fraction(use);
  } else if (result.trace.terrain_returns > 0) {  // the tracer's terrain rays: counts alone
    const radar::TraceStats& t = result.trace;
    p.sigma0_tracked = true;
    p.sigma0_flags = t.terrain_sigma0_flags;
    p.sigma0_patch_fraction =
        static_cast<double>(t.terrain_returns_flagged) / static_cast<double>(t.terrain_returns);
    p.sigma0_power_fraction = std::numeric_limits<double>::quiet_NaN();  // not tracked
    if (p.sigma0_flags != 0) {
      char line[96];
      std::snprintf(line, sizeof line,
                    "terrain rays at %.4g GHz: ", m.scenario.sbr.carrier_hz * 1e-9);
      char share[96];
      std::snprintf(share, sizeof share, " (%.1f %% of the terrain returns)",
                    100.0 * p.sigma0_patch_fraction);
      p.sigma0_lines.push_back(line + radar::clutter::describe_validity(p.sigma0_flags) + share);
    }
  }
  p.governor = m.governor.config();
  p.governor_trace_factor = m.governor.trace_factor();
  p.governor_sensor_factor = m.governor.sensor_factor();
  const radar::Sensor& sn = m.sensor.sensor;
  p.sensor = {sn.range_cell_m(),
              sn.unambiguous_range_m(),
              sn.doppler_cell_mps(),
              sn.unambiguous_velocity_mps(),
              sn.antenna().beams(),
              sn.antenna().sum_beamwidth_az_rad(),
              sn.antenna().sum_beamwidth_el_rad(),
              sn.processor().processing_gain(),
              sn.cfar_training_cells()};
  for (const auto& obj : sc.description().objects)
    p.object_names.push_back(obj.name);
  p.out_dir = m.options.out_dir;
  p.outputs = output_counters();
  p.live_view = live_view_counters();
  return p;
}

void ClosedLoop::write_outputs(const RunResult& r) {
  Impl& m = *impl_;
  if (!m.outputs.stream)
    throw std::runtime_error("write_outputs: no output directory (RunOptions::out_dir)");
  // The streamed files first: the writer finishes what the run handed it.
  (void)m.outputs.stream->finish();
  write_report_json(report(r), m.options.out_dir / "report.json");
  GovernorTrace gov;
  gov.enabled = m.governor.config().enabled;
  gov.deadline_ms = m.governor.config().compute_fraction * 1e3 / m.scenario.rate_hz;
  gov.levels = r.governor.per_frame_level;
  write_timing_png(m.accounting.profiler, 1.0 / m.scenario.rate_hz, gov,
                   m.options.out_dir / "timing.png");
}

void ClosedLoop::write_trace_events() const {
  const Impl& m = *impl_;
  const std::filesystem::path& path = m.options.trace_events_file;
  if (path.empty())
    return;
  // Chrome trace-event format ("JSON Object Format", complete events ph "X"): ts and dur in
  // microseconds; opens in https://ui.perfetto.dev and chrome://tracing.
  const std::span<const timing::StageEvent> events = m.accounting.profiler.events();
  std::int64_t t0_ns = events.empty() ? 0 : events.front().start_ns;
  for (const timing::StageEvent& e : events)
    t0_ns = std::min(t0_ns, e.start_ns);
  nlohmann::ordered_json list = nlohmann::ordered_json::array();
  for (const timing::StageEvent& e : events) {
    list.push_back({{"name", std::string(timing::stage_name(e.stage))},
                    {"cat", e.stage == timing::Stage::kFrame ? "frame" : "stage"},
                    {"ph", "X"},
                    {"ts", static_cast<double>(e.start_ns - t0_ns) * 1e-3},
                    {"dur", static_cast<double>(e.duration_ns) * 1e-3},
                    {"pid", 1},
                    {"tid", 1},
                    {"args", {{"frame", e.frame}}}});
  }
  nlohmann::ordered_json doc;
  doc["traceEvents"] = std::move(list);
  doc["displayTimeUnit"] = "ms";
  doc["otherData"] = {{"scenario", m.scenario.name},
                      {"rate_hz", m.scenario.rate_hz},
                      {"dropped_events", m.accounting.profiler.events_dropped()}};
  // The file was opened (and the path checked) at setup.
  std::FILE* f = m.paths.trace_events;
  const std::string text = doc.dump() + '\n';
  if (f != nullptr) {
    std::rewind(f);  // a second call replaces the first
    (void)::ftruncate(::fileno(f), 0);
  }
  if (f == nullptr || std::fwrite(text.data(), 1, text.size(), f) != text.size() ||
      std::fflush(f) != 0) {
    throw std::runtime_error(path.string() + ": write failed");
  }
}

}  // namespace radar_emu::loop
