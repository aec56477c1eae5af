#include "loop/closed_loop.hpp"

#include <unistd.h>

#include <algorithm>
#include <atomic>
#include <cerrno>
#include <cmath>
#include <csignal>
#include <cstdio>
#include <cstring>
#include <ctime>
#include <fstream>
#include <nlohmann/json.hpp>
#include <numbers>
#include <optional>
#include <stdexcept>

#include "common/units.hpp"
#include "io/modbus.hpp"
#include "io/modbus_map.hpp"
#include "loop/bus_backends.hpp"
#include "loop/outputs/output_stream.hpp"
#include "loop/outputs/run_plots.hpp"
#include "loop/ownship.hpp"
#include "radar/materials.hpp"
#include "radar/propagation/itu.hpp"
#include "radar/propagation/path.hpp"
#include "scene/airport_gen.hpp"
#include "scene/default_scene.hpp"
#include "scene/geo.hpp"
#include "scene/gltf.hpp"
#include "scene/scene.hpp"
#include "scene/terrain_gen.hpp"
#include "sim_bus/aircraft_player.hpp"
#include "sim_bus/avionics_sink.hpp"
#include "sim_bus/fault_injector.hpp"
#include "sim_bus/faulty_node.hpp"
#include "sim_bus/loopback_can.hpp"
#include "sim_bus/loopback_registers.hpp"
#include "sim_bus/nav_register_player.hpp"
#include "timing/clock.hpp"
#include "timing/scheduler.hpp"

namespace radar_emu::loop {

namespace {

constexpr std::uint8_t kFaultyNodeId = 99;
// Spans a frame puts on the --trace-events timeline: input, scene_update, trace, sensor, output,
// frame.
constexpr std::size_t kTimelineStagesPerFrame = 6;
// Bound on the truth entries RunResult keeps in memory (40 bytes each); beyond it they are
// counted (truth.json, streamed, has them all).
constexpr std::size_t kTruthEntriesMax = 1u << 20;

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

// The scripted ownship: the scenario's straight line in anchor ENU, sampled every second as the
// INS would report it (geodetic position; velocity and attitude in the local ENU frame).
sim_bus::Trajectory ownship_trajectory(const Scenario& s, const scene::wgs84::EnuFrame& enu) {
  const double duration_s = static_cast<double>(s.frames) / s.rate_hz + 2.0;
  const auto samples = static_cast<std::size_t>(std::ceil(duration_s)) + 1;
  const glm::dmat3 anchor_from_body =
      enu_from_body(s.ownship_heading_rad, s.ownship_pitch_rad, s.ownship_roll_rad);
  std::vector<sim_bus::AircraftState> waypoints;
  waypoints.reserve(samples);
  for (std::size_t i = 0; i < samples; ++i) {
    const double t = static_cast<double>(i);
    const glm::dvec3 p = s.ownship_start_enu_m + s.ownship_velocity_enu_mps * t;
    const scene::wgs84::Geodetic g = enu.geodetic_from_enu(p);
    const glm::dmat3 local_from_anchor = glm::transpose(anchor_from_local(enu, g));
    const glm::dvec3 v_local = local_from_anchor * s.ownship_velocity_enu_mps;
    const EulerAngles e = euler_from_enu_body(local_from_anchor * anchor_from_body);
    sim_bus::AircraftState a;
    a.time_s = t;
    a.latitude_rad = g.latitude_rad;
    a.longitude_rad = g.longitude_rad;
    a.height_m = g.height_m;
    a.pitch_rad = e.pitch_rad;
    a.roll_rad = e.roll_rad;
    a.true_heading_rad = e.heading_rad < 0 ? e.heading_rad + 2.0 * std::numbers::pi : e.heading_rad;
    a.vel_east_mps = v_local.x;
    a.vel_north_mps = v_local.y;
    a.vel_up_mps = v_local.z;
    waypoints.push_back(a);
  }
  return sim_bus::Trajectory(std::move(waypoints));
}

io::icd::Detection to_icd(const radar::Detection& d) noexcept {
  io::icd::Detection o;
  o.range_m = d.range_m;
  o.azimuth_deg = common::degrees(d.azimuth_rad);
  o.elevation_deg = common::degrees(d.elevation_rad);
  o.radial_velocity_mps = d.radial_velocity_mps;
  o.snr_db = common::db_from_power(d.snr);
  o.rcs_dbsm = common::db_from_power(d.rcs_m2);
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
radar::SensorConfig sensor_config(const Scenario& s, const radar::SbrTracer& tracer) {
  radar::SensorConfig c = s.sensor;
  // Up to 2^18 a frame (the default traces 43 k; the tracer's worst case, 2.5 M, would cost the
  // sensor 260 MB of per-return state); beyond it returns are counted as dropped_input.
  c.max_contributions = std::clamp<std::size_t>(tracer.max_contributions(), 1, 1u << 18);
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

}  // namespace

scene::SceneDescription scene_description(const Scenario& s) {
  scene::SceneDescription d;
  if (!s.scene_file.empty()) {
    d = scene::load_gltf(s.scene_file);
  } else if (s.scene_builtin == "airport") {
    scene::AirportSpec spec;
    spec.seed = s.scene_seed;
    spec.corner_reflectors = s.scene_corner_reflectors;
    d = scene::generate_airport(spec);
  } else if (s.scene_builtin == "terrain") {
    scene::TerrainSpec spec;
    spec.seed = s.scene_seed;
    d = scene::generate_terrain(spec);
  } else {
    d = scene::default_scene();  // parse_scenario() accepts only these built-ins
  }
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
      try {
        (void)radar::resolve_materials(std::span<const scene::Material>(&d.materials[k], 1));
      } catch (const std::invalid_argument& e) {
        const std::string what = e.what();
        const std::size_t known = what.find("(known:");
        throw std::runtime_error(s.targets[i - first_target].context + ": mesh_file material '" +
                                 d.materials[k].name + "' is not a radar material " +
                                 (known == std::string::npos ? "" : what.substr(known)) +
                                 "; set material = \"NAME\" in the table");
      }
    }
  }
  return d;
}

struct ClosedLoop::Impl {
  Impl(const Scenario& s, const RunOptions& o)
      : paths(o),
        scenario(s),
        options(o),
        scene(scene_description(s)),
        enu(scene.anchor()),
        tracer(scene, s.sbr),
        sensor(sensor_config(s, tracer)),
        governor(governor_config(s, o), scene, tracer, sensor, 1.0 / s.rate_hz),
        ins(bus.add_endpoint("ins", 1 << 16)),
        faulty_ep(bus.add_endpoint("faulty", 16)),
        replay_ep(bus.add_endpoint("replay", 16)),
        radar_ep(bus.add_endpoint("radar", 1 << 16)),
        avionics(bus.add_endpoint("avionics", 1 << 16)),
        player(ownship_trajectory(s, enu), player_config(s)),
        faulty(kFaultyNodeId),
        sink(std::min<std::uint64_t>(s.frames, o.record_frames_max)),
        decoder(s.input),
        recorded_frames(std::min<std::uint64_t>(s.frames, o.record_frames_max)),
        timed_frames(std::max<std::uint64_t>(std::min(s.frames, o.timing_frames_max), 1)),
        profiler(static_cast<std::size_t>(timed_frames),
                 o.trace_events_file.empty()
                     ? 0
                     : static_cast<std::size_t>(timed_frames) * kTimelineStagesPerFrame) {
    if (s.frames == 0)
      throw std::runtime_error("scenario: frames must be >= 1");
    contributions.resize(tracer.max_contributions());
    detections.resize(s.sensor.max_detections);
    icd_detections.resize(s.sensor.max_detections);
    out_frames.resize(list_frames(s));
    // The radar's receiving side of the bus, with the scenario's faults (none in a replay: the
    // log already holds what the recording run received after its faults).
    link = std::make_unique<sim_bus::FaultyCanLink>(
        radar_ep, o.replay ? sim_bus::FaultConfig{} : s.link_faults);
    if (s.stale_sender && !o.replay) {
      sim_bus::StaleConfig c = s.stale;
      c.epoch_ns = s.epoch_unix_ns;
      stale_ins = std::make_unique<sim_bus::StaleSender>(ins, c);
    }
    if (s.babbling_node && !o.replay) {
      sim_bus::BabbleConfig c = s.babble;
      c.epoch_ns = s.epoch_unix_ns;
      babbler = std::make_unique<sim_bus::BabblingNode>(c);
      babble_ep = &bus.add_endpoint("babbler", 16);
    }
    setup_backends(s, o);
    setup_weather(s);
    // Ground truth covers the objects with a conducting material (the tracer's targets); pure
    // terrain (ground, pavement, grass) is left out of truth.json.
    const std::vector<radar::RadarMaterial> mats = radar::resolve_materials(scene.materials());
    const auto& desc = scene.description();
    for (std::size_t i = 0; i < desc.objects.size(); ++i) {
      for (std::uint16_t k : desc.objects[i].mesh.triangle_material) {
        if (k < mats.size() && mats[k].conductor) {
          truth_objects.push_back(static_cast<std::uint32_t>(i));
          break;
        }
      }
    }
    truth_capacity = std::min<std::size_t>(
        static_cast<std::size_t>(recorded_frames) * truth_objects.size(), kTruthEntriesMax);
    frame_truth.resize(truth_objects.size());
    if (!o.out_dir.empty())
      setup_outputs(o);
    if (!o.serve.empty())
      setup_live_view(o);
  }

  // The streamed outputs (loop/outputs/output_stream.hpp): real-time runs drop what the writer
  // cannot take in time (counted); simulated-clock runs wait for it between frames.
  void setup_outputs(const RunOptions& o) {
    OutputStreamConfig c;
    c.dir = o.out_dir;
    c.scenario = &scenario;
    c.frames_planned = scenario.frames;
    for (const auto& obj : scene.description().objects)
      c.object_names.push_back(obj.name);
    c.truth_objects = truth_objects;
    c.max_detections = detections.size();
    c.bus_frames_per_frame =
        static_cast<std::size_t>(input_frames_per_frame(scenario)) + list_frames(scenario);
    c.wait_when_full = !o.realtime;
    c.wake_latency = o.realtime;
    outputs = std::make_unique<OutputStream>(std::move(c));
  }

  // The live view (loop/outputs/live_view.hpp): binds its server now, so that a bad address or a
  // port in use is an error before the run.
  void setup_live_view(const RunOptions& o) {
    LiveViewConfig c;
    c.serve = o.serve;
    c.scenario = &scenario;
    for (const auto& obj : scene.description().objects)
      c.object_names.push_back(obj.name);
    c.max_detections = detections.size();
    c.max_truth = std::max<std::size_t>(frame_truth.size(), 1);
    live_view = std::make_unique<LiveView>(std::move(c));
  }

  // [weather]: the one-way specific attenuation at the carrier, built once from the ITU-R
  // models (radar/propagation/path.hpp sums P.676 gases, P.838 rain and P.840 fog). The SBR
  // transmits vertical polarisation (radar/em/sbr.cpp), so rain takes P.838's tilt pi/2.
  void setup_weather(const Scenario& s) {
    const WeatherSpec& w = s.weather;
    if (!w.enabled)
      return;
    const double f = s.sbr.carrier_hz;
    const radar::Atmosphere air{w.pressure_hpa, w.temperature_k, w.humidity_gm3};
    constexpr double kTiltVertical = std::numbers::pi / 2.0;
    try {
      radar::MediumSpec medium;
      medium.name = w.condition;
      medium.atmosphere = air;
      medium.rain_mm_per_h = w.rain_mm_per_h;
      medium.liquid_water_gm3 = w.fog_water_gm3;
      const radar::PathAttenuation path(f, kTiltVertical, std::span(&medium, 1));
      weather_db_per_m = path.specific_db_per_m(0);
      weather_gas_db_per_km = radar::gaseous_specific_attenuation(f, air).total_db_per_km();
      weather_rain_db_per_km =
          radar::rain_specific_attenuation_db_per_km(f, w.rain_mm_per_h, 0.0, kTiltVertical);
      if (w.fog_water_gm3 > 0.0) {
        weather_fog_db_per_km =
            radar::cloud_fog_specific_attenuation_db_per_km(f, w.fog_water_gm3, w.temperature_k);
      }
    } catch (const std::invalid_argument& e) {
      throw std::runtime_error("scenario: [weather] at carrier_hz " + std::to_string(f) + ": " +
                               e.what());
    }
  }

  // Hardware CAN, Modbus navigation and the Modbus detection table (setup; throws with context).
  void setup_backends(const Scenario& s, const RunOptions& o) {
    can_spec = parse_can_spec(o.can);
    hardware_can = can_spec.kind != CanSpec::Kind::kSim;
    // ",fd" on the command line sends FD lists too (the frame buffers, sized for classic
    // lists, hold FD lists: those take fewer frames).
    if (can_spec.fd)
      scenario.can_fd = true;
    nav_modbus_sim = o.nav_modbus == "sim";
    nav_external = !o.nav_modbus.empty() && !nav_modbus_sim;
    if ((hardware_can || nav_external) && !o.realtime) {
      throw std::runtime_error(
          std::string(hardware_can ? "--can " + o.can : "--nav-modbus " + o.nav_modbus) +
          ": a real bus runs on the wall clock: add --realtime");
    }
    if ((hardware_can || !o.nav_modbus.empty()) && o.replay)
      throw std::runtime_error("replay runs on the software bus only (no --can or --nav-modbus)");
    if (hardware_can) {
      // Bus time is Unix time (set when the run starts), as the kernel's CLOCK_REALTIME stamps.
      hw_can = open_can(can_spec, 0, warnings);
    }
    if (nav_modbus_sim || nav_external) {
      nav_regs.resize(io::modbus::nav_register_count(nav_map));
    }
    if (nav_modbus_sim) {
      nav_bank =
          std::make_unique<sim_bus::LoopbackRegisterBank>(nav_map.base_address, nav_regs.size());
      sim_bus::NavPlayerConfig pc;
      pc.map = nav_map;
      pc.rate_hz = s.navigation_rate_hz;
      nav_player = std::make_unique<sim_bus::NavRegisterPlayer>(player.trajectory(), pc);
      // The scenario's link faults act on the register transport too: a lost frame is a lost
      // transaction, a stale INS a frozen register image (sim_bus/fault_injector.hpp).
      sim_bus::RegisterFaultConfig rf;
      if (!o.replay) {
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
      nav_faulty = std::make_unique<sim_bus::FaultyRegisterBank>(*nav_bank, rf);
    }
    if (nav_external) {
      io::modbus::ModbusClientConfig cc;
      cc.endpoint = o.nav_modbus;
      nav_client = std::make_unique<io::modbus::ModbusClient>(cc);
      nav_retry_max_s = cc.reconnect_max_interval_s;
      io::modbus::NavPollerConfig pc;
      pc.map = nav_map;
      std::atomic<std::int64_t>* offset = &bus_from_monotonic_ns;
      pc.clock_ns = [offset] {
        timespec ts{};
        clock_gettime(CLOCK_MONOTONIC, &ts);
        return offset->load(std::memory_order_relaxed) +
               static_cast<std::int64_t>(ts.tv_sec) * 1'000'000'000LL + ts.tv_nsec;
      };
      // The source's state on stderr as it changes (from the poller's thread, never the loop).
      pc.on_link = [client = nav_client.get(), endpoint = o.nav_modbus,
                    retry = cc.reconnect_max_interval_s](const io::modbus::NavLinkEvent& e) {
        const std::string line = nav_link_message(endpoint, e, client->last_error_text(), retry);
        std::fprintf(stderr, "%s\n", line.c_str());
        std::fflush(stderr);
      };
      nav_poller = std::make_unique<io::modbus::NavPoller>(*nav_client, pc);
    }
    if (!o.modbus_server.empty()) {
      table_config.max_detections = std::max<std::size_t>(1, s.sensor.max_detections);
      table_regs.resize(io::modbus::detection_table_registers(table_config));
      io::modbus::ModbusServerConfig sc;
      sc.endpoint = modbus_server_endpoint(o.modbus_server);
      sc.start_address = table_config.base_address;
      sc.register_count = table_regs.size();
      modbus_server = std::make_unique<io::modbus::ModbusServer>(sc);
    }
  }

  // Frames one detection list takes on the bus (classic or FD).
  static std::size_t list_frames(const Scenario& s) {
    return s.can_fd ? io::icd::frames_for_fd(s.sensor.max_detections)
                    : io::icd::frames_for(s.sensor.max_detections);
  }

  static sim_bus::PlayerConfig player_config(const Scenario& s) {
    sim_bus::PlayerConfig c;
    c.node_id = s.ins_node_id;
    c.attitude_rate_hz = s.attitude_rate_hz;
    c.navigation_rate_hz = s.navigation_rate_hz;
    c.epoch_ns = s.epoch_unix_ns;
    for (std::size_t k = 0; k < c.can_ids.size(); ++k)
      c.can_ids[k] = s.input.fields[k].can_id;
    return c;
  }

  // Input frames one radar frame can receive (sizes the input log): the INS schedule, doubled
  // for duplicates, plus a babbling node's rate.
  static std::uint64_t input_frames_per_frame(const Scenario& s) {
    double per_s = (3.0 * s.attitude_rate_hz + 8.0 * s.navigation_rate_hz) *
                   (1.0 + s.link_faults.duplicate_probability);
    if (s.babbling_node)
      per_s += s.babble.rate_hz * (1.0 + s.link_faults.duplicate_probability);
    return static_cast<std::uint64_t>(std::ceil(per_s / s.rate_hz)) + 12;
  }

  OutputPaths paths;  ///< first: checked before the rest of the setup
  Scenario scenario;
  RunOptions options;
  scene::Scene scene;
  scene::wgs84::EnuFrame enu;
  radar::SbrTracer tracer;
  radar::Sensor sensor;
  FidelityGovernor governor;
  sim_bus::LoopbackCanBus bus;
  sim_bus::LoopbackEndpoint& ins;
  sim_bus::LoopbackEndpoint& faulty_ep;
  sim_bus::LoopbackEndpoint& replay_ep;
  std::size_t replay_next = 0;  ///< next frame of options.replay_input to put on the bus
  sim_bus::LoopbackEndpoint& radar_ep;
  sim_bus::LoopbackEndpoint& avionics;
  sim_bus::AircraftStatePlayer player;
  sim_bus::FaultyNode faulty;
  std::unique_ptr<sim_bus::FaultyCanLink> link;     ///< what the radar receives through
  std::unique_ptr<sim_bus::StaleSender> stale_ins;  ///< the INS's sending side, when stale
  std::unique_ptr<sim_bus::BabblingNode> babbler;
  sim_bus::LoopbackEndpoint* babble_ep = nullptr;
  sim_bus::AvionicsSink sink;
  io::canas::Decoder decoder;
  std::uint64_t recorded_frames;  ///< frames RunResult keeps in memory
  std::uint64_t timed_frames;     ///< frames whose stage times are kept one by one
  timing::StageProfiler profiler;
  std::unique_ptr<OutputStream> outputs;  ///< null without an output directory
  std::unique_ptr<LiveView> live_view;    ///< null without RunOptions::serve
  std::vector<ObjectTruth> frame_truth;   ///< the current frame's objects in view
  double weather_db_per_m = 0.0;          ///< one-way specific attenuation [dB/m]; 0: free space
  double weather_gas_db_per_km = 0.0, weather_rain_db_per_km = 0.0, weather_fog_db_per_km = 0.0;
  std::vector<std::uint32_t> truth_objects;  ///< objects truth.json covers
  std::size_t truth_capacity = 0;
  std::vector<radar::Contribution> contributions;
  std::vector<radar::Detection> detections;
  std::vector<io::icd::Detection> icd_detections;
  std::vector<io::CanFrame> out_frames;
  // Backends (setup_backends()).
  std::vector<std::string> warnings;
  CanSpec can_spec;
  bool hardware_can = false;
  std::unique_ptr<io::CanEndpoint> hw_can;
  bool nav_modbus_sim = false;
  bool nav_external = false;
  io::modbus::NavMapConfig nav_map{};
  std::vector<std::uint16_t> nav_regs;
  std::unique_ptr<sim_bus::LoopbackRegisterBank> nav_bank;
  std::unique_ptr<sim_bus::NavRegisterPlayer> nav_player;
  std::unique_ptr<sim_bus::FaultyRegisterBank> nav_faulty;
  io::modbus::NavDecoder nav_decoder{};
  std::uint64_t nav_read_failures = 0;
  std::unique_ptr<io::modbus::ModbusClient> nav_client;
  std::unique_ptr<io::modbus::NavPoller> nav_poller;
  std::uint64_t nav_frames_source_down = 0;  ///< frames run while the nav source did not answer
  double nav_retry_max_s = 0.0;              ///< the client's back-off ceiling (retry period)
  std::atomic<std::int64_t> bus_from_monotonic_ns{0};  ///< bus time - CLOCK_MONOTONIC [ns]
  io::canas::OwnshipState nav_state{};                 ///< last state from the poller
  io::modbus::DetectionTableConfig table_config{};
  std::vector<std::uint16_t> table_regs;
  std::unique_ptr<io::modbus::ModbusServer> modbus_server;
  // The run under way (begin() to finish()): its result so far, its clocks and its schedule.
  struct RunState {
    explicit RunState(std::int64_t epoch_ns) : simulated(epoch_ns) {}
    RunResult r;
    timing::MonotonicClock wall;
    timing::SimulatedClock simulated;
    std::optional<timing::FixedRateScheduler> scheduler;
    std::int64_t period_ns = 0, start_ns = 0, timeout_ns = 0, run_start_wall = 0;
    std::uint16_t frame_counter = 0;
    std::uint64_t done = 0;  ///< frames run
    bool finished = false;
  };
  std::unique_ptr<RunState> run;
};

ClosedLoop::ClosedLoop(const Scenario& scenario, const RunOptions& options)
    : impl_(std::make_unique<Impl>(scenario, options)) {}

ClosedLoop::~ClosedLoop() = default;

const Scenario& ClosedLoop::scenario() const noexcept {
  return impl_->scenario;
}

std::string ClosedLoop::live_view_address() const {
  return impl_->live_view ? impl_->live_view->address() : std::string();
}

bool ClosedLoop::wait_for_viewer(double timeout_s) const {
  return impl_->live_view && impl_->live_view->wait_for_client(timeout_s, impl_->options.stop);
}

std::optional<LiveViewCounters> ClosedLoop::live_view_counters() const {
  if (!impl_->live_view)
    return std::nullopt;
  return impl_->live_view->counters();
}

std::string ClosedLoop::modbus_server_address() const {
  return impl_->modbus_server ? impl_->modbus_server->address() : std::string();
}

std::string ClosedLoop::nav_source_failure() const {
  const Impl& m = *impl_;
  if (!m.nav_poller || m.nav_poller->counters().ever_up)
    return {};
  const std::string error = m.nav_client->last_error_text();
  return "navigation source " + m.options.nav_modbus + " never answered" +
         (error.empty() ? "" : " (" + error + ")") +
         ": no frame had a valid ownship state (report.json nav_modbus.link)";
}

const std::vector<std::string>& ClosedLoop::setup_warnings() const noexcept {
  return impl_->warnings;
}

void ClosedLoop::begin() {
  Impl& m = *impl_;
  if (m.run)
    throw std::logic_error("ClosedLoop: the run has already begun (a loop runs once)");
  const Scenario& s = m.scenario;
  m.run = std::make_unique<Impl::RunState>(s.epoch_unix_ns);
  Impl::RunState& rs = *m.run;
  RunResult& r = rs.r;
  r.frames_planned = s.frames;
  r.records.reserve(static_cast<std::size_t>(m.recorded_frames));
  r.detections.reserve(static_cast<std::size_t>(m.recorded_frames) * s.sensor.max_detections);
  r.sensor_detections.reserve(r.detections.capacity());
  r.truth.reserve(m.truth_capacity);
  r.governor.per_frame_level.reserve(
      static_cast<std::size_t>(std::min<std::uint64_t>(s.frames, RunResult::kGovernorFramesKept)));
  r.governor.per_frame_predicted_ms.reserve(r.governor.per_frame_level.capacity());
  r.detections_min = std::numeric_limits<std::uint64_t>::max();
  r.field_age_max_s.fill(0.0);
  r.field_stale_frames.fill(0);

  timing::MonotonicClock& wall = rs.wall;
  timing::Clock& sched_clock = m.options.realtime ? static_cast<timing::Clock&>(wall)
                                                  : static_cast<timing::Clock&>(rs.simulated);
  if (m.options.realtime)
    r.realtime = timing::bring_up_realtime(m.options.rt);
  rs.period_ns = std::llround(1e9 / s.rate_hz);
  const std::int64_t start_ns =
      m.options.realtime ? wall.now_ns() + 20'000'000 : rs.simulated.now_ns();  // 20 ms to settle
  if (m.hardware_can || m.nav_external) {
    // A real bus: bus time is Unix time (CLOCK_REALTIME, as SocketCAN's and gs_usb's stamps),
    // taken once here and carried on by the monotonic clock.
    timespec rt{};
    clock_gettime(CLOCK_REALTIME, &rt);
    const std::int64_t realtime_now_ns =
        static_cast<std::int64_t>(rt.tv_sec) * 1'000'000'000LL + rt.tv_nsec;
    m.scenario.epoch_unix_ns = realtime_now_ns + (start_ns - wall.now_ns());
    m.bus_from_monotonic_ns.store(m.scenario.epoch_unix_ns - start_ns);
  }
  rs.start_ns = start_ns;
  rs.scheduler.emplace(sched_clock, rs.period_ns, start_ns);
  rs.timeout_ns = std::llround(s.state_timeout_s * 1e9);
  rs.run_start_wall = wall.now_ns();
}

bool ClosedLoop::step(FrameOutput& out, const OwnshipInput* ownship) {
  Impl& m = *impl_;
  if (!m.run)
    begin();
  Impl::RunState& rs = *m.run;
  if (rs.finished)
    return false;
  const Scenario& s = m.scenario;
  RunResult& r = rs.r;
  timing::MonotonicClock& wall = rs.wall;
  timing::FixedRateScheduler& scheduler = *rs.scheduler;
  const std::int64_t start_ns = rs.start_ns, period_ns = rs.period_ns, timeout_ns = rs.timeout_ns;
  std::uint16_t& frame_counter = rs.frame_counter;
  const std::uint64_t done = rs.done;
  // A stop request ends the run at a frame boundary: before the wait, or after it (a real-time
  // run may sleep a period in between).
  auto stop_requested = [&] {
    const int sig = m.options.stop ? m.options.stop->load(std::memory_order_relaxed) : 0;
    if (sig != 0) {
      r.interrupted = true;
      r.stop_signal = sig;
    }
    return sig != 0;
  };
  if (done >= s.frames || stop_requested())
    return false;
  if (m.outputs)
    m.outputs->wait_for_room();  // simulated clock only: the writer keeps up
  const timing::Tick tick = scheduler.wait_next();
  if (stop_requested())
    return false;
  const std::int64_t frame_start_wall = wall.now_ns();
  m.profiler.set_frame(done);
  const std::int64_t since_start_ns = tick.deadline_ns - start_ns;
  const double t_s = static_cast<double>(since_start_ns) * 1e-9;
  const std::int64_t bus_now_ns = s.epoch_unix_ns + since_start_ns;
  if (m.options.realtime) {
    m.profiler.record(timing::Stage::kWakeLatency, tick.wake_ns - tick.deadline_ns);
  }

  // Peers on the software bus act first: the INS publishes what is due by now, or, in a
  // replay, the recorded frames the radar had received by now.
  if (m.options.replay) {
    const std::vector<io::CanFrame>& log = m.options.replay_input;
    while (m.replay_next < log.size() && log[m.replay_next].timestamp_ns <= bus_now_ns) {
      if (m.replay_ep.send(log[m.replay_next]))
        ++r.replay_frames_fed;
      ++m.replay_next;
    }
  } else if (!m.hardware_can && !m.nav_external) {
    if (m.nav_player)
      (void)m.nav_player->publish_until(t_s, *m.nav_bank);
    (void)m.player.publish_until(t_s,
                                 m.stale_ins ? static_cast<io::CanEndpoint&>(*m.stale_ins) : m.ins);
    if (m.babbler)
      (void)m.babbler->publish_until(t_s, *m.babble_ep);
    if (s.malformed_every_n_frames > 0 && done % s.malformed_every_n_frames == 0) {
      m.faulty.send_next(m.faulty_ep, bus_now_ns);
    }
  }

  // ---- input: decode the bus into the ownship state ----
  radar::RadarPose pose;
  bool valid = false;
  {
    timing::ScopedStage stage(m.profiler, wall, timing::Stage::kInput);
    io::CanFrame f;
    m.link->advance_to(bus_now_ns);
    io::CanEndpoint& rx = m.hw_can ? *m.hw_can : static_cast<io::CanEndpoint&>(*m.link);
    while (rx.receive(f)) {
      ++r.bus_frames_in;
      // Reception times are kept to the microsecond, the resolution of the candump log, so
      // that a replay of bus_in.log decodes exactly what this run decoded.
      f.timestamp_ns -= f.timestamp_ns % 1000;
      if (m.outputs)
        m.outputs->bus_in(f);
      (void)m.decoder.decode(f, f.timestamp_ns);
    }
    // The ownship state: CANaerospace from the bus, or the Modbus navigation map.
    const io::canas::OwnshipState* state = &m.decoder.state();
    if (m.nav_faulty) {
      m.nav_faulty->advance_to(bus_now_ns);
      if (m.nav_faulty->read_holding(m.nav_map.base_address, m.nav_regs) ==
          io::RegisterStatus::kOk) {
        (void)m.nav_decoder.decode(m.nav_regs, bus_now_ns);
      } else {
        ++m.nav_read_failures;
      }
      state = &m.nav_decoder.state();
    } else if (m.nav_poller) {
      (void)m.nav_poller->latest(m.nav_state);
      state = &m.nav_state;
      if (m.nav_poller->link_state() != io::modbus::NavLinkState::kUp)
        ++m.nav_frames_source_down;  // reported with the link (report.json nav_modbus.link)
    }
    valid = radar_pose_from_state(*state, bus_now_ns, timeout_ns, m.enu, s.antenna_depression_rad,
                                  pose);
    if (ownship != nullptr) {
      // A stepped frame with the caller's state (step()): it replaces the bus's, in the
      // scenario's [ownship] conventions (anchor ENU, body attitude, the mount depression).
      pose.position_m = ownship->position_enu_m;
      pose.velocity_mps = ownship->velocity_enu_mps;
      pose.world_from_antenna =
          enu_from_body(ownship->heading_rad, ownship->pitch_rad, ownship->roll_rad) *
          body_from_antenna(s.antenna_depression_rad);
      valid = true;
    }
    const io::canas::OwnshipState& st = *state;
    for (std::size_t k = 0; k < io::canas::kFieldCount; ++k) {
      const auto field = static_cast<io::canas::Field>(k);
      if (st[field].received)
        r.field_age_max_s[k] = std::max(r.field_age_max_s[k], st.age_s(field, bus_now_ns));
      if (!st.fresh(field, bus_now_ns, timeout_ns))
        ++r.field_stale_frames[k];
    }
  }
  // ---- scene update: moving objects to frame time ----
  {
    timing::ScopedStage stage(m.profiler, wall, timing::Stage::kSceneUpdate);
    m.scene.set_time(t_s);
    if (valid) {
      // Model no more than the radar sees: terrain tiles outside the beam are dropped, the
      // others take the coarsest level of detail whose facets stay within a resolution cell.
      scene::ViewVolume view;
      view.position_m = pose.position_m;
      view.world_from_antenna = pose.world_from_antenna;
      view.azimuth_min_rad = s.sbr.azimuth_min_rad;
      view.azimuth_max_rad = s.sbr.azimuth_max_rad;
      view.elevation_min_rad = s.sbr.elevation_min_rad;
      view.elevation_max_rad = s.sbr.elevation_max_rad;
      view.max_range_m = s.sbr.max_range_m;
      view.range_cell_m = radar::range_resolution_m(s.sensor.processing.waveform);
      view.angular_cell_rad = s.sbr.terrain_ray_spacing_rad;
      m.scene.set_view(view);
      const scene::ViewStats& vs = m.scene.view_stats();
      r.view.lod_groups_culled += vs.lod_groups_culled;
      r.view.lod_groups_in_view += vs.lod_groups_in_view;
      r.view.triangles_active += vs.triangles_active;
      for (std::size_t k = 0; k < r.view.lod_groups_at_level.size(); ++k)
        r.view.lod_groups_at_level[k] += vs.lod_groups_at_level[k];
      ++r.view.frames;
    }
  }
  // ---- trace: the governor sets the fidelity, then shoot and bounce ----
  std::size_t n_contrib = 0;
  const std::uint64_t rays_before = r.trace.rays;
  const std::uint64_t cells_before = r.sensor.cells_synthesised;
  const GovernorDecision* decision = nullptr;
  {
    timing::ScopedStage stage(m.profiler, wall, timing::Stage::kTrace);
    if (valid) {
      decision = &m.governor.decide(pose);
      n_contrib = m.tracer.trace(pose, m.contributions, r.trace, decision->knobs);  // adds
    }
    // [weather]: every return loses the two-way attenuation of its path (diffuse ones too).
    radar::apply_two_way_loss(std::span(m.contributions.data(), n_contrib), m.weather_db_per_m);
  }
  // ---- sensor: cells, CFAR, detections ----
  std::size_t n_det = 0;
  const std::uint64_t truncated_before = r.sensor.truncated;
  {
    timing::ScopedStage stage(m.profiler, wall, timing::Stage::kSensor);
    if (valid) {
      n_det = m.sensor.process(std::span(m.contributions.data(), n_contrib), m.detections,
                               r.sensor);  // accumulates
    }
  }
  if (valid) {
    m.governor.observe(static_cast<double>(m.profiler.last_ns(timing::Stage::kTrace)) * 1e-6,
                       static_cast<double>(m.profiler.last_ns(timing::Stage::kSensor)) * 1e-6,
                       r.trace.rays - rays_before, n_contrib,
                       r.sensor.cells_synthesised - cells_before);
    ++r.governor.level_frames[static_cast<std::size_t>(decision->level)];
    r.governor.frames_degraded += decision->degraded ? 1 : 0;
    r.governor.frames_predicted_late += decision->over_deadline ? 1 : 0;
    r.governor.max_level = std::max(r.governor.max_level, decision->level);
  }
  if (r.governor.per_frame_level.size() < r.governor.per_frame_level.capacity()) {
    // Every frame, valid or not (-1: no state, nothing traced), up to kGovernorFramesKept.
    r.governor.per_frame_level.push_back(
        static_cast<std::int8_t>(decision != nullptr ? decision->level : -1));
    r.governor.per_frame_predicted_ms.push_back(
        decision != nullptr ? static_cast<float>(decision->predicted_ms) : 0.0f);
  }
  // ---- output: ICD frames on the bus ----
  FrameRecord rec;
  std::size_t n_truth = 0;
  {
    timing::ScopedStage stage(m.profiler, wall, timing::Stage::kOutput);
    for (std::size_t i = 0; i < n_det; ++i)
      m.icd_detections[i] = to_icd(m.detections[i]);
    io::icd::Header h;
    h.frame_counter = frame_counter++;
    h.time_ms = static_cast<std::uint32_t>(since_start_ns / 1'000'000);
    if (!valid)
      h.status |= io::icd::status::kOwnshipInvalid;
    if (tick.late)
      h.status |= io::icd::status::kOverrun;
    if (r.sensor.truncated > truncated_before)
      h.status |= io::icd::status::kTruncated;
    if (decision != nullptr && decision->degraded)
      h.status |= io::icd::status::kDegraded;
    // A stale state sends an empty list flagged OWNSHIP_INVALID, or nothing ("silent").
    const bool send_list = valid || !s.stale_output_silent;
    io::icd::EncodeResult enc{};
    if (send_list) {
      const std::span<const io::icd::Detection> list(m.icd_detections.data(), n_det);
      enc = s.can_fd ? io::icd::encode_fd(h, list, m.out_frames)
                     : io::icd::encode(h, list, m.out_frames);
    } else {
      ++r.lists_suppressed;
    }
    r.icd_dropped += enc.dropped;
    r.icd_truncated += enc.truncated;
    io::CanEndpoint& tx = m.hw_can ? *m.hw_can : static_cast<io::CanEndpoint&>(m.radar_ep);
    for (std::size_t i = 0; i < enc.frames; ++i) {
      io::CanFrame& f = m.out_frames[i];
      f.timestamp_ns = bus_now_ns;
      if (tx.send(f))
        ++r.bus_frames_out;
      if (m.outputs)
        m.outputs->bus_out(f);
    }
    if (m.modbus_server) {
      // The Modbus table is state, not a message: it is published every frame, stale or not.
      const io::modbus::TableEncodeResult te = io::modbus::encode_detection_table(
          h, std::span<const io::icd::Detection>(m.icd_detections.data(), n_det), m.table_regs,
          m.table_config);
      (void)te;
      (void)m.modbus_server->publish(m.table_regs);
    }
    // Ground truth: each target whose box centre is inside the field of view and range.
    n_truth =
        valid ? objects_in_view(pose, m.scene.objects(), m.truth_objects, s.sbr, m.frame_truth) : 0;
    rec.frame_index = tick.period_index;
    rec.time_s = t_s;
    rec.header = h;
    rec.header.detection_count = static_cast<std::uint8_t>(enc.encoded);
    rec.detection_count = static_cast<std::uint32_t>(n_det);
    rec.truth_count = static_cast<std::uint32_t>(n_truth);
    rec.late = tick.late;
    rec.sent = send_list;
    rec.ownship_valid = valid;
    rec.ownship_enu_m = valid ? pose.position_m : glm::dvec3(0.0);
    rec.governor_level = decision != nullptr ? decision->level : 0;
    rec.governor_predicted_ms = decision != nullptr ? decision->predicted_ms : 0.0;
    rec.governor_error_db = decision != nullptr ? decision->estimated_snr_error_db : 0.0;
    rec.rays = decision != nullptr ? decision->rays : 0;
  }
  const std::int64_t frame_end_wall = wall.now_ns();
  const std::int64_t frame_ns = frame_end_wall - frame_start_wall;
  m.profiler.record_span(timing::Stage::kFrame, frame_start_wall, frame_end_wall);
  if (frame_ns > period_ns)
    ++r.frames_over_budget;

  // The frame's record: to the writer thread, and to memory for the first recorded_frames.
  const std::span<const ObjectTruth> truth(m.frame_truth.data(), n_truth);
  if (m.outputs || m.live_view) {
    std::array<std::int64_t, timing::kStageCount> stage_ns{};
    for (std::size_t k = 0; k < timing::kStageCount; ++k)
      stage_ns[k] = m.profiler.last_ns(static_cast<timing::Stage>(k));
    if (m.outputs) {
      m.outputs->frame(rec, stage_ns, std::span(m.icd_detections.data(), n_det),
                       std::span(m.detections.data(), n_det), truth);
    }
    // The live view: a copy into a preallocated snapshot and one atomic exchange.
    if (m.live_view) {
      m.live_view->publish(rec, valid ? pose.velocity_mps : glm::dvec3(0.0), stage_ns,
                           std::span(m.icd_detections.data(), n_det), truth);
    }
  }
  out.record = rec;
  out.detections = std::span<const io::icd::Detection>(m.icd_detections.data(), n_det);
  out.sensor_detections = std::span<const radar::Detection>(m.detections.data(), n_det);
  out.truth = truth;
  if (r.records.size() < m.recorded_frames) {
    rec.first_detection = static_cast<std::uint32_t>(r.detections.size());
    rec.first_truth = static_cast<std::uint32_t>(r.truth.size());
    const std::size_t room = r.truth.capacity() - r.truth.size();
    rec.truth_count = static_cast<std::uint32_t>(std::min(n_truth, room));
    r.truth_overflows += n_truth - rec.truth_count;
    r.truth.insert(r.truth.end(), truth.begin(), truth.begin() + rec.truth_count);
    r.records.push_back(rec);
    r.detections.insert(r.detections.end(), m.icd_detections.begin(),
                        m.icd_detections.begin() + static_cast<std::ptrdiff_t>(n_det));
    r.sensor_detections.insert(r.sensor_detections.end(), m.detections.begin(),
                               m.detections.begin() + static_cast<std::ptrdiff_t>(n_det));
  }

  // The avionics under test read what the radar sent.
  (void)m.sink.poll(m.avionics);

  ++r.frames;
  if (valid)
    ++r.frames_valid;
  r.detections_total += n_det;
  r.detections_min = std::min<std::uint64_t>(r.detections_min, n_det);
  r.detections_max = std::max<std::uint64_t>(r.detections_max, n_det);
  ++rs.done;
  if (m.options.progress)
    m.options.progress(done + 1, s.frames);
  return true;
}

RunResult ClosedLoop::finish() {
  Impl& m = *impl_;
  if (!m.run)
    begin();
  Impl::RunState& rs = *m.run;
  if (rs.finished)
    throw std::logic_error("ClosedLoop: finish() called twice");
  rs.finished = true;
  if (m.live_view)
    m.live_view->end();
  RunResult& r = rs.r;
  r.wall_time_s = static_cast<double>(rs.wall.now_ns() - rs.run_start_wall) * 1e-9;
  r.overruns = rs.scheduler->overruns();
  r.missed_periods = rs.scheduler->missed_periods();
  r.decoder = m.decoder.counters();
  r.link_faults = m.link->counters();
  if (m.stale_ins)
    r.stale_sender = m.stale_ins->counters();
  if (m.babbler)
    r.babble = m.babbler->counters();
  if (m.options.replay)
    r.replay_frames_left = m.options.replay_input.size() - m.replay_next;
  r.bus_rx_overflows = m.radar_ep.rx_overflows() + m.avionics.rx_overflows();
  r.record_overflows = m.outputs ? m.outputs->bus_frames_dropped() : 0;
  r.trace_events_dropped = m.profiler.events_dropped();
  r.sink_lists = m.sink.lists_completed();
  r.sink_malformed = m.sink.decoder().malformed() + m.sink.decoder().orphans();
  for (std::size_t k = 0; k < r.injected_malformed.size(); ++k) {
    r.injected_malformed[k] = m.faulty.sent()[k];
  }
  for (std::size_t k = 0; k < timing::kStageCount; ++k) {
    r.stages[k] = m.profiler.summary(static_cast<timing::Stage>(k));
  }
  if (r.frames == 0)
    r.detections_min = 0;
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
  return impl_->outputs ? impl_->outputs->counters() : OutputCounters{};
}

void ClosedLoop::write_outputs(const RunResult& r) {
  Impl& m = *impl_;
  const Scenario& s = m.scenario;
  if (!m.outputs)
    throw std::runtime_error("write_outputs: no output directory (RunOptions::out_dir)");
  const std::filesystem::path& dir = m.options.out_dir;
  // The streamed files first: the writer finishes what the run handed it.
  const OutputCounters& oc = m.outputs->finish();

  auto write_json = [&](const std::filesystem::path& path, const nlohmann::ordered_json& j) {
    std::ofstream out(path, std::ios::binary);
    out << j.dump(1) << '\n';
    if (!out)
      throw std::runtime_error(path.string() + ": write failed");
  };

  // report.json: the run's summary.
  nlohmann::ordered_json rep;
  rep["scenario"] = s.name;
  rep["mode"] = m.options.realtime ? "realtime" : "as-fast-as-possible";
  rep["rate_hz"] = s.rate_hz;
  rep["frames"] = r.frames;
  rep["frames_planned"] = r.frames_planned;
  // A stop request (SIGINT, SIGTERM) ended the run at a frame boundary: every output holds the
  // frames run until then.
  rep["interrupted"] = r.interrupted;
  if (r.interrupted) {
    rep["stop_signal"] = r.stop_signal == SIGINT    ? "SIGINT"
                         : r.stop_signal == SIGTERM ? "SIGTERM"
                                                    : std::to_string(r.stop_signal);
  }
  rep["frames_valid"] = r.frames_valid;
  rep["backends"] = {
      {"can", m.options.replay ? std::string("replay") : m.can_spec.text},
      {"ownship_from", m.options.nav_modbus.empty() ? std::string("canaerospace")
                                                    : "modbus:" + m.options.nav_modbus},
      {"detection_lists", s.can_fd ? "can_fd" : "can_classic"},
      {"modbus_server", m.modbus_server ? m.modbus_server->address() : std::string()}};
  if (m.hw_can)
    rep["can_backend"] = nlohmann::ordered_json::parse(can_backend_report_json(*m.hw_can));
  if (m.nav_faulty || m.nav_poller) {
    const io::modbus::NavDecoderCounters& nc =
        m.nav_poller ? m.nav_poller->counters().decoder : m.nav_decoder.counters();
    nlohmann::ordered_json nav = {
        {"samples", nc.samples},           {"new_samples", nc.new_samples},
        {"stale_samples", nc.stale},       {"rejected", nc.rejected()},
        {"not_a_number", nc.not_a_number}, {"out_of_range", nc.out_of_range},
        {"wrong_size", nc.wrong_size},     {"counter_gaps", nc.counter_gaps}};
    if (m.nav_faulty) {
      const sim_bus::RegisterFaultCounters& fc = m.nav_faulty->counters();
      nav["read_failures"] = m.nav_read_failures;
      nav["faults"] = {{"timeouts", fc.timeouts},
                       {"corrupted", fc.corrupted},
                       {"frozen_reads", fc.frozen_reads}};
    } else {
      const io::modbus::NavPollerCounters pc = m.nav_poller->counters();
      nav["polls"] = pc.polls;
      nav["timeouts"] = pc.timeouts;
      nav["disconnected"] = pc.disconnected;
      nav["read_errors"] = pc.read_errors;
      nav["missed_periods"] = pc.missed_periods;
      nav["link"] = nlohmann::ordered_json::parse(nav_link_report_json(
          pc, m.nav_poller->link_state(), m.nav_client->counters(), m.nav_client->last_error_text(),
          m.nav_retry_max_s, m.nav_frames_source_down));
    }
    rep["nav_modbus"] = std::move(nav);
  }
  if (m.modbus_server) {
    rep["modbus_server"] = nlohmann::ordered_json::parse(
        modbus_server_report_json(m.modbus_server->address(), m.modbus_server->counters()));
  }
  rep["wall_time_s"] = r.wall_time_s;
  rep["detections"] = {
      {"total", r.detections_total},
      {"per_frame_mean",
       r.frames ? static_cast<double>(r.detections_total) / static_cast<double>(r.frames) : 0.0},
      {"per_frame_min", r.detections_min},
      {"per_frame_max", r.detections_max},
      {"icd_dropped", r.icd_dropped},
      {"icd_truncated", r.icd_truncated}};
  nlohmann::ordered_json stages;
  for (std::size_t k = 0; k < timing::kStageCount; ++k) {
    const timing::StageSummary& st = r.stages[k];
    stages[std::string(timing::stage_name(static_cast<timing::Stage>(k)))] = {
        {"count", st.count},
        {"p50_ms", st.p50_s * 1e3},
        {"p99_ms", st.p99_s * 1e3},
        {"max_ms", st.max_s * 1e3},
        {"mean_ms", st.mean_s * 1e3},
        {"percentiles", st.percentiles_exact ? "exact" : "histogram (within 0.4 %)"}};
  }
  rep["stage_timing"] = std::move(stages);
  // What a run keeps of its per-frame timing (docs/performance.md, "Long runs").
  rep["timing_record"] = {
      {"summaries",
       "every frame (stage_timing: count, mean, max exact; percentiles exact up "
       "to frames_kept frames, beyond from a log histogram of every frame)"},
      {"frames_csv", "every frame's stage times [ms]"},
      {"frames_kept", std::min<std::uint64_t>(r.frames, m.profiler.capacity_frames())},
      {"timing_png", "the last frames_kept frames"},
      {"trace_events", m.options.trace_events_file.empty() ? "off" : "the first frames_kept"}};
  rep["schedule"] = {{"period_ms", 1e3 / s.rate_hz},
                     {"frames_over_budget", r.frames_over_budget},
                     {"overruns", r.overruns},
                     {"missed_periods", r.missed_periods}};
  const io::canas::DecoderCounters& c = r.decoder;
  rep["input"] = {{"frames", c.frames},
                  {"accepted", c.accepted},
                  {"ignored_id", c.ignored_id},
                  {"rejected", c.rejected()},
                  {"rejected_by_reason",
                   {{"short_frame", c.short_frame},
                    {"unknown_data_type", c.unknown_data_type},
                    {"unsupported_data_type", c.unsupported_data_type},
                    {"not_a_number", c.not_a_number},
                    {"out_of_range", c.out_of_range},
                    {"unpaired_double", c.unpaired_double},
                    {"extended_id", c.extended_id}}},
                  {"other_node", c.other_node},
                  {"repeated_message_code", c.repeated_message_code},
                  {"message_code_gaps", c.message_code_gaps}};
  {
    // Validity: each field's worst age at a frame's time and how many frames found it stale.
    static constexpr std::array<const char*, io::canas::kFieldCount> kFieldNames{
        "pitch",  "roll",     "true_heading", "latitude", "longitude",
        "height", "vel_east", "vel_north",    "vel_up"};
    nlohmann::ordered_json ages;
    for (std::size_t k = 0; k < io::canas::kFieldCount; ++k) {
      const double age = r.field_age_max_s[k];  // over the frames after its first reception
      ages[kFieldNames[k]] = {{"age_max_s", age}, {"stale_frames", r.field_stale_frames[k]}};
    }
    rep["validity"] = {{"state_timeout_s", s.state_timeout_s},
                       {"stale_output", s.stale_output_silent ? "silent" : "flag"},
                       {"frames_invalid", r.frames - r.frames_valid},
                       {"lists_suppressed", r.lists_suppressed},
                       {"fields", std::move(ages)}};
  }
  if (m.options.replay) {
    rep["replay"] = {{"log_frames", m.options.replay_input.size()},
                     {"frames_fed", r.replay_frames_fed},
                     {"frames_after_last_radar_frame", r.replay_frames_left}};
  }
  rep["faults_injected"] = {
      {"seed", s.link_faults.seed},
      {"malformed",
       {{"short_dlc", r.injected_malformed[0]},
        {"unknown_data_type", r.injected_malformed[1]},
        {"not_a_number", r.injected_malformed[2]},
        {"out_of_range", r.injected_malformed[3]}}},
      {"link",
       {{"frames_in", r.link_faults.frames_in},
        {"frames_out", r.link_faults.frames_out},
        {"dropped", r.link_faults.dropped},
        {"delayed", r.link_faults.delayed},
        {"corrupted", r.link_faults.corrupted},
        {"reordered", r.link_faults.reordered},
        {"duplicated", r.link_faults.duplicated},
        {"held_overflow", r.link_faults.held_overflow}}},
      {"stale_sender",
       {{"mode", !s.stale_sender                               ? "none"
                 : s.stale.mode == sim_bus::StaleMode::kSilent ? "silent"
                 : s.stale.mode == sim_bus::StaleMode::kFrozen ? "frozen"
                                                               : "frozen_value"},
        {"suppressed", r.stale_sender.suppressed},
        {"replayed", r.stale_sender.replayed}}},
      {"babbling_node",
       {{"sent", r.babble.sent},
        {"send_failures", r.babble.send_failures},
        {"skipped", r.babble.skipped}}}};
  {
    const double n = r.view.frames > 0 ? static_cast<double>(r.view.frames) : 1.0;
    rep["scene"] = {
        {"source", s.scene_file.empty() ? "builtin:" + s.scene_builtin : s.scene_file.string()},
        {"seed", s.scene_seed},
        {"objects", m.scene.objects().size()},
        {"triangles", m.scene.triangle_count()},
        {"lod_tiles", m.scene.view_stats().lod_groups},
        {"per_frame_mean",
         {{"lod_tiles_in_view", static_cast<double>(r.view.lod_groups_in_view) / n},
          {"lod_tiles_culled", static_cast<double>(r.view.lod_groups_culled) / n},
          {"lod_tiles_at_level",
           {static_cast<double>(r.view.lod_groups_at_level[0]) / n,
            static_cast<double>(r.view.lod_groups_at_level[1]) / n,
            static_cast<double>(r.view.lod_groups_at_level[2]) / n,
            static_cast<double>(r.view.lod_groups_at_level[3]) / n}},
          {"triangles_active", static_cast<double>(r.view.triangles_active) / n}}}};
  }
  {
    // The atmosphere the returns crossed and its two-way loss at reference ranges.
    const WeatherSpec& w = s.weather;
    nlohmann::ordered_json weather;
    if (!w.enabled) {
      weather["condition"] = "none (no [weather] table: free space)";
    } else {
      constexpr double kReferenceRangeM = 1000.0;
      weather = {{"condition", w.condition},
                 {"rain_rate_mmph", w.rain_mm_per_h},
                 {"fog_water_gpm3", w.fog_water_gm3},
                 {"humidity_gpm3", w.humidity_gm3},
                 {"temperature_c", w.temperature_k - 273.15},
                 {"pressure_hpa", w.pressure_hpa},
                 {"models",
                  "ITU-R P.676-13 (gases), P.838-3 (rain, vertical polarisation), "
                  "P.840-9 (fog)"},
                 {"carrier_hz", s.sbr.carrier_hz},
                 {"one_way_db_per_km",
                  {{"gases", m.weather_gas_db_per_km},
                   {"rain", m.weather_rain_db_per_km},
                   {"fog", m.weather_fog_db_per_km},
                   {"total", m.weather_db_per_m * 1e3}}},
                 {"reference_range_m", kReferenceRangeM},
                 {"two_way_loss_db_at_reference", 2.0 * m.weather_db_per_m * kReferenceRangeM},
                 {"two_way_loss_db_at_max_range", 2.0 * m.weather_db_per_m * s.sbr.max_range_m}};
    }
    rep["weather"] = std::move(weather);
  }
  {
    // The fidelity governor: its settings, how often each level was chosen, and per recorded
    // frame the level, the predicted cost and the estimated error.
    const GovernorConfig& g = m.governor.config();
    nlohmann::ordered_json levels = nlohmann::ordered_json::array();
    for (std::size_t k = 0; k <= static_cast<std::size_t>(r.governor.max_level); ++k)
      levels.push_back(r.governor.level_frames[k]);
    nlohmann::ordered_json level = nlohmann::ordered_json::array(),
                           predicted = nlohmann::ordered_json::array(),
                           error = nlohmann::ordered_json::array();
    for (std::size_t i = 0; i < r.governor.per_frame_level.size(); ++i) {
      const int l = r.governor.per_frame_level[i];
      level.push_back(l);
      predicted.push_back(
          std::round(static_cast<double>(r.governor.per_frame_predicted_ms[i]) * 1e3) * 1e-3);
      if (l < 0)
        error.push_back(nullptr);
      else
        error.push_back(FidelityGovernor::kLevelSnrError_db[static_cast<std::size_t>(l)]);
    }
    rep["governor"] = {
        {"enabled", g.enabled},
        {"mode", g.mode == GovernorConfig::Mode::kMeasured ? "measured" : "model"},
        {"deadline_ms", g.compute_fraction * 1e3 / s.rate_hz},
        {"compute_fraction", g.compute_fraction},
        {"cost_model",
         {{"trace_ns_per_ray", g.trace_ns_per_ray},
          {"sensor_ns_per_cell", g.sensor_ns_per_cell},
          {"sensor_ns_per_return", g.sensor_ns_per_return},
          {"final_trace_factor", m.governor.trace_factor()},
          {"final_sensor_factor", m.governor.sensor_factor()}}},
        {"max_level", g.max_level},
        {"frames_at_level", std::move(levels)},
        {"frames_degraded", r.governor.frames_degraded},
        {"frames_predicted_late", r.governor.frames_predicted_late},
        {"per_frame",
         {{"note",
           "every frame in order (the first 1,048,576; frames.csv has them all and the rays); "
           "level 0 is the scenario's fidelity, -1 a frame without an ownship state; "
           "estimated_snr_error_db is the mean |SNR error| measured at that level on the "
           "default scenario (radar-emu tradeoff), an estimate, not a bound"},
          {"level", std::move(level)},
          {"predicted_ms", std::move(predicted)},
          {"estimated_snr_error_db", std::move(error)}}}};
  }
  rep["trace"] = {{"rays", r.trace.rays},
                  {"target_bundles", r.trace.target_bundles},
                  {"coarsened_bundles", r.trace.coarsened_bundles},
                  {"hits", r.trace.hits},
                  {"contributions", r.trace.contributions},
                  {"dropped_contributions", r.trace.dropped_contributions},
                  {"grazing_skipped", r.trace.grazing_skipped},
                  {"dielectric_reflections", r.trace.dielectric_reflections},
                  {"pruned_paths", r.trace.pruned_paths},
                  {"lit_facets", r.trace.lit_facets},
                  {"partial_facets", r.trace.partial_facets},
                  {"facet_queries", r.trace.facet_queries},
                  {"edges_used", r.trace.edges_used},
                  {"edges_shadowed", r.trace.edges_shadowed},
                  {"edges_skipped", r.trace.edges_skipped},
                  {"edges_double", r.trace.edges_double},
                  {"knob_fallbacks", r.trace.knob_fallbacks}};
  const radar::Waveform& wf = s.sensor.processing.waveform;
  rep["sensor"] = {
      {"waveform", radar::waveform_name(wf.kind)},
      {"range_bin_m", m.sensor.range_cell_m()},
      {"range_resolution_m", radar::range_resolution_m(wf)},
      {"range_bins", wf.range_bins},
      {"swath_start_m", radar::first_range_m(wf)},
      {"unambiguous_range_m", m.sensor.unambiguous_range_m()},
      {"velocity_bin_mps", m.sensor.doppler_cell_mps()},
      {"unambiguous_velocity_mps", m.sensor.unambiguous_velocity_mps()},
      {"beams", m.sensor.antenna().beams()},
      {"sum_beamwidth_az_deg", common::degrees(m.sensor.antenna().sum_beamwidth_az_rad())},
      {"sum_beamwidth_el_deg", common::degrees(m.sensor.antenna().sum_beamwidth_el_rad())},
      {"antenna_gain_db", common::db_from_power(s.sensor.antenna.peak_gain)},
      {"processing_gain_db", common::db_from_power(m.sensor.processor().processing_gain())},
      {"cfar", s.sensor.cfar.kind == radar::CfarKind::kCellAveraging ? "ca" : "os"},
      {"cfar_training_cells", m.sensor.cfar_training_cells()},
      {"noise_seed", s.sensor.noise_seed},
      {"cells_processed", r.sensor.cells_touched},
      {"cells_synthesised", r.sensor.cells_synthesised},
      {"returns_merged", r.sensor.merged_returns},
      {"cfar_crossings", r.sensor.cfar_crossings},
      {"false_alarm_rate_upper_bound", r.sensor.cells_touched
                                           ? static_cast<double>(r.sensor.cfar_crossings) /
                                                 static_cast<double>(r.sensor.cells_touched)
                                           : 0.0},
      {"merged_across_beams", r.sensor.merged},
      {"detections", r.sensor.detections},
      {"truncated", r.sensor.truncated},
      {"out_of_swath", r.sensor.out_of_grid},
      {"hits_overflowed", r.sensor.hits_overflowed},
      {"rejected_input", r.sensor.rejected_input},
      {"dropped_input", r.sensor.dropped_input}};
  rep["bus"] = {{"frames_in", r.bus_frames_in},
                {"frames_out", r.bus_frames_out},
                {"rx_overflows", r.bus_rx_overflows},
                {"log_overflows", r.record_overflows},
                {"avionics_lists_received", r.sink_lists},
                {"avionics_malformed", r.sink_malformed}};
  if (m.options.realtime) {
    rep["realtime"] = {{"memory_locked", r.realtime.memory_locked},
                       {"sched_fifo", r.realtime.fifo},
                       {"pinned", r.realtime.pinned},
                       {"warnings", r.realtime.warnings}};
  }
  rep["outputs"] = {"report.json",    "detections.json", "truth.json", "frames.csv",
                    "detections.png", "timing.png",      "bus_in.log", "bus_out.log"};
  {
    nlohmann::ordered_json files;
    for (const OutputFileCounters& f : oc.files) {
      files[f.name] = {{"bytes", f.bytes_written},
                       {"write_errors", f.write_errors},
                       {"bytes_lost", f.bytes_lost},
                       {"first_error", f.first_error}};
    }
    rep["output_stream"] = {
        {"complete", oc.complete()},
        {"policy", m.options.realtime ? "real time: drop what the writer cannot take, count it"
                                      : "simulated clock: wait for the writer between frames"},
        {"frames_written", oc.frames_written},
        {"frames_dropped", oc.frames_dropped},
        {"bus_frames_written", oc.bus_frames_written},
        {"bus_frames_dropped", oc.bus_frames_dropped},
        {"detections_written", oc.detections_written},
        {"writer_waits", oc.waits},
        {"files", std::move(files)}};
  }
  if (m.live_view) {
    // The live view: updates the frame loop handed over, and what became of them.
    const LiveViewCounters lc = m.live_view->counters();
    const io::ws::ServerCounters& sc = lc.server;
    rep["live_view"] = {
        {"address", "http://" + lc.address + "/"},
        {"view_updates_published", lc.updates_published},
        {"view_updates_dropped", lc.updates_dropped},
        {"view_updates_taken", lc.updates_taken},
        {"view_updates_sent", lc.updates_sent},
        {"view_updates_unseen", lc.updates_unseen},
        {"note",
         "dropped: superseded before the server took it (it takes the newest every 40 ms); "
         "sent: pushed to at least one browser; unseen: taken with no browser connected"},
        {"server",
         {{"connections", sc.connections},
          {"refused", sc.refused},
          {"pages_served", sc.pages_served},
          {"not_found", sc.not_found},
          {"bad_requests", sc.bad_requests},
          {"bad_handshakes", sc.bad_handshakes},
          {"websocket_clients", sc.websocket_clients},
          {"messages", sc.messages},
          {"frames_queued", sc.frames_queued},
          {"frames_skipped_slow_client", sc.frames_skipped},
          {"slow_clients_closed", sc.slow_clients_closed},
          {"clients_closed", sc.clients_closed},
          {"accept_failures", sc.accept_failures}}}};
  }
  if (!m.options.trace_events_file.empty()) {
    rep["trace_events"] = {{"file", m.options.trace_events_file.string()},
                           {"events", m.profiler.events().size()},
                           {"dropped", r.trace_events_dropped}};
  }
  write_json(dir / "report.json", rep);

  write_timing_png(m.profiler, 1.0 / s.rate_hz, dir / "timing.png");
}

void ClosedLoop::write_trace_events() const {
  const Impl& m = *impl_;
  const std::filesystem::path& path = m.options.trace_events_file;
  if (path.empty())
    return;
  // Chrome trace-event format ("JSON Object Format", complete events ph "X"): ts and dur in
  // microseconds; opens in https://ui.perfetto.dev and chrome://tracing.
  const std::span<const timing::StageEvent> events = m.profiler.events();
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
                      {"dropped_events", m.profiler.events_dropped()}};
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
