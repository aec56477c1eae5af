#include "loop/outputs/report.hpp"

#include <algorithm>
#include <array>
#include <cmath>
#include <csignal>
#include <fstream>
#include <nlohmann/json.hpp>
#include <numbers>
#include <stdexcept>

#include "common/units.hpp"
#include "radar/clutter/terrain.hpp"
#include "radar/sensor/sensor.hpp"
#include "timing/profiler.hpp"

namespace radar_emu::loop {

namespace {

using Json = nlohmann::ordered_json;
using ull = unsigned long long;

// A run's count as a mean a frame (0 for a run of no frames).
double per_frame(const RunResult& r, std::uint64_t count) {
  return r.frames ? static_cast<double>(count) / static_cast<double>(r.frames) : 0.0;
}

// ---- report.json, one block of keys at a time (in the file's order) ----

Json nav_json(const NavSourceReport& n) {
  const io::modbus::NavDecoderCounters& nc = n.decoder;
  Json nav = {{"samples", nc.samples},           {"new_samples", nc.new_samples},
              {"stale_samples", nc.stale},       {"rejected", nc.rejected()},
              {"not_a_number", nc.not_a_number}, {"out_of_range", nc.out_of_range},
              {"wrong_size", nc.wrong_size},     {"counter_gaps", nc.counter_gaps}};
  if (n.register_bank) {
    nav["read_failures"] = n.read_failures;
    nav["faults"] = {{"timeouts", n.faults.timeouts},
                     {"corrupted", n.faults.corrupted},
                     {"frozen_reads", n.faults.frozen_reads}};
  } else {
    nav["polls"] = n.poller.polls;
    nav["timeouts"] = n.poller.timeouts;
    nav["disconnected"] = n.poller.disconnected;
    nav["read_errors"] = n.poller.read_errors;
    nav["missed_periods"] = n.poller.missed_periods;
    nav["link"] = Json::parse(n.link_json);
  }
  return nav;
}

// scenario ... detections: what ran, on which buses, and what it found.
void add_run(const RunReport& p, Json& rep) {
  const Scenario& s = *p.scenario;
  const RunResult& r = *p.result;
  rep["scenario"] = s.name;
  rep["mode"] = p.realtime ? "realtime" : "as-fast-as-possible";
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
  rep["backends"] = {{"can", p.replay ? std::string("replay") : p.can},
                     {"ownship_from", p.nav_modbus.empty() ? std::string("canaerospace")
                                                           : "modbus:" + p.nav_modbus},
                     {"detection_lists", s.can_fd ? "can_fd" : "can_classic"},
                     {"modbus_server", p.modbus_server_address}};
  if (!p.can_backend_json.empty())
    rep["can_backend"] = Json::parse(p.can_backend_json);
  if (p.nav)
    rep["nav_modbus"] = nav_json(*p.nav);
  if (!p.modbus_server_json.empty())
    rep["modbus_server"] = Json::parse(p.modbus_server_json);
  rep["wall_time_s"] = r.wall_time_s;
  rep["detections"] = {
      {"total", r.detections_total},       {"per_frame_mean", per_frame(r, r.detections_total)},
      {"per_frame_min", r.detections_min}, {"per_frame_max", r.detections_max},
      {"icd_dropped", r.icd_dropped},      {"icd_truncated", r.icd_truncated}};
}

// stage_timing, timing_record, schedule.
void add_timing(const RunReport& p, Json& rep) {
  const Scenario& s = *p.scenario;
  const RunResult& r = *p.result;
  Json stages;
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
      {"frames_kept", std::min<std::uint64_t>(r.frames, p.timing_frames_kept)},
      {"timing_png", "the last frames_kept frames"},
      {"trace_events", p.trace_events_file.empty() ? "off" : "the first frames_kept"}};
  rep["schedule"] = {{"period_ms", 1e3 / s.rate_hz},
                     {"frames_over_budget", r.frames_over_budget},
                     {"overruns", r.overruns},
                     {"missed_periods", r.missed_periods}};
}

// input, validity, replay.
void add_input(const RunReport& p, Json& rep) {
  const Scenario& s = *p.scenario;
  const RunResult& r = *p.result;
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
  // Validity: each field's worst age at a frame's time and how many frames found it stale.
  static constexpr std::array<const char*, io::canas::kFieldCount> kFieldNames{
      "pitch",  "roll",     "true_heading", "latitude", "longitude",
      "height", "vel_east", "vel_north",    "vel_up"};
  Json ages;
  for (std::size_t k = 0; k < io::canas::kFieldCount; ++k) {
    const double age = r.field_age_max_s[k];  // over the frames after its first reception
    ages[kFieldNames[k]] = {{"age_max_s", age}, {"stale_frames", r.field_stale_frames[k]}};
  }
  rep["validity"] = {{"state_timeout_s", s.state_timeout_s},
                     {"stale_output", s.stale_output_silent ? "silent" : "flag"},
                     {"frames_invalid", r.frames - r.frames_valid},
                     {"lists_suppressed", r.lists_suppressed},
                     {"fields", std::move(ages)}};
  if (p.replay) {
    rep["replay"] = {{"log_frames", p.replay_log_frames},
                     {"frames_fed", r.replay_frames_fed},
                     {"frames_after_last_radar_frame", r.replay_frames_left}};
  }
}

// faults_injected.
void add_faults(const RunReport& p, Json& rep) {
  const Scenario& s = *p.scenario;
  const RunResult& r = *p.result;
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
}

// The polarisation P.838's rain loss was taken at (ClosedLoop's rain_tilt_rad()).
const char* rain_polarisation(radar::Polarisation p) noexcept {
  switch (p) {
    case radar::Polarisation::kHH:
      return "horizontal polarisation";
    case radar::Polarisation::kVV:
      return "vertical polarisation";
    default:
      return "tilt 45 deg: one way H, the other V";
  }
}

// scene, weather.
void add_scene_and_weather(const RunReport& p, Json& rep) {
  const Scenario& s = *p.scenario;
  const RunResult& r = *p.result;
  const double n = r.view.frames > 0 ? static_cast<double>(r.view.frames) : 1.0;
  rep["scene"] = {{"source", s.scene_import         ? "import:" + s.scene_import->dem.string()
                             : s.scene_file.empty() ? "builtin:" + s.scene_builtin
                                                    : s.scene_file.string()},
                  {"seed", s.scene_seed},
                  {"objects", p.scene.objects},
                  {"triangles", p.scene.triangles},
                  {"lod_tiles", p.scene.lod_tiles},
                  {"per_frame_mean",
                   {{"lod_tiles_in_view", static_cast<double>(r.view.lod_groups_in_view) / n},
                    {"lod_tiles_culled", static_cast<double>(r.view.lod_groups_culled) / n},
                    {"lod_tiles_at_level",
                     {static_cast<double>(r.view.lod_groups_at_level[0]) / n,
                      static_cast<double>(r.view.lod_groups_at_level[1]) / n,
                      static_cast<double>(r.view.lod_groups_at_level[2]) / n,
                      static_cast<double>(r.view.lod_groups_at_level[3]) / n}},
                    {"triangles_active", static_cast<double>(r.view.triangles_active) / n}}}};
  if (p.scene.import) {
    const SceneFigures::Import& im = *p.scene.import;
    rep["scene"]["import"] = {{"vertical", im.vertical},
                              {"anchor_height_m", im.anchor_height_m},
                              {"anchor_undulation_m", im.anchor_undulation_m},
                              {"dem_holes_filled", im.dem_holes_filled},
                              {"unknown_class_cells", im.unknown_class_cells},
                              {"osm_broken_ways", im.osm_broken_ways},
                              {"osm_outside", im.osm_outside},
                              {"seconds", im.seconds}};
  }
  // The atmosphere the returns crossed and its two-way loss at reference ranges.
  const WeatherSpec& w = s.weather;
  const WeatherFigures& f = p.weather;
  Json weather;
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
               {"models", std::string("ITU-R P.676-13 (gases), P.838-3 (rain, ") +
                              rain_polarisation(s.sbr.polarisation) + "), P.840-9 (fog)"},
               {"carrier_hz", s.sbr.carrier_hz},
               {"one_way_db_per_km",
                {{"gases", f.gas_db_per_km},
                 {"rain", f.rain_db_per_km},
                 {"fog", f.fog_db_per_km},
                 {"total", f.total_db_per_m * 1e3}}},
               {"reference_range_m", kReferenceRangeM},
               {"two_way_loss_db_at_reference", 2.0 * f.total_db_per_m * kReferenceRangeM},
               {"two_way_loss_db_at_max_range", 2.0 * f.total_db_per_m * s.sbr.max_range_m}};
  }
  rep["weather"] = std::move(weather);
}

// governor: its settings, how often each level was chosen, and per recorded frame the level,
// the predicted cost and the estimated error.
void add_governor(const RunReport& p, Json& rep) {
  const RunResult& r = *p.result;
  const GovernorConfig& g = p.governor;
  Json levels = Json::array();
  for (std::size_t k = 0; k <= static_cast<std::size_t>(r.governor.max_level); ++k)
    levels.push_back(r.governor.level_frames[k]);
  Json level = Json::array(), predicted = Json::array(), error = Json::array();
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
      {"deadline_ms", g.compute_fraction * 1e3 / p.scenario->rate_hz},
      {"compute_fraction", g.compute_fraction},
      {"cost_model",
       {{"trace_ms_per_frame", g.trace_ms_per_frame},
        {"trace_ns_per_facet", g.trace_ns_per_facet},
        {"trace_ns_per_ray", g.trace_ns_per_ray},
        {"trace_ns_per_kept_return", g.trace_ns_per_kept_return},
        {"terrain_ns_per_patch", g.terrain_ns_per_patch},
        {"sensor_ns_per_cell", g.sensor_ns_per_cell},
        {"sensor_ns_per_return", g.sensor_ns_per_return},
        {"sensor_ns_per_unmerged_return", g.sensor_ns_per_unmerged_return},
        {"sensor_ns_per_terrain_return", g.sensor_ns_per_terrain_return},
        {"final_trace_factor", p.governor_trace_factor},
        {"final_sensor_factor", p.governor_sensor_factor}}},
      {"max_level", g.max_level},
      {"frames_at_level", std::move(levels)},
      {"frames_degraded", r.governor.frames_degraded},
      {"frames_predicted_late", r.governor.frames_predicted_late},
      {"error_model",
       {{"source",
         "FidelityGovernor::kLevelSnrError_db: mean |SNR error| per level measured by "
         "`radar-emu tradeoff --cases frame` on the default scenario's frame"},
        {"measured_on_this_scenario", false},
        {"summary_estimate", "the estimate of the coarsest level used (the worst)"}}},
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

// The object's name by id ("object N" when the report has no names).
std::string object_name(const RunReport& p, std::uint32_t id) {
  return id < p.object_names.size() ? p.object_names[id] : "object " + std::to_string(id);
}

// One error's statistics (loop/outcome.hpp), scaled to the output's unit; null without samples.
Json error_json(const ErrorStats& e, double scale) {
  if (e.count == 0)
    return nullptr;
  return {{"mean", e.mean * scale},
          {"std", e.std_dev() * scale},
          {"stated_sigma_rms", e.stated_sigma_rms() * scale}};
}

// outcome: per truth object, frames in the beam, detected, Pd and the errors; the false alarms.
void add_outcome(const RunReport& p, Json& rep) {
  const OutcomeTotals& o = p.result->outcome;
  const AssociationGate& g = o.gate;
  Json targets = Json::array();
  for (const TargetOutcome& t : o.targets) {
    targets.push_back({{"object_id", t.object_id},
                       {"object", object_name(p, t.object_id)},
                       {"frames_in_beam", t.frames_in_beam},
                       {"frames_detected", t.frames_detected},
                       {"pd", t.frames_in_beam > 0 ? Json(t.pd()) : Json(nullptr)},
                       {"detections_associated", t.detections_associated},
                       {"range_error_m", error_json(t.range_m, 1.0)},
                       {"azimuth_error_deg", error_json(t.azimuth_rad, common::degrees(1.0))},
                       {"elevation_error_deg", error_json(t.elevation_rad, common::degrees(1.0))},
                       {"radial_velocity_error_mps", error_json(t.radial_velocity_mps, 1.0)}});
  }
  rep["outcome"] = {
      {"note",
       "per truth object (truth.json's objects): frames in the beam, frames with a detection "
       "associated (pd = detected / in beam), and the error of its associated detection "
       "(detection - truth: mean, sample std, and the rms of the one-sigma accuracies the "
       "sensor stated for those detections); a false alarm is a detection associated with no "
       "object in the beam (clutter or noise, or an object whose box centre is outside the "
       "field of view); association: docs/outcome.md"},
      {"gate",
       {{"rule",
         "|detection - truth| <= cell + sigmas x stated one-sigma + size in range, azimuth and "
         "elevation each (size: half the bounding-box diagonal, over the range in the angles); "
         "nearest object in normalised distance; radial velocity not gated"},
        {"range_cell_m", g.range_cell_m},
        {"azimuth_cell_deg", common::degrees(g.azimuth_cell_rad)},
        {"elevation_cell_deg", common::degrees(g.elevation_cell_rad)},
        {"sigmas", g.sigmas},
        {"unambiguous_range_m", g.unambiguous_range_m},
        {"unambiguous_velocity_mps", g.unambiguous_velocity_mps}}},
      {"frames_scored", o.frames_scored},
      {"detections", o.detections},
      {"false_alarms", o.false_alarms},
      {"false_alarms_on_objects", o.false_alarms_on_objects},
      {"false_alarms_per_frame", o.false_alarms_per_frame()},
      {"targets", std::move(targets)}};
}

// trace, sensor.
void add_trace_and_sensor(const RunReport& p, Json& rep) {
  const Scenario& s = *p.scenario;
  const RunResult& r = *p.result;
  rep["trace"] = {{"rays", r.trace.rays},
                  {"target_bundles", r.trace.target_bundles},
                  {"coarsened_bundles", r.trace.coarsened_bundles},
                  {"hits", r.trace.hits},
                  {"contributions", r.trace.contributions},
                  {"dropped_contributions", r.trace.dropped_contributions},
                  {"grazing_skipped", r.trace.grazing_skipped},
                  {"dielectric_reflections", r.trace.dielectric_reflections},
                  {"pruned_paths", r.trace.pruned_paths},
                  {"target_facets", r.trace.target_facets},
                  {"lit_facets", r.trace.lit_facets},
                  {"partial_facets", r.trace.partial_facets},
                  {"facet_queries", r.trace.facet_queries},
                  {"mover_facets", r.trace.mover_facets},
                  {"replayed_mover_facets", r.trace.replayed_mover_facets},
                  {"self_replayed_mover_facets", r.trace.self_replayed_mover_facets},
                  {"edges_used", r.trace.edges_used},
                  {"edges_shadowed", r.trace.edges_shadowed},
                  {"edges_skipped", r.trace.edges_skipped},
                  {"edges_double", r.trace.edges_double},
                  {"knob_fallbacks", r.trace.knob_fallbacks},
                  {"reuse_static_paths", s.sbr.reuse_static_paths},
                  {"reused_bundles", r.trace.reused_bundles},
                  {"reused_rays", r.trace.reused_rays},
                  {"reused_contributions", r.trace.reused_contributions},
                  {"refreshed_bundles", r.trace.refreshed_bundles},
                  {"reuse_max_angle_fraction", r.trace.reuse_max_angle_fraction},
                  {"reuse_max_age_frames", r.trace.reuse_max_age_frames},
                  {"refresh_deferred_frames", r.trace.refresh_deferred},
                  {"kept_paths_left_view", r.trace.kept_paths_left_view},
                  {"mask_target_rays", s.sbr.mask_target_rays},
                  {"masked_rays", r.trace.masked_rays}};
  rep["terrain"] = {{"source", s.terrain_engine ? "engine" : "rays"},
                    {"facets_considered", r.terrain.facets_considered},
                    {"patches", r.terrain.patches},
                    {"patches_lit", r.terrain.patches_lit},
                    {"patches_shadowed", r.terrain.patches_shadowed},
                    {"horizon_patches", r.terrain.horizon_patches},
                    {"occlusion_queries", r.terrain.occlusion_queries},
                    {"budget_cut", r.terrain.budget_cut},
                    {"dropped_returns", r.terrain_dropped},
                    // Issue 28: sigma0 values outside a model's validity the terrain read.
                    {"sigma0_validity",
                     {{"tracked", p.sigma0_tracked},
                      {"flagged", p.sigma0_flags != 0},
                      {"flags", p.sigma0_flags},
                      {"description", radar::clutter::describe_validity(p.sigma0_flags)},
                      {"flagged_patch_fraction", p.sigma0_patch_fraction},
                      {"flagged_power_fraction", std::isnan(p.sigma0_power_fraction)
                                                     ? nlohmann::json(nullptr)
                                                     : nlohmann::json(p.sigma0_power_fraction)},
                      {"materials", p.sigma0_lines}}}};
  const radar::Waveform& wf = s.sensor.processing.waveform;
  const SensorFigures& f = p.sensor;
  rep["sensor"] = {{"waveform", radar::waveform_name(wf.kind)},
                   {"range_bin_m", f.range_bin_m},
                   {"range_resolution_m", radar::range_resolution_m(wf)},
                   {"range_bins", wf.range_bins},
                   {"swath_start_m", radar::first_range_m(wf)},
                   {"unambiguous_range_m", f.unambiguous_range_m},
                   {"velocity_bin_mps", f.velocity_bin_mps},
                   {"unambiguous_velocity_mps", f.unambiguous_velocity_mps},
                   {"beams", f.beams},
                   {"sum_beamwidth_az_deg", common::degrees(f.sum_beamwidth_az_rad)},
                   {"sum_beamwidth_el_deg", common::degrees(f.sum_beamwidth_el_rad)},
                   {"antenna_gain_db", common::db_from_power(s.sensor.antenna.peak_gain)},
                   {"processing_gain_db", common::db_from_power(f.processing_gain)},
                   {"cfar", s.sensor.cfar.kind == radar::CfarKind::kCellAveraging ? "ca" : "os"},
                   {"cfar_training_cells", f.cfar_training_cells},
                   {"noise_seed", s.sensor.noise_seed},
                   {"cells_processed", r.sensor.cells_touched},
                   {"cells_synthesised", r.sensor.cells_synthesised},
                   {"returns_merged", r.sensor.merged_returns},
                   // (return, beam) pairs left out under the floor; the floor null when off
                   {"return_floor_db",
                    s.sensor.thermal_noise && s.sensor.return_floor_db > radar::kReturnFloorOff_db
                        ? nlohmann::json(s.sensor.return_floor_db)
                        : nlohmann::json(nullptr)},
                   {"returns_below_floor", r.sensor.returns_below_floor},
                   // coherent returns left out before the merge, under the floor at any angle
                   {"returns_under_floor", r.sensor.returns_under_floor},
                   {"cfar_crossings", r.sensor.cfar_crossings},
                   {"false_alarm_rate_upper_bound",
                    r.sensor.cells_touched ? static_cast<double>(r.sensor.cfar_crossings) /
                                                 static_cast<double>(r.sensor.cells_touched)
                                           : 0.0},
                   {"merged_across_beams", r.sensor.merged},
                   {"detections", r.sensor.detections},
                   {"truncated", r.sensor.truncated},
                   {"out_of_swath", r.sensor.out_of_grid},
                   {"hits_overflowed", r.sensor.hits_overflowed},
                   {"rejected_input", r.sensor.rejected_input},
                   {"dropped_input", r.sensor.dropped_input}};
}

// bus, realtime, outputs, output_stream.
void add_bus_and_outputs(const RunReport& p, Json& rep) {
  const RunResult& r = *p.result;
  rep["bus"] = {{"frames_in", r.bus_frames_in},
                {"frames_out", r.bus_frames_out},
                {"rx_overflows", r.bus_rx_overflows},
                {"log_overflows", r.record_overflows},
                {"avionics_lists_received", r.sink_lists},
                {"avionics_malformed", r.sink_malformed}};
  if (p.realtime) {
    rep["realtime"] = {{"memory_locked", r.realtime.memory_locked},
                       {"sched_fifo", r.realtime.fifo},
                       {"pinned", r.realtime.pinned},
                       {"warnings", r.realtime.warnings}};
  }
  rep["outputs"] = {"report.json",    "detections.json", "truth.json", "frames.csv",
                    "detections.png", "timing.png",      "bus_in.log", "bus_out.log"};
  const OutputCounters& oc = p.outputs;
  Json files;
  for (const OutputFileCounters& f : oc.files) {
    files[f.name] = {{"bytes", f.bytes_written},
                     {"write_errors", f.write_errors},
                     {"bytes_lost", f.bytes_lost},
                     {"first_error", f.first_error}};
  }
  rep["output_stream"] = {
      {"complete", oc.complete()},
      {"policy", p.realtime ? "real time: drop what the writer cannot take, count it"
                            : "simulated clock: wait for the writer between frames"},
      {"frames_written", oc.frames_written},
      {"frames_dropped", oc.frames_dropped},
      {"bus_frames_written", oc.bus_frames_written},
      {"bus_frames_dropped", oc.bus_frames_dropped},
      {"detections_written", oc.detections_written},
      {"writer_waits", oc.waits},
      {"files", std::move(files)}};
}

// live_view (the updates the frame loop handed over, and what became of them), trace_events.
void add_live_view_and_trace_events(const RunReport& p, Json& rep) {
  if (p.live_view) {
    const LiveViewCounters& lc = *p.live_view;
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
  if (!p.trace_events_file.empty()) {
    rep["trace_events"] = {{"file", p.trace_events_file.string()},
                           {"events", p.trace_events},
                           {"dropped", p.result->trace_events_dropped}};
  }
}

// ---- the summary, line by line ----

void print_run_lines(const RunReport& p, std::FILE* out) {
  const Scenario& s = *p.scenario;
  const RunResult& r = *p.result;
  std::fprintf(out, "radar-emu run: %s\n", s.name.c_str());
  std::fprintf(
      out, "  frames      %llu at %.1f Hz (%llu with a valid ownship state), wall %.2f s\n",
      static_cast<ull>(r.frames), s.rate_hz, static_cast<ull>(r.frames_valid), r.wall_time_s);
  std::fprintf(out, "  detections  %.2f per frame (min %llu, max %llu), %llu in total\n",
               per_frame(r, r.detections_total), static_cast<ull>(r.detections_min),
               static_cast<ull>(r.detections_max), static_cast<ull>(r.detections_total));
  const radar::Waveform& w = s.sensor.processing.waveform;
  const double cells = static_cast<double>(r.sensor.cells_touched);
  std::fprintf(
      out,
      "  sensor      %s %.4g GHz, %zu beams x %d range bins x %d pulses; CFAR %s Pfa %.0e: "
      "%.3g crossings a cell (%llu peaks merged across beams)\n",
      radar::waveform_name(w.kind), w.carrier_hz * 1e-9, s.sensor.antenna.beam_azimuth_rad.size(),
      w.range_bins, w.pulses, s.sensor.cfar.kind == radar::CfarKind::kCellAveraging ? "CA" : "OS",
      s.sensor.cfar.pfa, cells > 0.0 ? static_cast<double>(r.sensor.cfar_crossings) / cells : 0.0,
      static_cast<ull>(r.sensor.merged));
  if (r.sensor.returns_under_floor > 0)
    std::fprintf(
        out,
        "              %.0f coherent returns a frame left out before the merge, each below %.0f "
        "dB of a cell's noise at any angle ([detector] return_floor_db)\n",
        per_frame(r, r.sensor.returns_under_floor), s.sensor.return_floor_db);
  if (r.sensor.returns_below_floor > 0)
    std::fprintf(
        out,
        "              %.0f returns a frame left out of a beam's image, each below %.0f dB "
        "of a cell's noise there ([detector] return_floor_db)\n",
        per_frame(r, r.sensor.returns_below_floor), s.sensor.return_floor_db);
  using timing::Stage;
  std::fprintf(out, "  stage times [ms]      p50      p99      max\n");
  for (Stage st : {Stage::kInput, Stage::kSceneUpdate, Stage::kTrace, Stage::kSensor,
                   Stage::kOutput, Stage::kFrame}) {
    const timing::StageSummary& x = r.stages[static_cast<std::size_t>(st)];
    std::fprintf(out, "    %-14s %8.3f %8.3f %8.3f\n", std::string(timing::stage_name(st)).c_str(),
                 x.p50_s * 1e3, x.p99_s * 1e3, x.max_s * 1e3);
  }
  std::fprintf(out,
               "  budget      %.1f ms: %llu frames over budget, %llu overruns, %llu missed "
               "periods\n",
               1e3 / s.rate_hz, static_cast<ull>(r.frames_over_budget),
               static_cast<ull>(r.overruns), static_cast<ull>(r.missed_periods));
  std::fprintf(out,
               "  bus         %llu frames in (%llu rejected), %llu frames out, %llu lists at the "
               "avionics\n",
               static_cast<ull>(r.bus_frames_in), static_cast<ull>(r.decoder.rejected()),
               static_cast<ull>(r.bus_frames_out), static_cast<ull>(r.sink_lists));
}

// "N of M frames degraded (levels a-b, est. X dB)": X the governor's estimated SNR error at the
// coarsest level used (the worst), and where that estimate comes from.
void print_governor_line(const RunReport& p, std::FILE* out) {
  const RunResult& r = *p.result;
  const RunResult::GovernorTotals& g = r.governor;
  if (g.frames_degraded == 0)
    return;
  int lowest = g.max_level;
  for (int k = 1; k <= g.max_level; ++k) {
    if (g.level_frames[static_cast<std::size_t>(k)] > 0) {
      lowest = k;
      break;
    }
  }
  const double est_db = FidelityGovernor::kLevelSnrError_db[static_cast<std::size_t>(
      std::clamp(g.max_level, 0, FidelityGovernor::kMaxLevel))];
  std::fprintf(out, "  governor    %llu of %llu frames degraded (levels %d-%d, est. %.1f dB)\n",
               static_cast<ull>(g.frames_degraded), static_cast<ull>(r.frames), lowest, g.max_level,
               est_db);
  std::fprintf(out,
               "              est.: mean |SNR error| of level %d (the worst used), measured by "
               "radar-emu tradeoff on the default scenario's frame, not on this scenario\n",
               g.max_level);
}

// Static path reuse ([radar] reuse_static_paths): how much of the targets' rays came from kept
// paths, how old and how far from their limit (radar/em/sbr.hpp).
void print_reuse_line(const RunReport& p, std::FILE* out) {
  const RunResult& r = *p.result;
  const radar::TraceStats& t = r.trace;
  if (t.reused_rays == 0)
    return;
  const double all = static_cast<double>(t.rays + t.reused_rays);
  std::fprintf(out,
               "  reuse       %.1f %% of the rays' paths kept from earlier frames (static targets; "
               "oldest %llu frames, aspect change <= %.2f of its limit, phase error <= %.1f deg)\n",
               100.0 * static_cast<double>(t.reused_rays) / all,
               static_cast<ull>(t.reuse_max_age_frames), t.reuse_max_angle_fraction,
               p.scenario->sbr.reuse_max_phase_rad * 180.0 / std::numbers::pi);
  if (t.kept_paths_left_view > 0) {
    std::fprintf(out,
                 "              %llu kept paths of targets leaving the field of view left out "
                 "(their first hit out of view: a trace would not shoot them)\n",
                 static_cast<ull>(t.kept_paths_left_view));
  }
  if (t.refresh_deferred > 0) {
    std::fprintf(out,
                 "              the refresh of kept paths waited in %llu frames (the governor's "
                 "resort before a coarser level)\n",
                 static_cast<ull>(t.refresh_deferred));
  }
}

// The facet memo of moving targets (radar/em/sbr.hpp, SbrTracer's mover_memo_): what share of
// their facets' shadowing answers came from earlier frames.
void print_mover_memo_line(const RunReport& p, std::FILE* out) {
  const radar::TraceStats& t = p.result->trace;
  if (t.replayed_mover_facets + t.self_replayed_mover_facets == 0 || t.mover_facets == 0)
    return;
  std::fprintf(
      out,
      "  movers      %.1f %% of the moving targets' facets read their shadowing from "
      "earlier frames (motion since within half a ray tube, no other mover near), %.1f %% "
      "the shadows of their own body (aspect since within half a tube; the scene asked)\n",
      100.0 * static_cast<double>(t.replayed_mover_facets) / static_cast<double>(t.mover_facets),
      100.0 * static_cast<double>(t.self_replayed_mover_facets) /
          static_cast<double>(t.mover_facets));
}

// The outcome per target: one row per object that was in the beam, then the false alarms.
void print_outcome_lines(const RunReport& p, std::FILE* out) {
  const OutcomeTotals& o = p.result->outcome;
  if (o.frames_scored == 0)
    return;
  constexpr double kDeg = 180.0 / std::numbers::pi;
  std::fprintf(out,
               "  outcome     per object in the beam (association: docs/outcome.md); error = "
               "detection - truth: mean std [stated one-sigma rms]\n");
  std::fprintf(out, "    %-22s %6s %6s %5s  %-26s %-27s %-27s %s\n", "object", "beam", "det", "Pd",
               "range [m]", "azimuth [deg]", "elevation [deg]", "radial vel [m/s]");
  std::size_t never = 0;
  std::string never_names;
  for (const TargetOutcome& t : o.targets) {
    const std::string name = object_name(p, t.object_id);
    if (t.frames_in_beam == 0) {
      if (never < 6)
        never_names += (never > 0 ? ", " : "") + name;
      ++never;
      continue;
    }
    std::fprintf(out, "    %-22s %6llu %6llu %5.2f", name.c_str(),
                 static_cast<ull>(t.frames_in_beam), static_cast<ull>(t.frames_detected), t.pd());
    if (t.frames_detected == 0) {
      std::fprintf(out, "  %-26s %-27s %-27s %s\n", "-", "-", "-", "-");
      continue;
    }
    std::fprintf(out, "  %+8.2f %6.2f [%7.3f] ", t.range_m.mean, t.range_m.std_dev(),
                 t.range_m.stated_sigma_rms());
    for (const ErrorStats* e : {&t.azimuth_rad, &t.elevation_rad}) {
      std::fprintf(out, " %+8.3f %6.3f [%7.4f] ", e->mean * kDeg, e->std_dev() * kDeg,
                   e->stated_sigma_rms() * kDeg);
    }
    std::fprintf(out, " %+7.2f %5.2f [%6.3f]\n", t.radial_velocity_mps.mean,
                 t.radial_velocity_mps.std_dev(), t.radial_velocity_mps.stated_sigma_rms());
  }
  std::fprintf(out,
               "  false alarms %.2f per frame (%llu of %llu detections associated with no object "
               "in the beam, over %llu frames; %llu of them the return of a scene object truth "
               "does not cover)\n",
               o.false_alarms_per_frame(), static_cast<ull>(o.false_alarms),
               static_cast<ull>(o.detections), static_cast<ull>(o.frames_scored),
               static_cast<ull>(o.false_alarms_on_objects));
  if (never > 0) {
    std::fprintf(out, "  never in the beam: %zu of %zu objects (%s%s)\n", never, o.targets.size(),
                 never_names.c_str(), never > 6 ? ", ..." : "");
  }
}

void print_exception_lines(const RunReport& p, std::FILE* out) {
  const Scenario& s = *p.scenario;
  const RunResult& r = *p.result;
  if (r.frames_valid < r.frames) {
    std::fprintf(out,
                 "  validity    %llu frames with a stale ownship state (older than %.3g s): %s\n",
                 static_cast<ull>(r.frames - r.frames_valid), s.state_timeout_s,
                 s.stale_output_silent ? "no list sent" : "empty lists flagged OWNSHIP_INVALID");
  }
  if (r.replay_frames_fed > 0 || r.replay_frames_left > 0) {
    std::fprintf(out, "  replay      %llu log frames fed, %llu after the last frame\n",
                 static_cast<ull>(r.replay_frames_fed), static_cast<ull>(r.replay_frames_left));
  }
  if (r.interrupted) {
    std::fprintf(out, "  interrupted by %s after %llu of %llu frames\n",
                 r.stop_signal == SIGINT    ? "SIGINT"
                 : r.stop_signal == SIGTERM ? "SIGTERM"
                                            : "a stop",
                 static_cast<ull>(r.frames), static_cast<ull>(r.frames_planned));
  }
}

void print_output_lines(const RunReport& p, std::FILE* out) {
  if (p.sigma0_flags != 0) {  // issue 28: the terrain read flagged sigma0 values
    std::fprintf(out,
                 "  terrain     sigma0 outside model validity in %.1f %% of the terrain's patches "
                 "(report.json terrain.sigma0_validity):\n",
                 100.0 * p.sigma0_patch_fraction);
    for (const std::string& line : p.sigma0_lines)
      std::fprintf(out, "              %s\n", line.c_str());
  }
  if (const std::optional<LiveViewCounters>& lv = p.live_view) {
    std::fprintf(out,
                 "  live view   http://%s/: %llu of %llu updates sent to browsers, %llu dropped "
                 "(superseded), %llu unseen (no browser); %llu browsers connected\n",
                 lv->address.c_str(), static_cast<ull>(lv->updates_sent),
                 static_cast<ull>(lv->updates_published), static_cast<ull>(lv->updates_dropped),
                 static_cast<ull>(lv->updates_unseen),
                 static_cast<ull>(lv->server.websocket_clients));
  }
  if (p.out_dir.empty())
    return;
  const OutputCounters& oc = p.outputs;
  std::fprintf(out,
               "  outputs     %s/{report.json,detections.json,truth.json,frames.csv,"
               "detections.png,timing.png,bus_in.log,bus_out.log}\n",
               p.out_dir.c_str());
  std::uint64_t write_errors = 0;
  for (const OutputFileCounters& f : oc.files)
    write_errors += f.write_errors;
  std::fprintf(out,
               "              %s: %llu frames and %llu bus frames written, %llu and %llu "
               "dropped, %llu write errors\n",
               oc.complete() ? "complete" : "INCOMPLETE", static_cast<ull>(oc.frames_written),
               static_cast<ull>(oc.bus_frames_written), static_cast<ull>(oc.frames_dropped),
               static_cast<ull>(oc.bus_frames_dropped), static_cast<ull>(write_errors));
}

}  // namespace

void write_report_json(const RunReport& report, const std::filesystem::path& path) {
  Json rep;
  add_run(report, rep);
  add_timing(report, rep);
  add_input(report, rep);
  add_faults(report, rep);
  add_scene_and_weather(report, rep);
  add_governor(report, rep);
  add_outcome(report, rep);
  add_trace_and_sensor(report, rep);
  add_bus_and_outputs(report, rep);
  add_live_view_and_trace_events(report, rep);
  std::ofstream out(path, std::ios::binary);
  out << rep.dump(1) << '\n';
  if (!out)
    throw std::runtime_error(path.string() + ": write failed");
}

void print_summary(const RunReport& report, std::FILE* out) {
  print_run_lines(report, out);
  print_governor_line(report, out);
  print_reuse_line(report, out);
  print_mover_memo_line(report, out);
  print_exception_lines(report, out);
  print_outcome_lines(report, out);
  print_output_lines(report, out);
}

}  // namespace radar_emu::loop
