#include "emulator/closed_loop.hpp"

#include <algorithm>
#include <cmath>
#include <fstream>
#include <nlohmann/json.hpp>
#include <numbers>
#include <stdexcept>

#include "emulator/ownship.hpp"
#include "emulator/plot.hpp"
#include "io/candump.hpp"
#include "scene/default_scene.hpp"
#include "scene/geo.hpp"
#include "scene/gltf.hpp"
#include "scene/scene.hpp"
#include "sim_bus/aircraft_player.hpp"
#include "sim_bus/avionics_sink.hpp"
#include "sim_bus/faulty_node.hpp"
#include "sim_bus/loopback_can.hpp"
#include "timing/clock.hpp"
#include "timing/scheduler.hpp"

namespace radar_emu::emulator {

namespace {

constexpr double kDegPerRad = 180.0 / std::numbers::pi;
constexpr std::uint8_t kFaultyNodeId = 99;

scene::SceneDescription scene_description(const Scenario& s) {
  if (!s.scene_file.empty())
    return scene::load_gltf(s.scene_file);
  return scene::default_scene();  // parse_scenario() accepts only "default" as built-in
}

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
  o.azimuth_deg = d.azimuth_rad * kDegPerRad;
  o.elevation_deg = d.elevation_rad * kDegPerRad;
  o.radial_velocity_mps = d.radial_velocity_mps;
  o.snr_db = 10.0 * std::log10(d.snr);
  o.rcs_dbsm = 10.0 * std::log10(d.rcs_m2);
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

}  // namespace

struct ClosedLoop::Impl {
  Impl(const Scenario& s, const RunOptions& o)
      : scenario(s),
        options(o),
        scene(scene_description(s)),
        enu(scene.anchor()),
        tracer(scene, s.sbr),
        sensor(sensor_config(s, tracer)),
        ins(bus.add_endpoint("ins", 1 << 16)),
        faulty_ep(bus.add_endpoint("faulty", 16)),
        replay_ep(bus.add_endpoint("replay", 16)),
        radar_ep(bus.add_endpoint("radar", 1 << 16)),
        avionics(bus.add_endpoint("avionics", 1 << 16)),
        player(ownship_trajectory(s, enu),
               sim_bus::PlayerConfig{s.ins_node_id, s.attitude_rate_hz, s.navigation_rate_hz,
                                     s.epoch_unix_ns}),
        faulty(kFaultyNodeId),
        sink(std::min<std::uint64_t>(s.frames, o.record_frames_max)),
        recorded_frames(std::min<std::uint64_t>(s.frames, o.record_frames_max)),
        rx_log("can0", static_cast<std::size_t>(recorded_frames * input_frames_per_frame(s))),
        tx_log("can0", static_cast<std::size_t>(recorded_frames *
                                                io::icd::frames_for(s.sensor.max_detections))),
        profiler(static_cast<std::size_t>(std::max<std::uint64_t>(recorded_frames, 1))) {
    if (s.frames == 0)
      throw std::runtime_error("scenario: frames must be >= 1");
    contributions.resize(tracer.max_contributions());
    detections.resize(s.sensor.max_detections);
    icd_detections.resize(s.sensor.max_detections);
    out_frames.resize(io::icd::frames_for(s.sensor.max_detections));
  }

  static std::uint64_t input_frames_per_frame(const Scenario& s) {
    const double per_s = 3.0 * s.attitude_rate_hz + 8.0 * s.navigation_rate_hz;
    return static_cast<std::uint64_t>(std::ceil(per_s / s.rate_hz)) + 12;
  }

  Scenario scenario;
  RunOptions options;
  scene::Scene scene;
  scene::wgs84::EnuFrame enu;
  radar::SbrTracer tracer;
  radar::Sensor sensor;
  sim_bus::LoopbackCanBus bus;
  sim_bus::LoopbackEndpoint& ins;
  sim_bus::LoopbackEndpoint& faulty_ep;
  sim_bus::LoopbackEndpoint& replay_ep;
  std::size_t replay_next = 0;  ///< next frame of options.replay_input to put on the bus
  sim_bus::LoopbackEndpoint& radar_ep;
  sim_bus::LoopbackEndpoint& avionics;
  sim_bus::AircraftStatePlayer player;
  sim_bus::FaultyNode faulty;
  sim_bus::AvionicsSink sink;
  io::canas::Decoder decoder;
  std::uint64_t recorded_frames;
  io::CandumpRecorder rx_log;
  io::CandumpRecorder tx_log;
  timing::StageProfiler profiler;
  std::vector<radar::Contribution> contributions;
  std::vector<radar::Detection> detections;
  std::vector<io::icd::Detection> icd_detections;
  std::vector<io::CanFrame> out_frames;
};

ClosedLoop::ClosedLoop(const Scenario& scenario, const RunOptions& options)
    : impl_(std::make_unique<Impl>(scenario, options)) {}

ClosedLoop::~ClosedLoop() = default;

const Scenario& ClosedLoop::scenario() const noexcept {
  return impl_->scenario;
}

RunResult ClosedLoop::run() {
  Impl& m = *impl_;
  const Scenario& s = m.scenario;
  RunResult r;
  r.records.reserve(static_cast<std::size_t>(m.recorded_frames));
  r.detections.reserve(static_cast<std::size_t>(m.recorded_frames) * s.sensor.max_detections);
  r.sensor_detections.reserve(r.detections.capacity());
  r.detections_min = std::numeric_limits<std::uint64_t>::max();
  r.field_age_max_s.fill(0.0);
  r.field_stale_frames.fill(0);

  timing::MonotonicClock wall;
  timing::SimulatedClock simulated(s.epoch_unix_ns);
  timing::Clock& sched_clock = m.options.realtime ? static_cast<timing::Clock&>(wall)
                                                  : static_cast<timing::Clock&>(simulated);
  if (m.options.realtime)
    r.realtime = timing::bring_up_realtime(m.options.rt);
  const std::int64_t period_ns = std::llround(1e9 / s.rate_hz);
  const std::int64_t start_ns =
      m.options.realtime ? wall.now_ns() + 20'000'000 : simulated.now_ns();  // 20 ms to settle
  timing::FixedRateScheduler scheduler(sched_clock, period_ns, start_ns);
  const std::int64_t timeout_ns = std::llround(s.state_timeout_s * 1e9);
  const std::int64_t run_start_wall = wall.now_ns();
  std::uint16_t frame_counter = 0;

  for (std::uint64_t done = 0; done < s.frames; ++done) {
    const timing::Tick tick = scheduler.wait_next();
    const std::int64_t frame_start_wall = wall.now_ns();
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
    } else {
      (void)m.player.publish_until(t_s, m.ins);
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
      while (m.radar_ep.receive(f)) {
        ++r.bus_frames_in;
        (void)m.rx_log.record(f);
        (void)m.decoder.decode(f, f.timestamp_ns);
      }
      valid = radar_pose_from_state(m.decoder.state(), bus_now_ns, timeout_ns, m.enu,
                                    s.antenna_depression_rad, pose);
      const io::canas::OwnshipState& st = m.decoder.state();
      for (std::size_t k = 0; k < io::canas::kFieldCount; ++k) {
        const auto field = static_cast<io::canas::Field>(k);
        r.field_age_max_s[k] = std::max(r.field_age_max_s[k], st.age_s(field, bus_now_ns));
        if (!st.fresh(field, bus_now_ns, timeout_ns))
          ++r.field_stale_frames[k];
      }
    }
    // ---- scene update: moving objects to frame time ----
    {
      timing::ScopedStage stage(m.profiler, wall, timing::Stage::kSceneUpdate);
      m.scene.set_time(t_s);
    }
    // ---- trace: shoot and bounce ----
    std::size_t n_contrib = 0;
    {
      timing::ScopedStage stage(m.profiler, wall, timing::Stage::kTrace);
      if (valid)
        n_contrib = m.tracer.trace(pose, m.contributions, r.trace);  // accumulates
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
    // ---- output: ICD frames on the bus ----
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
      // A stale state sends an empty list flagged OWNSHIP_INVALID, or nothing ("silent").
      const bool send_list = valid || !s.stale_output_silent;
      io::icd::EncodeResult enc{};
      if (send_list) {
        enc = io::icd::encode(h, std::span(m.icd_detections.data(), n_det), m.out_frames);
      } else {
        ++r.lists_suppressed;
      }
      r.icd_dropped += enc.dropped;
      r.icd_truncated += enc.truncated;
      for (std::size_t i = 0; i < enc.frames; ++i) {
        io::CanFrame& f = m.out_frames[i];
        f.timestamp_ns = bus_now_ns;
        if (m.radar_ep.send(f))
          ++r.bus_frames_out;
        (void)m.tx_log.record(f);
      }
      if (r.records.size() < m.recorded_frames) {
        FrameRecord rec;
        rec.frame_index = tick.period_index;
        rec.time_s = t_s;
        rec.header = h;
        rec.header.detection_count = static_cast<std::uint8_t>(enc.encoded);
        rec.first_detection = static_cast<std::uint32_t>(r.detections.size());
        rec.detection_count = static_cast<std::uint32_t>(n_det);
        rec.late = tick.late;
        rec.sent = send_list;
        r.records.push_back(rec);
        r.detections.insert(r.detections.end(), m.icd_detections.begin(),
                            m.icd_detections.begin() + static_cast<std::ptrdiff_t>(n_det));
        r.sensor_detections.insert(r.sensor_detections.end(), m.detections.begin(),
                                   m.detections.begin() + static_cast<std::ptrdiff_t>(n_det));
      }
    }
    const std::int64_t frame_ns = wall.now_ns() - frame_start_wall;
    m.profiler.record(timing::Stage::kFrame, frame_ns);
    if (frame_ns > period_ns)
      ++r.frames_over_budget;

    // The avionics under test read what the radar sent.
    (void)m.sink.poll(m.avionics);

    ++r.frames;
    if (valid)
      ++r.frames_valid;
    r.detections_total += n_det;
    r.detections_min = std::min<std::uint64_t>(r.detections_min, n_det);
    r.detections_max = std::max<std::uint64_t>(r.detections_max, n_det);
    if (m.options.progress)
      m.options.progress(done + 1, s.frames);
  }

  r.wall_time_s = static_cast<double>(wall.now_ns() - run_start_wall) * 1e-9;
  r.overruns = scheduler.overruns();
  r.missed_periods = scheduler.missed_periods();
  r.decoder = m.decoder.counters();
  if (m.options.replay)
    r.replay_frames_left = m.options.replay_input.size() - m.replay_next;
  r.bus_rx_overflows = m.radar_ep.rx_overflows() + m.avionics.rx_overflows();
  r.record_overflows = m.rx_log.overflowed() + m.tx_log.overflowed();
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
  return r;
}

void ClosedLoop::write_outputs(const RunResult& r, const std::filesystem::path& dir) const {
  const Impl& m = *impl_;
  const Scenario& s = m.scenario;
  std::error_code ec;
  std::filesystem::create_directories(dir, ec);
  if (ec)
    throw std::runtime_error(dir.string() + ": cannot create directory: " + ec.message());

  auto write_json = [&](const std::filesystem::path& path, const nlohmann::ordered_json& j) {
    std::ofstream out(path, std::ios::binary);
    out << j.dump(1) << '\n';
    if (!out)
      throw std::runtime_error(path.string() + ": write failed");
  };

  // detections.json: what the radar sent, frame by frame (values before ICD quantisation).
  nlohmann::ordered_json dets;
  dets["scenario"] = s.name;
  dets["units"] = {
      {"range", "m"},
      {"azimuth", "deg, positive right of boresight"},
      {"elevation", "deg, positive up"},
      {"radial_velocity", "m/s, positive receding"},
      {"snr", "dB"},
      {"rcs", "dBsm"},
      {"*_std", "one-sigma thermal-noise accuracy, same unit as the value"},
      {"range_ambiguous / velocity_ambiguous",
       "the waveform may have folded this value (unambiguous interval in report.json)"}};
  nlohmann::ordered_json frames = nlohmann::ordered_json::array();
  for (const FrameRecord& rec : r.records) {
    nlohmann::ordered_json f;
    f["frame_counter"] = rec.header.frame_counter;
    f["time_s"] = rec.time_s;
    f["status"] = rec.header.status;
    if (!rec.sent)
      f["sent"] = false;  // stale_output = "silent": nothing went on the bus
    nlohmann::ordered_json list = nlohmann::ordered_json::array();
    for (std::uint32_t i = 0; i < rec.detection_count; ++i) {
      const io::icd::Detection& d = r.detections[rec.first_detection + i];
      const radar::Detection& q = r.sensor_detections[rec.first_detection + i];
      list.push_back({{"range_m", d.range_m},
                      {"azimuth_deg", d.azimuth_deg},
                      {"elevation_deg", d.elevation_deg},
                      {"radial_velocity_mps", d.radial_velocity_mps},
                      {"snr_db", d.snr_db},
                      {"rcs_dbsm", d.rcs_dbsm},
                      {"range_std_m", q.range_std_m},
                      {"azimuth_std_deg", q.azimuth_std_rad * kDegPerRad},
                      {"elevation_std_deg", q.elevation_std_rad * kDegPerRad},
                      {"radial_velocity_std_mps", q.velocity_std_mps},
                      {"range_ambiguous", q.range_ambiguous},
                      {"velocity_ambiguous", q.velocity_ambiguous}});
    }
    f["detections"] = std::move(list);
    frames.push_back(std::move(f));
  }
  dets["frames"] = std::move(frames);
  write_json(dir / "detections.json", dets);

  // report.json: the run's summary.
  nlohmann::ordered_json rep;
  rep["scenario"] = s.name;
  rep["mode"] = m.options.realtime ? "realtime" : "as-fast-as-possible";
  rep["rate_hz"] = s.rate_hz;
  rep["frames"] = r.frames;
  rep["frames_valid"] = r.frames_valid;
  rep["input_source"] = m.options.replay ? "replay" : "sim";
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
        {"mean_ms", st.mean_s * 1e3}};
  }
  rep["stage_timing"] = std::move(stages);
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
                  {"message_code_gaps", c.message_code_gaps}};
  {
    // Validity: each field's worst age at a frame's time and how many frames found it stale.
    static constexpr std::array<const char*, io::canas::kFieldCount> kFieldNames{
        "pitch",  "roll",     "true_heading", "latitude", "longitude",
        "height", "vel_east", "vel_north",    "vel_up"};
    nlohmann::ordered_json ages;
    for (std::size_t k = 0; k < io::canas::kFieldCount; ++k) {
      const double age = r.field_age_max_s[k];
      ages[kFieldNames[k]] = {{"age_max_s", std::isfinite(age) ? nlohmann::ordered_json(age)
                                                               : nlohmann::ordered_json(nullptr)},
                              {"stale_frames", r.field_stale_frames[k]}};
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
  rep["faults_injected"] = {{"short_dlc", r.injected_malformed[0]},
                            {"unknown_data_type", r.injected_malformed[1]},
                            {"not_a_number", r.injected_malformed[2]},
                            {"out_of_range", r.injected_malformed[3]}};
  rep["trace"] = {{"rays", r.trace.rays},
                  {"target_bundles", r.trace.target_bundles},
                  {"coarsened_bundles", r.trace.coarsened_bundles},
                  {"hits", r.trace.hits},
                  {"contributions", r.trace.contributions},
                  {"dropped_contributions", r.trace.dropped_contributions},
                  {"grazing_skipped", r.trace.grazing_skipped}};
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
      {"sum_beamwidth_az_deg", m.sensor.antenna().sum_beamwidth_az_rad() * kDegPerRad},
      {"sum_beamwidth_el_deg", m.sensor.antenna().sum_beamwidth_el_rad() * kDegPerRad},
      {"antenna_gain_db", 10.0 * std::log10(s.sensor.antenna.peak_gain)},
      {"processing_gain_db", 10.0 * std::log10(m.sensor.processor().processing_gain())},
      {"cfar", s.sensor.cfar.kind == radar::CfarKind::kCellAveraging ? "ca" : "os"},
      {"cfar_training_cells", m.sensor.cfar_training_cells()},
      {"noise_seed", s.sensor.noise_seed},
      {"cells_processed", r.sensor.cells_touched},
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
  rep["outputs"] = {"report.json", "detections.json", "detections.png", "bus_in.log",
                    "bus_out.log"};
  write_json(dir / "report.json", rep);

  write_bscope_png(r, s, dir / "detections.png");
  m.rx_log.write_file(dir / "bus_in.log");
  m.tx_log.write_file(dir / "bus_out.log");
}

}  // namespace radar_emu::emulator
