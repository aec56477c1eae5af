#pragma once
// A small HTTP/1.1 + WebSocket (RFC 6455) server that pushes text messages to browsers: it
// serves one page (GET /) and upgrades GET <ws_path> to a WebSocket, over which it broadcasts
// whatever its `source` hands it. It only pushes: what a client sends is parsed (RFC 6455
// sec. 5.2) and answered where the protocol says so (ping: pong, close: close), its data
// discarded.
//
// Why our own (about 500 lines on POSIX sockets) rather than a library: the server is push-only,
// loopback by default, and has no TLS, so it needs the opening handshake (sec. 4.2, SHA-1 and
// base64), unmasked server frames and the parsing of masked client frames: little protocol.
// Boost.Beast would bring Boost into the build (Debian's 1.74, header-only, minutes more of
// compile on CI's two cores for one source file); libwebsockets brings its own event loop and
// TLS configuration to keep robust. Everything here runs on one thread with non-blocking
// sockets and poll(): no client, however slow or hostile, blocks it or the caller.
//
// Robustness: a client's queued output is bounded (client_buffer_bytes): a message that does
// not fit is skipped for that client and counted; a client that keeps not reading is closed.
// Requests that are malformed, too long, not GET, or bad WebSocket handshakes get a 4xx answer
// and are counted; a client that sends no complete request within request_timeout_s is closed;
// beyond max_clients connections are refused with 503.

#include <array>
#include <atomic>
#include <cstddef>
#include <cstdint>
#include <functional>
#include <memory>
#include <span>
#include <string>
#include <string_view>
#include <thread>

namespace radar_emu::io::ws {

/// SHA-1 of `data` (FIPS 180-4 sec. 6.1), as the WebSocket handshake needs it (RFC 6455
/// sec. 4.2.2). Not for security.
[[nodiscard]] std::array<std::uint8_t, 20> sha1(std::string_view data) noexcept;
/// Base64 (RFC 4648 sec. 4, with padding).
[[nodiscard]] std::string base64(std::span<const std::uint8_t> data);
/// Sec-WebSocket-Accept for a client's Sec-WebSocket-Key: base64(SHA-1(key + the RFC 6455
/// GUID)) (sec. 4.2.2 item 5.4).
[[nodiscard]] std::string accept_key(std::string_view key);

/// Opcodes (RFC 6455 sec. 5.2).
enum class Opcode : std::uint8_t {
  kText = 0x1,
  kBinary = 0x2,
  kClose = 0x8,
  kPing = 0x9,
  kPong = 0xA
};
/// Header of an unmasked, unfragmented (FIN) server frame carrying `payload_bytes` (RFC 6455
/// sec. 5.2: 7-bit length, or 126 + 16-bit, or 127 + 64-bit, network byte order). Writes it to
/// `out`; returns its length, 2, 4 or 10.
std::size_t frame_header(Opcode opcode, std::uint64_t payload_bytes,
                         std::array<std::uint8_t, 10>& out) noexcept;

/// What the server makes of one HTTP request head (the bytes before the blank line that ends
/// it, RFC 9112 sec. 2.1), given its WebSocket endpoint. Pure: the server calls it on every
/// request, the fuzz harness (tests/fuzz/fuzz_websocket.cpp) on arbitrary bytes.
struct Request {
  enum class Kind : std::uint8_t {
    kMalformed,         ///< no "METHOD SP TARGET SP HTTP/1.x" request line: 400
    kMethodNotAllowed,  ///< a method other than GET: 405 (Allow: GET)
    kWrongVersion,      ///< GET ws_path without Sec-WebSocket-Version: 13: 426 (sec. 4.4)
    kBadHandshake,      ///< GET ws_path without Host, Upgrade: websocket, Connection: Upgrade
                        ///< or a valid 16-byte Sec-WebSocket-Key: 400 (sec. 4.2.1)
    kWebSocket,         ///< a valid opening handshake: 101 Switching Protocols
    kPage,              ///< GET / or GET /index.html (query ignored): 200
    kNotFound           ///< GET of any other path: 404
  };
  Kind kind = Kind::kMalformed;
  std::string key;  ///< kWebSocket: the client's Sec-WebSocket-Key (24 base64 characters)
};
/// The HTTP status code of each kind (101, 200, 400, 404, 405 or 426).
[[nodiscard]] int http_status(Request::Kind kind) noexcept;
/// Parses a request head (no trailing "\r\n\r\n"); never throws anything but std::bad_alloc.
[[nodiscard]] Request parse_request(std::string_view head, std::string_view ws_path);

/// One client frame (RFC 6455 sec. 5.2) at the front of the bytes received.
struct ClientFrame {
  enum class Status : std::uint8_t {
    kIncomplete,  ///< more bytes needed; nothing consumed
    kFrame,       ///< a whole frame: `opcode`, `payload` (unmasked), `size` bytes consumed
    kError        ///< a protocol violation: the server closes with `close_code`
  };
  Status status = Status::kIncomplete;
  std::uint8_t opcode = 0;  ///< kFrame: 0x0 (continuation), text, binary, close, ping or pong
  std::size_t size = 0;     ///< kFrame: header + mask + payload bytes
  /// kError: 1002 (protocol error: unmasked, a control frame over 125 bytes, a reserved opcode)
  /// or 1009 (payload over max_payload_bytes, sec. 7.4.1).
  std::uint16_t close_code = 0;
};
/// Parses the frame at the front of `in` (client frames must be masked, sec. 5.3) and writes
/// its unmasked payload (at most max_payload_bytes, and never more than `in` holds) to
/// `payload` (left as is unless kFrame). FIN and RSV bits are not checked (data is discarded).
[[nodiscard]] ClientFrame parse_client_frame(std::span<const std::uint8_t> in,
                                             std::size_t max_payload_bytes, std::string& payload);

struct ServerConfig {
  std::string host = "127.0.0.1";  ///< a numeric address or a name (getaddrinfo)
  std::uint16_t port = 0;          ///< 0: a free one (see Server::address())
  std::string page;                ///< served as text/html for GET / and GET /index.html
  std::string ws_path = "/ws";     ///< the WebSocket endpoint
  std::size_t max_clients = 32;    ///< connections beyond are answered 503 and closed
  /// Output queued per client at most [bytes]; a message that does not fit is skipped for that
  /// client (counted), and a client that misses slow_client_skips_max in a row is closed.
  std::size_t client_buffer_bytes = 1u << 20;
  std::uint32_t slow_client_skips_max = 100;
  double request_timeout_s = 5.0;  ///< a client must send its whole request within this
  std::size_t request_max_bytes = 8192;
  int poll_interval_ms = 40;  ///< how often the server thread asks `source` for a message
  /// Called on the server thread every poll_interval_ms with the WebSocket clients connected:
  /// writes a new message into its first argument and returns true, or returns false when
  /// there is nothing new. The last message is also sent to every client as it connects.
  std::function<bool(std::string&, std::uint64_t)> source;
};

/// What the server did (all of it since it started).
/// How long the server stops taking connections after accept() ran out of descriptors [ms].
inline constexpr int kAcceptBackoffMs = 100;

struct ServerCounters {
  std::uint64_t connections = 0;          ///< TCP connections accepted
  std::uint64_t refused = 0;              ///< over max_clients (503)
  std::uint64_t pages_served = 0;         ///< GET / (200)
  std::uint64_t not_found = 0;            ///< other paths (404)
  std::uint64_t bad_requests = 0;         ///< malformed, too long, not GET, timed out (400/405/408)
  std::uint64_t bad_handshakes = 0;       ///< GET ws_path without a valid RFC 6455 handshake (400)
  std::uint64_t websocket_clients = 0;    ///< handshakes completed
  std::uint64_t messages = 0;             ///< distinct messages taken from `source`
  std::uint64_t frames_queued = 0;        ///< message frames queued to clients (one per client)
  std::uint64_t frames_skipped = 0;       ///< ... skipped: the client's buffer was full
  std::uint64_t slow_clients_closed = 0;  ///< closed after slow_client_skips_max skips in a row
  std::uint64_t clients_closed = 0;       ///< WebSocket clients gone (close frame, EOF, error)
  std::uint64_t clients_now = 0;          ///< WebSocket clients connected now
  /// accept() failed for want of descriptors or memory (EMFILE, ENFILE, ENOBUFS, ENOMEM): the
  /// server stops listening for kAcceptBackoffMs, then tries again (no busy loop meanwhile).
  std::uint64_t accept_failures = 0;
};

class Server {
 public:
  /// Binds and listens (throws std::runtime_error "HOST:PORT: cannot listen: REASON" when the
  /// address does not resolve, is not local, or the port is taken), then starts the thread.
  explicit Server(ServerConfig config);
  /// Stops the thread and closes every connection.
  ~Server();
  Server(const Server&) = delete;
  Server& operator=(const Server&) = delete;

  /// "HOST:PORT" bound (the port the system chose when config.port was 0).
  [[nodiscard]] const std::string& address() const noexcept { return address_; }
  [[nodiscard]] std::uint16_t port() const noexcept { return port_; }
  /// Thread-safe snapshot.
  [[nodiscard]] ServerCounters counters() const noexcept;
  /// WebSocket clients connected now (thread-safe).
  [[nodiscard]] std::uint64_t clients() const noexcept;

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
  std::string address_;
  std::uint16_t port_ = 0;
  std::thread thread_;
};

}  // namespace radar_emu::io::ws
