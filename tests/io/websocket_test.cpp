// io/websocket.hpp: SHA-1 and base64 against their standards' test vectors, the handshake key
// against RFC 6455's worked example, frame headers against RFC 6455 sec. 5.2 / 5.7, and the
// server over loopback TCP with a raw client written here (handshake, ping, close, protocol
// errors, bad requests, a client that never reads, too many clients, a silent client).

#include "io/websocket.hpp"

#include <arpa/inet.h>
#include <gtest/gtest.h>
#include <netinet/in.h>
#include <poll.h>
#include <sys/resource.h>
#include <sys/socket.h>
#include <unistd.h>

#include <atomic>
#include <chrono>
#include <cstring>
#include <iostream>
#include <string>
#include <thread>
#include <vector>

namespace ws = radar_emu::io::ws;

namespace {

std::string hex(std::span<const std::uint8_t> d) {
  static constexpr char k[] = "0123456789abcdef";
  std::string o;
  for (std::uint8_t b : d) {
    o += k[b >> 4];
    o += k[b & 15];
  }
  return o;
}

std::span<const std::uint8_t> bytes(std::string_view s) {
  return {reinterpret_cast<const std::uint8_t*>(s.data()), s.size()};
}

TEST(Sha1, Fips180Examples) {
  // FIPS 180-2 appendix A (one block, two blocks, a million 'a'), and the empty message.
  EXPECT_EQ(hex(ws::sha1("abc")), "a9993e364706816aba3e25717850c26c9cd0d89d");
  EXPECT_EQ(hex(ws::sha1("abcdbcdecdefdefgefghfghighijhijkijkljklmklmnlmnomnopnopq")),
            "84983e441c3bd26ebaae4aa1f95129e5e54670f1");
  EXPECT_EQ(hex(ws::sha1(std::string(1'000'000, 'a'))), "34aa973cd4c4daa4f61eeb2bdbad27316534016f");
  EXPECT_EQ(hex(ws::sha1("")), "da39a3ee5e6b4b0d3255bfef95601890afd80709");
}

TEST(Base64, Rfc4648Vectors) {
  // RFC 4648 sec. 10.
  const char* in[] = {"", "f", "fo", "foo", "foob", "fooba", "foobar"};
  const char* out[] = {"", "Zg==", "Zm8=", "Zm9v", "Zm9vYg==", "Zm9vYmE=", "Zm9vYmFy"};
  for (int i = 0; i < 7; ++i)
    EXPECT_EQ(ws::base64(bytes(in[i])), out[i]) << in[i];
}

TEST(WebSocket, AcceptKeyOfRfc6455Example) {
  // RFC 6455 sec. 1.3.
  EXPECT_EQ(ws::accept_key("dGhlIHNhbXBsZSBub25jZQ=="), "s3pPLMBiTxaQ9kYGzzhZRbK+xOo=");
}

TEST(WebSocket, FrameHeaderLengths) {
  std::array<std::uint8_t, 10> h{};
  // RFC 6455 sec. 5.7: "A single-frame unmasked text message" "Hello": 0x81 0x05.
  ASSERT_EQ(ws::frame_header(ws::Opcode::kText, 5, h), 2u);
  EXPECT_EQ(h[0], 0x81);
  EXPECT_EQ(h[1], 0x05);
  ASSERT_EQ(ws::frame_header(ws::Opcode::kText, 125, h), 2u);
  EXPECT_EQ(h[1], 125);
  // 126 to 65535: 126 then 16 bits (sec. 5.7: 256 bytes is 0x82 0x7E 0x0100).
  ASSERT_EQ(ws::frame_header(ws::Opcode::kBinary, 256, h), 4u);
  EXPECT_EQ(hex(std::span(h.data(), 4)), "827e0100");
  ASSERT_EQ(ws::frame_header(ws::Opcode::kText, 65535, h), 4u);
  EXPECT_EQ(hex(std::span(h.data(), 4)), "817effff");
  // Beyond: 127 then 64 bits (sec. 5.7: 64 KiB is 0x82 0x7F 0x0000000000010000).
  ASSERT_EQ(ws::frame_header(ws::Opcode::kBinary, 65536, h), 10u);
  EXPECT_EQ(hex(std::span(h.data(), 10)), "827f0000000000010000");
}

// ---- the server over loopback ----

class RawClient {
 public:
  explicit RawClient(std::uint16_t port) {
    fd_ = ::socket(AF_INET, SOCK_STREAM, 0);
    sockaddr_in a{};
    a.sin_family = AF_INET;
    a.sin_port = htons(port);
    a.sin_addr.s_addr = htonl(INADDR_LOOPBACK);
    connected_ = ::connect(fd_, reinterpret_cast<sockaddr*>(&a), sizeof a) == 0;
  }
  ~RawClient() {
    if (fd_ >= 0)
      ::close(fd_);
  }
  [[nodiscard]] bool connected() const { return connected_; }
  void send(std::string_view s) {
    ASSERT_EQ(::send(fd_, s.data(), s.size(), MSG_NOSIGNAL), static_cast<ssize_t>(s.size()));
  }
  // Reads until `n` bytes are buffered, EOF, or 10 s without data.
  bool fill(std::size_t n) {
    while (buf_.size() < n) {
      pollfd p{fd_, POLLIN, 0};
      if (::poll(&p, 1, 10'000) <= 0)
        return false;
      char b[65536];
      const ssize_t k = ::recv(fd_, b, sizeof b, 0);
      if (k <= 0)
        return false;
      buf_.append(b, static_cast<std::size_t>(k));
    }
    return true;
  }
  // Everything until the peer closes (or 10 s of silence).
  std::string read_all() {
    while (fill(buf_.size() + 1)) {
    }
    return std::exchange(buf_, {});
  }
  std::string read_head() {
    while (buf_.find("\r\n\r\n") == std::string::npos) {
      if (!fill(buf_.size() + 1))
        return std::exchange(buf_, {});
    }
    const std::size_t e = buf_.find("\r\n\r\n") + 4;
    std::string head = buf_.substr(0, e);
    buf_.erase(0, e);
    return head;
  }
  // One server frame: opcode and payload (-1: none).
  std::pair<int, std::string> read_frame() {
    if (!fill(2))
      return {-1, {}};
    const auto b1 = static_cast<std::uint8_t>(buf_[1]);
    EXPECT_EQ(b1 & 0x80, 0) << "server frames are not masked";
    std::size_t n = b1 & 0x7fu, hdr = 2;
    if (n == 126) {
      hdr = 4;
      if (!fill(4))
        return {-1, {}};
      n = static_cast<std::size_t>(static_cast<std::uint8_t>(buf_[2])) << 8 |
          static_cast<std::uint8_t>(buf_[3]);
    }
    if (!fill(hdr + n))
      return {-1, {}};
    const int op = static_cast<std::uint8_t>(buf_[0]) & 0x0f;
    std::string payload = buf_.substr(hdr, n);
    buf_.erase(0, hdr + n);
    return {op, payload};
  }
  // A client frame, masked (RFC 6455 sec. 5.3) unless told otherwise.
  void send_frame(int opcode, std::string_view payload, bool mask = true) {
    std::string f;
    f += static_cast<char>(0x80 | opcode);
    f += static_cast<char>((mask ? 0x80 : 0) | static_cast<int>(payload.size()));
    const char key[4] = {0x12, 0x34, 0x56, 0x78};
    if (mask)
      f.append(key, 4);
    for (std::size_t i = 0; i < payload.size(); ++i)
      f += mask ? static_cast<char>(payload[i] ^ key[i & 3]) : payload[i];
    send(f);
  }
  void handshake(std::string_view extra = {}) {
    send(std::string("GET /ws HTTP/1.1\r\nHost: localhost\r\nUpgrade: websocket\r\n"
                     "Connection: keep-alive, Upgrade\r\nSec-WebSocket-Key: "
                     "dGhlIHNhbXBsZSBub25jZQ==\r\nSec-WebSocket-Version: 13\r\n") +
         std::string(extra) + "\r\n");
  }

 private:
  int fd_ = -1;
  bool connected_ = false;
  std::string buf_;
};

template <typename F>
bool eventually(F f) {
  for (int i = 0; i < 1000; ++i) {
    if (f())
      return true;
    std::this_thread::sleep_for(std::chrono::milliseconds(10));
  }
  return false;
}

ws::ServerConfig config() {
  ws::ServerConfig c;
  c.page = "<html>radar</html>";
  c.poll_interval_ms = 5;
  return c;
}

TEST(WebSocketServer, ServesThePageAndAnswersBadRequests) {
  ws::Server s(config());
  ASSERT_NE(s.port(), 0);
  EXPECT_EQ(s.address(), "127.0.0.1:" + std::to_string(s.port()));
  {
    RawClient c(s.port());
    c.send("GET / HTTP/1.1\r\nHost: x\r\n\r\n");
    const std::string r = c.read_all();
    EXPECT_TRUE(r.starts_with("HTTP/1.1 200 OK\r\n")) << r;
    EXPECT_NE(r.find("Content-Length: 18\r\n"), std::string::npos) << r;
    EXPECT_TRUE(r.ends_with("\r\n\r\n<html>radar</html>")) << r;
  }
  auto status = [&](std::string_view request) {
    RawClient c(s.port());
    c.send(request);
    const std::string r = c.read_all();
    return r.substr(0, r.find("\r\n"));
  };
  EXPECT_EQ(status("GET /nothing HTTP/1.1\r\nHost: x\r\n\r\n"), "HTTP/1.1 404 Not Found");
  EXPECT_EQ(status("POST / HTTP/1.1\r\nHost: x\r\n\r\n"), "HTTP/1.1 405 Method Not Allowed");
  EXPECT_EQ(status("garbage\r\n\r\n"), "HTTP/1.1 400 Bad Request");
  // Handshakes: no key, a key that is not 16 bytes, no Upgrade, wrong version.
  EXPECT_EQ(status("GET /ws HTTP/1.1\r\nHost: x\r\nUpgrade: websocket\r\nConnection: Upgrade\r\n"
                   "Sec-WebSocket-Version: 13\r\n\r\n"),
            "HTTP/1.1 400 Bad Request");
  EXPECT_EQ(status("GET /ws HTTP/1.1\r\nHost: x\r\nUpgrade: websocket\r\nConnection: Upgrade\r\n"
                   "Sec-WebSocket-Key: c2hvcnQ=\r\nSec-WebSocket-Version: 13\r\n\r\n"),
            "HTTP/1.1 400 Bad Request");
  EXPECT_EQ(
      status("GET /ws HTTP/1.1\r\nHost: x\r\nConnection: Upgrade\r\n"
             "Sec-WebSocket-Key: dGhlIHNhbXBsZSBub25jZQ==\r\nSec-WebSocket-Version: 13\r\n\r\n"),
      "HTTP/1.1 400 Bad Request");
  EXPECT_EQ(
      status("GET /ws HTTP/1.1\r\nHost: x\r\nUpgrade: websocket\r\nConnection: Upgrade\r\n"
             "Sec-WebSocket-Key: dGhlIHNhbXBsZSBub25jZQ==\r\nSec-WebSocket-Version: 8\r\n\r\n"),
      "HTTP/1.1 426 Upgrade Required");
  // A request past request_max_bytes.
  EXPECT_EQ(status("GET / HTTP/1.1\r\nX: " + std::string(10'000, 'a')),
            "HTTP/1.1 431 Request Header Fields Too Large");
  const ws::ServerCounters k = s.counters();
  EXPECT_EQ(k.pages_served, 1u);
  EXPECT_EQ(k.not_found, 1u);
  EXPECT_EQ(k.bad_requests, 3u);  // POST, garbage, too long
  EXPECT_EQ(k.bad_handshakes, 4u);
  EXPECT_EQ(k.websocket_clients, 0u);
}

TEST(WebSocketServer, PushesMessagesAnswersPingAndClose) {
  std::atomic<int> n{0};
  ws::ServerConfig c = config();
  c.source = [&](std::string& m, std::uint64_t clients) {
    if (clients == 0 || n.load() >= 3)
      return false;
    m = "message " + std::to_string(n++);
    return true;
  };
  ws::Server s(std::move(c));
  RawClient cl(s.port());
  cl.handshake();
  const std::string head = cl.read_head();
  EXPECT_TRUE(head.starts_with("HTTP/1.1 101 Switching Protocols\r\n")) << head;
  EXPECT_NE(head.find("Sec-WebSocket-Accept: s3pPLMBiTxaQ9kYGzzhZRbK+xOo=\r\n"), std::string::npos);
  for (int i = 0; i < 3; ++i) {
    const auto [op, payload] = cl.read_frame();
    EXPECT_EQ(op, 0x1);
    EXPECT_EQ(payload, "message " + std::to_string(i));
  }
  EXPECT_EQ(s.clients(), 1u);
  cl.send_frame(0x1, "ignored data");
  cl.send_frame(0x9, "ping!");
  {
    const auto [op, payload] = cl.read_frame();
    EXPECT_EQ(op, 0xA);
    EXPECT_EQ(payload, "ping!");
  }
  cl.send_frame(0x8, std::string("\x03\xe8", 2));  // 1000, normal closure
  {
    const auto [op, payload] = cl.read_frame();
    EXPECT_EQ(op, 0x8);
    EXPECT_EQ(payload, std::string("\x03\xe8", 2));
  }
  EXPECT_EQ(cl.read_all(), "");  // then the server closes
  ASSERT_TRUE(eventually([&] { return s.clients() == 0; }));
  const ws::ServerCounters k = s.counters();
  EXPECT_EQ(k.websocket_clients, 1u);
  EXPECT_EQ(k.clients_closed, 1u);
  EXPECT_EQ(k.messages, 3u);
  EXPECT_EQ(k.frames_queued, 3u);
}

TEST(WebSocketServer, NewClientGetsTheLastMessageAndProtocolErrorsClose) {
  std::atomic<bool> once{false};
  ws::ServerConfig c = config();
  c.source = [&](std::string& m, std::uint64_t) {
    if (once.exchange(true))
      return false;
    m = "the last frame";
    return true;
  };
  ws::Server s(std::move(c));
  ASSERT_TRUE(eventually([&] { return s.counters().messages == 1; }));
  RawClient cl(s.port());
  cl.handshake();
  (void)cl.read_head();
  EXPECT_EQ(cl.read_frame().second, "the last frame");
  // An unmasked client frame is a protocol error (RFC 6455 sec. 5.1): close 1002.
  cl.send_frame(0x1, "x", false);
  const auto [op, payload] = cl.read_frame();
  EXPECT_EQ(op, 0x8);
  EXPECT_EQ(payload, std::string("\x03\xea", 2));
  ASSERT_TRUE(eventually([&] { return s.clients() == 0; }));
  EXPECT_EQ(s.counters().clients_closed, 1u);
}

TEST(WebSocketServer, ASlowClientIsSkippedThenClosedAndOthersCarryOn) {
  ws::ServerConfig c = config();
  c.poll_interval_ms = 1;
  c.client_buffer_bytes = 64 * 1024;
  c.slow_client_skips_max = 20;
  const std::string big(32 * 1024, 'x');
  c.source = [&](std::string& m, std::uint64_t clients) {
    if (clients == 0)
      return false;
    m = big;
    return true;
  };
  ws::Server s(std::move(c));
  RawClient slow(s.port());
  slow.handshake();  // and never reads: the kernel's buffers fill, then the server's
  // The server thread updates its counters and its client list one after the other: wait for
  // all three (under load a read between them saw the slow close counted, the close not yet).
  ASSERT_TRUE(eventually([&] {
    const ws::ServerCounters now = s.counters();
    return now.slow_clients_closed == 1 && now.clients_closed == 1 && s.clients() == 0;
  }));
  const ws::ServerCounters k = s.counters();
  EXPECT_GE(k.frames_skipped, 20u);
  EXPECT_EQ(k.clients_closed, 1u);
  EXPECT_EQ(s.clients(), 0u);
  // The server still serves.
  RawClient next(s.port());
  next.handshake();
  EXPECT_TRUE(next.read_head().starts_with("HTTP/1.1 101"));
  EXPECT_EQ(next.read_frame().second.size(), big.size());
}

TEST(WebSocketServer, RefusesClientsBeyondTheLimit) {
  ws::ServerConfig c = config();
  c.max_clients = 1;
  ws::Server s(std::move(c));
  RawClient first(s.port());
  first.handshake();
  EXPECT_TRUE(first.read_head().starts_with("HTTP/1.1 101"));
  RawClient second(s.port());
  const std::string r = second.read_all();
  EXPECT_TRUE(r.starts_with("HTTP/1.1 503 Service Unavailable")) << r;
  EXPECT_EQ(s.counters().refused, 1u);
  EXPECT_EQ(s.clients(), 1u);
}

TEST(WebSocketServer, RunningOutOfDescriptorsBacksOffInsteadOfSpinning) {
  // With the process's descriptor limit just above those in use, a client can connect (the
  // kernel queues it) but the server's accept() fails with EMFILE. The listening socket stays
  // readable; the server must stop polling it for kAcceptBackoffMs between tries (a busy loop
  // would count thousands of failures in the 0.6 s below, the back-off at most about 7), and
  // take the connection once descriptors are back.
  ws::Server s(config());
  // A page served first: the server's thread is in its loop before the limit tightens. (The
  // sanitizers' runtime checks memory through a pipe of its own; at the limit, its check of the
  // thread's start would fail and read as a bad vptr under clang's UBSan.)
  {
    RawClient warm(s.port());
    warm.send("GET / HTTP/1.1\r\nHost: x\r\n\r\n");
    ASSERT_TRUE(warm.read_all().starts_with("HTTP/1.1 200 OK\r\n"));
  }
  rlimit old{};
  ASSERT_EQ(::getrlimit(RLIMIT_NOFILE, &old), 0);
  const int lowest_free = ::dup(0);
  ASSERT_GE(lowest_free, 0);
  ::close(lowest_free);
  rlimit tight = old;
  tight.rlim_cur = static_cast<rlim_t>(lowest_free + 1);  // room for the client's socket only
  ASSERT_EQ(::setrlimit(RLIMIT_NOFILE, &tight), 0);
  std::uint64_t failures = 0, connections = 0;
  {
    RawClient c(s.port());
    const bool connected = c.connected();
    std::this_thread::sleep_for(std::chrono::milliseconds(600));
    failures = s.counters().accept_failures;
    connections = s.counters().connections;
    ASSERT_EQ(::setrlimit(RLIMIT_NOFILE, &old), 0);
    ASSERT_TRUE(connected);
    EXPECT_TRUE(eventually([&] { return s.counters().connections == 2; }));
  }
  std::cout << "accept failures in 0.6 s at the descriptor limit: " << failures << "\n";
  EXPECT_GE(failures, 1u);
  EXPECT_LE(failures, 20u);
  EXPECT_EQ(connections, 1u);  // the page before the limit only
}

TEST(WebSocketServer, ClosesASilentClient) {
  // A client that sends nothing is answered 408 once request_timeout_s has passed.
  ws::ServerConfig c = config();
  c.request_timeout_s = 0.2;
  ws::Server s(std::move(c));
  RawClient silent(s.port());
  const std::string t = silent.read_all();
  EXPECT_TRUE(t.starts_with("HTTP/1.1 408 Request Timeout")) << t;
  EXPECT_EQ(s.counters().bad_requests, 1u);
}

TEST(WebSocketServer, PortInUseIsOneLineError) {
  ws::Server s(config());
  ws::ServerConfig c = config();
  c.port = s.port();
  try {
    ws::Server again(std::move(c));
    FAIL() << "bound a port in use";
  } catch (const std::runtime_error& e) {
    EXPECT_EQ(std::string(e.what()), s.address() + ": cannot listen: Address already in use");
  }
  ws::ServerConfig bad = config();
  bad.host = "no.such.host.invalid";
  EXPECT_THROW(ws::Server x(std::move(bad)), std::runtime_error);
}

}  // namespace
