#pragma once
// SocketCAN backend: a raw CAN socket (PF_CAN, SOCK_RAW, CAN_RAW) on a Linux CAN interface
// (Documentation/networking/can.rst, "How to use SocketCAN"), non-blocking, with kernel receive
// time stamps (SO_TIMESTAMPNS) and error frames (CAN_RAW_ERR_FILTER) decoded into counters.
//
// Time stamps: the kernel stamps each received frame with CLOCK_REALTIME (socket(7),
// SO_TIMESTAMPNS: "struct timespec", wall-clock time). CanFrame::timestamp_ns is that time plus
// SocketCanOptions::timestamp_offset_ns, so a run whose bus clock is not the wall clock can map
// kernel stamps onto it (see realtime_offset_ns()).
//
// Bit rate, restart and start/stop of the interface are set up separately (configure_socketcan,
// libsocketcan over rtnetlink), which needs CAP_NET_ADMIN; the endpoint itself needs none.

#include <linux/can.h>
#include <sys/socket.h>
#include <time.h>

#include <cstddef>
#include <cstdint>
#include <memory>
#include <string>
#include <string_view>

#include "io/can_error.hpp"
#include "io/can_frame.hpp"

namespace radar_emu::io {

struct SocketCanOptions {
  bool fd = false;           ///< CAN FD frames (CAN_RAW_FD_FRAMES; the interface needs MTU 72)
  bool receive_own = false;  ///< also receive the frames this socket sent (CAN_RAW_RECV_OWN_MSGS)
  bool error_frames = true;  ///< subscribe to error frames (CAN_RAW_ERR_FILTER = CAN_ERR_MASK)
  bool kernel_timestamps = true;  ///< SO_TIMESTAMPNS; off: stamp with CLOCK_REALTIME at receive()
  /// Added to every CLOCK_REALTIME receive stamp to give CanFrame::timestamp_ns [ns]. 0 keeps
  /// Unix time; realtime_offset_ns(bus_now_ns) maps onto a run's bus clock.
  std::int64_t timestamp_offset_ns = 0;
};

/// Counters of one endpoint. Updated only by the thread that calls send()/receive().
struct SocketCanStats {
  std::uint64_t frames_sent = 0;
  std::uint64_t frames_received = 0;  ///< data frames handed out by receive()
  std::uint64_t tx_queue_full = 0;    ///< send() refused: ENOBUFS/EAGAIN (interface queue full)
  std::uint64_t tx_rejected = 0;      ///< send() refused: frame invalid for this socket
  std::uint64_t tx_errors = 0;        ///< send() failed otherwise (last_errno says why)
  std::uint64_t rx_malformed = 0;     ///< datagrams that are neither CAN_MTU nor CANFD_MTU bytes
  std::uint64_t rx_rtr_dropped = 0;   ///< remote frames (CanFrame cannot carry CAN_RTR_FLAG)
  std::uint64_t rx_errors = 0;        ///< recvmsg failed other than EAGAIN
  std::uint64_t rx_socket_drops =
      0;  ///< frames the kernel dropped, socket buffer full (SO_RXQ_OVFL)
  std::uint64_t timestamps_missing = 0;  ///< frames without a kernel stamp (stamped at receive())
  int last_errno = 0;                    ///< errno of the last failed send/recvmsg
};

/// CLOCK_REALTIME now [ns]. Real-time safe.
[[nodiscard]] std::int64_t realtime_now_ns() noexcept;
/// The SocketCanOptions::timestamp_offset_ns that maps CLOCK_REALTIME onto a bus clock reading
/// `bus_now_ns` taken now. Real-time safe.
[[nodiscard]] std::int64_t realtime_offset_ns(std::int64_t bus_now_ns) noexcept;

/// A kernel time stamp (CLOCK_REALTIME) in nanoseconds plus `offset_ns`. Real-time safe.
[[nodiscard]] constexpr std::int64_t timestamp_ns_from_timespec(const timespec& ts,
                                                                std::int64_t offset_ns) noexcept {
  return static_cast<std::int64_t>(ts.tv_sec) * 1'000'000'000 +
         static_cast<std::int64_t>(ts.tv_nsec) + offset_ns;
}

/// Ancillary data of one recvmsg() on a CAN socket (socket(7): SCM_TIMESTAMPNS carries a struct
/// timespec; SO_RXQ_OVFL a uint32 count of frames dropped so far).
struct SocketCanAncillary {
  bool has_timestamp = false;
  timespec timestamp{};  ///< CLOCK_REALTIME of reception
  bool has_drop_count = false;
  std::uint32_t drop_count = 0;  ///< cumulative drops of this socket
};
/// Walks the control messages of `msg`. Real-time safe.
[[nodiscard]] SocketCanAncillary parse_socketcan_ancillary(const msghdr& msg) noexcept;

/// Kernel frame <-> CanFrame (linux/can.h: struct can_frame is CAN_MTU = 16 bytes, struct
/// canfd_frame CANFD_MTU = 72; the two share the layout of can_id and len).
enum class KernelFrameKind : std::uint8_t { kData, kError, kRemote, kMalformed };
/// Decodes `nbytes` received bytes held in `kf` (CAN_MTU: classic, CANFD_MTU: FD). Fills `out`
/// (timestamp left as is) for kData. Real-time safe.
[[nodiscard]] KernelFrameKind from_kernel_frame(const canfd_frame& kf, std::size_t nbytes,
                                                CanFrame& out) noexcept;
/// Encodes `f` into `kf`; returns the bytes to write (CAN_MTU or CANFD_MTU), or 0 when `f` is
/// invalid: id out of range, classic len > 8, FD len not a CAN FD length (0..8, 12, 16, 20, 24,
/// 32, 48, 64). Real-time safe.
[[nodiscard]] std::size_t to_kernel_frame(const CanFrame& f, canfd_frame& kf) noexcept;

/// True when this kernel offers AF_CAN raw sockets; otherwise false and, if `why` is given, a
/// one-line reason ("AF_CAN unavailable: errno 97 EAFNOSUPPORT (Address family not supported by
/// protocol)"). Setup.
[[nodiscard]] bool socketcan_available(std::string* why = nullptr);

/// "errno N NAME" for messages, e.g. "errno 97 EAFNOSUPPORT".
[[nodiscard]] std::string errno_text(int err);

/// ARPHRD_* link type of a network interface (ARPHRD_CAN = 280 for CAN, ARPHRD_LOOPBACK = 772),
/// or -errno when it cannot be read (-ENODEV: no such interface). Read-only query; setup.
[[nodiscard]] int interface_link_type(std::string_view interface_name);

/// Sets a CAN controller up through libsocketcan: stops it, sets `bitrate_bps` (0 = leave) and
/// `restart_ms` (automatic restart after bus-off; 0 = manual), starts it, reads its state. Needs
/// CAP_NET_ADMIN. Never throws for refusals: returns "" when everything was done, else one line
/// per problem ("socketcan:can0: cannot set bit rate 500000 (can_set_bitrate: errno 1 EPERM);
/// run as root or: sudo ip link set can0 down type can bitrate 500000 restart-ms 100 && ..."). It
/// refuses interfaces that are not CAN (link type != ARPHRD_CAN) before touching them, and
/// virtual CAN (vcan: no bit timing). `dbitrate_bps` (CAN FD data phase) cannot be set through
/// libsocketcan 0.0.12: a non-zero value gives the `ip link` command to use instead. Setup.
[[nodiscard]] std::string configure_socketcan(std::string_view interface_name,
                                              std::uint32_t bitrate_bps, std::uint32_t dbitrate_bps,
                                              std::uint32_t restart_ms);

/// A raw CAN socket bound to one interface. Non-copyable; closes the socket on destruction.
class SocketCanEndpoint final : public CanEndpoint {
 public:
  /// Opens and binds the socket (setup). Throws std::runtime_error with one line such as
  /// "socketcan:can0: AF_CAN not supported by this kernel (errno 97 EAFNOSUPPORT)" or
  /// "socketcan:can9: no such network interface (errno 19 ENODEV)".
  explicit SocketCanEndpoint(std::string_view interface_name, const SocketCanOptions& options = {});
  /// Takes ownership of an open socket `fd` carrying struct can_frame/canfd_frame datagrams:
  /// an AF_CAN socket already bound (e.g. handed over by a privileged parent; the CAN options
  /// are applied to it), or any other datagram socket (a SOCK_SEQPACKET socketpair in tests;
  /// only non-blocking mode and the SOL_SOCKET stamps are set). Closes `fd` and throws
  /// std::runtime_error on failure.
  [[nodiscard]] static std::unique_ptr<SocketCanEndpoint> adopt(int fd, std::string_view name,
                                                                const SocketCanOptions& options);

  SocketCanEndpoint(const SocketCanEndpoint&) = delete;
  SocketCanEndpoint& operator=(const SocketCanEndpoint&) = delete;
  ~SocketCanEndpoint() override;

  /// Writes one frame without blocking. False and counted when the interface queue is full
  /// (ENOBUFS/EAGAIN: tx_queue_full), when the frame does not fit this socket (FD frame on a
  /// classic socket, bad length: tx_rejected) or on any other error (tx_errors). Real-time safe.
  [[nodiscard]] bool send(const CanFrame& frame) noexcept override;
  /// Reads the next data frame without blocking. Error frames met on the way are decoded into
  /// error_counters()/bus_state() and not returned; at most 64 datagrams are read per call.
  /// Real-time safe.
  [[nodiscard]] bool receive(CanFrame& out) noexcept override;

  [[nodiscard]] const std::string& name() const noexcept { return name_; }
  [[nodiscard]] const SocketCanOptions& options() const noexcept { return options_; }
  [[nodiscard]] const SocketCanStats& stats() const noexcept { return stats_; }
  [[nodiscard]] const CanErrorCounters& error_counters() const noexcept {
    return errors_.counters();
  }
  /// State from error frames; initially what libsocketcan's can_get_state reported at open
  /// (kUnknown where it cannot tell, e.g. vcan).
  [[nodiscard]] CanBusState bus_state() const noexcept { return errors_.state(); }
  [[nodiscard]] int native_handle() const noexcept { return fd_; }

 private:
  SocketCanEndpoint(int fd, std::string name, const SocketCanOptions& options) noexcept;
  void apply_options(bool can_socket);  // throws; closes nothing

  int fd_ = -1;
  std::string name_;
  SocketCanOptions options_;
  SocketCanStats stats_;
  CanErrorTracker errors_;
};

}  // namespace radar_emu::io
