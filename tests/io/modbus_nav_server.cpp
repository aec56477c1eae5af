// The project's Modbus navigation test server: serves the navigation register map
// (docs/icd/modbus.md) on TCP, playing a straight-line trajectory at a fixed update rate, for a
// given time, then exits 0. Readiness signal: the line "listening HOST:PORT" on stdout (flushed)
// once the socket listens (port 0 = ephemeral; the line names the bound port).
//
//   modbus_nav_server --port 0 --lat-deg 51.47 --lon-deg -0.46 --height-m 300
//       --vel-east-mps 70 --vel-north-mps 0 --vel-up-mps -3.5 --heading-deg 90
//       --rate-hz 50 --duration-s 3 [--order abcd|cdab] [--encoding float32|scaled] [--base 0]
//
// The straight line: latitude, longitude and height advance linearly with the ENU velocity,
// using the WGS84 radii of curvature at the start point (meridian M = a (1 - e^2) / (1 - e^2
// sin^2 lat)^1.5, prime vertical N = a / sqrt(1 - e^2 sin^2 lat); NIMA TR8350.2, sec. 3 and 4):
// lat(t) = lat0 + v_n t / (M + h0), lon(t) = lon0 + v_e t / ((N + h0) cos lat0),
// h(t) = h0 + v_u t.

#include <CLI/CLI.hpp>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <exception>
#include <thread>

#include "common/units.hpp"
#include "io/modbus.hpp"
#include "io/modbus_map.hpp"
#include "sim_bus/nav_register_player.hpp"

namespace {

using namespace radar_emu;

constexpr double kWgs84A_m = 6378137.0;               // semi-major axis (TR8350.2 table 3.1)
constexpr double kWgs84F = 1.0 / 298.257223563;       // flattening
constexpr double kWgs84E2 = kWgs84F * (2 - kWgs84F);  // first eccentricity squared

}  // namespace

int main(int argc, char** argv) {
  CLI::App app{"Modbus TCP navigation test server (radar-emu)"};
  std::string bind = "127.0.0.1";
  int port = 0;
  int base = 0;
  std::string order = "abcd";
  std::string encoding = "float32";
  double lat_deg = 0, lon_deg = 0, height_m = 0, ve = 0, vn = 0, vu = 0;
  double heading_deg = 0, pitch_deg = 0, roll_deg = 0;
  double rate_hz = 50.0, duration_s = 3.0;
  app.add_option("--bind", bind, "address to listen on");
  app.add_option("--port", port, "TCP port (0 = ephemeral)")->check(CLI::Range(0, 65535));
  app.add_option("--base", base, "protocol address of the map")->check(CLI::Range(0, 65000));
  app.add_option("--order", order, "word order")->check(CLI::IsMember({"abcd", "cdab"}));
  app.add_option("--encoding", encoding, "value encoding")
      ->check(CLI::IsMember({"float32", "scaled"}));
  app.add_option("--lat-deg", lat_deg, "start latitude [deg]")->required();
  app.add_option("--lon-deg", lon_deg, "start longitude [deg]")->required();
  app.add_option("--height-m", height_m, "start height above WGS84 [m]")->required();
  app.add_option("--vel-east-mps", ve, "east velocity [m/s]");
  app.add_option("--vel-north-mps", vn, "north velocity [m/s]");
  app.add_option("--vel-up-mps", vu, "up velocity [m/s]");
  app.add_option("--heading-deg", heading_deg, "true heading [deg]");
  app.add_option("--pitch-deg", pitch_deg, "pitch [deg]");
  app.add_option("--roll-deg", roll_deg, "roll [deg]");
  app.add_option("--rate-hz", rate_hz, "updates per second")->check(CLI::Range(0.1, 1000.0));
  app.add_option("--duration-s", duration_s, "run time [s]")->check(CLI::Range(0.01, 3600.0));
  CLI11_PARSE(app, argc, argv);

  try {
    const double lat0 = common::radians(lat_deg);
    const double s2 = std::sin(lat0) * std::sin(lat0);
    const double m_m = kWgs84A_m * (1 - kWgs84E2) / std::pow(1 - kWgs84E2 * s2, 1.5);
    const double n_m = kWgs84A_m / std::sqrt(1 - kWgs84E2 * s2);
    sim_bus::AircraftState a;
    a.time_s = 0.0;
    a.latitude_rad = lat0;
    a.longitude_rad = common::radians(lon_deg);
    a.height_m = height_m;
    a.true_heading_rad = common::radians(heading_deg);
    a.pitch_rad = common::radians(pitch_deg);
    a.roll_rad = common::radians(roll_deg);
    a.vel_east_mps = ve;
    a.vel_north_mps = vn;
    a.vel_up_mps = vu;
    sim_bus::AircraftState b = a;
    b.time_s = duration_s;
    b.latitude_rad = lat0 + vn * duration_s / (m_m + height_m);
    b.longitude_rad = a.longitude_rad + ve * duration_s / ((n_m + height_m) * std::cos(lat0));
    b.height_m = height_m + vu * duration_s;

    io::modbus::NavMapConfig map;
    map.base_address = static_cast<std::uint16_t>(base);
    map.order = order == "cdab" ? io::modbus::WordOrder::kCDAB : io::modbus::WordOrder::kABCD;
    map.encoding = encoding == "scaled" ? io::modbus::NavMapConfig::Encoding::kScaledInt
                                        : io::modbus::NavMapConfig::Encoding::kFloat32;
    sim_bus::NavRegisterPlayer player(sim_bus::Trajectory({a, b}),
                                      {.map = map, .rate_hz = rate_hz});
    io::modbus::ModbusServer server({.endpoint = "tcp:" + bind + ":" + std::to_string(port),
                                     .start_address = map.base_address,
                                     .register_count = io::modbus::nav_register_count(map)});
    // Registers hold the state at t = 0 before the first client can read.
    (void)player.publish_until(0.0, server);
    std::printf("listening %s\n", server.address().c_str());
    std::fflush(stdout);

    const auto start = std::chrono::steady_clock::now();
    const auto period = std::chrono::nanoseconds(std::llround(1e9 / rate_hz));
    auto next = start;
    for (;;) {
      const double t_s =
          std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
      if (t_s >= duration_s)
        break;
      (void)player.publish_until(t_s, server);
      next += period;
      std::this_thread::sleep_until(next);
    }
    server.stop();
    const auto c = server.counters();
    std::fprintf(stderr, "modbus_nav_server: %llu updates, %llu requests, %llu refused writes\n",
                 static_cast<unsigned long long>(player.updates()),
                 static_cast<unsigned long long>(c.requests),
                 static_cast<unsigned long long>(c.refused_writes));
    return 0;
  } catch (const std::exception& e) {
    std::fprintf(stderr, "modbus_nav_server: %s\n", e.what());
    return 2;
  }
}
