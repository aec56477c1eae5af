// Modbus backends (io/modbus.hpp) on loopback TCP with ephemeral ports, and on RTU over a socat
// pty pair. Waits are bounded polls on a condition (never a bare sleep), and no assertion is
// about elapsed time.

#include "io/modbus.hpp"

#include <gtest/gtest.h>
#include <netinet/in.h>
#include <signal.h>
#include <spawn.h>
#include <sys/socket.h>
#include <sys/stat.h>
#include <sys/wait.h>
#include <unistd.h>

#include <atomic>
#include <chrono>
#include <cmath>
#include <cstdlib>
#include <filesystem>
#include <mutex>
#include <stdexcept>
#include <string>
#include <thread>
#include <vector>

#include "common/units.hpp"
#include "io/modbus_map.hpp"
#include "sim_bus/loopback_registers.hpp"
#include "sim_bus/nav_register_player.hpp"
#include "tests/alloc_counter.hpp"

extern char** environ;

namespace {

using namespace radar_emu::io;
using namespace radar_emu::io::modbus;
namespace common = radar_emu::common;
using radar_emu::io::canas::Field;

// Polls `done` every 2 ms until it holds or `timeout_s` passes.
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

std::string tcp(std::uint16_t port) {
  return "tcp:127.0.0.1:" + std::to_string(port);
}

// Reads `n` registers from `address` in requests of at most 125.
RegisterStatus read_all(RegisterBank& bank, std::uint16_t address,
                        std::vector<std::uint16_t>& out) {
  for (std::size_t done = 0; done < out.size();) {
    const std::size_t n = std::min(kModbusMaxReadRegisters, out.size() - done);
    const RegisterStatus s = bank.read_holding(static_cast<std::uint16_t>(address + done),
                                               std::span(out).subspan(done, n));
    if (s != RegisterStatus::kOk)
      return s;
    done += n;
  }
  return RegisterStatus::kOk;
}

// A TCP socket that listens on 127.0.0.1 (ephemeral port) and never accepts or answers: the
// kernel completes connections into its backlog, requests go unanswered.
class SilentListener {
 public:
  SilentListener() {
    fd_ = ::socket(AF_INET, SOCK_STREAM | SOCK_CLOEXEC, 0);
    sockaddr_in a{};
    a.sin_family = AF_INET;
    a.sin_addr.s_addr = htonl(INADDR_LOOPBACK);
    socklen_t len = sizeof(a);
    if (fd_ < 0 || ::bind(fd_, reinterpret_cast<sockaddr*>(&a), len) != 0 ||
        ::listen(fd_, 4) != 0 || ::getsockname(fd_, reinterpret_cast<sockaddr*>(&a), &len) != 0) {
      throw std::runtime_error("silent listener: socket setup failed");
    }
    port_ = ntohs(a.sin_port);
  }
  ~SilentListener() { ::close(fd_); }
  [[nodiscard]] std::uint16_t port() const { return port_; }

 private:
  int fd_ = -1;
  std::uint16_t port_ = 0;
};

// ---- Endpoints ------------------------------------------------------------------------------

TEST(ModbusEndpointSpec, ParsesTcpAndRtu) {
  ModbusEndpoint e = parse_modbus_endpoint("tcp:127.0.0.1:1502");
  EXPECT_EQ(e.kind, ModbusEndpoint::Kind::kTcp);
  EXPECT_EQ(e.host, "127.0.0.1");
  EXPECT_EQ(e.port, 1502);
  e = parse_modbus_endpoint("ins.local:502");
  EXPECT_EQ(e.host, "ins.local");
  e = parse_modbus_endpoint("tcp:[::1]:0");
  EXPECT_EQ(e.host, "::1");
  EXPECT_EQ(e.port, 0);
  EXPECT_EQ(to_string(e), "tcp:[::1]:0");
  e = parse_modbus_endpoint("rtu:/dev/ttyUSB0:115200");
  EXPECT_EQ(e.kind, ModbusEndpoint::Kind::kRtu);
  EXPECT_EQ(e.device, "/dev/ttyUSB0");
  EXPECT_EQ(e.baud, 115200);
  EXPECT_EQ(e.parity, 'N');
  e = parse_modbus_endpoint("rtu:/dev/ttyS1:9600:7E2");
  EXPECT_EQ(e.data_bits, 7);
  EXPECT_EQ(e.parity, 'E');
  EXPECT_EQ(e.stop_bits, 2);
  EXPECT_EQ(to_string(e), "rtu:/dev/ttyS1:9600:7E2");
}

TEST(ModbusEndpointSpec, RejectsMalformedSpecsWithOneLine) {
  for (const char* bad : {"", "tcp:", "tcp:host", "tcp::502", "tcp:host:65536", "tcp:host:-1",
                          "tcp:host:50x", "::1:502", "tcp:[::1]502", "rtu:", "rtu:/dev/x",
                          "rtu:/dev/x:fast", "rtu:/dev/x:9600:8X1", "rtu::9600"}) {
    try {
      (void)parse_modbus_endpoint(bad);
      ADD_FAILURE() << "accepted '" << bad << "'";
    } catch (const std::invalid_argument& e) {
      const std::string msg = e.what();
      EXPECT_NE(msg.find(std::string("'") + bad + "'"), std::string::npos) << msg;
      EXPECT_EQ(msg.find('\n'), std::string::npos) << msg;
    }
  }
}

// ---- Client <-> server on loopback TCP -------------------------------------------------------

TEST(ModbusTcp, ClientReadsBackAPublishedDetectionTable) {
  const DetectionTableConfig table{.base_address = 1000, .max_detections = 16};
  const std::size_t n = detection_table_registers(table);
  ModbusServer server(
      {.endpoint = "tcp:127.0.0.1:0", .start_address = table.base_address, .register_count = n});
  ASSERT_NE(server.port(), 0);
  EXPECT_EQ(server.address(), "127.0.0.1:" + std::to_string(server.port()));

  std::vector<icd::Detection> dets(11);
  for (std::size_t i = 0; i < dets.size(); ++i) {
    dets[i].range_m = 100.0 + 37.5 * static_cast<double>(i);
    dets[i].azimuth_deg = -10.0 + static_cast<double>(i);
    dets[i].snr_db = 13.0;
  }
  icd::Header h;
  h.frame_counter = 42;
  h.time_ms = 123456;
  std::vector<std::uint16_t> image(n);
  ASSERT_TRUE(encode_detection_table(h, dets, image, table).ok);
  ASSERT_TRUE(server.publish(image));

  ModbusClient client({.endpoint = tcp(server.port())});
  EXPECT_TRUE(client.connected());
  std::vector<std::uint16_t> got(n);
  ASSERT_EQ(read_all(client, table.base_address, got), RegisterStatus::kOk);
  EXPECT_EQ(got, image);
  icd::DetectionList list;
  ASSERT_EQ(decode_detection_table(got, table, list), TableDecodeStatus::kOk);
  ASSERT_EQ(list.count, dets.size());
  EXPECT_EQ(list.header.time_ms, 123456u);
  for (std::size_t i = 0; i < dets.size(); ++i) {
    EXPECT_EQ(list.detections[i].range_m, dets[i].range_m);  // exact in float32
    EXPECT_EQ(list.detections[i].azimuth_deg, dets[i].azimuth_deg);
  }

  // A newer image is what the next request sees.
  h.frame_counter = 43;
  ASSERT_TRUE(encode_detection_table(h, std::span(dets).first(2), image, table).ok);
  ASSERT_TRUE(server.publish(image));
  ASSERT_EQ(read_all(client, table.base_address, got), RegisterStatus::kOk);
  ASSERT_EQ(decode_detection_table(got, table, list), TableDecodeStatus::kOk);
  EXPECT_EQ(list.header.frame_counter, 43);
  EXPECT_EQ(list.count, 2u);

  // Outside the table: exception 2. Writes: refused (exception 1).
  std::array<std::uint16_t, 2> two{};
  EXPECT_EQ(client.read_holding(999, two), RegisterStatus::kIllegalAddress);
  EXPECT_EQ(client.read_holding(static_cast<std::uint16_t>(1000 + n - 1), two),
            RegisterStatus::kIllegalAddress);
  EXPECT_EQ(client.write_holding(1000, two), RegisterStatus::kError);
  EXPECT_TRUE(eventually([&] { return server.counters().refused_writes == 1; }));
  ASSERT_EQ(read_all(client, table.base_address, got), RegisterStatus::kOk);
  EXPECT_EQ(got, image);  // the write changed nothing
  EXPECT_EQ(client.counters().exceptions, 3u);
  EXPECT_EQ(client.counters().disconnected, 0u);

  // A wrong-size image is refused and counted.
  EXPECT_FALSE(server.publish(std::span(image).first(n - 1)));
  EXPECT_EQ(server.counters().publishes_rejected, 1u);
}

TEST(ModbusTcp, ServesSeveralClientsAtOnce) {
  ModbusServer server({.endpoint = "127.0.0.1:0", .register_count = 10, .max_clients = 3});
  std::vector<std::uint16_t> image(10);
  for (std::size_t i = 0; i < image.size(); ++i)
    image[i] = static_cast<std::uint16_t>(0xA000 + i);
  ASSERT_TRUE(server.publish(image));
  ModbusClient a({.endpoint = tcp(server.port())});
  ModbusClient b({.endpoint = tcp(server.port())});
  std::vector<std::uint16_t> ga(10), gb(10);
  for (int k = 0; k < 3; ++k) {
    ASSERT_EQ(read_all(a, 0, ga), RegisterStatus::kOk);
    ASSERT_EQ(read_all(b, 0, gb), RegisterStatus::kOk);
  }
  EXPECT_EQ(ga, image);
  EXPECT_EQ(gb, image);
  EXPECT_EQ(server.counters().clients_accepted, 2u);
}

TEST(ModbusTcp, ClientReconnectsAfterTheServerRestarts) {
  auto server = std::make_unique<ModbusServer>(
      ModbusServerConfig{.endpoint = "tcp:127.0.0.1:0", .register_count = 4});
  const std::uint16_t port = server->port();
  ASSERT_TRUE(server->publish(std::vector<std::uint16_t>{1, 2, 3, 4}));
  ModbusClient client({.endpoint = tcp(port), .response_timeout_s = 0.5});
  std::vector<std::uint16_t> got(4);
  ASSERT_EQ(read_all(client, 0, got), RegisterStatus::kOk);
  EXPECT_EQ(got, (std::vector<std::uint16_t>{1, 2, 3, 4}));

  server.reset();  // the server goes away: the link breaks
  EXPECT_NE(read_all(client, 0, got), RegisterStatus::kOk);
  EXPECT_FALSE(client.connected());

  server = std::make_unique<ModbusServer>(
      ModbusServerConfig{.endpoint = tcp(port), .register_count = 4});
  ASSERT_EQ(server->port(), port);
  ASSERT_TRUE(server->publish(std::vector<std::uint16_t>{5, 6, 7, 8}));
  EXPECT_TRUE(eventually([&] { return read_all(client, 0, got) == RegisterStatus::kOk; }));
  EXPECT_EQ(got, (std::vector<std::uint16_t>{5, 6, 7, 8}));
  EXPECT_EQ(client.counters().reconnects, 1u);
  EXPECT_GE(client.counters().disconnected, 1u);
}

TEST(ModbusTcp, TimesOutWhenNobodyAnswers) {
  SilentListener silent;
  ModbusClient client(
      {.endpoint = tcp(silent.port()), .response_timeout_s = 0.1, .timeouts_before_reconnect = 2});
  ASSERT_TRUE(client.connected());  // the kernel accepted into the backlog
  std::array<std::uint16_t, 4> out{};
  EXPECT_EQ(client.read_holding(0, out), RegisterStatus::kTimeout);
  EXPECT_TRUE(client.connected());
  EXPECT_EQ(client.read_holding(0, out), RegisterStatus::kTimeout);
  EXPECT_FALSE(client.connected());  // two timeouts in a row drop the link
  EXPECT_EQ(client.read_holding(0, out), RegisterStatus::kTimeout);  // reconnected, silent again
  const ModbusClientCounters c = client.counters();
  EXPECT_EQ(c.timeouts, 3u);
  EXPECT_EQ(c.reconnects, 1u);
  EXPECT_EQ(c.ok, 0u);
}

TEST(ModbusTcp, RefusedConnectionIsCountedNotThrown) {
  std::uint16_t port = 0;
  {
    SilentListener gone;  // take a free port, then free it: nobody listens there
    port = gone.port();
  }
  ModbusClient client({.endpoint = tcp(port), .reconnect_interval_s = 0.0});
  EXPECT_FALSE(client.connected());
  std::array<std::uint16_t, 1> out{};
  EXPECT_EQ(client.read_holding(0, out), RegisterStatus::kDisconnected);
  EXPECT_GE(client.counters().connect_failures, 2u);
  EXPECT_EQ(client.counters().reconnects, 0u);
}

TEST(ModbusTcp, SetupErrorsAreOneLine) {
  ModbusServer first({.endpoint = "tcp:127.0.0.1:0", .register_count = 1});
  try {
    ModbusServer second({.endpoint = tcp(first.port()), .register_count = 1});
    ADD_FAILURE() << "two servers listen on one port";
  } catch (const std::runtime_error& e) {
    const std::string msg = e.what();
    EXPECT_NE(msg.find("cannot listen on 127.0.0.1:" + std::to_string(first.port())),
              std::string::npos)
        << msg;
    EXPECT_EQ(msg.find('\n'), std::string::npos);
  }
  EXPECT_THROW(ModbusServer({.endpoint = "tcp:127.0.0.1:0", .register_count = 0}),
               std::invalid_argument);
  EXPECT_THROW(
      ModbusServer({.endpoint = "tcp:127.0.0.1:0", .start_address = 65000, .register_count = 600}),
      std::invalid_argument);
  EXPECT_THROW(ModbusServer({.endpoint = "rtu:/nonexistent/tty:9600", .register_count = 1}),
               std::runtime_error);
  EXPECT_THROW(ModbusClient({.endpoint = "tcp:127.0.0.1:0"}), std::invalid_argument);
  EXPECT_THROW(ModbusClient({.endpoint = "tcp:127.0.0.1:502", .response_timeout_s = 0.0}),
               std::invalid_argument);
  EXPECT_THROW(ModbusClient({.endpoint = "rtu:/dev/null:9600", .unit_id = 0}),
               std::invalid_argument);
}

// ---- Navigation poller ----------------------------------------------------------------------

radar_emu::sim_bus::Trajectory straight_line() {
  radar_emu::sim_bus::AircraftState a, b;
  a.time_s = 0.0;
  a.latitude_rad = common::radians(51.47);
  a.longitude_rad = common::radians(-0.46);
  a.height_m = 300.0;
  a.pitch_rad = common::radians(-3.0);
  a.roll_rad = common::radians(1.0);
  a.true_heading_rad = common::radians(90.0);
  a.vel_east_mps = 70.0;
  a.vel_up_mps = -3.5;
  b = a;
  b.time_s = 10.0;
  b.longitude_rad = a.longitude_rad + 1e-4;
  b.height_m = 265.0;
  return radar_emu::sim_bus::Trajectory({a, b});
}

TEST(ModbusNavPoller, DeliversTheServedStateAndGoesStaleWhenTheSenderFreezes) {
  const NavMapConfig map{.base_address = 200};
  ModbusServer server({.endpoint = "tcp:127.0.0.1:0",
                       .start_address = map.base_address,
                       .register_count = nav_register_count(map)});
  radar_emu::sim_bus::NavRegisterPlayer player(straight_line(), {.map = map, .rate_hz = 50.0});
  ASSERT_EQ(player.publish_until(0.0, server), 1u);  // the player writes the server's table

  ModbusClient client({.endpoint = tcp(server.port())});
  std::atomic<std::int64_t> fake_now{1000};
  NavPoller poller(client,
                   {.map = map, .period_s = 0.005, .clock_ns = [&] { return fake_now.load(); }});
  canas::OwnshipState st;
  ASSERT_TRUE(eventually([&] {
    (void)poller.latest(st);
    return st.all_fresh(1000, 0);
  }));
  const auto want = straight_line().at(0.0);
  EXPECT_NEAR(st[Field::kLatitude].value, want.latitude_rad, 1e-15);
  EXPECT_NEAR(st[Field::kLongitude].value, want.longitude_rad, 1e-15);
  EXPECT_NEAR(st[Field::kHeight].value, 300.0, 1e-12);
  EXPECT_NEAR(st[Field::kTrueHeading].value, want.true_heading_rad, 1e-7);
  EXPECT_NEAR(st[Field::kVelEast].value, 70.0, 1e-12);
  EXPECT_NEAR(st[Field::kVelUp].value, -3.5, 1e-12);

  // The sender freezes: polls go on, samples are stale, the fields keep their time stamp.
  fake_now = 2000;
  const std::uint64_t stale_before = poller.counters().decoder.stale;
  ASSERT_TRUE(eventually([&] { return poller.counters().decoder.stale >= stale_before + 3; }));
  EXPECT_FALSE(poller.latest(st));
  EXPECT_EQ(st[Field::kHeight].updated_ns, 1000);

  // A new update (counter +1) is taken with the new time.
  ASSERT_EQ(player.publish_until(0.02, server), 1u);
  ASSERT_TRUE(eventually([&] {
    (void)poller.latest(st);
    return st[Field::kHeight].updated_ns == 2000;
  }));
  EXPECT_NEAR(st[Field::kHeight].value, straight_line().at(0.02).height_m, 1e-4);
  const NavPollerCounters c = poller.counters();
  EXPECT_EQ(c.decoder.rejected(), 0u);
  EXPECT_EQ(c.decoder.new_samples, 2u);
  EXPECT_EQ(c.timeouts, 0u);
  poller.stop();
}

TEST(ModbusNavPoller, CountsTimeoutsAndPublishesNothing) {
  SilentListener silent;
  ModbusClient client({.endpoint = tcp(silent.port()), .response_timeout_s = 0.05});
  NavPoller poller(client, {.period_s = 0.01});
  ASSERT_TRUE(eventually([&] { return poller.counters().timeouts >= 2; }));
  canas::OwnshipState st;
  EXPECT_FALSE(poller.latest(st));
  for (const auto& f : st.fields)
    EXPECT_FALSE(f.received);
  EXPECT_EQ(poller.counters().published, 0u);
  poller.stop();  // returns although a read may be blocked in its timeout
}

// A bank whose reads follow a script (then repeat its last entry): what a source does over
// time, without timing.
class ScriptedBank final : public RegisterBank {
 public:
  explicit ScriptedBank(std::vector<RegisterStatus> script) : script_(std::move(script)) {}
  RegisterStatus read_holding(std::uint16_t, std::span<std::uint16_t> out) noexcept override {
    std::fill(out.begin(), out.end(), std::uint16_t{0});
    const std::size_t i = std::min(next_.fetch_add(1), script_.size() - 1);
    return script_[i];
  }
  RegisterStatus write_holding(std::uint16_t, std::span<const std::uint16_t>) noexcept override {
    return RegisterStatus::kError;
  }
  [[nodiscard]] bool done() const { return next_.load() >= script_.size() + 2; }

 private:
  std::vector<RegisterStatus> script_;
  std::atomic<std::size_t> next_{0};
};

TEST(ModbusNavPoller, ReportsUnreachableLostAndRecoveredSources) {
  using S = RegisterStatus;
  using K = NavLinkEvent::Kind;
  // Refused twice (unreachable), up; two time-outs (not an outage: fewer than
  // kFailedReadsForDown), up; three time-outs (lost), up; a broken link (lost at once), up.
  ScriptedBank bank({S::kDisconnected, S::kDisconnected, S::kOk, S::kOk, S::kTimeout, S::kTimeout,
                     S::kOk, S::kTimeout, S::kTimeout, S::kTimeout, S::kOk, S::kOk,
                     S::kDisconnected, S::kDisconnected, S::kOk});
  std::mutex m;
  std::vector<NavLinkEvent> events;
  NavPoller poller(bank, {.period_s = 0.001, .on_link = [&](const NavLinkEvent& e) {
                            std::lock_guard<std::mutex> lock(m);
                            events.push_back(e);
                          }});
  ASSERT_TRUE(eventually([&] { return bank.done(); }));
  poller.stop();
  ASSERT_EQ(events.size(), 6u);
  EXPECT_EQ(events[0].kind, K::kUnreachable);
  EXPECT_EQ(events[0].status, S::kDisconnected);
  EXPECT_EQ(events[1].kind, K::kRecovered);
  EXPECT_EQ(events[1].failed_polls, 2u);
  EXPECT_EQ(events[2].kind, K::kLost);
  EXPECT_EQ(events[2].status, S::kTimeout);
  EXPECT_EQ(events[3].kind, K::kRecovered);
  EXPECT_EQ(events[3].failed_polls, 3u);
  EXPECT_EQ(events[4].kind, K::kLost);
  EXPECT_EQ(events[4].status, S::kDisconnected);
  EXPECT_EQ(events[5].kind, K::kRecovered);
  EXPECT_EQ(events[5].failed_polls, 2u);
  const NavPollerCounters c = poller.counters();
  EXPECT_EQ(c.outages, 2u);  // the unreachable start is not an outage (first_read_s says it)
  EXPECT_TRUE(c.ever_up);
  EXPECT_GT(c.first_read_s, 0.0);
  EXPECT_GT(c.outage_s_total, 0.0);
  EXPECT_LE(c.longest_outage_s, c.outage_s_total);
  EXPECT_EQ(poller.link_state(), NavLinkState::kUp);
  EXPECT_EQ(c.timeouts, 5u);
  EXPECT_EQ(c.disconnected, 4u);
}

TEST(ModbusNavPoller, ASourceThatNeverAnswersIsUnreachableOnce) {
  ScriptedBank bank({RegisterStatus::kTimeout});
  std::atomic<int> unreachable{0}, other{0};
  NavPoller poller(bank, {.period_s = 0.001, .on_link = [&](const NavLinkEvent& e) {
                            ++(e.kind == NavLinkEvent::Kind::kUnreachable ? unreachable : other);
                          }});
  ASSERT_TRUE(eventually([&] { return poller.counters().polls >= 20; }));
  poller.stop();
  EXPECT_EQ(unreachable.load(), 1);
  EXPECT_EQ(other.load(), 0);
  EXPECT_FALSE(poller.counters().ever_up);
  EXPECT_EQ(poller.counters().first_read_s, -1.0);
  EXPECT_EQ(poller.counters().outages, 0u);
  EXPECT_EQ(poller.link_state(), NavLinkState::kDown);
}

TEST(ModbusTcp, ConnectionAttemptsBackOff) {
  std::uint16_t port = 0;
  {
    SilentListener gone;  // a free port nobody listens on
    port = gone.port();
  }
  // 0.05 s doubling to 0.4 s: attempts at 0 (constructor), 0.05, 0.15, 0.35, 0.75, 1.15 s in
  // 1.2 s of polling every 5 ms; a fixed 0.05 s interval would make 25.
  ModbusClient client(
      {.endpoint = tcp(port), .reconnect_interval_s = 0.05, .reconnect_max_interval_s = 0.4});
  std::array<std::uint16_t, 1> out{};
  const auto until = std::chrono::steady_clock::now() + std::chrono::milliseconds(1200);
  while (std::chrono::steady_clock::now() < until) {
    EXPECT_EQ(client.read_holding(0, out), RegisterStatus::kDisconnected);
    std::this_thread::sleep_for(std::chrono::milliseconds(5));
  }
  EXPECT_GE(client.counters().connect_failures, 4u);
  EXPECT_LE(client.counters().connect_failures, 8u);
  EXPECT_DOUBLE_EQ(client.reconnect_interval_s(), 0.4);
  EXPECT_EQ(client.last_error(), ECONNREFUSED);
  EXPECT_EQ(client.last_error_text(), "Connection refused");
  EXPECT_THROW(
      ModbusClient(
          {.endpoint = tcp(port), .reconnect_interval_s = 1.0, .reconnect_max_interval_s = 0.5}),
      std::invalid_argument);
}

TEST(ModbusNavPoller, RejectsBadSettings) {
  radar_emu::sim_bus::LoopbackRegisterBank bank(0, 64);
  EXPECT_THROW(NavPoller(bank, {.period_s = 0.0}), std::invalid_argument);
  EXPECT_THROW(NavPoller(bank, {.map = {.base_address = 65530}}), std::invalid_argument);
}

// ---- Real-time safety -----------------------------------------------------------------------

// A bank that never answers: a NavPoller over it runs without allocating or touching shared
// state.
class DeadBank final : public RegisterBank {
 public:
  RegisterStatus read_holding(std::uint16_t, std::span<std::uint16_t>) noexcept override {
    return RegisterStatus::kTimeout;
  }
  RegisterStatus write_holding(std::uint16_t, std::span<const std::uint16_t>) noexcept override {
    return RegisterStatus::kTimeout;
  }
};

TEST(ModbusRealTime, FramePathCallsDoNotAllocate) {
  const DetectionTableConfig table{.max_detections = 32};
  ModbusServer server(
      {.endpoint = "tcp:127.0.0.1:0", .register_count = detection_table_registers(table)});
  DeadBank dead;
  NavPoller poller(dead, {.period_s = 0.001});
  std::vector<icd::Detection> dets(40);
  std::vector<std::uint16_t> image(detection_table_registers(table));
  NavDecoder decoder;
  NavEncoder encoder;
  std::vector<std::uint16_t> nav(nav_register_count({}));
  radar_emu::sim_bus::LoopbackRegisterBank bank(0, nav.size());
  radar_emu::sim_bus::NavRegisterPlayer player(straight_line(), {});
  canas::OwnshipState st;

  radar_emu::test::start_counting_allocations();
  for (int frame = 0; frame < 50; ++frame) {
    icd::Header h;
    h.frame_counter = static_cast<std::uint16_t>(frame);
    (void)encode_detection_table(h, dets, image, table);
    (void)server.publish(image);
    (void)poller.latest(st);
    (void)player.publish_until(0.02 * frame, bank);
    (void)bank.read_holding(0, nav);
    (void)decoder.decode(nav, frame);
    (void)encoder.encode({}, nav_status::kAllValid, 0, nav);
    (void)server.write_holding(0, std::span(nav).first(4));
  }
  const std::uint64_t allocations = radar_emu::test::stop_counting_allocations();
  EXPECT_EQ(allocations, 0u);
  EXPECT_EQ(server.counters().publishes, 100u);
}

// ---- RTU over a socat pty pair --------------------------------------------------------------

std::string find_on_path(const std::string& name) {
  const char* path = std::getenv("PATH");
  std::string p = path != nullptr ? path : "/usr/bin:/bin";
  for (std::size_t start = 0; start <= p.size();) {
    const std::size_t end = std::min(p.find(':', start), p.size());
    const std::string candidate = p.substr(start, end - start) + "/" + name;
    if (::access(candidate.c_str(), X_OK) == 0)
      return candidate;
    start = end + 1;
  }
  return {};
}

// Two linked pseudo-terminals from socat (what two serial ports joined by a cable look like).
class PtyPair {
 public:
  PtyPair(const std::string& socat, const std::filesystem::path& dir)
      : a_(dir / "a"), b_(dir / "b") {
    std::filesystem::create_directories(dir);
    std::filesystem::remove(a_);
    std::filesystem::remove(b_);
    const std::string end_a = "pty,raw,echo=0,link=" + a_.string();
    const std::string end_b = "pty,raw,echo=0,link=" + b_.string();
    std::vector<char*> argv = {const_cast<char*>(socat.c_str()), const_cast<char*>(end_a.c_str()),
                               const_cast<char*>(end_b.c_str()), nullptr};
    if (posix_spawn(&pid_, socat.c_str(), nullptr, nullptr, argv.data(), environ) != 0)
      pid_ = -1;
  }
  ~PtyPair() {
    if (pid_ > 0) {
      ::kill(pid_, SIGTERM);
      ::waitpid(pid_, nullptr, 0);
    }
  }
  [[nodiscard]] bool ready() const {
    return pid_ > 0 &&
           eventually([&] { return std::filesystem::exists(a_) && std::filesystem::exists(b_); });
  }
  [[nodiscard]] std::string a() const { return a_.string(); }
  [[nodiscard]] std::string b() const { return b_.string(); }

 private:
  std::filesystem::path a_, b_;
  pid_t pid_ = -1;
};

TEST(ModbusRtu, ClientAndServerOverAPtyPair) {
  const std::string socat = find_on_path("socat");
  if (socat.empty())
    GTEST_SKIP() << "socat not installed (Debian package socat): no pty pair for RTU";
  const auto dir = std::filesystem::temp_directory_path() /
                   ("radar_emu_modbus_rtu_" + std::to_string(::getpid()));
  PtyPair pty(socat, dir);
  ASSERT_TRUE(pty.ready()) << "socat did not create " << pty.a() << " and " << pty.b();

  ModbusServer server({.endpoint = "rtu:" + pty.a() + ":115200",
                       .start_address = 10,
                       .register_count = 26,
                       .unit_id = 7});
  EXPECT_EQ(server.port(), 0);
  std::vector<std::uint16_t> image(26);
  for (std::size_t i = 0; i < image.size(); ++i)
    image[i] = static_cast<std::uint16_t>(0x1111 * (i % 15) + i);
  ASSERT_TRUE(server.publish(image));

  {
    ModbusClient client(
        {.endpoint = "rtu:" + pty.b() + ":115200:8N1", .unit_id = 7, .response_timeout_s = 0.5});
    ASSERT_TRUE(client.connected());
    std::vector<std::uint16_t> got(26);
    ASSERT_EQ(read_all(client, 10, got), RegisterStatus::kOk);
    EXPECT_EQ(got, image);
    std::array<std::uint16_t, 1> one{};
    EXPECT_EQ(client.read_holding(9, one), RegisterStatus::kIllegalAddress);
    EXPECT_EQ(client.write_holding(10, one), RegisterStatus::kError);
  }
  // Another slave address: the server stays silent, as RTU requires (Modbus over serial line
  // v1.02, sec. 2.2: only the addressed slave replies).
  ModbusClient other(
      {.endpoint = "rtu:" + pty.b() + ":115200", .unit_id = 8, .response_timeout_s = 0.1});
  std::array<std::uint16_t, 1> one{};
  EXPECT_EQ(other.read_holding(10, one), RegisterStatus::kTimeout);
  EXPECT_TRUE(eventually([&] { return server.counters().refused_writes == 1; }));
}

}  // namespace
