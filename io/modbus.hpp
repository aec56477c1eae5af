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
  /// Back-off: after each failed connection attempt the interval doubles, up to this ceiling
  /// (the retry period of an unreachable source); a success resets it. A link that breaks is
  /// retried at once, then backs off the same way.
  double reconnect_max_interval_s = 2.0;
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
  /// errno of the last failed connection attempt or transaction (0: none yet). Thread-safe.
  [[nodiscard]] int last_error() const noexcept { return last_error_.load(); }
  /// The last error as one line ("Connection refused", "Connection timed out", "Modbus
  /// exception 2 (illegal data address)", ...; "" when none). Not real-time safe.
  [[nodiscard]] std::string last_error_text() const;
  /// Current wait between connection attempts while down [s] (see reconnect_max_interval_s).
  [[nodiscard]] double reconnect_interval_s() const noexcept {
    return static_cast<double>(backoff_ns_.load()) * 1e-9;
  }
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
  std::atomic<int> last_error_{0};
  std::atomic<std::int64_t> backoff_ns_{0};
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

/// A change of the navigation source's state, as the poller saw it (NavPollerConfig::on_link).
struct NavLinkEvent {
  enum class Kind : std::uint8_t {
    kUnreachable = 0,  ///< the first read(s) failed: the source never answered yet
    kLost,             ///< reads failed after the source had answered
    kRecovered,        ///< a read succeeded after failed ones
  };
  Kind kind = Kind::kUnreachable;
  RegisterStatus status = RegisterStatus::kOk;  ///< of the failed read (kUnreachable, kLost)
  double outage_s = 0.0;                        ///< kRecovered: time from the first failed read [s]
  std::uint64_t failed_polls = 0;               ///< kRecovered: failed reads in the outage
};

struct NavPollerConfig {
  NavMapConfig map{};
  double period_s = 0.02;  ///< poll period (absolute deadlines; missed periods are skipped)
  /// Time stamp given to decoded fields (OwnshipState::updated_ns). It must be the clock the
  /// frame path compares against; empty = CLOCK_MONOTONIC [ns].
  std::function<std::int64_t()> clock_ns{};
  /// Called from the poller's thread (never from the frame path) when the source becomes
  /// unreachable, is lost or recovers: where a program reports it (stderr, a log). Optional.
  std::function<void(const NavLinkEvent&)> on_link{};
};

/// State of the navigation source as the poller sees it.
enum class NavLinkState : std::uint8_t {
  kNotYet = 0,  ///< no read finished yet
  kUp,          ///< answering (reads succeed; fewer than kFailedReadsForDown failed since)
  kDown,        ///< not answering: refused or broken connection, or kFailedReadsForDown reads
                ///< in a row timed out or got exceptions; until the next good read
};
/// Failed reads in a row (time-outs, exceptions) that make a source down; a refused or broken
/// connection does at once. The outage is dated from the first of them.
inline constexpr std::uint64_t kFailedReadsForDown = 3;

struct NavPollerCounters {
  std::uint64_t polls = 0;           ///< read attempts
  std::uint64_t reads_ok = 0;        ///< images read
  std::uint64_t timeouts = 0;        ///< RegisterStatus::kTimeout
  std::uint64_t disconnected = 0;    ///< RegisterStatus::kDisconnected
  std::uint64_t read_errors = 0;     ///< kIllegalAddress or kError
  std::uint64_t recoveries = 0;      ///< first good read after failed ones
  std::uint64_t missed_periods = 0;  ///< poll periods skipped because a read overran
  std::uint64_t published = 0;       ///< states handed to the frame path
  std::uint64_t outages = 0;         ///< times the source went down after having answered
  bool ever_up = false;              ///< the source answered at least once
  double first_read_s = -1.0;        ///< time from start to the first good read [s]; -1: none
  double outage_s_total = 0.0;       ///< time spent down after having answered [s] (so far)
  double longest_outage_s = 0.0;     ///< longest such outage [s] (the current one included)
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
  /// The source's state after the last read. Real-time safe (one atomic load).
  [[nodiscard]] NavLinkState link_state() const noexcept { return link_.load(); }
  /// Stops and joins the thread (idempotent; also done by the destructor).
  void stop() noexcept;

 private:
  void run() noexcept;
  void track_link(RegisterStatus status, std::int64_t now_ns) noexcept;

  RegisterBank& bank_;
  NavPollerConfig config_;
  NavDecoder decoder_;
  TripleBuffer<canas::OwnshipState> states_;
  std::atomic<bool> stop_{false};
  std::mutex wake_mutex_;  // only for the stop() wake-up of the poller's sleep
  std::condition_variable wake_;
  struct AtomicCounters {
    std::atomic<std::uint64_t> polls{0}, reads_ok{0}, timeouts{0}, disconnected{0}, read_errors{0},
        recoveries{0}, missed_periods{0}, published{0}, outages{0};
    std::atomic<std::uint64_t> samples{0}, new_samples{0}, fields_accepted{0}, stale{0},
        wrong_size{0}, not_a_number{0}, out_of_range{0}, flagged_invalid{0}, counter_gaps{0};
    // Link timing [ns, CLOCK_MONOTONIC]: start, first good read (0: none), start of the current
    // outage after having been up (0: none), closed outages' total and longest.
    std::atomic<std::int64_t> start_ns{0}, first_ok_ns{0}, down_since_ns{0}, outage_total_ns{0},
        longest_outage_ns{0};
  } counters_;
  std::atomic<NavLinkState> link_{NavLinkState::kNotYet};
  std::int64_t failing_since_ns_ = 0;  // poller thread only: first failed read of this run
  std::uint64_t failed_polls_ = 0;     // poller thread only: failed reads in this run
  std::thread thread_;
};

// ---- Server ---------------------------------------------------------------------------------

struct ModbusServerConfig {
  /// tcp:HOST:PORT / HOST:PORT (PORT 0 = ephemeral, see port()) or rtu:DEVICE:BAUD[:8N1].
  std::string endpoint = "tcp:127.0.0.1:502";
  std::uint16_t start_address = 0;  ///< protocol address of the first register
  std::size_t register_count = 0;   ///< 1 .. 65536 - start_address
  int unit_id = 1;                  ///< RTU: the slave address answered; TCP answers any unit
  int max_clients = 32;             ///< TCP connections served at once (1..1024)
  /// TCP: a connection that sent part of a request and nothing more for this long is closed
  /// (`incomplete`): a stalled or half-open client cannot hold a slot or the server.
  double request_timeout_s = 1.0;
  /// TCP: a connection silent for this long is closed (`idle_closed`).
  double idle_timeout_s = 60.0;
  /// TCP: with every slot taken, a new connection takes the place of the connection silent for
  /// longest if that one has been silent for at least this long (`clients_evicted`); else the
  /// new one is closed (`clients_refused`). Clients that poll keep their slots.
  double evict_idle_s = 1.0;
};

/// What the server saw. TCP requests are framed by their MBAP header (Modbus messaging on
/// TCP/IP implementation guide v1.0b, sec. 3.1.3): transaction id, protocol id 0, length of
/// what follows (unit id + PDU: 2..254 bytes), unit id. Every request lands in exactly one of
/// replies (read answered, or an exception), malformed_mbap, send_failures.
struct ModbusServerCounters {
  std::uint64_t requests = 0;        ///< complete requests received (and RTU frames)
  std::uint64_t replies = 0;         ///< answers sent (normal or exception)
  std::uint64_t reads = 0;           ///< function 0x03 answered with registers
  std::uint64_t refused_writes = 0;  ///< write requests answered with exception 1
  /// TCP: function codes the server does not implement (anything but 0x03 and the writes),
  /// answered with exception 1 (illegal function).
  std::uint64_t unknown_function = 0;
  /// TCP: a PDU whose length does not fit its function (0x03 takes 5 bytes), answered with
  /// exception 3 (illegal data value).
  std::uint64_t bad_length = 0;
  std::uint64_t illegal_quantity = 0;  ///< TCP: 0x03 quantity 0 or > 125: exception 3
  std::uint64_t illegal_address = 0;   ///< TCP: 0x03 outside the table: exception 2
  /// TCP: MBAP header with a protocol id other than 0 or a length outside 2..254: the stream
  /// cannot be framed any more; the connection is closed, nothing answered.
  std::uint64_t malformed_mbap = 0;
  std::uint64_t incomplete = 0;     ///< TCP: connections closed with a request unfinished
                                    ///< after request_timeout_s (stalled, half-open)
  std::uint64_t idle_closed = 0;    ///< TCP: connections closed after idle_timeout_s of silence
  std::uint64_t send_failures = 0;  ///< TCP: answers the peer would not take at once (it does
                                    ///< not read): connection closed
  std::uint64_t errors = 0;         ///< other failures (RTU garbage or CRC errors, socket errors)
  std::uint64_t clients_accepted = 0;    ///< TCP connections accepted
  std::uint64_t clients_refused = 0;     ///< TCP connections closed at once (all slots busy)
  std::uint64_t clients_evicted = 0;     ///< idle TCP connections closed for a new one
  std::uint64_t clients_closed = 0;      ///< TCP connections the peer closed (or reset)
  std::uint64_t publishes = 0;           ///< images published
  std::uint64_t publishes_rejected = 0;  ///< publish() with the wrong image size
};

/// Serves `register_count` holding registers (function 0x03) from a background thread. The
/// table is read-only for clients: write functions (0x05, 0x06, 0x0F, 0x10, 0x16, 0x17) get
/// exception 1 (illegal function); reads outside it get exception 2. The producer (the frame
/// path, or a scripted player through the RegisterBank interface) hands over complete images
/// through a wait-free triple buffer: a request is always answered from one complete image, the
/// newest published before it arrived, and nothing a client does can block the producer.
///
/// TCP is served without libmodbus, on non-blocking sockets from one poll() loop: no client can
/// hold the thread (a partial request waits in its connection's buffer; an answer the peer does
/// not take at once closes that connection), each connection gets at most a few requests per
/// round (a flooding client cannot starve the others), and malformed MBAP headers, wrong
/// lengths, unknown functions, stalled or half-open connections and connection floods are
/// each answered or closed as documented in ModbusServerCounters, and counted there. RTU is
/// served through libmodbus (one master on a serial line).
class ModbusServer final : public RegisterBank {
 public:
  /// Listens (TCP) or opens the serial device (RTU) before it returns, then starts the thread.
  /// Throws std::invalid_argument (settings) or std::runtime_error ("modbus server: cannot
  /// listen on 127.0.0.1:502: Permission denied"), one line each. Registers start at zero.
  /// Allocates everything it needs here: serving allocates nothing.
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
  struct Connection;
  void run_rtu() noexcept;
  void run_tcp() noexcept;
  void serve_rtu_request(int length) noexcept;
  // TCP: reads what the peer sent; answers up to a few complete requests. False: closed.
  bool serve_connection(Connection& c, bool readable, std::int64_t now_ns) noexcept;
  void answer(Connection& c, const std::uint8_t* adu, std::size_t length) noexcept;
  void accept_clients(std::int64_t now_ns) noexcept;
  void close_connection(Connection& c) noexcept;

  ModbusServerConfig config_;
  ModbusEndpoint endpoint_;
  std::unique_ptr<Impl> impl_;
  std::uint16_t port_ = 0;
  std::string address_;
  std::vector<std::uint16_t> working_;  // producer's image
  TripleBuffer<std::vector<std::uint16_t>> images_;
  struct AtomicCounters {
    std::atomic<std::uint64_t> requests{0}, replies{0}, reads{0}, refused_writes{0},
        unknown_function{0}, bad_length{0}, illegal_quantity{0}, illegal_address{0},
        malformed_mbap{0}, incomplete{0}, idle_closed{0}, send_failures{0}, errors{0},
        clients_accepted{0}, clients_refused{0}, clients_evicted{0}, clients_closed{0},
        publishes{0}, publishes_rejected{0};
  } counters_;
  std::thread thread_;
};

}  // namespace radar_emu::io::modbus
