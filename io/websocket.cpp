#include "io/websocket.hpp"

#include <netdb.h>
#include <netinet/in.h>
#include <netinet/tcp.h>
#include <poll.h>
#include <sys/socket.h>
#include <unistd.h>

#include <algorithm>
#include <cctype>
#include <cerrno>
#include <chrono>
#include <cstring>
#include <stdexcept>
#include <vector>

namespace radar_emu::io::ws {

// ---- SHA-1, FIPS 180-4 sec. 5.1.1 (padding), 5.3.1 (initial hash), 6.1.2 (computation) ----

namespace {

constexpr std::uint32_t rotl(std::uint32_t x, int n) noexcept {
  return (x << n) | (x >> (32 - n));
}

void sha1_block(const std::uint8_t* p, std::array<std::uint32_t, 5>& h) noexcept {
  std::array<std::uint32_t, 80> w{};
  for (std::size_t t = 0; t < 16; ++t) {
    w[t] = static_cast<std::uint32_t>(p[4 * t]) << 24 |
           static_cast<std::uint32_t>(p[4 * t + 1]) << 16 |
           static_cast<std::uint32_t>(p[4 * t + 2]) << 8 | static_cast<std::uint32_t>(p[4 * t + 3]);
  }
  for (std::size_t t = 16; t < 80; ++t)
    w[t] = rotl(w[t - 3] ^ w[t - 8] ^ w[t - 14] ^ w[t - 16], 1);
  std::uint32_t a = h[0], b = h[1], c = h[2], d = h[3], e = h[4];
  for (std::size_t t = 0; t < 80; ++t) {
    std::uint32_t f = 0, k = 0;
    if (t < 20) {
      f = (b & c) | (~b & d);  // Ch
      k = 0x5a827999u;
    } else if (t < 40) {
      f = b ^ c ^ d;  // Parity
      k = 0x6ed9eba1u;
    } else if (t < 60) {
      f = (b & c) | (b & d) | (c & d);  // Maj
      k = 0x8f1bbcdcu;
    } else {
      f = b ^ c ^ d;
      k = 0xca62c1d6u;
    }
    const std::uint32_t tmp = rotl(a, 5) + f + e + k + w[t];
    e = d;
    d = c;
    c = rotl(b, 30);
    b = a;
    a = tmp;
  }
  h[0] += a;
  h[1] += b;
  h[2] += c;
  h[3] += d;
  h[4] += e;
}

}  // namespace

std::array<std::uint8_t, 20> sha1(std::string_view data) noexcept {
  std::array<std::uint32_t, 5> h{0x67452301u, 0xefcdab89u, 0x98badcfeu, 0x10325476u, 0xc3d2e1f0u};
  const auto* p = reinterpret_cast<const std::uint8_t*>(data.data());
  std::size_t n = data.size();
  while (n >= 64) {
    sha1_block(p, h);
    p += 64;
    n -= 64;
  }
  // The tail, 0x80, zeros, and the message length in bits (64-bit big-endian): one or two blocks.
  std::array<std::uint8_t, 128> tail{};
  std::memcpy(tail.data(), p, n);
  tail[n] = 0x80;
  const std::size_t blocks = n + 1 + 8 <= 64 ? 1 : 2;
  const std::uint64_t bits = static_cast<std::uint64_t>(data.size()) * 8u;
  for (int i = 0; i < 8; ++i)
    tail[blocks * 64 - 1 - static_cast<std::size_t>(i)] =
        static_cast<std::uint8_t>(bits >> (8 * i));
  for (std::size_t b = 0; b < blocks; ++b)
    sha1_block(tail.data() + 64 * b, h);
  std::array<std::uint8_t, 20> out{};
  for (std::size_t i = 0; i < 5; ++i) {
    for (std::size_t j = 0; j < 4; ++j)
      out[4 * i + j] = static_cast<std::uint8_t>(h[i] >> (24 - 8 * j));
  }
  return out;
}

std::string base64(std::span<const std::uint8_t> data) {
  static constexpr char kAlphabet[] =
      "ABCDEFGHIJKLMNOPQRSTUVWXYZabcdefghijklmnopqrstuvwxyz0123456789+/";
  std::string out;
  out.reserve((data.size() + 2) / 3 * 4);
  std::size_t i = 0;
  for (; i + 3 <= data.size(); i += 3) {
    const std::uint32_t v = static_cast<std::uint32_t>(data[i]) << 16 |
                            static_cast<std::uint32_t>(data[i + 1]) << 8 | data[i + 2];
    for (int s = 18; s >= 0; s -= 6)
      out.push_back(kAlphabet[(v >> s) & 63u]);
  }
  const std::size_t rest = data.size() - i;
  if (rest > 0) {
    std::uint32_t v = static_cast<std::uint32_t>(data[i]) << 16;
    if (rest == 2)
      v |= static_cast<std::uint32_t>(data[i + 1]) << 8;
    out.push_back(kAlphabet[(v >> 18) & 63u]);
    out.push_back(kAlphabet[(v >> 12) & 63u]);
    out.push_back(rest == 2 ? kAlphabet[(v >> 6) & 63u] : '=');
    out.push_back('=');
  }
  return out;
}

std::string accept_key(std::string_view key) {
  // RFC 6455 sec. 1.3 / 4.2.2: the GUID every server appends.
  std::string s(key);
  s += "258EAFA5-E914-47DA-95CA-C5AB0DC85B11";
  const std::array<std::uint8_t, 20> digest = sha1(s);
  return base64(digest);
}

std::size_t frame_header(Opcode opcode, std::uint64_t payload_bytes,
                         std::array<std::uint8_t, 10>& out) noexcept {
  out[0] = static_cast<std::uint8_t>(0x80u | static_cast<std::uint8_t>(opcode));  // FIN
  if (payload_bytes < 126) {
    out[1] = static_cast<std::uint8_t>(payload_bytes);
    return 2;
  }
  if (payload_bytes <= 0xffff) {
    out[1] = 126;
    out[2] = static_cast<std::uint8_t>(payload_bytes >> 8);
    out[3] = static_cast<std::uint8_t>(payload_bytes);
    return 4;
  }
  out[1] = 127;
  for (int i = 0; i < 8; ++i)
    out[2 + static_cast<std::size_t>(i)] = static_cast<std::uint8_t>(payload_bytes >> (56 - 8 * i));
  return 10;
}

// ---- the server ----

namespace {

using Clock = std::chrono::steady_clock;

std::string lower(std::string_view s) {
  std::string o(s);
  for (char& c : o)
    c = static_cast<char>(std::tolower(static_cast<unsigned char>(c)));
  return o;
}

std::string_view trim(std::string_view s) {
  while (!s.empty() && (s.front() == ' ' || s.front() == '\t'))
    s.remove_prefix(1);
  while (!s.empty() && (s.back() == ' ' || s.back() == '\t'))
    s.remove_suffix(1);
  return s;
}

// A comma-separated header value holds `token` (case-insensitive), e.g. Connection: keep-alive,
// Upgrade.
bool has_token(std::string_view value, std::string_view token) {
  const std::string v = lower(value);
  std::string_view rest = v;
  while (!rest.empty()) {
    const std::size_t comma = rest.find(',');
    if (trim(rest.substr(0, comma)) == token)
      return true;
    if (comma == std::string_view::npos)
      break;
    rest.remove_prefix(comma + 1);
  }
  return false;
}

// A Sec-WebSocket-Key is the base64 of 16 bytes: 22 characters of the alphabet and "=="
// (RFC 6455 sec. 4.1 item 7, sec. 11.3.1).
bool valid_key(std::string_view k) {
  if (k.size() != 24 || k.substr(22) != "==")
    return false;
  return std::all_of(k.begin(), k.begin() + 22, [](char c) {
    return std::isalnum(static_cast<unsigned char>(c)) != 0 || c == '+' || c == '/';
  });
}

std::string response(std::string_view status, std::string_view extra_headers,
                     std::string_view content_type, std::string_view body) {
  std::string r = "HTTP/1.1 ";
  r += status;
  r += "\r\nServer: radar-emu\r\nCache-Control: no-store\r\nConnection: close\r\n";
  r += extra_headers;
  r += "Content-Type: ";
  r += content_type;
  r += "\r\nContent-Length: " + std::to_string(body.size()) + "\r\n\r\n";
  r += body;
  return r;
}

std::string plain(std::string_view status, std::string_view extra = {}) {
  return response(status, extra, "text/plain; charset=utf-8", std::string(status) + "\n");
}

}  // namespace

int http_status(Request::Kind kind) noexcept {
  switch (kind) {
    case Request::Kind::kMalformed:
    case Request::Kind::kBadHandshake:
      return 400;
    case Request::Kind::kMethodNotAllowed:
      return 405;
    case Request::Kind::kWrongVersion:
      return 426;
    case Request::Kind::kWebSocket:
      return 101;
    case Request::Kind::kPage:
      return 200;
    case Request::Kind::kNotFound:
      return 404;
  }
  return 400;
}

Request parse_request(std::string_view head, std::string_view ws_path) {
  Request r;
  // Request line: METHOD SP TARGET SP HTTP/1.x (RFC 9112 sec. 3).
  const std::size_t eol = head.find("\r\n");
  const std::string_view line = head.substr(0, eol);
  const std::size_t sp1 = line.find(' ');
  const std::size_t sp2 = sp1 == std::string_view::npos ? sp1 : line.find(' ', sp1 + 1);
  if (sp2 == std::string_view::npos || !line.substr(sp2 + 1).starts_with("HTTP/1.")) {
    r.kind = Request::Kind::kMalformed;
    return r;
  }
  const std::string_view method = line.substr(0, sp1);
  std::string_view path = line.substr(sp1 + 1, sp2 - sp1 - 1);
  path = path.substr(0, path.find('?'));
  // Headers, names case-insensitive.
  std::string upgrade, connection, version, key;
  bool host = false;
  std::string_view rest = eol == std::string_view::npos ? std::string_view() : head.substr(eol + 2);
  while (!rest.empty()) {
    const std::size_t e = rest.find("\r\n");
    const std::string_view h = rest.substr(0, e);
    rest = e == std::string_view::npos ? std::string_view() : rest.substr(e + 2);
    const std::size_t colon = h.find(':');
    if (colon == std::string_view::npos)
      continue;
    const std::string name = lower(trim(h.substr(0, colon)));
    const std::string_view value = trim(h.substr(colon + 1));
    if (name == "upgrade")
      upgrade = value;
    else if (name == "connection")
      connection = value;
    else if (name == "sec-websocket-version")
      version = value;
    else if (name == "sec-websocket-key")
      key = value;
    else if (name == "host")
      host = true;
  }
  if (method != "GET") {
    r.kind = Request::Kind::kMethodNotAllowed;
    return r;
  }
  if (path == ws_path) {
    // The opening handshake, RFC 6455 sec. 4.2.1: Host, Upgrade: websocket, Connection:
    // Upgrade, a 16-byte key, version 13 (else 426 with the version we speak, sec. 4.4).
    if (version != "13") {
      r.kind = Request::Kind::kWrongVersion;
      return r;
    }
    if (!host || !has_token(upgrade, "websocket") || !has_token(connection, "upgrade") ||
        !valid_key(key)) {
      r.kind = Request::Kind::kBadHandshake;
      return r;
    }
    r.kind = Request::Kind::kWebSocket;
    r.key = std::move(key);
    return r;
  }
  r.kind = path == "/" || path == "/index.html" ? Request::Kind::kPage : Request::Kind::kNotFound;
  return r;
}

ClientFrame parse_client_frame(std::span<const std::uint8_t> in, std::size_t max_payload_bytes,
                               std::string& payload) {
  ClientFrame f;
  const std::size_t avail = in.size();
  if (avail < 2)
    return f;
  const std::uint8_t op = in[0] & 0x0fu;
  const bool masked = (in[1] & 0x80u) != 0;
  std::uint64_t len = in[1] & 0x7fu;
  std::size_t hdr = 2;
  if (len == 126) {
    hdr = 4;
    if (avail < hdr)
      return f;
    len = static_cast<std::uint64_t>(in[2]) << 8 | in[3];
  } else if (len == 127) {
    hdr = 10;
    if (avail < hdr)
      return f;
    len = 0;
    for (std::size_t i = 0; i < 8; ++i)
      len = len << 8 | in[2 + i];
  }
  if (!masked) {
    f.status = ClientFrame::Status::kError;
    f.close_code = 1002;  // protocol error
    return f;
  }
  if (len > max_payload_bytes) {
    f.status = ClientFrame::Status::kError;
    f.close_code = 1009;  // message too big
    return f;
  }
  const std::size_t total = hdr + 4 + static_cast<std::size_t>(len);
  if (avail < total)
    return f;
  const bool control = (op & 0x8u) != 0;
  const bool known = op <= 0x2 || op == static_cast<std::uint8_t>(Opcode::kClose) ||
                     op == static_cast<std::uint8_t>(Opcode::kPing) ||
                     op == static_cast<std::uint8_t>(Opcode::kPong);
  if ((control && len > 125) || !known) {
    f.status = ClientFrame::Status::kError;
    f.close_code = 1002;  // a control frame over 125 bytes (sec. 5.5), or a reserved opcode
    return f;
  }
  payload.assign(static_cast<std::size_t>(len), '\0');
  for (std::size_t i = 0; i < payload.size(); ++i)
    payload[i] = static_cast<char>(in[hdr + 4 + i] ^ in[hdr + (i & 3u)]);
  f.status = ClientFrame::Status::kFrame;
  f.opcode = op;
  f.size = total;
  return f;
}

struct Server::Impl {
  struct Client {
    int fd = -1;
    enum class State { kHttp, kWebSocket, kClosing } state = State::kHttp;
    std::string in;
    std::string out;
    std::size_t out_sent = 0;
    Clock::time_point since{};
    std::uint32_t skips_in_a_row = 0;
    [[nodiscard]] std::size_t pending() const noexcept { return out.size() - out_sent; }
  };
  struct Counters {
    std::atomic<std::uint64_t> connections{0}, refused{0}, pages_served{0}, not_found{0},
        bad_requests{0}, bad_handshakes{0}, websocket_clients{0}, messages{0}, frames_queued{0},
        frames_skipped{0}, slow_clients_closed{0}, clients_closed{0}, clients_now{0},
        accept_failures{0};
  };
  static void bump(std::atomic<std::uint64_t>& x) noexcept {
    x.fetch_add(1, std::memory_order_relaxed);
  }

  ServerConfig config;
  int listen_fd = -1;
  Clock::time_point accept_resume{};  ///< no accept() before this (after running out of fds)
  std::atomic<bool> stop{false};
  Counters counters;
  std::vector<Client> clients;  // at most max_clients (reserved at setup)
  std::vector<pollfd> fds;      // max_clients + 1 (reserved: an idle server allocates nothing)
  std::string last_message;     // sent to each client as it connects
  bool have_message = false;

  ~Impl() {
    for (Client& c : clients)
      close_client(c, false);
    if (listen_fd >= 0)
      ::close(listen_fd);
  }

  void close_client(Client& c, bool count = true) {
    if (c.fd < 0)
      return;
    ::close(c.fd);
    c.fd = -1;
    if (c.state == Client::State::kWebSocket && count) {
      bump(counters.clients_closed);
      counters.clients_now.fetch_sub(1, std::memory_order_relaxed);
    }
  }

  // Queues `bytes` for the client unless that would pass client_buffer_bytes.
  bool queue(Client& c, std::string_view bytes) {
    if (c.pending() + bytes.size() > config.client_buffer_bytes)
      return false;
    if (c.out_sent > 0 && c.out_sent == c.out.size()) {
      c.out.clear();
      c.out_sent = 0;
    }
    c.out.append(bytes);
    return true;
  }
  bool queue_frame(Client& c, Opcode op, std::string_view payload) {
    std::array<std::uint8_t, 10> h{};
    const std::size_t n = frame_header(op, payload.size(), h);
    if (c.pending() + n + payload.size() > config.client_buffer_bytes)
      return false;
    (void)queue(c, std::string_view(reinterpret_cast<const char*>(h.data()), n));
    (void)queue(c, payload);
    return true;
  }
  // Answers and closes once the answer is sent. A WebSocket client leaving this way is counted
  // as closed here (its fd closes later).
  void answer_and_close(Client& c, const std::string& text) {
    if (c.state == Client::State::kWebSocket) {
      bump(counters.clients_closed);
      counters.clients_now.fetch_sub(1, std::memory_order_relaxed);
    }
    (void)queue(c, text);
    c.state = Client::State::kClosing;
    c.in.clear();
  }
  void close_frame_and_close(Client& c, std::uint16_t code) {
    std::array<std::uint8_t, 12> f{};
    std::array<std::uint8_t, 10> h{};
    const std::size_t n = frame_header(Opcode::kClose, 2, h);
    std::memcpy(f.data(), h.data(), n);
    f[n] = static_cast<std::uint8_t>(code >> 8);
    f[n + 1] = static_cast<std::uint8_t>(code);
    answer_and_close(c, std::string(reinterpret_cast<const char*>(f.data()), n + 2));
  }

  void flush(Client& c) {
    while (c.fd >= 0 && c.pending() > 0) {
      const ssize_t n =
          ::send(c.fd, c.out.data() + c.out_sent, c.pending(), MSG_NOSIGNAL | MSG_DONTWAIT);
      if (n > 0) {
        c.out_sent += static_cast<std::size_t>(n);
        continue;
      }
      if (n < 0 && (errno == EAGAIN || errno == EWOULDBLOCK || errno == EINTR))
        return;
      close_client(c);
      return;
    }
    if (c.fd >= 0) {
      c.out.clear();
      c.out_sent = 0;
      if (c.state == Client::State::kClosing) {
        ::shutdown(c.fd, SHUT_WR);
        close_client(c);
      }
    }
  }

  void accept_all() {
    for (;;) {
      const int fd = ::accept4(listen_fd, nullptr, nullptr, SOCK_NONBLOCK | SOCK_CLOEXEC);
      if (fd < 0) {
        // Out of descriptors or memory: the pending connection stays queued and the listening
        // socket stays readable, so stop polling it for a while rather than spin on it.
        if (errno == EMFILE || errno == ENFILE || errno == ENOBUFS || errno == ENOMEM) {
          bump(counters.accept_failures);
          accept_resume = Clock::now() + std::chrono::milliseconds(kAcceptBackoffMs);
        }
        return;  // EAGAIN, or a connection that went away before we took it
      }
      bump(counters.connections);
      if (clients.size() >= config.max_clients) {
        bump(counters.refused);
        const std::string r = plain("503 Service Unavailable");
        (void)::send(fd, r.data(), r.size(), MSG_NOSIGNAL | MSG_DONTWAIT);
        ::close(fd);
        continue;
      }
      const int one = 1;
      (void)::setsockopt(fd, IPPROTO_TCP, TCP_NODELAY, &one, sizeof one);
      Client c;
      c.fd = fd;
      c.since = Clock::now();
      clients.push_back(std::move(c));
    }
  }

  void handle_request(Client& c, std::string_view head) {
    Request req = parse_request(head, config.ws_path);
    switch (req.kind) {
      case Request::Kind::kMalformed:
        bump(counters.bad_requests);
        answer_and_close(c, plain("400 Bad Request"));
        return;
      case Request::Kind::kMethodNotAllowed:
        bump(counters.bad_requests);
        answer_and_close(c, plain("405 Method Not Allowed", "Allow: GET\r\n"));
        return;
      case Request::Kind::kWrongVersion:
        bump(counters.bad_handshakes);
        answer_and_close(c, plain("426 Upgrade Required", "Sec-WebSocket-Version: 13\r\n"));
        return;
      case Request::Kind::kBadHandshake:
        bump(counters.bad_handshakes);
        answer_and_close(c, plain("400 Bad Request"));
        return;
      case Request::Kind::kWebSocket: {
        std::string r =
            "HTTP/1.1 101 Switching Protocols\r\nUpgrade: websocket\r\nConnection: Upgrade\r\n"
            "Sec-WebSocket-Accept: ";
        r += accept_key(req.key);
        r += "\r\n\r\n";
        (void)queue(c, r);
        c.state = Client::State::kWebSocket;
        bump(counters.websocket_clients);
        bump(counters.clients_now);
        if (have_message && queue_frame(c, Opcode::kText, last_message))
          bump(counters.frames_queued);
        return;
      }
      case Request::Kind::kPage:
        bump(counters.pages_served);
        answer_and_close(c, response("200 OK", "", "text/html; charset=utf-8", config.page));
        return;
      case Request::Kind::kNotFound:
        break;
    }
    bump(counters.not_found);
    answer_and_close(c, plain("404 Not Found"));
  }

  // Client frames (RFC 6455 sec. 5.2, parse_client_frame): data is discarded; ping is answered
  // with pong, close with close (sec. 5.5.1); a protocol error closes with its code.
  void handle_frames(Client& c) {
    std::size_t pos = 0;
    const auto* b = reinterpret_cast<const std::uint8_t*>(c.in.data());
    std::string payload;
    while (c.state == Client::State::kWebSocket) {
      const ClientFrame f = parse_client_frame(std::span(b + pos, c.in.size() - pos),
                                               config.request_max_bytes, payload);
      if (f.status == ClientFrame::Status::kIncomplete)
        break;
      if (f.status == ClientFrame::Status::kError) {
        close_frame_and_close(c, f.close_code);
        return;
      }
      pos += f.size;
      if (f.opcode == static_cast<std::uint8_t>(Opcode::kClose)) {
        std::array<std::uint8_t, 10> h{};
        const std::size_t n =
            frame_header(Opcode::kClose, std::min<std::size_t>(payload.size(), 2), h);
        std::string reply(reinterpret_cast<const char*>(h.data()), n);
        reply += payload.substr(0, 2);
        answer_and_close(c, reply);
        return;
      }
      if (f.opcode == static_cast<std::uint8_t>(Opcode::kPing))
        (void)queue_frame(c, Opcode::kPong, payload);
    }
    c.in.erase(0, pos);
  }

  void read_client(Client& c) {
    char buf[4096];
    for (;;) {
      const ssize_t n = ::recv(c.fd, buf, sizeof buf, MSG_DONTWAIT);
      if (n == 0) {
        close_client(c);  // EOF
        return;
      }
      if (n < 0) {
        if (errno == EAGAIN || errno == EWOULDBLOCK || errno == EINTR)
          return;
        close_client(c);
        return;
      }
      if (c.state == Client::State::kClosing)
        continue;  // discarded
      c.in.append(buf, static_cast<std::size_t>(n));
      if (c.state == Client::State::kHttp) {
        const std::size_t end = c.in.find("\r\n\r\n");
        if (end == std::string::npos) {
          if (c.in.size() > config.request_max_bytes) {
            bump(counters.bad_requests);
            answer_and_close(c, plain("431 Request Header Fields Too Large"));
          }
          continue;
        }
        const std::string head = c.in.substr(0, end);
        c.in.erase(0, end + 4);
        handle_request(c, head);
      }
      if (c.state == Client::State::kWebSocket)
        handle_frames(c);
    }
  }

  void broadcast(const std::string& message) {
    for (Client& c : clients) {
      if (c.fd < 0 || c.state != Client::State::kWebSocket)
        continue;
      if (queue_frame(c, Opcode::kText, message)) {
        bump(counters.frames_queued);
        c.skips_in_a_row = 0;
        flush(c);
        continue;
      }
      bump(counters.frames_skipped);
      if (++c.skips_in_a_row >= config.slow_client_skips_max) {
        bump(counters.slow_clients_closed);
        close_client(c);
      }
    }
  }

  void main_loop() {
    std::string message;
    const auto interval = std::chrono::milliseconds(std::max(1, config.poll_interval_ms));
    auto next_source = Clock::now();
    while (!stop.load(std::memory_order_acquire)) {
      fds.clear();
      const bool listening = Clock::now() >= accept_resume;
      fds.push_back(pollfd{listen_fd, static_cast<short>(listening ? POLLIN : 0), 0});
      for (const Client& c : clients) {
        const short ev = static_cast<short>(POLLIN | (c.pending() > 0 ? POLLOUT : 0));
        fds.push_back(pollfd{c.fd, ev, 0});
      }
      const auto wait =
          std::chrono::duration_cast<std::chrono::milliseconds>(next_source - Clock::now());
      // At most 50 ms, so that a stop request is seen whatever the interval.
      (void)::poll(fds.data(), fds.size(),
                   static_cast<int>(std::clamp<std::int64_t>(wait.count(), 0, 50)));
      const std::size_t polled = clients.size();
      for (std::size_t i = 0; i < polled; ++i) {
        Client& c = clients[i];
        const short re = fds[i + 1].revents;
        if (c.fd >= 0 && (re & (POLLIN | POLLHUP | POLLERR)) != 0)
          read_client(c);
        if (c.fd >= 0 && (re & POLLOUT) != 0)
          flush(c);
      }
      if ((fds[0].revents & POLLIN) != 0)
        accept_all();
      const auto now = Clock::now();
      const auto timeout = std::chrono::duration<double>(config.request_timeout_s);
      for (Client& c : clients) {
        if (c.fd >= 0 && c.state == Client::State::kHttp && now - c.since > timeout) {
          bump(counters.bad_requests);
          answer_and_close(c, plain("408 Request Timeout"));
        }
        if (c.fd >= 0 && (c.pending() > 0 || c.state == Client::State::kClosing))
          flush(c);
      }
      if (now >= next_source) {
        next_source = now + interval;
        if (config.source &&
            config.source(message, counters.clients_now.load(std::memory_order_relaxed))) {
          bump(counters.messages);
          last_message = message;
          have_message = true;
          broadcast(last_message);
        }
      }
      std::erase_if(clients, [](const Client& c) { return c.fd < 0; });
    }
  }
};

Server::Server(ServerConfig config) : impl_(std::make_unique<Impl>()) {
  impl_->config = std::move(config);
  const ServerConfig& c = impl_->config;
  const std::string where = (c.host.find(':') != std::string::npos ? "[" + c.host + "]" : c.host) +
                            ":" + std::to_string(c.port);
  addrinfo hints{};
  hints.ai_family = AF_UNSPEC;
  hints.ai_socktype = SOCK_STREAM;
  hints.ai_flags = AI_PASSIVE | AI_NUMERICSERV;
  addrinfo* list = nullptr;
  const std::string port_text = std::to_string(c.port);
  if (const int rc = ::getaddrinfo(c.host.c_str(), port_text.c_str(), &hints, &list); rc != 0)
    throw std::runtime_error(where + ": cannot listen: " + ::gai_strerror(rc));
  std::string error = "no address";
  for (addrinfo* a = list; a != nullptr; a = a->ai_next) {
    const int fd =
        ::socket(a->ai_family, a->ai_socktype | SOCK_NONBLOCK | SOCK_CLOEXEC, a->ai_protocol);
    if (fd < 0) {
      error = std::strerror(errno);
      continue;
    }
    const int one = 1;
    (void)::setsockopt(fd, SOL_SOCKET, SO_REUSEADDR, &one, sizeof one);
    if (::bind(fd, a->ai_addr, a->ai_addrlen) == 0 && ::listen(fd, 64) == 0) {
      impl_->listen_fd = fd;
      break;
    }
    error = std::strerror(errno);
    ::close(fd);
  }
  ::freeaddrinfo(list);
  if (impl_->listen_fd < 0)
    throw std::runtime_error(where + ": cannot listen: " + error);
  sockaddr_storage ss{};
  socklen_t len = sizeof ss;
  if (::getsockname(impl_->listen_fd, reinterpret_cast<sockaddr*>(&ss), &len) == 0) {
    port_ = ntohs(ss.ss_family == AF_INET6 ? reinterpret_cast<sockaddr_in6*>(&ss)->sin6_port
                                           : reinterpret_cast<sockaddr_in*>(&ss)->sin_port);
  }
  address_ = (c.host.find(':') != std::string::npos ? "[" + c.host + "]" : c.host) + ":" +
             std::to_string(port_);
  impl_->clients.reserve(c.max_clients);
  impl_->fds.reserve(c.max_clients + 1);
  thread_ = std::thread([this] { impl_->main_loop(); });
}

Server::~Server() {
  impl_->stop.store(true, std::memory_order_release);
  if (thread_.joinable())
    thread_.join();
}

ServerCounters Server::counters() const noexcept {
  const Impl::Counters& k = impl_->counters;
  auto v = [](const std::atomic<std::uint64_t>& x) { return x.load(std::memory_order_relaxed); };
  ServerCounters s;
  s.connections = v(k.connections);
  s.refused = v(k.refused);
  s.pages_served = v(k.pages_served);
  s.not_found = v(k.not_found);
  s.bad_requests = v(k.bad_requests);
  s.bad_handshakes = v(k.bad_handshakes);
  s.websocket_clients = v(k.websocket_clients);
  s.messages = v(k.messages);
  s.frames_queued = v(k.frames_queued);
  s.frames_skipped = v(k.frames_skipped);
  s.slow_clients_closed = v(k.slow_clients_closed);
  s.clients_closed = v(k.clients_closed);
  s.clients_now = v(k.clients_now);
  s.accept_failures = v(k.accept_failures);
  return s;
}

std::uint64_t Server::clients() const noexcept {
  return impl_->counters.clients_now.load(std::memory_order_relaxed);
}

}  // namespace radar_emu::io::ws
