// The Modbus TCP server (io/modbus.hpp) against hostile clients, one kind at a time, on raw
// sockets: each gets the documented answer (an exception code, or the connection closed) and
// lands in its own counter, while a well-behaved client on another connection keeps being
// answered. Requests are built here from the protocol documents (Modbus application protocol
// v1.1b3; messaging on TCP/IP implementation guide v1.0b, MBAP header sec. 3.1.3). Waits are
// bounded polls on a condition; no assertion is about elapsed time.
// The 50-client acceptance run is tests/io/check_modbus_hostile.py.

#include <arpa/inet.h>
#include <gtest/gtest.h>
#include <netinet/in.h>
#include <poll.h>
#include <sys/socket.h>
#include <unistd.h>

#include <array>
#include <chrono>
#include <cstdint>
#include <string>
#include <thread>
#include <vector>

#include "io/modbus.hpp"

namespace {

using namespace radar_emu::io;
using namespace radar_emu::io::modbus;

template <typename F>
bool eventually(F done, double timeout_s = 5.0) {
  const auto until = std::chrono::steady_clock::now() + std::chrono::duration<double>(timeout_s);
  while (!done()) {
    if (std::chrono::steady_clock::now() > until)
      return false;
    std::this_thread::sleep_for(std::chrono::milliseconds(2));
  }
  return true;
}

using Bytes = std::vector<std::uint8_t>;

// MBAP header + PDU; `length` overrides the length field (unit id + PDU).
Bytes adu(std::uint16_t tid, const Bytes& pdu, std::uint16_t protocol = 0, int length = -1,
          std::uint8_t unit = 1) {
  const auto len =
      static_cast<std::uint16_t>(length >= 0 ? length : static_cast<int>(pdu.size()) + 1);
  Bytes b = {static_cast<std::uint8_t>(tid >> 8),
             static_cast<std::uint8_t>(tid),
             static_cast<std::uint8_t>(protocol >> 8),
             static_cast<std::uint8_t>(protocol),
             static_cast<std::uint8_t>(len >> 8),
             static_cast<std::uint8_t>(len),
             unit};
  b.insert(b.end(), pdu.begin(), pdu.end());
  return b;
}

Bytes read_pdu(std::uint16_t address, std::uint16_t quantity) {
  return {0x03, static_cast<std::uint8_t>(address >> 8), static_cast<std::uint8_t>(address),
          static_cast<std::uint8_t>(quantity >> 8), static_cast<std::uint8_t>(quantity)};
}

// A raw TCP client.
class Raw {
 public:
  explicit Raw(std::uint16_t port, int rcvbuf = 0) {
    fd_ = ::socket(AF_INET, SOCK_STREAM | SOCK_CLOEXEC, 0);
    if (rcvbuf > 0)
      (void)setsockopt(fd_, SOL_SOCKET, SO_RCVBUF, &rcvbuf, sizeof(rcvbuf));
    sockaddr_in a{};
    a.sin_family = AF_INET;
    a.sin_addr.s_addr = htonl(INADDR_LOOPBACK);
    a.sin_port = htons(port);
    ok_ = ::connect(fd_, reinterpret_cast<sockaddr*>(&a), sizeof(a)) == 0;
  }
  ~Raw() { ::close(fd_); }
  Raw(const Raw&) = delete;
  Raw& operator=(const Raw&) = delete;
  [[nodiscard]] bool ok() const { return ok_; }
  bool send(const Bytes& b) {
    return ::send(fd_, b.data(), b.size(), MSG_NOSIGNAL) == static_cast<ssize_t>(b.size());
  }
  // Up to `n` bytes, waiting at most `timeout_ms` for them; fewer on EOF or time-out.
  Bytes recv(std::size_t n, int timeout_ms = 3000) {
    Bytes out;
    const auto until = std::chrono::steady_clock::now() + std::chrono::milliseconds(timeout_ms);
    while (out.size() < n) {
      const auto left = std::chrono::duration_cast<std::chrono::milliseconds>(
                            until - std::chrono::steady_clock::now())
                            .count();
      pollfd p{fd_, POLLIN, 0};
      if (left <= 0 || ::poll(&p, 1, static_cast<int>(left)) <= 0)
        break;
      std::array<std::uint8_t, 512> buf{};
      const ssize_t r = ::recv(fd_, buf.data(), std::min(buf.size(), n - out.size()), 0);
      if (r <= 0) {
        eof_ = true;
        break;
      }
      out.insert(out.end(), buf.begin(), buf.begin() + r);
    }
    return out;
  }
  // True when the server has closed the connection (EOF or reset) within `timeout_ms`.
  bool closed_by_server(int timeout_ms = 5000) {
    (void)recv(1, timeout_ms);
    return eof_;
  }

 private:
  int fd_ = -1;
  bool ok_ = false;
  bool eof_ = false;
};

Bytes exception_answer(std::uint16_t tid, std::uint8_t fc, std::uint8_t code) {
  return {static_cast<std::uint8_t>(tid >> 8),
          static_cast<std::uint8_t>(tid),
          0,
          0,
          0,
          3,
          1,
          static_cast<std::uint8_t>(fc | 0x80),
          code};
}

struct Fixture {
  ModbusServer server;
  std::vector<std::uint16_t> image;
  explicit Fixture(ModbusServerConfig c) : server(std::move(c)), image(10) {
    for (std::size_t i = 0; i < image.size(); ++i)
      image[i] = static_cast<std::uint16_t>(0xB000 + i);
    (void)server.publish(image);
  }
  static ModbusServerConfig config() {
    return {.endpoint = "tcp:127.0.0.1:0", .start_address = 100, .register_count = 10};
  }
};

TEST(ModbusHostile, ReadIsAnsweredFromTheImage) {
  Fixture f(Fixture::config());
  Raw c(f.server.port());
  ASSERT_TRUE(c.ok());
  ASSERT_TRUE(c.send(adu(0x1234, read_pdu(102, 3), 0, -1, 77)));
  // Transaction id and unit id echoed, length 1 + 2 + 6, byte count 6, three registers.
  EXPECT_EQ(c.recv(15),
            (Bytes{0x12, 0x34, 0, 0, 0, 9, 77, 0x03, 6, 0xB0, 0x02, 0xB0, 0x03, 0xB0, 0x04}));
  EXPECT_EQ(f.server.counters().reads, 1u);
}

TEST(ModbusHostile, EachKindOfBadRequestGetsItsAnswerAndCounter) {
  Fixture f(Fixture::config());
  Raw c(f.server.port());
  ASSERT_TRUE(c.ok());
  // Unknown functions (also 0x01/0x02/0x04: no coils or input registers), and writes: 1.
  for (const std::uint8_t fc : Bytes{0x01, 0x02, 0x04, 0x07, 0x2B, 0x41, 0x83, 0xFF}) {
    ASSERT_TRUE(c.send(adu(7, {fc, 0, 0, 0, 1})));
    EXPECT_EQ(c.recv(9), exception_answer(7, fc, 0x01)) << int{fc};
  }
  for (const std::uint8_t fc : Bytes{0x05, 0x06, 0x0F, 0x10, 0x16, 0x17}) {
    ASSERT_TRUE(c.send(adu(8, {fc, 0, 100, 0, 1, 2, 0, 0})));
    EXPECT_EQ(c.recv(9), exception_answer(8, fc, 0x01)) << int{fc};
  }
  // 0x03 with a PDU of the wrong length: 3 (illegal data value).
  ASSERT_TRUE(c.send(adu(9, {0x03, 0, 100})));
  EXPECT_EQ(c.recv(9), exception_answer(9, 0x03, 0x03));
  ASSERT_TRUE(c.send(adu(10, {0x03, 0, 100, 0, 1, 0xEE})));
  EXPECT_EQ(c.recv(9), exception_answer(10, 0x03, 0x03));
  // Quantity 0 or above 125: 3, even outside the table (sec. 6.3: quantity is checked first).
  ASSERT_TRUE(c.send(adu(11, read_pdu(100, 0))));
  EXPECT_EQ(c.recv(9), exception_answer(11, 0x03, 0x03));
  ASSERT_TRUE(c.send(adu(12, read_pdu(5000, 126))));
  EXPECT_EQ(c.recv(9), exception_answer(12, 0x03, 0x03));
  // Outside the table: 2.
  ASSERT_TRUE(c.send(adu(13, read_pdu(99, 2))));
  EXPECT_EQ(c.recv(9), exception_answer(13, 0x03, 0x02));
  ASSERT_TRUE(c.send(adu(14, read_pdu(109, 2))));
  EXPECT_EQ(c.recv(9), exception_answer(14, 0x03, 0x02));
  // Requests split into single bytes are put together.
  const Bytes req = adu(15, read_pdu(109, 1));
  for (const std::uint8_t b : req)
    ASSERT_TRUE(c.send({b}));
  EXPECT_EQ(c.recv(11), (Bytes{0, 15, 0, 0, 0, 5, 1, 0x03, 2, 0xB0, 0x09}));
  // Two requests in one segment: two answers.
  Bytes two = adu(16, read_pdu(100, 1));
  const Bytes second = adu(17, read_pdu(101, 1));
  two.insert(two.end(), second.begin(), second.end());
  ASSERT_TRUE(c.send(two));
  EXPECT_EQ(c.recv(22), (Bytes{0, 16, 0, 0, 0, 5, 1, 0x03, 2, 0xB0, 0x00,
                               0, 17, 0, 0, 0, 5, 1, 0x03, 2, 0xB0, 0x01}));

  // The answer is counted just after it is sent.
  ASSERT_TRUE(eventually([&] { return f.server.counters().replies == 23; }));
  const ModbusServerCounters k = f.server.counters();
  EXPECT_EQ(k.unknown_function, 8u);
  EXPECT_EQ(k.refused_writes, 6u);
  EXPECT_EQ(k.bad_length, 2u);
  EXPECT_EQ(k.illegal_quantity, 2u);
  EXPECT_EQ(k.illegal_address, 2u);
  EXPECT_EQ(k.reads, 3u);
  EXPECT_EQ(k.requests, 23u);
  EXPECT_EQ(k.malformed_mbap, 0u);
}

TEST(ModbusHostile, MalformedMbapClosesTheConnectionOnly) {
  Fixture f(Fixture::config());
  ModbusClient good({.endpoint = "tcp:127.0.0.1:" + std::to_string(f.server.port())});
  std::array<std::uint16_t, 2> out{};
  const struct {
    std::uint16_t protocol;
    int length;
  } cases[] = {{1, -1}, {0xFFFF, -1}, {0, 0}, {0, 1}, {0, 255}, {0, 65535}};
  for (const auto& bad : cases) {
    Raw c(f.server.port());
    ASSERT_TRUE(c.ok());
    ASSERT_TRUE(c.send(adu(1, read_pdu(100, 1), bad.protocol, bad.length)));
    EXPECT_TRUE(c.closed_by_server());
    EXPECT_EQ(good.read_holding(100, out), RegisterStatus::kOk);  // others unaffected
  }
  EXPECT_EQ(out[0], 0xB000);
  EXPECT_EQ(f.server.counters().malformed_mbap, 6u);
  EXPECT_TRUE(eventually([&] { return f.server.counters().replies == 6; }));  // the good one's
}

TEST(ModbusHostile, PipelinedRequestsAreAllAnsweredAndAMalformedOneAfterThemCounted) {
  Fixture f(Fixture::config());
  Raw c(f.server.port());
  ASSERT_TRUE(c.ok());
  // Ten reads in one segment (more than one round's share), then a header with protocol id 9.
  Bytes burst;
  for (std::uint16_t i = 0; i < 10; ++i) {
    const Bytes r = adu(i, read_pdu(static_cast<std::uint16_t>(100 + i), 1));
    burst.insert(burst.end(), r.begin(), r.end());
  }
  const Bytes bad = adu(99, read_pdu(100, 1), 9);
  burst.insert(burst.end(), bad.begin(), bad.end());
  ASSERT_TRUE(c.send(burst));
  const Bytes answers = c.recv(10 * 11);
  ASSERT_EQ(answers.size(), 110u);
  for (std::size_t i = 0; i < 10; ++i) {
    EXPECT_EQ(answers[11 * i + 1], i);                              // transaction id
    EXPECT_EQ(answers[11 * i + 10], static_cast<std::uint8_t>(i));  // register 0xB00i
  }
  EXPECT_TRUE(c.closed_by_server(500));  // at once, not after the request time-out
  EXPECT_EQ(f.server.counters().malformed_mbap, 1u);
  EXPECT_EQ(f.server.counters().incomplete, 0u);
}

TEST(ModbusHostile, StalledRequestNeitherBlocksOthersNorHoldsItsSlot) {
  auto cfg = Fixture::config();
  cfg.request_timeout_s = 0.3;
  Fixture f(cfg);
  // Half a header, then nothing (a stalled or half-open peer).
  Raw stalled(f.server.port());
  ASSERT_TRUE(stalled.ok());
  ASSERT_TRUE(stalled.send({0, 1, 0}));
  Raw trickle(f.server.port());  // a whole request but one byte short
  const Bytes req = adu(2, read_pdu(100, 1));
  ASSERT_TRUE(trickle.send(Bytes(req.begin(), req.end() - 1)));
  // A well-behaved client is answered at once meanwhile: a 50 ms response time-out would not
  // be met by a server waiting on the stalled peers.
  ModbusClient good(
      {.endpoint = "tcp:127.0.0.1:" + std::to_string(f.server.port()), .response_timeout_s = 0.05});
  std::array<std::uint16_t, 10> out{};
  for (int i = 0; i < 20; ++i)
    ASSERT_EQ(good.read_holding(100, out), RegisterStatus::kOk);
  EXPECT_EQ(good.counters().timeouts, 0u);
  // Both stalled connections are closed once the request time-out passes, and counted.
  EXPECT_TRUE(stalled.closed_by_server());
  EXPECT_TRUE(trickle.closed_by_server());
  EXPECT_TRUE(eventually([&] { return f.server.counters().incomplete == 2; }));
}

TEST(ModbusHostile, SilentConnectionsAreClosedAfterTheIdleTimeout) {
  auto cfg = Fixture::config();
  cfg.idle_timeout_s = 0.2;
  Fixture f(cfg);
  Raw silent(f.server.port());
  ASSERT_TRUE(silent.ok());
  EXPECT_TRUE(silent.closed_by_server());
  EXPECT_TRUE(eventually([&] { return f.server.counters().idle_closed == 1; }));
}

TEST(ModbusHostile, ConnectionFloodEvictsIdleSlotsAndRefusesTheRest) {
  auto cfg = Fixture::config();
  cfg.max_clients = 3;
  cfg.evict_idle_s = 0.5;  // far longer than the fourth takes to arrive, even on a loaded machine
  Fixture f(cfg);
  ModbusClient good({.endpoint = "tcp:127.0.0.1:" + std::to_string(f.server.port())});
  std::array<std::uint16_t, 1> out{};
  ASSERT_EQ(good.read_holding(100, out), RegisterStatus::kOk);
  // Two idle connections fill the other slots; a fourth is refused while they are fresh.
  Raw idle1(f.server.port()), idle2(f.server.port());
  ASSERT_TRUE(eventually([&] { return f.server.counters().clients_accepted == 3; }));
  Raw fourth(f.server.port());
  EXPECT_TRUE(fourth.closed_by_server());
  EXPECT_TRUE(eventually([&] { return f.server.counters().clients_refused == 1; }));
  // Once they have been idle for evict_idle_s, a newcomer takes the place of the idlest, while
  // the client that keeps polling keeps its slot.
  for (int i = 0; i < 35; ++i) {  // 0.7 s
    ASSERT_EQ(good.read_holding(100, out), RegisterStatus::kOk);
    std::this_thread::sleep_for(std::chrono::milliseconds(20));
  }
  Raw fifth(f.server.port());
  ASSERT_TRUE(fifth.ok());
  EXPECT_TRUE(idle1.closed_by_server());
  ASSERT_TRUE(fifth.send(adu(3, read_pdu(100, 1))));
  EXPECT_EQ(fifth.recv(11).size(), 11u);
  EXPECT_EQ(good.read_holding(100, out), RegisterStatus::kOk);
  EXPECT_EQ(good.counters().disconnected, 0u);
  EXPECT_EQ(f.server.counters().clients_evicted, 1u);
}

TEST(ModbusHostile, ClientThatDoesNotReadItsAnswersIsDropped) {
  auto cfg = Fixture::config();
  cfg.register_count = 125;
  ModbusServer server(cfg);
  Raw hog(server.port(), 4096);  // small receive buffer, never read
  ASSERT_TRUE(hog.ok());
  // Pipelined reads of 125 registers (257-byte answers) until the server gives up on it.
  Bytes burst;
  for (int i = 0; i < 64; ++i) {
    const Bytes r = adu(static_cast<std::uint16_t>(i), read_pdu(100, 125));
    burst.insert(burst.end(), r.begin(), r.end());
  }
  const bool dropped =
      eventually([&] { return !hog.send(burst) || server.counters().send_failures > 0; }, 20.0);
  EXPECT_TRUE(dropped);
  EXPECT_TRUE(eventually([&] { return server.counters().send_failures == 1; }));
  ModbusClient good({.endpoint = "tcp:127.0.0.1:" + std::to_string(server.port())});
  std::array<std::uint16_t, 125> out{};
  EXPECT_EQ(good.read_holding(100, out), RegisterStatus::kOk);
}

}  // namespace
