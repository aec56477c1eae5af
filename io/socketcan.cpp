#include "io/socketcan.hpp"

#include <fcntl.h>
#include <libsocketcan.h>
#include <linux/can/error.h>
#include <linux/can/netlink.h>
#include <linux/can/raw.h>
#include <net/if.h>
#include <net/if_arp.h>
#include <sys/ioctl.h>
#include <unistd.h>

#include <algorithm>
#include <cerrno>
#include <cstring>
#include <stdexcept>

namespace radar_emu::io {

namespace {

// Datagrams read per receive() call at most: error frames "may flood" (linux/can/error.h,
// CAN_ERR_BUSERROR), and a call must return in bounded time.
constexpr int kMaxDatagramsPerReceive = 64;

std::string prefix(std::string_view name) {
  std::string p = "socketcan:";
  p.append(name);
  p += ": ";
  return p;
}

[[noreturn]] void fail(std::string_view name, const std::string& what) {
  throw std::runtime_error(prefix(name) + what);
}

void set_int_option(int fd, int level, int option, int value, std::string_view name,
                    const char* what) {
  if (::setsockopt(fd, level, option, &value, sizeof value) != 0)
    fail(name, std::string("setsockopt ") + what + " failed (" + errno_text(errno) + ")");
}

CanBusState from_netlink_state(int state) noexcept {
  // linux/can/netlink.h, enum can_state.
  switch (state) {
    case CAN_STATE_ERROR_ACTIVE:
      return CanBusState::kErrorActive;
    case CAN_STATE_ERROR_WARNING:
      return CanBusState::kErrorWarning;
    case CAN_STATE_ERROR_PASSIVE:
      return CanBusState::kErrorPassive;
    case CAN_STATE_BUS_OFF:
      return CanBusState::kBusOff;
    case CAN_STATE_STOPPED:
    case CAN_STATE_SLEEPING:
      return CanBusState::kStopped;
    default:
      return CanBusState::kUnknown;
  }
}

std::string ip_link_hint(std::string_view name, std::uint32_t bitrate_bps,
                         std::uint32_t dbitrate_bps, std::uint32_t restart_ms) {
  const std::string n(name);
  std::string cmd = "sudo ip link set " + n + " down && sudo ip link set " + n + " type can";
  if (bitrate_bps != 0)
    cmd += " bitrate " + std::to_string(bitrate_bps);
  if (dbitrate_bps != 0)
    cmd += " dbitrate " + std::to_string(dbitrate_bps) + " fd on";
  cmd += " restart-ms " + std::to_string(restart_ms) + " && sudo ip link set " + n + " up";
  return cmd;
}

}  // namespace

std::string errno_text(int err) {
  std::string s = "errno " + std::to_string(err);
  if (const char* n = ::strerrorname_np(err))
    s += std::string(" ") + n;
  return s;
}

std::int64_t realtime_now_ns() noexcept {
  timespec ts{};
  ::clock_gettime(CLOCK_REALTIME, &ts);
  return timestamp_ns_from_timespec(ts, 0);
}

std::int64_t realtime_offset_ns(std::int64_t bus_now_ns) noexcept {
  return bus_now_ns - realtime_now_ns();
}

SocketCanAncillary parse_socketcan_ancillary(const msghdr& msg) noexcept {
  SocketCanAncillary a;
  auto& m = const_cast<msghdr&>(msg);  // CMSG_NXTHDR takes a non-const pointer; nothing is written
  for (cmsghdr* c = CMSG_FIRSTHDR(&m); c != nullptr; c = CMSG_NXTHDR(&m, c)) {
    if (c->cmsg_level != SOL_SOCKET)
      continue;
    const auto* payload = static_cast<const unsigned char*>(CMSG_DATA(c));
    const std::size_t payload_bytes = c->cmsg_len - CMSG_LEN(0);
    if (c->cmsg_type == SCM_TIMESTAMPNS && payload_bytes >= sizeof(timespec)) {
      std::memcpy(&a.timestamp, payload, sizeof(timespec));
      a.has_timestamp = true;
    } else if (c->cmsg_type == SO_RXQ_OVFL && payload_bytes >= sizeof(std::uint32_t)) {
      std::memcpy(&a.drop_count, payload, sizeof(std::uint32_t));
      a.has_drop_count = true;
    }
  }
  return a;
}

KernelFrameKind from_kernel_frame(const canfd_frame& kf, std::size_t nbytes,
                                  CanFrame& out) noexcept {
  bool fd = false;
  if (nbytes == CANFD_MTU)
    fd = true;
  else if (nbytes != CAN_MTU)
    return KernelFrameKind::kMalformed;
  if (kf.len > (fd ? CANFD_MAX_DLEN : CAN_MAX_DLEN))
    return KernelFrameKind::kMalformed;
  if (kf.can_id & CAN_ERR_FLAG)
    return KernelFrameKind::kError;
  if (kf.can_id & CAN_RTR_FLAG)
    return KernelFrameKind::kRemote;
  out.extended = (kf.can_id & CAN_EFF_FLAG) != 0;
  out.id = kf.can_id & (out.extended ? CAN_EFF_MASK : CAN_SFF_MASK);
  out.fd = fd;
  out.fd_flags = fd ? static_cast<std::uint8_t>(kf.flags & (CANFD_BRS | CANFD_ESI)) : 0;
  out.len = kf.len;
  std::copy_n(kf.data, kf.len, out.data.begin());
  std::fill(out.data.begin() + kf.len, out.data.end(), std::uint8_t{0});
  return KernelFrameKind::kData;
}

std::size_t to_kernel_frame(const CanFrame& f, canfd_frame& kf) noexcept {
  kf = canfd_frame{};
  if (f.id > (f.extended ? CAN_EFF_MASK : CAN_SFF_MASK))
    return 0;
  if (f.fd ? !is_can_fd_length(f.len) : f.len > CAN_MAX_DLEN)
    return 0;
  kf.can_id = f.id | (f.extended ? CAN_EFF_FLAG : 0U);
  kf.len = f.len;
  std::copy_n(f.data.begin(), f.len, kf.data);
  if (!f.fd)
    return CAN_MTU;
  // candump's flag nibble and linux/can.h share the values: CANFD_BRS 0x01, CANFD_ESI 0x02.
  kf.flags = static_cast<std::uint8_t>(f.fd_flags & (CANFD_BRS | CANFD_ESI));
  return CANFD_MTU;
}

bool socketcan_available(std::string* why) {
  const int fd = ::socket(PF_CAN, SOCK_RAW | SOCK_CLOEXEC, CAN_RAW);
  if (fd < 0) {
    const int err = errno;
    if (why != nullptr)
      *why = "AF_CAN unavailable: " + errno_text(err) + " (" + std::strerror(err) + ")";
    return false;
  }
  ::close(fd);
  return true;
}

int interface_link_type(std::string_view interface_name) {
  if (interface_name.empty() || interface_name.size() >= IFNAMSIZ)
    return -EINVAL;
  const int fd = ::socket(AF_INET, SOCK_DGRAM | SOCK_CLOEXEC, 0);
  if (fd < 0)
    return -errno;
  ifreq ifr{};
  std::copy(interface_name.begin(), interface_name.end(), ifr.ifr_name);
  int result = 0;
  if (::ioctl(fd, SIOCGIFHWADDR, &ifr) != 0)
    result = -errno;
  else
    result = ifr.ifr_hwaddr.sa_family;
  ::close(fd);
  return result;
}

std::string configure_socketcan(std::string_view interface_name, std::uint32_t bitrate_bps,
                                std::uint32_t dbitrate_bps, std::uint32_t restart_ms) {
  const std::string name(interface_name);
  const std::string p = prefix(interface_name);
  const int type = interface_link_type(interface_name);
  if (type == -ENODEV)
    return p + "not configured: no such network interface (" + errno_text(ENODEV) + ")";
  if (type < 0)
    return p + "not configured: cannot read its link type (" + errno_text(-type) + ")";
  // Never stop a non-CAN interface: libsocketcan's can_do_stop brings any link down.
  if (type != ARPHRD_CAN)
    return p + "not configured: not a CAN interface (link type " + std::to_string(type) +
           ", CAN is " + std::to_string(ARPHRD_CAN) + "); left untouched";
  can_bittiming_const btc{};
  if (::can_get_bittiming_const(name.c_str(), &btc) != 0)
    return p + "not configured: no bit timing (a virtual CAN interface such as vcan has none)";

  const std::string hint = ip_link_hint(interface_name, bitrate_bps, dbitrate_bps, restart_ms);
  std::string warnings;
  auto warn = [&](const std::string& line) {
    if (!warnings.empty())
      warnings += '\n';
    warnings += p + line;
  };
  auto why = [](const char* call) {
    const int err = errno;
    return std::string(" (") + call + ": " + (err != 0 ? errno_text(err) : "failed") + ")";
  };

  errno = 0;
  if (::can_do_stop(name.c_str()) != 0) {
    warn("cannot stop the interface to configure it" + why("can_do_stop") +
         "; needs CAP_NET_ADMIN: run as root or: " + hint);
    return warnings;
  }
  if (bitrate_bps != 0) {
    errno = 0;
    if (::can_set_bitrate(name.c_str(), bitrate_bps) != 0)
      warn("cannot set bit rate " + std::to_string(bitrate_bps) + why("can_set_bitrate") +
           "; try: " + hint);
  }
  errno = 0;
  if (::can_set_restart_ms(name.c_str(), restart_ms) != 0)
    warn("cannot set restart-ms " + std::to_string(restart_ms) + why("can_set_restart_ms"));
  if (dbitrate_bps != 0)
    warn("data bit rate " + std::to_string(dbitrate_bps) +
         " not set: libsocketcan 0.0.12 has no CAN FD data-phase call; use: " + hint);
  errno = 0;
  if (::can_do_start(name.c_str()) != 0) {
    warn("cannot start the interface" + why("can_do_start") + "; try: " + hint);
    return warnings;
  }
  int state = -1;
  if (::can_get_state(name.c_str(), &state) == 0 && state != CAN_STATE_ERROR_ACTIVE)
    warn(std::string("started but its state is ") +
         std::string(to_string(from_netlink_state(state))));
  return warnings;
}

SocketCanEndpoint::SocketCanEndpoint(int fd, std::string name,
                                     const SocketCanOptions& options) noexcept
    : fd_(fd), name_(std::move(name)), options_(options) {}

SocketCanEndpoint::SocketCanEndpoint(std::string_view interface_name,
                                     const SocketCanOptions& options)
    : name_(interface_name), options_(options) {
  if (interface_name.empty() || interface_name.size() >= IFNAMSIZ)
    fail(interface_name,
         "interface name must have 1 to " + std::to_string(IFNAMSIZ - 1) + " characters");
  fd_ = ::socket(PF_CAN, SOCK_RAW | SOCK_NONBLOCK | SOCK_CLOEXEC, CAN_RAW);
  if (fd_ < 0) {
    const int err = errno;
    if (err == EAFNOSUPPORT)
      fail(interface_name, "AF_CAN not supported by this kernel (" + errno_text(err) + ")");
    if (err == EPROTONOSUPPORT)
      fail(interface_name, "CAN_RAW not supported by this kernel, can-raw module missing? (" +
                               errno_text(err) + ")");
    fail(interface_name, "cannot open a CAN_RAW socket (" + errno_text(err) + ")");
  }
  try {
    const unsigned index = ::if_nametoindex(name_.c_str());
    if (index == 0) {
      const int err = errno;
      fail(interface_name, (err == ENODEV ? std::string("no such network interface (")
                                          : std::string("if_nametoindex failed (")) +
                               errno_text(err) + ")");
    }
    apply_options(true);
    sockaddr_can addr{};
    addr.can_family = AF_CAN;
    addr.can_ifindex = static_cast<int>(index);
    if (::bind(fd_, reinterpret_cast<const sockaddr*>(&addr), sizeof addr) != 0) {
      const int err = errno;
      fail(interface_name, "cannot bind (" + errno_text(err) + ")" +
                               (err == ENODEV ? ": not a CAN interface" : ""));
    }
  } catch (...) {
    ::close(fd_);
    fd_ = -1;
    throw;
  }
  int state = -1;
  if (::can_get_state(name_.c_str(), &state) == 0)
    errors_.set_state(from_netlink_state(state));
}

std::unique_ptr<SocketCanEndpoint> SocketCanEndpoint::adopt(int fd, std::string_view name,
                                                            const SocketCanOptions& options) {
  std::unique_ptr<SocketCanEndpoint> ep(new SocketCanEndpoint(fd, std::string(name), options));
  int domain = 0;
  socklen_t len = sizeof domain;
  if (::getsockopt(fd, SOL_SOCKET, SO_DOMAIN, &domain, &len) != 0)
    fail(name, "adopt: not a socket (" + errno_text(errno) + ")");  // ~ep closes fd
  const int flags = ::fcntl(fd, F_GETFL);
  if (flags < 0 || ::fcntl(fd, F_SETFL, flags | O_NONBLOCK) != 0)
    fail(name, "adopt: cannot make the socket non-blocking (" + errno_text(errno) + ")");
  ep->apply_options(domain == AF_CAN);
  return ep;
}

void SocketCanEndpoint::apply_options(bool can_socket) {
  if (can_socket) {
    if (options_.fd) {
      // The interface must run CAN FD (MTU CANFD_MTU) for FD frames to pass (can.rst, "RAW
      // socket option CAN_RAW_FD_FRAMES").
      ifreq ifr{};
      std::copy(name_.begin(), name_.end(), ifr.ifr_name);
      if (::ioctl(fd_, SIOCGIFMTU, &ifr) == 0 && ifr.ifr_mtu != static_cast<int>(CANFD_MTU))
        fail(name_, "interface is not in CAN FD mode (MTU " + std::to_string(ifr.ifr_mtu) +
                        ", CAN FD needs " + std::to_string(CANFD_MTU) + "): sudo ip link set " +
                        name_ + " type can ... fd on");
      set_int_option(fd_, SOL_CAN_RAW, CAN_RAW_FD_FRAMES, 1, name_, "CAN_RAW_FD_FRAMES");
    }
    if (options_.receive_own)
      set_int_option(fd_, SOL_CAN_RAW, CAN_RAW_RECV_OWN_MSGS, 1, name_, "CAN_RAW_RECV_OWN_MSGS");
    if (options_.error_frames) {
      const can_err_mask_t mask = CAN_ERR_MASK;
      if (::setsockopt(fd_, SOL_CAN_RAW, CAN_RAW_ERR_FILTER, &mask, sizeof mask) != 0)
        fail(name_, "setsockopt CAN_RAW_ERR_FILTER failed (" + errno_text(errno) + ")");
    }
  }
  if (options_.kernel_timestamps)
    set_int_option(fd_, SOL_SOCKET, SO_TIMESTAMPNS, 1, name_, "SO_TIMESTAMPNS");
  set_int_option(fd_, SOL_SOCKET, SO_RXQ_OVFL, 1, name_, "SO_RXQ_OVFL");
}

SocketCanEndpoint::~SocketCanEndpoint() {
  if (fd_ >= 0)
    ::close(fd_);
}

bool SocketCanEndpoint::send(const CanFrame& frame) noexcept {
  if (frame.fd && !options_.fd) {
    ++stats_.tx_rejected;
    return false;
  }
  canfd_frame kf;
  const std::size_t bytes = to_kernel_frame(frame, kf);
  if (bytes == 0) {
    ++stats_.tx_rejected;
    return false;
  }
  for (;;) {
    const ssize_t n = ::send(fd_, &kf, bytes, MSG_DONTWAIT | MSG_NOSIGNAL);
    if (n == static_cast<ssize_t>(bytes)) {
      ++stats_.frames_sent;
      return true;
    }
    if (n < 0 && errno == EINTR)
      continue;
    if (n < 0) {
      stats_.last_errno = errno;
      // A full interface transmit queue (txqueuelen) makes the write fail with ENOBUFS, which
      // can-utils' cangen treats as "retry later" (its -i/-p options); EAGAIN: socket buffer full.
      if (errno == ENOBUFS || errno == EAGAIN || errno == EWOULDBLOCK)
        ++stats_.tx_queue_full;
      else
        ++stats_.tx_errors;
    } else {
      ++stats_.tx_errors;  // a partial datagram cannot happen on CAN_RAW; counted if it does
    }
    return false;
  }
}

bool SocketCanEndpoint::receive(CanFrame& out) noexcept {
  for (int i = 0; i < kMaxDatagramsPerReceive; ++i) {
    canfd_frame kf;
    iovec iov{&kf, sizeof kf};
    union {
      char bytes[CMSG_SPACE(sizeof(timespec)) + CMSG_SPACE(sizeof(std::uint32_t))];
      cmsghdr align;
    } control;
    msghdr msg{};
    msg.msg_iov = &iov;
    msg.msg_iovlen = 1;
    msg.msg_control = control.bytes;
    msg.msg_controllen = sizeof control.bytes;
    const ssize_t n = ::recvmsg(fd_, &msg, MSG_DONTWAIT);
    if (n < 0) {
      if (errno == EINTR)
        continue;
      if (errno != EAGAIN && errno != EWOULDBLOCK) {
        ++stats_.rx_errors;
        stats_.last_errno = errno;
      }
      return false;
    }
    const SocketCanAncillary anc = parse_socketcan_ancillary(msg);
    if (anc.has_drop_count)
      stats_.rx_socket_drops = anc.drop_count;
    if (msg.msg_flags & MSG_TRUNC) {  // longer than a canfd_frame
      ++stats_.rx_malformed;
      continue;
    }
    CanFrame f;
    switch (from_kernel_frame(kf, static_cast<std::size_t>(n), f)) {
      case KernelFrameKind::kMalformed:
        ++stats_.rx_malformed;
        continue;
      case KernelFrameKind::kRemote:
        ++stats_.rx_rtr_dropped;
        continue;
      case KernelFrameKind::kError:
        (void)errors_.on_error_frame(kf.can_id, std::span<const std::uint8_t, 8>(kf.data, 8));
        continue;
      case KernelFrameKind::kData:
        break;
    }
    if (anc.has_timestamp) {
      f.timestamp_ns = timestamp_ns_from_timespec(anc.timestamp, options_.timestamp_offset_ns);
    } else {
      if (options_.kernel_timestamps)
        ++stats_.timestamps_missing;
      f.timestamp_ns = realtime_now_ns() + options_.timestamp_offset_ns;
    }
    out = f;
    ++stats_.frames_received;
    return true;
  }
  return false;
}

}  // namespace radar_emu::io
