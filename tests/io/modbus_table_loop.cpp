// A frame loop that serves the detection table over Modbus TCP exactly as `radar-emu run
// --modbus-server` does (encode_detection_table + ModbusServer::publish once per frame), for
// the hostile-clients test (check_modbus_hostile.py): the emulator's own loop spends most of a
// frame in physics, whose time varies far more than anything Modbus could add, so the loop here
// does only the Modbus part and measures it.
//
//   modbus_table_loop --frames 2000 --period-ms 5 --max-detections 5 [--max-clients 64]
//       [--request-timeout-s 0.3] [--idle-timeout-s 60] [--evict-idle-s 1]
//
// Protocol on stdin/stdout: prints "listening 127.0.0.1:PORT" once the server listens; waits
// for a line "go" on stdin; runs the frames on absolute deadlines; prints one JSON line
// {"loop": ...} (frames, frames_over_budget: frames whose work took longer than the period,
// work_max_us, wake_late_max_us); keeps serving the last table until stdin reaches its end, then
// prints one JSON line {"server": ...} with every server counter and exits 0.
//
// The table of frame k (the test recomputes it independently): frame counter k mod 65536, time
// k x period [ms], status 0x02 when k is odd, k mod (max_detections + 1) detections, detection
// i with range 100 + k + 10 i m, azimuth 1.5 (i - 2) deg, elevation 0.5 i deg, radial velocity
// -20 + i m/s, SNR 10 + i dB, RCS (k mod 30) - 10 dBsm, accuracies 1 m, 0.1 deg, 0.1 deg,
// 0.2 m/s, range ambiguous when i is odd.

#include <time.h>

#include <CLI/CLI.hpp>
#include <algorithm>
#include <cstdio>
#include <exception>
#include <iostream>
#include <string>
#include <vector>

#include "io/detection_icd.hpp"
#include "io/modbus.hpp"
#include "io/modbus_map.hpp"

namespace {

using namespace radar_emu::io;

std::int64_t now_ns() {
  timespec ts{};
  clock_gettime(CLOCK_MONOTONIC, &ts);
  return static_cast<std::int64_t>(ts.tv_sec) * 1'000'000'000 + ts.tv_nsec;
}

void sleep_until_ns(std::int64_t t) {
  timespec ts{static_cast<time_t>(t / 1'000'000'000), static_cast<long>(t % 1'000'000'000)};
  while (clock_nanosleep(CLOCK_MONOTONIC, TIMER_ABSTIME, &ts, nullptr) != 0) {
  }
}

void fill_frame(std::uint64_t k, std::size_t max_detections, double period_ms, icd::Header& h,
                std::vector<icd::Detection>& dets) {
  h = {};
  h.frame_counter = static_cast<std::uint16_t>(k & 0xFFFF);
  h.time_ms = static_cast<std::uint32_t>(static_cast<double>(k) * period_ms);
  h.status = (k % 2 == 1) ? icd::status::kOverrun : 0;
  dets.resize(k % (max_detections + 1));
  for (std::size_t i = 0; i < dets.size(); ++i) {
    icd::Detection& d = dets[i];
    const auto fi = static_cast<double>(i);
    d.range_m = 100.0 + static_cast<double>(k) + 10.0 * fi;
    d.azimuth_deg = 1.5 * (fi - 2.0);
    d.elevation_deg = 0.5 * fi;
    d.radial_velocity_mps = -20.0 + fi;
    d.snr_db = 10.0 + fi;
    d.rcs_dbsm = static_cast<double>(k % 30) - 10.0;
    d.range_std_m = 1.0;
    d.azimuth_std_deg = 0.1;
    d.elevation_std_deg = 0.1;
    d.radial_velocity_std_mps = 0.2;
    d.range_ambiguous = i % 2 == 1;
    d.velocity_ambiguous = false;
  }
}

}  // namespace

int main(int argc, char** argv) {
  CLI::App app{"Detection-table frame loop on Modbus TCP (radar-emu hostile-clients test)"};
  std::uint64_t frames = 2000;
  double period_ms = 5.0;
  std::size_t max_detections = 5;
  radar_emu::io::modbus::ModbusServerConfig sc;
  sc.endpoint = "tcp:127.0.0.1:0";
  sc.max_clients = 64;
  app.add_option("--frames", frames)->check(CLI::Range(1, 10'000'000));
  app.add_option("--period-ms", period_ms)->check(CLI::Range(0.1, 1000.0));
  app.add_option("--max-detections", max_detections)->check(CLI::Range(1, 255));
  app.add_option("--max-clients", sc.max_clients);
  app.add_option("--request-timeout-s", sc.request_timeout_s);
  app.add_option("--idle-timeout-s", sc.idle_timeout_s);
  app.add_option("--evict-idle-s", sc.evict_idle_s);
  CLI11_PARSE(app, argc, argv);
  try {
    const modbus::DetectionTableConfig table{.max_detections = max_detections};
    std::vector<std::uint16_t> regs(modbus::detection_table_registers(table));
    sc.register_count = regs.size();
    modbus::ModbusServer server(sc);
    icd::Header h;
    std::vector<icd::Detection> dets;
    dets.reserve(max_detections);
    fill_frame(0, max_detections, period_ms, h, dets);
    (void)modbus::encode_detection_table(h, dets, regs, table);
    (void)server.publish(regs);
    std::printf("listening %s\n", server.address().c_str());
    std::fflush(stdout);
    std::string line;
    while (std::getline(std::cin, line) && line != "go") {
    }

    const auto period_ns = static_cast<std::int64_t>(period_ms * 1e6);
    std::uint64_t over_budget = 0;
    std::int64_t work_max = 0, late_max = 0;
    std::int64_t deadline = now_ns() + period_ns;
    for (std::uint64_t k = 1; k <= frames; ++k, deadline += period_ns) {
      sleep_until_ns(deadline);
      const std::int64_t t0 = now_ns();
      // The frame's Modbus work, as in the closed loop's output stage.
      fill_frame(k, max_detections, period_ms, h, dets);
      (void)modbus::encode_detection_table(h, dets, regs, table);
      (void)server.publish(regs);
      const std::int64_t t1 = now_ns();
      work_max = std::max(work_max, t1 - t0);
      late_max = std::max(late_max, t0 - deadline);
      if (t1 - t0 > period_ns)
        ++over_budget;
    }
    std::printf(
        "{\"loop\": {\"frames\": %llu, \"period_ms\": %g, \"frames_over_budget\": %llu, "
        "\"work_max_us\": %.1f, \"wake_late_max_us\": %.1f, \"last_frame\": %llu}}\n",
        static_cast<unsigned long long>(frames), period_ms,
        static_cast<unsigned long long>(over_budget), static_cast<double>(work_max) * 1e-3,
        static_cast<double>(late_max) * 1e-3, static_cast<unsigned long long>(frames));
    std::fflush(stdout);
    while (std::getline(std::cin, line)) {
    }
    server.stop();
    const modbus::ModbusServerCounters c = server.counters();
    const auto u = [](std::uint64_t v) { return static_cast<unsigned long long>(v); };
    std::printf(
        "{\"server\": {\"requests\": %llu, \"replies\": %llu, \"reads\": %llu, "
        "\"refused_writes\": %llu, \"unknown_function\": %llu, \"bad_length\": %llu, "
        "\"illegal_quantity\": %llu, \"illegal_address\": %llu, \"malformed_mbap\": %llu, "
        "\"incomplete\": %llu, \"idle_closed\": %llu, \"send_failures\": %llu, \"errors\": %llu, "
        "\"clients_accepted\": %llu, \"clients_refused\": %llu, \"clients_evicted\": %llu, "
        "\"clients_closed\": %llu, \"publishes\": %llu}}\n",
        u(c.requests), u(c.replies), u(c.reads), u(c.refused_writes), u(c.unknown_function),
        u(c.bad_length), u(c.illegal_quantity), u(c.illegal_address), u(c.malformed_mbap),
        u(c.incomplete), u(c.idle_closed), u(c.send_failures), u(c.errors), u(c.clients_accepted),
        u(c.clients_refused), u(c.clients_evicted), u(c.clients_closed), u(c.publishes));
    std::fflush(stdout);
    return 0;
  } catch (const std::exception& e) {
    std::fprintf(stderr, "modbus_table_loop: %s\n", e.what());
    return 2;
  }
}
