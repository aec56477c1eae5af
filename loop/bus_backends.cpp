#include "loop/bus_backends.hpp"

#include <charconv>
#include <cstdio>
#include <nlohmann/json.hpp>
#include <stdexcept>

#include "io/gs_usb.hpp"
#include "io/socketcan.hpp"

namespace radar_emu::loop {

namespace {

std::uint32_t parse_rate(std::string_view key, std::string_view value) {
  std::uint64_t v = 0;
  const auto [end, ec] = std::from_chars(value.data(), value.data() + value.size(), v);
  if (ec != std::errc{} || end != value.data() + value.size() || v == 0 || v > 20'000'000) {
    throw std::invalid_argument("--can: " + std::string(key) + "=" + std::string(value) +
                                ": expected a bit rate in bit/s (1 .. 20000000)");
  }
  return static_cast<std::uint32_t>(v);
}

nlohmann::ordered_json errors_json(const io::CanErrorCounters& e, io::CanBusState state) {
  return {{"bus_state", std::string(io::to_string(state))},
          {"error_frames", e.error_frames},
          {"bus_off", e.bus_off},
          {"error_passive", e.error_passive},
          {"error_warning", e.error_warning},
          {"restarted", e.restarted},
          {"lost_arbitration", e.lost_arbitration},
          {"protocol_errors", e.protocol_errors},
          {"transceiver_errors", e.transceiver_errors},
          {"no_ack", e.no_ack},
          {"rx_overflows", e.rx_overflows},
          {"tx_overflows", e.tx_overflows}};
}

}  // namespace

CanSpec parse_can_spec(std::string_view spec) {
  CanSpec c;
  c.text = std::string(spec);
  // Backend and its argument, then ",option" items.
  const std::size_t comma = spec.find(',');
  const std::string_view head = spec.substr(0, comma);
  std::string_view options = comma == std::string_view::npos ? "" : spec.substr(comma + 1);
  const std::size_t colon = head.find(':');
  const std::string_view kind = head.substr(0, colon);
  const std::string_view arg = colon == std::string_view::npos ? "" : head.substr(colon + 1);
  if (kind == "sim") {
    c.kind = CanSpec::Kind::kSim;
    if (colon != std::string_view::npos)
      throw std::invalid_argument("--can: 'sim' takes no argument");
  } else if (kind == "socketcan") {
    c.kind = CanSpec::Kind::kSocketCan;
    if (arg.empty() || arg.size() > 15) {
      throw std::invalid_argument(
          "--can: socketcan needs an interface name of 1-15 characters, e.g. socketcan:can0");
    }
    c.interface_name = std::string(arg);
  } else if (kind == "gsusb") {
    c.kind = CanSpec::Kind::kGsUsb;
    c.serial = std::string(arg);
  } else {
    throw std::invalid_argument("--can: unknown backend '" + std::string(kind) +
                                "' (sim, socketcan:IFACE, gsusb[:SERIAL])");
  }
  while (!options.empty()) {
    const std::size_t next = options.find(',');
    const std::string_view item = options.substr(0, next);
    options = next == std::string_view::npos ? "" : options.substr(next + 1);
    const std::size_t eq = item.find('=');
    const std::string_view key = item.substr(0, eq);
    const std::string_view value = eq == std::string_view::npos ? "" : item.substr(eq + 1);
    if (key == "fd" && eq == std::string_view::npos) {
      c.fd = true;
    } else if (key == "bitrate" && c.kind != CanSpec::Kind::kSim) {
      c.bitrate_bps = parse_rate(key, value);
    } else if (key == "dbitrate" && c.kind != CanSpec::Kind::kSim) {
      c.dbitrate_bps = parse_rate(key, value);
    } else {
      throw std::invalid_argument("--can: unknown option '" + std::string(item) +
                                  "' (fd, bitrate=N, dbitrate=N; bit rates not with sim)");
    }
  }
  if (c.dbitrate_bps != 0 && !c.fd)
    throw std::invalid_argument("--can: dbitrate needs fd");
  return c;
}

std::unique_ptr<io::CanEndpoint> open_can(const CanSpec& spec, std::int64_t timestamp_offset_ns,
                                          std::vector<std::string>& warnings) {
  switch (spec.kind) {
    case CanSpec::Kind::kSim:
      throw std::logic_error("open_can: the software bus is not opened here");
    case CanSpec::Kind::kSocketCan: {
      if (spec.bitrate_bps != 0) {
        const std::string w = io::configure_socketcan(spec.interface_name, spec.bitrate_bps,
                                                      spec.dbitrate_bps, /*restart_ms=*/100);
        if (!w.empty())
          warnings.push_back(w);
      }
      io::SocketCanOptions o;
      o.fd = spec.fd;
      o.timestamp_offset_ns = timestamp_offset_ns;
      return std::make_unique<io::SocketCanEndpoint>(spec.interface_name, o);
    }
    case CanSpec::Kind::kGsUsb: {
      io::GsUsbOptions o;
      if (spec.bitrate_bps != 0)
        o.bitrate_bps = spec.bitrate_bps;
      o.fd = spec.fd;
      if (spec.dbitrate_bps != 0)
        o.dbitrate_bps = spec.dbitrate_bps;
      o.timestamp_offset_ns = timestamp_offset_ns;
      try {
        return io::GsUsbEndpoint::open(spec.serial, o);
      } catch (const std::invalid_argument& e) {
        throw std::runtime_error(std::string("gsusb: ") + e.what());
      }
    }
  }
  throw std::logic_error("open_can: unknown backend");
}

std::string can_backend_report_json(const io::CanEndpoint& endpoint) {
  nlohmann::ordered_json j = nlohmann::ordered_json::object();
  if (const auto* s = dynamic_cast<const io::SocketCanEndpoint*>(&endpoint)) {
    const io::SocketCanStats& st = s->stats();
    j = {{"backend", "socketcan"},
         {"frames_sent", st.frames_sent},
         {"frames_received", st.frames_received},
         {"tx_queue_full", st.tx_queue_full},
         {"tx_rejected", st.tx_rejected},
         {"tx_errors", st.tx_errors},
         {"rx_malformed", st.rx_malformed},
         {"rx_socket_drops", st.rx_socket_drops},
         {"errors", errors_json(s->error_counters(), s->bus_state())}};
  } else if (const auto* g = dynamic_cast<const io::GsUsbEndpoint*>(&endpoint)) {
    const io::GsUsbStats& st = g->stats();
    j = {{"backend", "gsusb"},
         {"frames_sent", st.frames_sent},
         {"frames_received", st.frames_received},
         {"echoes", st.echoes},
         {"unknown_echoes", st.unknown_echoes},
         {"tx_pool_exhausted", st.tx_pool_exhausted},
         {"tx_queue_full", st.tx_queue_full},
         {"tx_failed", st.tx_failed},
         {"rx_truncated", st.rx_truncated},
         {"rx_malformed", st.rx_malformed},
         {"errors", errors_json(g->error_counters(), g->bus_state())}};
  }
  return j.dump();
}

std::string nav_link_message(const std::string& endpoint, const io::modbus::NavLinkEvent& e,
                             const std::string& error, double retry_max_s) {
  using Kind = io::modbus::NavLinkEvent::Kind;
  char buf[512];
  const std::string why = error.empty() ? std::string() : " (" + error + ")";
  switch (e.kind) {
    case Kind::kUnreachable:
      std::snprintf(buf, sizeof buf,
                    "radar-emu: warning: navigation source %s unreachable%s: no valid ownship "
                    "state until it answers; retrying (back-off up to %.1f s)",
                    endpoint.c_str(), why.c_str(), retry_max_s);
      break;
    case Kind::kLost:
      std::snprintf(buf, sizeof buf,
                    "radar-emu: warning: navigation source %s lost%s: frames go invalid once "
                    "the state is older than state_timeout_s; retrying (back-off up to %.1f s)",
                    endpoint.c_str(), why.c_str(), retry_max_s);
      break;
    case Kind::kRecovered:
      std::snprintf(buf, sizeof buf,
                    "radar-emu: navigation source %s answers again after %.2f s (%llu failed "
                    "polls)",
                    endpoint.c_str(), e.outage_s, static_cast<unsigned long long>(e.failed_polls));
      break;
  }
  return buf;
}

std::string nav_link_report_json(const io::modbus::NavPollerCounters& p,
                                 io::modbus::NavLinkState state,
                                 const io::modbus::ModbusClientCounters& c,
                                 const std::string& last_error, double retry_max_s,
                                 std::uint64_t frames_source_down) {
  using io::modbus::NavLinkState;
  const char* state_name = !p.ever_up                   ? "never_answered"
                           : state == NavLinkState::kUp ? "up"
                                                        : "down";
  const nlohmann::ordered_json j = {{"state", state_name},
                                    {"first_read_s", p.first_read_s},
                                    {"outages", p.outages},
                                    {"outage_s_total", p.outage_s_total},
                                    {"longest_outage_s", p.longest_outage_s},
                                    {"frames_source_down", frames_source_down},
                                    {"connect_failures", c.connect_failures},
                                    {"reconnects", c.reconnects},
                                    {"retry_max_interval_s", retry_max_s},
                                    {"last_error", last_error}};
  return j.dump();
}

std::string modbus_server_report_json(const std::string& address,
                                      const io::modbus::ModbusServerCounters& c) {
  const nlohmann::ordered_json j = {{"address", address},
                                    {"requests", c.requests},
                                    {"replies", c.replies},
                                    {"reads", c.reads},
                                    {"refused_writes", c.refused_writes},
                                    {"unknown_function", c.unknown_function},
                                    {"bad_length", c.bad_length},
                                    {"illegal_quantity", c.illegal_quantity},
                                    {"illegal_address", c.illegal_address},
                                    {"malformed_mbap", c.malformed_mbap},
                                    {"incomplete", c.incomplete},
                                    {"idle_closed", c.idle_closed},
                                    {"send_failures", c.send_failures},
                                    {"errors", c.errors},
                                    {"clients_accepted", c.clients_accepted},
                                    {"clients_refused", c.clients_refused},
                                    {"clients_evicted", c.clients_evicted},
                                    {"clients_closed", c.clients_closed},
                                    {"publishes", c.publishes}};
  return j.dump();
}

std::string modbus_server_endpoint(std::string_view spec) {
  if (spec.empty())
    throw std::invalid_argument("--modbus-server: expected HOST:PORT, :PORT or PORT");
  if (spec.starts_with("rtu:") || spec.starts_with("tcp:"))
    return std::string(spec);
  const std::size_t colon = spec.rfind(':');
  const std::string_view host = colon == std::string_view::npos ? "" : spec.substr(0, colon);
  const std::string_view port = colon == std::string_view::npos ? spec : spec.substr(colon + 1);
  unsigned value = 0;
  const auto [end, ec] = std::from_chars(port.data(), port.data() + port.size(), value);
  if (port.empty() || ec != std::errc{} || end != port.data() + port.size() || value > 65535) {
    throw std::invalid_argument("--modbus-server: '" + std::string(spec) +
                                "': expected HOST:PORT, :PORT or PORT with a port 0-65535");
  }
  // Bind to the loopback interface unless told otherwise: a detection table is no business of
  // the wider network by default.
  return "tcp:" + std::string(host.empty() ? "127.0.0.1" : host) + ":" + std::string(port);
}

}  // namespace radar_emu::loop
