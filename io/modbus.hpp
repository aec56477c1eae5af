#pragma once
// Modbus TCP and RTU backends on libmodbus (Debian 12: 3.1.6): a client that is a RegisterBank,
// a background poller that turns a navigation device's registers into the OwnshipState the
// frame path reads without blocking, and a server that publishes a register table (the
// detection table, or the navigation map of a test server). Register maps: io/modbus_map.hpp,
// docs/icd/modbus.md. Protocol: Modbus application protocol v1.1b3; Modbus messaging on TCP/IP
// implementation guide v1.0b; Modbus over serial line v1.02 (RTU).
//
// libmodbus stays behind these classes (linked PRIVATE to radar_emu_io); its float setters are
// never used (broken in 3.1.6, see modbus_map.hpp).

#include <atomic>
#include <condition_variable>
#include <cstddef>
#include <cstdint>
#include <functional>
#include <memory>
#include <mutex>
#include <span>
#include <string>
#include <string_view>
#include <thread>
#include <vector>

#include "io/canaerospace.hpp"
#include "io/modbus_map.hpp"
#include "io/register_bank.hpp"
#include "io/triple_buffer.hpp"

namespace radar_emu::io::modbus {

// ---- Endpoints ------------------------------------------------------------------------------

struct ModbusEndpoint {
  enum class Kind : std::uint8_t { kTcp = 0, kRtu };
  Kind kind = Kind::kTcp;
  std::string host;          ///< TCP: IPv4/IPv6 address or host name
  std::uint16_t port = 502;  ///< TCP port; 0 = an ephemeral port (servers only)
  std::string device;        ///< RTU: serial device, e.g. /dev/ttyUSB0
  int baud = 19200;          ///< RTU bit rate [bit/s]
  char parity = 'N';         ///< RTU: 'N', 'E' or 'O'
  int data_bits = 8;         ///< RTU: 7 or 8
  int stop_bits = 1;         ///< RTU: 1 or 2
};

/// Parses "tcp:HOST:PORT", "HOST:PORT" (TCP; IPv6 as "[::1]:502"), or
/// "rtu:DEVICE:BAUD[:8N1]" (data bits 7|8, parity N|E|O, stop bits 1|2). Throws
/// std::invalid_argument with a one-line message naming what was expected (setup).
[[nodiscard]] ModbusEndpoint parse_modbus_endpoint(std::string_view spec);
/// "tcp:HOST:PORT" or "rtu:DEVICE:BAUD:8N1".
[[nodiscard]] std::string to_string(const ModbusEndpoint& endpoint);

// ---- Client ---------------------------------------------------------------------------------

struct ModbusClientConfig {
  std::string endpoint{};             ///< see parse_modbus_endpoint()
  int unit_id = 1;                    ///< unit identifier (TCP 0..255) / slave address (RTU 1..247)
  double response_timeout_s = 0.1;    ///< per request, and per TCP connection attempt
  double reconnect_interval_s = 0.2;  ///< least time between connection attempts while down
  int timeouts_before_reconnect = 3;  ///< consecutive timeouts after which a TCP link is dropped
};

struct ModbusClientCounters {
  std::uint64_t requests = 0;          ///< read/write transactions attempted
  std::uint64_t ok = 0;                ///< answered normally
  std::uint64_t timeouts = 0;          ///< no (complete) answer within response_timeout_s
  std::uint64_t disconnected = 0;      ///< transactions failed because the link was down or broke
  std::uint64_t exceptions = 0;        ///< Modbus exception responses (illegal address, ...)
  std::uint64_t errors = 0;            ///< malformed answers (CRC, wrong length, wrong unit)
  std::uint64_t connect_failures = 0;  ///< connection attempts that failed
  std::uint64_t reconnects = 0;        ///< successful connections after the first one
};

/// A Modbus client as a RegisterBank. Every call blocks for up to the response timeout: drive
/// it from a non-real-time thread (NavPoller), one thread at a time. The link is opened in the
/// constructor (a failure there is not fatal: it is counted and retried) and re-opened by
/// itself after a failure, at most once per reconnect_interval_s.
class ModbusClient final : public RegisterBank {
 public:
  /// Throws std::invalid_argument (bad endpoint or settings) or std::runtime_error (libmodbus
  /// refused the context), one line each.
  explicit ModbusClient(const ModbusClientConfig& config);
  ~ModbusClient() override;
  ModbusClient(const ModbusClient&) = delete;
  ModbusClient& operator=(const ModbusClient&) = delete;

  /// Function 0x03. kTimeout, kDisconnected (link down or lost; retried on a later call),
  /// kIllegalAddress (exception 2), kError (other exception or malformed answer).
  [[nodiscard]] RegisterStatus read_holding(std::uint16_t address,
                                            std::span<std::uint16_t> out) noexcept override;
  /// Function 0x10 (write multiple registers).
  [[nodiscard]] RegisterStatus write_holding(
      std::uint16_t address, std::span<const std::uint16_t> values) noexcept override;

  [[nodiscard]] bool connected() const noexcept { return connected_.load(); }
  /// Thread-safe snapshot.
  [[nodiscard]] ModbusClientCounters counters() const noexcept;
  [[nodiscard]] const ModbusEndpoint& endpoint() const noexcept { return endpoint_; }

 private:
  struct Impl;
  bool ensure_connected() noexcept;
  // One request of `count` registers (1..max) at `address`: bounds, connection, the libmodbus
  // call (returns registers transferred or -1 with errno), counters and failure classification.
  template <class Call>
  RegisterStatus transact(std::uint16_t address, std::size_t count, std::size_t max,
                          Call call) noexcept;
  void drop_link() noexcept;
  RegisterStatus classify_failure(int error) noexcept;

  ModbusEndpoint endpoint_;
  ModbusClientConfig config_;
  std::unique_ptr<Impl> impl_;
  std::atomic<bool> connected_{false};
  bool ever_connected_ = false;
  bool link_lost_ = false;
  int consecutive_timeouts_ = 0;
  std::int64_t next_connect_ns_ = 0;
  struct AtomicCounters {
    std::atomic<std::uint64_t> requests{0}, ok{0}, timeouts{0}, disconnected{0}, exceptions{0},
        errors{0}, connect_failures{0}, reconnects{0};
  } counters_;
};

// ---- Navigation poller ----------------------------------------------------------------------

struct NavPollerConfig {
  NavMapConfig map{};
  double period_s = 0.02;  ///< poll period (absolute deadlines; missed periods are skipped)
  /// Time stamp given to decoded fields (OwnshipState::updated_ns). It must be the clock the
  /// frame path compares against; empty = CLOCK_MONOTONIC [ns].
  std::function<std::int64_t()> clock_ns{};
};

struct NavPollerCounters {
  std::uint64_t polls = 0;           ///< read attempts
  std::uint64_t reads_ok = 0;        ///< images read
  std::uint64_t timeouts = 0;        ///< RegisterStatus::kTimeout
  std::uint64_t disconnected = 0;    ///< RegisterStatus::kDisconnected
  std::uint64_t read_errors = 0;     ///< kIllegalAddress or kError
  std::uint64_t recoveries = 0;      ///< first good read after failed ones
  std::uint64_t missed_periods = 0;  ///< poll periods skipped because a read overran
  std::uint64_t published = 0;       ///< states handed to the frame path
  NavDecoderCounters decoder{};      ///< samples: stale, rejected by reason, ...
};

/// Polls a RegisterBank from its own thread every period_s, decodes the navigation map with
/// NavDecoder and hands the latest OwnshipState to the frame path through a wait-free triple
/// buffer. The bank is used only from the poller's thread while it runs, and must outlive the
/// poller.
class NavPoller {
 public:
  /// Starts the thread. Throws std::invalid_argument on a bad period or a map longer than one
  /// read (kModbusMaxReadRegisters).
  NavPoller(RegisterBank& bank, NavPollerConfig config);
  ~NavPoller();
  NavPoller(const NavPoller&) = delete;
  NavPoller& operator=(const NavPoller&) = delete;

  /// Copies the newest published state into `out` (always; the empty state before the first);
  /// returns true if it is newer than the one the previous call returned. One consumer thread.
  /// Real-time safe (wait-free, no allocation).
  bool latest(canas::OwnshipState& out) noexcept;
  /// Thread-safe snapshot. Real-time safe.
  [[nodiscard]] NavPollerCounters counters() const noexcept;
  /// Stops and joins the thread (idempotent; also done by the destructor).
  void stop() noexcept;

 private:
  void run() noexcept;

  RegisterBank& bank_;
  NavPollerConfig config_;
  NavDecoder decoder_;
  TripleBuffer<canas::OwnshipState> states_;
  std::atomic<bool> stop_{false};
  std::mutex wake_mutex_;  // only for the stop() wake-up of the poller's sleep
  std::condition_variable wake_;
  struct AtomicCounters {
    std::atomic<std::uint64_t> polls{0}, reads_ok{0}, timeouts{0}, disconnected{0}, read_errors{0},
        recoveries{0}, missed_periods{0}, published{0};
    std::atomic<std::uint64_t> samples{0}, new_samples{0}, fields_accepted{0}, stale{0},
        wrong_size{0}, not_a_number{0}, out_of_range{0}, flagged_invalid{0}, counter_gaps{0};
  } counters_;
  std::thread thread_;
};

// ---- Server ---------------------------------------------------------------------------------

struct ModbusServerConfig {
  /// tcp:HOST:PORT / HOST:PORT (PORT 0 = ephemeral, see port()) or rtu:DEVICE:BAUD[:8N1].
  std::string endpoint = "tcp:127.0.0.1:502";
  std::uint16_t start_address = 0;  ///< protocol address of the first register
  std::size_t register_count = 0;   ///< 1 .. 65536 - start_address
  int unit_id = 1;                  ///< RTU: the slave address answered; TCP answers any unit
  int max_clients = 8;              ///< TCP connections served at once; more are closed
};

struct ModbusServerCounters {
  std::uint64_t requests = 0;            ///< requests received
  std::uint64_t replies = 0;             ///< answers sent (normal or exception)
  std::uint64_t refused_writes = 0;      ///< write requests answered with exception 1
  std::uint64_t errors = 0;              ///< malformed requests, receive or send failures
  std::uint64_t clients_accepted = 0;    ///< TCP connections accepted
  std::uint64_t clients_refused = 0;     ///< TCP connections closed at once (max_clients)
  std::uint64_t publishes = 0;           ///< images published
  std::uint64_t publishes_rejected = 0;  ///< publish() with the wrong image size
};

/// Serves `register_count` holding registers (function 0x03) from a background thread. The
/// table is read-only for clients: write functions (0x05, 0x06, 0x0F, 0x10, 0x16, 0x17) get
/// exception 1 (illegal function); reads outside it get exception 2 (libmodbus). The producer
/// (the frame path, or a scripted player through the RegisterBank interface) hands over
/// complete images through a wait-free triple buffer: a request is always answered from one
/// complete image, the newest published before it arrived.
class ModbusServer final : public RegisterBank {
 public:
  /// Listens (TCP) or opens the serial device (RTU) before it returns, then starts the thread.
  /// Throws std::invalid_argument (settings) or std::runtime_error ("modbus server: cannot
  /// listen on 127.0.0.1:502: Permission denied"), one line each. Registers start at zero.
  explicit ModbusServer(const ModbusServerConfig& config);
  ~ModbusServer() override;
  ModbusServer(const ModbusServer&) = delete;
  ModbusServer& operator=(const ModbusServer&) = delete;

  /// TCP: the bound port (the ephemeral one when configured with 0). RTU: 0.
  [[nodiscard]] std::uint16_t port() const noexcept { return port_; }
  /// "HOST:PORT" (bound port) or the serial device.
  [[nodiscard]] const std::string& address() const noexcept { return address_; }

  /// Producer: publishes a complete image (register_count registers). Returns false (counted)
  /// on a wrong size. Real-time safe: two copies of the image, one atomic exchange.
  bool publish(std::span<const std::uint16_t> image) noexcept;
  /// Producer (same thread as publish): read from / write into the image being served; a
  /// write publishes the updated image. Real-time safe; never blocks.
  [[nodiscard]] RegisterStatus read_holding(std::uint16_t address,
                                            std::span<std::uint16_t> out) noexcept override;
  [[nodiscard]] RegisterStatus write_holding(
      std::uint16_t address, std::span<const std::uint16_t> values) noexcept override;

  /// Thread-safe snapshot. Real-time safe.
  [[nodiscard]] ModbusServerCounters counters() const noexcept;
  /// Stops the thread and closes every connection (idempotent; also done by the destructor).
  void stop() noexcept;

 private:
  struct Impl;
  void run() noexcept;
  void serve_request(int length) noexcept;

  ModbusServerConfig config_;
  ModbusEndpoint endpoint_;
  std::unique_ptr<Impl> impl_;
  std::uint16_t port_ = 0;
  std::string address_;
  std::vector<std::uint16_t> working_;  // producer's image
  TripleBuffer<std::vector<std::uint16_t>> images_;
  struct AtomicCounters {
    std::atomic<std::uint64_t> requests{0}, replies{0}, refused_writes{0}, errors{0},
        clients_accepted{0}, clients_refused{0}, publishes{0}, publishes_rejected{0};
  } counters_;
  std::thread thread_;
};

}  // namespace radar_emu::io::modbus
