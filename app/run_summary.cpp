// run's printed summary (app/loop_runner.hpp).

#include <csignal>
#include <cstdint>
#include <cstdio>
#include <string>

#include "app/loop_runner.hpp"

namespace radar_emu::app {

void print_summary(const loop::ClosedLoop& loop, const loop::RunResult& r,
                   const std::string& out_dir, const loop::OutputCounters& oc) {
  using radar_emu::timing::Stage;
  using radar_emu::timing::stage_name;
  const auto& s = loop.scenario();
  std::printf("radar-emu run: %s\n", s.name.c_str());
  std::printf("  frames      %llu at %.1f Hz (%llu with a valid ownship state), wall %.2f s\n",
              static_cast<unsigned long long>(r.frames), s.rate_hz,
              static_cast<unsigned long long>(r.frames_valid), r.wall_time_s);
  std::printf(
      "  detections  %.2f per frame (min %llu, max %llu), %llu in total\n",
      r.frames ? static_cast<double>(r.detections_total) / static_cast<double>(r.frames) : 0.0,
      static_cast<unsigned long long>(r.detections_min),
      static_cast<unsigned long long>(r.detections_max),
      static_cast<unsigned long long>(r.detections_total));
  {
    const auto& w = s.sensor.processing.waveform;
    const double cells = static_cast<double>(r.sensor.cells_touched);
    std::printf(
        "  sensor      %s %.4g GHz, %zu beams x %d range bins x %d pulses; CFAR %s Pfa %.0e: "
        "%.3g crossings a cell (%llu peaks merged across beams)\n",
        radar_emu::radar::waveform_name(w.kind), w.carrier_hz * 1e-9,
        s.sensor.antenna.beam_azimuth_rad.size(), w.range_bins, w.pulses,
        s.sensor.cfar.kind == radar_emu::radar::CfarKind::kCellAveraging ? "CA" : "OS",
        s.sensor.cfar.pfa, cells > 0.0 ? static_cast<double>(r.sensor.cfar_crossings) / cells : 0.0,
        static_cast<unsigned long long>(r.sensor.merged));
  }
  std::printf("  stage times [ms]      p50      p99      max\n");
  for (Stage st : {Stage::kInput, Stage::kSceneUpdate, Stage::kTrace, Stage::kSensor,
                   Stage::kOutput, Stage::kFrame}) {
    const auto& x = r.stages[static_cast<std::size_t>(st)];
    std::printf("    %-14s %8.3f %8.3f %8.3f\n", std::string(stage_name(st)).c_str(), x.p50_s * 1e3,
                x.p99_s * 1e3, x.max_s * 1e3);
  }
  std::printf(
      "  budget      %.1f ms: %llu frames over budget, %llu overruns, %llu missed periods\n",
      1e3 / s.rate_hz, static_cast<unsigned long long>(r.frames_over_budget),
      static_cast<unsigned long long>(r.overruns),
      static_cast<unsigned long long>(r.missed_periods));
  std::printf(
      "  bus         %llu frames in (%llu rejected), %llu frames out, %llu lists at the "
      "avionics\n",
      static_cast<unsigned long long>(r.bus_frames_in),
      static_cast<unsigned long long>(r.decoder.rejected()),
      static_cast<unsigned long long>(r.bus_frames_out),
      static_cast<unsigned long long>(r.sink_lists));
  if (r.frames_valid < r.frames) {
    std::printf("  validity    %llu frames with a stale ownship state (older than %.3g s): %s\n",
                static_cast<unsigned long long>(r.frames - r.frames_valid), s.state_timeout_s,
                s.stale_output_silent ? "no list sent" : "empty lists flagged OWNSHIP_INVALID");
  }
  if (r.replay_frames_fed > 0 || r.replay_frames_left > 0) {
    std::printf("  replay      %llu log frames fed, %llu after the last frame\n",
                static_cast<unsigned long long>(r.replay_frames_fed),
                static_cast<unsigned long long>(r.replay_frames_left));
  }
  if (r.interrupted) {
    std::printf("  interrupted by %s after %llu of %llu frames\n",
                r.stop_signal == SIGINT    ? "SIGINT"
                : r.stop_signal == SIGTERM ? "SIGTERM"
                                           : "a stop",
                static_cast<unsigned long long>(r.frames),
                static_cast<unsigned long long>(r.frames_planned));
  }
  if (const auto lv = loop.live_view_counters()) {
    std::printf(
        "  live view   http://%s/: %llu of %llu updates sent to browsers, %llu dropped "
        "(superseded), %llu unseen (no browser); %llu browsers connected\n",
        lv->address.c_str(), static_cast<unsigned long long>(lv->updates_sent),
        static_cast<unsigned long long>(lv->updates_published),
        static_cast<unsigned long long>(lv->updates_dropped),
        static_cast<unsigned long long>(lv->updates_unseen),
        static_cast<unsigned long long>(lv->server.websocket_clients));
  }
  if (!out_dir.empty()) {
    std::printf(
        "  outputs     %s/{report.json,detections.json,truth.json,frames.csv,detections.png,"
        "timing.png,bus_in.log,bus_out.log}\n",
        out_dir.c_str());
    std::uint64_t write_errors = 0;
    for (const auto& f : oc.files)
      write_errors += f.write_errors;
    std::printf(
        "              %s: %llu frames and %llu bus frames written, %llu and %llu dropped, %llu "
        "write errors\n",
        oc.complete() ? "complete" : "INCOMPLETE",
        static_cast<unsigned long long>(oc.frames_written),
        static_cast<unsigned long long>(oc.bus_frames_written),
        static_cast<unsigned long long>(oc.frames_dropped),
        static_cast<unsigned long long>(oc.bus_frames_dropped),
        static_cast<unsigned long long>(write_errors));
  }
}

}  // namespace radar_emu::app
