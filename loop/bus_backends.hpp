#pragma once
// Bus backends of `radar-emu run`, chosen on the command line (setup only): the CAN bus the radar
// talks on (the software loopback, SocketCAN, or a gs_usb adapter through libusb), where the
// ownship state comes from (CANaerospace on that bus, or a Modbus navigation register map), and
// an optional Modbus server for the detection table. docs/icd/ documents every format.

#include <cstdint>
#include <memory>
#include <string>
#include <string_view>
#include <vector>

#include "io/can_frame.hpp"
#include "io/modbus.hpp"

namespace radar_emu::loop {

/// `--can` value: "sim" | "socketcan:IFACE[,fd][,bitrate=N][,dbitrate=N]" |
/// "gsusb[:SERIAL][,fd][,bitrate=N][,dbitrate=N]".
struct CanSpec {
  enum class Kind : std::uint8_t { kSim, kSocketCan, kGsUsb };
  Kind kind = Kind::kSim;
  std::string interface_name;      ///< SocketCAN interface, e.g. "can0"
  std::string serial;              ///< gs_usb: USB serial number to pick ("" = the first adapter)
  bool fd = false;                 ///< open the interface in CAN FD mode (and send FD lists)
  std::uint32_t bitrate_bps = 0;   ///< nominal bit rate to configure (0 = leave as it is)
  std::uint32_t dbitrate_bps = 0;  ///< CAN FD data-phase bit rate (0 = backend default)
  std::string text;                ///< the spec as given, for reports
};

/// Parses a `--can` value. Throws std::invalid_argument "--can: ..." naming what is wrong.
[[nodiscard]] CanSpec parse_can_spec(std::string_view spec);

/// Opens a hardware CAN backend (not kSim). `timestamp_offset_ns` maps the backend's
/// CLOCK_REALTIME stamps onto the run's bus clock. Warnings (bit rate not set for lack of
/// privileges, ...) are appended to `warnings`. Throws std::runtime_error with the backend's
/// one-line reason (no AF_CAN, no such interface, no adapter, impossible bit rate).
[[nodiscard]] std::unique_ptr<io::CanEndpoint> open_can(const CanSpec& spec,
                                                        std::int64_t timestamp_offset_ns,
                                                        std::vector<std::string>& warnings);

/// Counters and state of a hardware CAN endpoint opened by open_can(), as JSON text for
/// report.json ("{}" for other endpoints).
[[nodiscard]] std::string can_backend_report_json(const io::CanEndpoint& endpoint);

// ---- Modbus status for stderr and report.json (docs/icd/modbus.md, "Lost sources" and
// "Serving hostile clients"): the keys live here, in one place.

/// The line printed on stderr when the navigation source `endpoint` becomes unreachable, is
/// lost or answers again (NavPoller's on_link). `error`: the client's last error text.
[[nodiscard]] std::string nav_link_message(const std::string& endpoint,
                                           const io::modbus::NavLinkEvent& event,
                                           const std::string& error, double retry_max_s);

/// report.json "nav_modbus" "link": the source's state, its outages and retries, and the
/// frames the loop ran while it was not answering. JSON text.
[[nodiscard]] std::string nav_link_report_json(const io::modbus::NavPollerCounters& poller,
                                               io::modbus::NavLinkState state,
                                               const io::modbus::ModbusClientCounters& client,
                                               const std::string& last_error, double retry_max_s,
                                               std::uint64_t frames_source_down);

/// report.json "modbus_server": every counter of the detection-table server. JSON text.
[[nodiscard]] std::string modbus_server_report_json(const std::string& address,
                                                    const io::modbus::ModbusServerCounters& c);

/// `--modbus-server` value "HOST:PORT", ":PORT" or "PORT" (bind to 127.0.0.1 unless a host is
/// given), or "rtu:DEV:BAUD": the endpoint string io::modbus understands. Throws
/// std::invalid_argument "--modbus-server: ...".
[[nodiscard]] std::string modbus_server_endpoint(std::string_view spec);

}  // namespace radar_emu::loop
