// Reads the navigation register map (docs/icd/modbus.md) once with ModbusClient, decodes it
// with NavDecoder and prints one JSON object on stdout: what radar-emu makes of a Modbus
// navigation device. Used by tests/io/check_modbus_peers.py against a pymodbus server.
//
//   modbus_nav_read tcp:127.0.0.1:5020 [--base 0] [--order abcd|cdab] [--encoding float32|scaled]
//
// Exit status: 0 read and decoded (fields may still be rejected: see "counters"), 1 read
// failed, 2 bad arguments.

#include <CLI/CLI.hpp>
#include <cstdio>
#include <exception>
#include <string>
#include <vector>

#include "io/modbus.hpp"
#include "io/modbus_map.hpp"

namespace {

using namespace radar_emu::io;
using namespace radar_emu::io::modbus;

const char* status_name(NavDecodeStatus s) {
  switch (s) {
    case NavDecodeStatus::kAccepted:
      return "accepted";
    case NavDecodeStatus::kPartial:
      return "partial";
    case NavDecodeStatus::kRejected:
      return "rejected";
    case NavDecodeStatus::kStale:
      return "stale";
    case NavDecodeStatus::kWrongSize:
      return "wrong_size";
  }
  return "?";
}

}  // namespace

int main(int argc, char** argv) {
  CLI::App app{"Read a Modbus navigation map once and print it decoded, as JSON"};
  std::string endpoint;
  int base = 0;
  std::string order = "abcd";
  std::string encoding = "float32";
  double timeout_s = 1.0;
  app.add_option("endpoint", endpoint, "tcp:HOST:PORT or rtu:DEVICE:BAUD")->required();
  app.add_option("--base", base, "protocol address of the map")->check(CLI::Range(0, 65000));
  app.add_option("--order", order, "word order")->check(CLI::IsMember({"abcd", "cdab"}));
  app.add_option("--encoding", encoding, "value encoding")
      ->check(CLI::IsMember({"float32", "scaled"}));
  app.add_option("--timeout-s", timeout_s, "response timeout [s]");
  CLI11_PARSE(app, argc, argv);

  try {
    NavMapConfig map;
    map.base_address = static_cast<std::uint16_t>(base);
    map.order = order == "cdab" ? WordOrder::kCDAB : WordOrder::kABCD;
    map.encoding = encoding == "scaled" ? NavMapConfig::Encoding::kScaledInt
                                        : NavMapConfig::Encoding::kFloat32;
    ModbusClient client({.endpoint = endpoint, .response_timeout_s = timeout_s});
    NavDecoder decoder(map);
    std::vector<std::uint16_t> regs(decoder.register_count());
    const RegisterStatus rs = client.read_holding(map.base_address, regs);
    if (rs != RegisterStatus::kOk) {
      std::fprintf(stderr, "modbus_nav_read: read from %s failed (status %d)\n", endpoint.c_str(),
                   static_cast<int>(rs));
      return 1;
    }
    const NavDecodeStatus ds = decoder.decode(regs, 1);
    const auto& st = decoder.state();
    std::printf("{\"decode\": \"%s\", \"update_counter\": %u, \"status\": %u, \"time_ms\": %u",
                status_name(ds), decoder.last_update_counter(), decoder.last_status(),
                decoder.last_sender_time_ms());
    const std::pair<const char*, canas::Field> fields[] = {
        {"latitude_rad", canas::Field::kLatitude}, {"longitude_rad", canas::Field::kLongitude},
        {"height_m", canas::Field::kHeight},       {"true_heading_rad", canas::Field::kTrueHeading},
        {"pitch_rad", canas::Field::kPitch},       {"roll_rad", canas::Field::kRoll},
        {"vel_east_mps", canas::Field::kVelEast},  {"vel_north_mps", canas::Field::kVelNorth},
        {"vel_up_mps", canas::Field::kVelUp}};
    std::printf(", \"fields\": {");
    const char* sep = "";
    for (const auto& [name, field] : fields) {
      if (st[field].received)
        std::printf("%s\"%s\": %.17g", sep, name, st[field].value);
      else
        std::printf("%s\"%s\": null", sep, name);
      sep = ", ";
    }
    const NavDecoderCounters& c = decoder.counters();
    std::printf(
        "}, \"counters\": {\"not_a_number\": %llu, \"out_of_range\": %llu, "
        "\"flagged_invalid\": %llu, \"wrong_size\": %llu}}\n",
        static_cast<unsigned long long>(c.not_a_number),
        static_cast<unsigned long long>(c.out_of_range),
        static_cast<unsigned long long>(c.flagged_invalid),
        static_cast<unsigned long long>(c.wrong_size));
    return 0;
  } catch (const std::exception& e) {
    std::fprintf(stderr, "modbus_nav_read: %s\n", e.what());
    return 2;
  }
}
