// SocketCAN backend. The build machines have no kernel CAN (socket(AF_CAN) fails with
// EAFNOSUPPORT), so the tests split in three:
//   - what needs no socket: error-frame decoding from frames built by hand after
//     include/uapi/linux/can/error.h, kernel frame layouts (linux/can.h), time-stamp conversion
//     and control-message parsing (socket(7));
//   - the endpoint's real recvmsg/send path over a SOCK_SEQPACKET socketpair that carries
//     struct can_frame datagrams, with kernel SO_TIMESTAMPNS stamps;
//   - AF_CAN itself (setup error message; a vcan round trip), skipped with the reason where the
//     kernel lacks it.

#include "io/socketcan.hpp"

#include <fcntl.h>
#include <gtest/gtest.h>
#include <linux/can.h>
#include <linux/can/error.h>
#include <net/if_arp.h>
#include <sys/socket.h>
#include <unistd.h>

#include <array>
#include <cerrno>
#include <cstdlib>
#include <cstring>
#include <memory>
#include <span>
#include <stdexcept>
#include <string>

#include "io/can_error.hpp"
#include "tests/alloc_counter.hpp"

namespace radar_emu::io {
namespace {

// A classic error frame exactly as the kernel lays it out: can_id = CAN_ERR_FLAG | classes,
// len = CAN_ERR_DLC (8), data[0..7] per error.h.
can_frame error_frame(std::uint32_t classes, std::array<std::uint8_t, 8> data) {
  can_frame f{};
  f.can_id = CAN_ERR_FLAG | classes;
  f.len = CAN_ERR_DLC;
  std::memcpy(f.data, data.data(), 8);
  return f;
}

bool feed(CanErrorTracker& t, const can_frame& f) {
  return t.on_error_frame(f.can_id, std::span<const std::uint8_t, 8>(f.data, 8));
}

TEST(CanErrorTracker, DecodesStateTransitionsAsTheKernelReportsThem) {
  CanErrorTracker t(CanBusState::kErrorActive);
  // can_change_state (drivers/net/can/dev/dev.c): TX warning -> CAN_ERR_CRTL, data[1] TX_WARNING.
  EXPECT_TRUE(feed(t, error_frame(CAN_ERR_CRTL, {0, CAN_ERR_CRTL_TX_WARNING, 0, 0, 0, 0, 97, 0})));
  EXPECT_EQ(t.state(), CanBusState::kErrorWarning);
  // TX and RX both passive: both bits set, the state is passive.
  EXPECT_TRUE(feed(t, error_frame(CAN_ERR_CRTL | CAN_ERR_CNT,
                                  {0, CAN_ERR_CRTL_TX_PASSIVE | CAN_ERR_CRTL_RX_PASSIVE, 0, 0, 0, 0,
                                   130, 128})));
  EXPECT_EQ(t.state(), CanBusState::kErrorPassive);
  EXPECT_EQ(t.counters().tx_error_counter, 130);
  EXPECT_EQ(t.counters().rx_error_counter, 128);
  // Passive TX with an RX warning (tx_state > rx_state): the TX bit decides.
  EXPECT_TRUE(feed(
      t, error_frame(CAN_ERR_CRTL,
                     {0, CAN_ERR_CRTL_TX_PASSIVE | CAN_ERR_CRTL_RX_WARNING, 0, 0, 0, 0, 0, 0})));
  EXPECT_EQ(t.state(), CanBusState::kErrorPassive);
  EXPECT_TRUE(feed(t, error_frame(CAN_ERR_BUSOFF, {})));
  EXPECT_EQ(t.state(), CanBusState::kBusOff);
  EXPECT_TRUE(feed(t, error_frame(CAN_ERR_RESTARTED, {})));
  EXPECT_EQ(t.state(), CanBusState::kErrorActive);
  EXPECT_TRUE(feed(t, error_frame(CAN_ERR_CRTL, {0, CAN_ERR_CRTL_RX_WARNING, 0, 0, 0, 0, 0, 0})));
  EXPECT_EQ(t.state(), CanBusState::kErrorWarning);
  EXPECT_TRUE(feed(t, error_frame(CAN_ERR_CRTL, {0, CAN_ERR_CRTL_ACTIVE, 0, 0, 0, 0, 0, 0})));
  EXPECT_EQ(t.state(), CanBusState::kErrorActive);

  const CanErrorCounters& c = t.counters();
  EXPECT_EQ(c.error_frames, 7U);
  EXPECT_EQ(c.controller, 5U);
  EXPECT_EQ(c.error_warning, 2U);
  EXPECT_EQ(c.error_passive, 2U);
  EXPECT_EQ(c.back_to_active, 1U);
  EXPECT_EQ(c.bus_off, 1U);
  EXPECT_EQ(c.restarted, 1U);
}

TEST(CanErrorTracker, CountsEachClassAndKeepsItsDetails) {
  CanErrorTracker t;
  EXPECT_EQ(t.state(), CanBusState::kUnknown);
  // Lost arbitration in bit 5; a stuff error in the data field, on transmission; a CANH short to
  // ground; no ACK; bus error; overflows; a TX timeout: all in one frame, as a driver may send.
  const can_frame f = error_frame(
      CAN_ERR_TX_TIMEOUT | CAN_ERR_LOSTARB | CAN_ERR_CRTL | CAN_ERR_PROT | CAN_ERR_TRX |
          CAN_ERR_ACK | CAN_ERR_BUSERROR,
      {5, CAN_ERR_CRTL_RX_OVERFLOW | CAN_ERR_CRTL_TX_OVERFLOW, CAN_ERR_PROT_STUFF | CAN_ERR_PROT_TX,
       CAN_ERR_PROT_LOC_DATA, CAN_ERR_TRX_CANH_SHORT_TO_GND, 0, 0, 0});
  EXPECT_TRUE(feed(t, f));
  const CanErrorCounters& c = t.counters();
  EXPECT_EQ(c.tx_timeouts, 1U);
  EXPECT_EQ(c.lost_arbitration, 1U);
  EXPECT_EQ(c.last_lostarb_bit, 5);
  EXPECT_EQ(c.rx_overflows, 1U);
  EXPECT_EQ(c.tx_overflows, 1U);
  EXPECT_EQ(c.protocol_errors, 1U);
  EXPECT_EQ(c.last_protocol_type, 0x84);      // CAN_ERR_PROT_STUFF 0x04 | CAN_ERR_PROT_TX 0x80
  EXPECT_EQ(c.last_protocol_location, 0x0A);  // CAN_ERR_PROT_LOC_DATA
  EXPECT_EQ(c.transceiver_errors, 1U);
  EXPECT_EQ(c.last_transceiver, 0x07);  // CAN_ERR_TRX_CANH_SHORT_TO_GND
  EXPECT_EQ(c.no_ack, 1U);
  EXPECT_EQ(c.bus_errors, 1U);
  EXPECT_EQ(c.error_passive + c.error_warning + c.bus_off, 0U);
  EXPECT_EQ(t.state(), CanBusState::kUnknown);  // overflows do not change the state

  // The raw values of the classes, from error.h, so a header change would show.
  EXPECT_EQ(CAN_ERR_FLAG, 0x20000000U);
  EXPECT_EQ(CAN_ERR_BUSOFF, 0x40U);
  EXPECT_EQ(CAN_ERR_RESTARTED, 0x100U);
  // A data frame is not an error frame.
  EXPECT_FALSE(t.on_error_frame(0x123, std::span<const std::uint8_t, 8>(f.data, 8)));
  EXPECT_EQ(t.counters().error_frames, 1U);
}

TEST(SocketCanFrames, KernelLayoutsBothWays) {
  // struct can_frame (16 bytes) and canfd_frame (72): can_id at 0, len at 4, flags at 5, data at 8.
  static_assert(CAN_MTU == 16 && CANFD_MTU == 72);
  static_assert(offsetof(canfd_frame, len) == 4 && offsetof(canfd_frame, flags) == 5 &&
                offsetof(canfd_frame, data) == 8);

  CanFrame f;
  f.id = 0x1ABCDEF0;
  f.extended = true;
  f.len = 3;
  f.data[0] = 0xDE;
  f.data[1] = 0xAD;
  f.data[2] = 0xBE;
  canfd_frame kf;
  ASSERT_EQ(to_kernel_frame(f, kf), CAN_MTU);
  EXPECT_EQ(kf.can_id, 0x9ABCDEF0U);  // CAN_EFF_FLAG 0x80000000 | id
  EXPECT_EQ(kf.len, 3);
  EXPECT_EQ(kf.data[2], 0xBE);
  EXPECT_EQ(kf.data[3], 0);

  CanFrame back;
  ASSERT_EQ(from_kernel_frame(kf, CAN_MTU, back), KernelFrameKind::kData);
  EXPECT_EQ(back.id, f.id);
  EXPECT_TRUE(back.extended);
  EXPECT_FALSE(back.fd);
  EXPECT_EQ(back.len, 3);
  EXPECT_EQ(back.data, f.data);

  CanFrame fd;
  fd.id = 0x7FF;
  fd.fd = true;
  fd.fd_flags = 0x3;  // BRS | ESI in candump's nibble
  fd.len = 12;
  for (int i = 0; i < 12; ++i)
    fd.data[static_cast<std::size_t>(i)] = static_cast<std::uint8_t>(i + 1);
  ASSERT_EQ(to_kernel_frame(fd, kf), CANFD_MTU);
  EXPECT_EQ(kf.can_id, 0x7FFU);
  EXPECT_EQ(kf.flags, CANFD_BRS | CANFD_ESI);
  ASSERT_EQ(from_kernel_frame(kf, CANFD_MTU, back), KernelFrameKind::kData);
  EXPECT_TRUE(back.fd);
  EXPECT_EQ(back.fd_flags, 0x3);
  EXPECT_EQ(back.len, 12);
  EXPECT_EQ(back.data, fd.data);

  // Rejections: 11-bit id above 0x7FF, classic len 9, FD len 13 (not a CAN FD length).
  CanFrame bad;
  bad.id = 0x800;
  EXPECT_EQ(to_kernel_frame(bad, kf), 0U);
  bad.id = 1;
  bad.len = 9;
  EXPECT_EQ(to_kernel_frame(bad, kf), 0U);
  bad.fd = true;
  bad.len = 13;
  EXPECT_EQ(to_kernel_frame(bad, kf), 0U);

  // Kinds: RTR, error, wrong size, classic len > 8.
  canfd_frame k{};
  k.can_id = CAN_RTR_FLAG | 0x100;
  EXPECT_EQ(from_kernel_frame(k, CAN_MTU, back), KernelFrameKind::kRemote);
  k.can_id = CAN_ERR_FLAG | CAN_ERR_BUSOFF;
  EXPECT_EQ(from_kernel_frame(k, CAN_MTU, back), KernelFrameKind::kError);
  k.can_id = 0x100;
  EXPECT_EQ(from_kernel_frame(k, 10, back), KernelFrameKind::kMalformed);
  k.len = 9;
  EXPECT_EQ(from_kernel_frame(k, CAN_MTU, back), KernelFrameKind::kMalformed);
}

TEST(SocketCanTime, TimespecToNanosecondsAndOffset) {
  static_assert(timestamp_ns_from_timespec(timespec{1'700'000'000, 123'456'789}, 0) ==
                1'700'000'000'123'456'789);
  EXPECT_EQ(
      timestamp_ns_from_timespec(timespec{1'700'000'000, 999'999'999}, -1'700'000'000'000'000'000),
      999'999'999);
  EXPECT_EQ(timestamp_ns_from_timespec(timespec{0, 5}, 10), 15);
}

TEST(SocketCanTime, ParsesTimestampAndDropCountControlMessages) {
  // Two control messages built with the CMSG macros (cmsg(3)), as recvmsg() returns them.
  union {
    char bytes[CMSG_SPACE(sizeof(timespec)) + CMSG_SPACE(sizeof(std::uint32_t))];
    cmsghdr align;
  } control{};
  msghdr msg{};
  msg.msg_control = control.bytes;
  msg.msg_controllen = sizeof control.bytes;
  cmsghdr* c = CMSG_FIRSTHDR(&msg);
  c->cmsg_level = SOL_SOCKET;
  c->cmsg_type = SCM_TIMESTAMPNS;
  c->cmsg_len = CMSG_LEN(sizeof(timespec));
  const timespec ts{1'700'000'123, 456'789'012};
  std::memcpy(CMSG_DATA(c), &ts, sizeof ts);
  c = CMSG_NXTHDR(&msg, c);
  ASSERT_NE(c, nullptr);
  c->cmsg_level = SOL_SOCKET;
  c->cmsg_type = SO_RXQ_OVFL;
  c->cmsg_len = CMSG_LEN(sizeof(std::uint32_t));
  const std::uint32_t drops = 42;
  std::memcpy(CMSG_DATA(c), &drops, sizeof drops);

  const SocketCanAncillary a = parse_socketcan_ancillary(msg);
  ASSERT_TRUE(a.has_timestamp);
  EXPECT_EQ(timestamp_ns_from_timespec(a.timestamp, 0), 1'700'000'123'456'789'012);
  ASSERT_TRUE(a.has_drop_count);
  EXPECT_EQ(a.drop_count, 42U);

  msghdr empty{};
  const SocketCanAncillary none = parse_socketcan_ancillary(empty);
  EXPECT_FALSE(none.has_timestamp);
  EXPECT_FALSE(none.has_drop_count);
}

// The endpoint over one end of a SOCK_SEQPACKET socketpair: the other end plays the kernel.
struct Pair {
  std::unique_ptr<SocketCanEndpoint> ep;
  int peer = -1;
  explicit Pair(const SocketCanOptions& o) {
    int sv[2];
    if (::socketpair(AF_UNIX, SOCK_SEQPACKET | SOCK_CLOEXEC, 0, sv) != 0)
      throw std::runtime_error("socketpair failed");
    ep = SocketCanEndpoint::adopt(sv[0], "pair0", o);
    peer = sv[1];
  }
  ~Pair() { ::close(peer); }
  void put(const void* bytes, std::size_t n) const {
    ASSERT_EQ(::send(peer, bytes, n, 0), static_cast<ssize_t>(n));
  }
};

TEST(SocketCanEndpoint, ReceivesDataSkipsErrorFramesAndStampsWithTheKernelClock) {
  SocketCanOptions o;
  o.timestamp_offset_ns = -1'000'000'000;  // the run's clock one second behind CLOCK_REALTIME
  Pair p(o);

  can_frame data{};
  data.can_id = 0x123;
  data.len = 2;
  data.data[0] = 0xAB;
  data.data[1] = 0xCD;
  const can_frame err = error_frame(CAN_ERR_BUSOFF, {});
  can_frame rtr{};
  rtr.can_id = CAN_RTR_FLAG | 0x55;
  const std::array<std::uint8_t, 10> runt{};  // neither CAN_MTU nor CANFD_MTU

  const std::int64_t before = realtime_now_ns();
  p.put(&err, sizeof err);
  p.put(&rtr, sizeof rtr);
  p.put(runt.data(), runt.size());
  p.put(&data, sizeof data);
  const std::int64_t after = realtime_now_ns();

  CanFrame f;
  ASSERT_TRUE(p.ep->receive(f));
  EXPECT_EQ(f.id, 0x123U);
  EXPECT_EQ(f.len, 2);
  EXPECT_EQ(f.data[1], 0xCD);
  EXPECT_FALSE(f.extended);
  // The kernel stamped the datagram between `before` and `after` (CLOCK_REALTIME), then the
  // offset applies.
  EXPECT_GE(f.timestamp_ns, before + o.timestamp_offset_ns);
  EXPECT_LE(f.timestamp_ns, after + o.timestamp_offset_ns);
  EXPECT_EQ(p.ep->stats().timestamps_missing, 0U);

  EXPECT_FALSE(p.ep->receive(f));  // nothing left, and no blocking
  EXPECT_EQ(p.ep->bus_state(), CanBusState::kBusOff);
  EXPECT_EQ(p.ep->error_counters().bus_off, 1U);
  EXPECT_EQ(p.ep->stats().rx_rtr_dropped, 1U);
  EXPECT_EQ(p.ep->stats().rx_malformed, 1U);
  EXPECT_EQ(p.ep->stats().frames_received, 1U);
}

TEST(SocketCanEndpoint, SendRefusesWhenTheQueueIsFullAndNeverAllocates) {
  Pair p(SocketCanOptions{});
  CanFrame f;
  f.id = 0x321;
  f.len = 8;
  // Fill the socket until the kernel refuses (EAGAIN): the frame path must say false and count.
  radar_emu::test::start_counting_allocations();
  std::uint64_t accepted = 0;
  bool refused = false;
  for (int i = 0; i < 1'000'000 && !refused; ++i) {
    if (p.ep->send(f))
      ++accepted;
    else
      refused = true;
  }
  CanFrame in;
  (void)p.ep->receive(in);
  const std::uint64_t allocations = radar_emu::test::stop_counting_allocations();
  EXPECT_EQ(allocations, 0U);
  ASSERT_TRUE(refused);
  EXPECT_GT(accepted, 0U);
  EXPECT_EQ(p.ep->stats().frames_sent, accepted);
  EXPECT_EQ(p.ep->stats().tx_queue_full, 1U);
  EXPECT_EQ(p.ep->stats().last_errno, EAGAIN);

  // What went out is struct can_frame, byte for byte.
  can_frame got{};
  ASSERT_EQ(::recv(p.peer, &got, sizeof got, 0), static_cast<ssize_t>(CAN_MTU));
  EXPECT_EQ(got.can_id, 0x321U);
  EXPECT_EQ(got.len, 8);

  // An FD frame on a classic endpoint is refused before any I/O.
  CanFrame fd;
  fd.fd = true;
  fd.len = 16;
  EXPECT_FALSE(p.ep->send(fd));
  EXPECT_EQ(p.ep->stats().tx_rejected, 1U);
}

TEST(SocketCanSetup, ReportsAMissingAfCanInOneLine) {
  std::string why;
  const bool available = socketcan_available(&why);
  if (!available) {
    EXPECT_NE(why.find("AF_CAN unavailable: errno"), std::string::npos) << why;
  }
  try {
    SocketCanEndpoint ep("radaremu-none0");  // 14 characters: a valid name that does not exist
    FAIL() << "opened a non-existent interface";
  } catch (const std::runtime_error& e) {
    const std::string msg = e.what();
    EXPECT_EQ(msg.find('\n'), std::string::npos);
    if (!available && why.find("errno 97") != std::string::npos) {
      EXPECT_EQ(msg,
                "socketcan:radaremu-none0: AF_CAN not supported by this kernel "
                "(errno 97 EAFNOSUPPORT)");
    } else if (available) {
      EXPECT_EQ(msg, "socketcan:radaremu-none0: no such network interface (errno 19 ENODEV)");
    }
  }
  try {
    SocketCanEndpoint ep("a-name-that-is-too-long");
    FAIL() << "accepted a 23-character interface name";
  } catch (const std::runtime_error& e) {
    EXPECT_EQ(std::string(e.what()),
              "socketcan:a-name-that-is-too-long: interface name must have 1 to 15 characters");
  }
}

TEST(SocketCanSetup, ConfigureRefusesWhatItMustNotTouchWithAWarning) {
  // A missing interface: a one-line warning, no exception, no crash.
  const std::string w = configure_socketcan("radaremu-none0", 500'000, 0, 100);
  EXPECT_EQ(w,
            "socketcan:radaremu-none0: not configured: no such network interface "
            "(errno 19 ENODEV)");
  // The guard that keeps configure_socketcan off non-CAN links reads the link type; the loopback
  // interface is ARPHRD_LOOPBACK (772), a CAN interface would be ARPHRD_CAN (280). Read only.
  EXPECT_EQ(interface_link_type("lo"), ARPHRD_LOOPBACK);
  EXPECT_EQ(interface_link_type("radaremu-none0"), -ENODEV);
  EXPECT_EQ(ARPHRD_CAN, 280);
}

// Needs AF_CAN and a vcan interface (sudo modprobe vcan; sudo ip link add vcan0 type vcan;
// sudo ip link set vcan0 up). Name it with RADAR_EMU_VCAN (default vcan0).
TEST(SocketCanVcan, RoundTripBetweenTwoSockets) {
  std::string why;
  if (!socketcan_available(&why))
    GTEST_SKIP() << why;
  const char* env = std::getenv("RADAR_EMU_VCAN");
  const std::string name = env != nullptr ? env : "vcan0";
  if (interface_link_type(name) != ARPHRD_CAN)
    GTEST_SKIP() << "no CAN interface '" << name
                 << "' (sudo ip link add vcan0 type vcan && sudo ip link set vcan0 up)";
  SocketCanEndpoint a(name);
  SocketCanEndpoint b(name);
  CanFrame f;
  f.id = 0x1CEB00DA;
  f.extended = true;
  f.len = 4;
  f.data = {1, 2, 3, 4};
  const std::int64_t before = realtime_now_ns();
  ASSERT_TRUE(a.send(f));
  CanFrame got;
  bool ok = false;
  for (int i = 0; i < 1000 && !ok; ++i) {
    ok = b.receive(got);
    if (!ok)
      ::usleep(1000);
  }
  ASSERT_TRUE(ok);
  EXPECT_EQ(got.id, f.id);
  EXPECT_TRUE(got.extended);
  EXPECT_EQ(got.len, 4);
  EXPECT_EQ(got.data, f.data);
  EXPECT_GE(got.timestamp_ns, before);
  CanFrame own;
  EXPECT_FALSE(a.receive(own));  // receive_own is off
}

}  // namespace
}  // namespace radar_emu::io
