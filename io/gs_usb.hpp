#pragma once
// gs_usb backend: candleLight / CANable / CANtact-style USB-CAN adapters (USB 1D50:606F and the
// other IDs of Linux's gs_usb driver) driven from user space through libusb, so CAN works where
// the kernel has no SocketCAN.
//
// Protocol source: Linux drivers/net/can/usb/gs_usb.c (the struct definitions gs_host_config,
// gs_device_config, gs_device_mode, gs_device_bittiming, gs_device_bt_const(_extended),
// gs_host_frame, the enum gs_usb_breq and the GS_CAN_* flags). Every multi-byte field is little
// endian: the host announces it with HOST_FORMAT 0x0000beef, and candleLight firmware always
// uses it.
//
// Layers, each testable alone:
//   - bit-timing arithmetic (compute_gs_usb_bit_timing),
//   - byte packing of the control-request payloads and of struct gs_host_frame,
//   - the echo-id pool that matches the device's TX confirmations,
//   - GsUsbTransport: what the protocol needs from USB (control transfers, bulk OUT, an
//     asynchronous bulk IN path), implemented by GsUsbDevice over libusb and by fakes in tests,
//   - GsUsbEndpoint: a CanEndpoint over a transport.

#include <array>
#include <cstddef>
#include <cstdint>
#include <memory>
#include <span>
#include <string>
#include <string_view>
#include <vector>

#include "io/can_error.hpp"
#include "io/can_frame.hpp"

namespace radar_emu::io {

// ---- Constants (gs_usb.c) --------------------------------------------------------------------

inline constexpr std::uint16_t kGsUsbVendorId = 0x1D50;   ///< USB_GS_USB_1_VENDOR_ID
inline constexpr std::uint16_t kGsUsbProductId = 0x606F;  ///< USB_GS_USB_1_PRODUCT_ID
/// Every vendor:product pair of gs_usb.c's gs_usb_table (1D50:606F, candleLight 1209:2323,
/// CES CANext FD 1CD2:606F, ABE CANdebugger FD 16D0:10B8, Xylanta SAINT3 16D0:0F30).
struct GsUsbId {
  std::uint16_t vendor_id;
  std::uint16_t product_id;
};
inline constexpr std::array<GsUsbId, 5> kGsUsbIds{
    {{0x1D50, 0x606F}, {0x1209, 0x2323}, {0x1CD2, 0x606F}, {0x16D0, 0x10B8}, {0x16D0, 0x0F30}}};

inline constexpr std::uint8_t kGsUsbEndpointIn = 0x81;   ///< bulk IN, GS_USB_ENDPOINT_IN 1
inline constexpr std::uint8_t kGsUsbEndpointOut = 0x02;  ///< bulk OUT, GS_USB_ENDPOINT_OUT 2
/// bmRequestType of the vendor requests: USB_DIR_OUT/IN | USB_TYPE_VENDOR | USB_RECIP_INTERFACE
/// (USB 2.0 sec. 9.3.1: bit 7 direction, bits 6..5 type 2 = vendor, bits 4..0 recipient 1).
inline constexpr std::uint8_t kGsUsbRequestTypeOut = 0x41;
inline constexpr std::uint8_t kGsUsbRequestTypeIn = 0xC1;

/// bRequest codes, enum gs_usb_breq.
enum class GsUsbRequest : std::uint8_t {
  kHostFormat = 0,
  kBitTiming = 1,
  kMode = 2,
  kBerr = 3,
  kBtConst = 4,
  kDeviceConfig = 5,
  kTimestamp = 6,
  kIdentify = 7,
  kGetUserId = 8,
  kSetUserId = 9,
  kDataBitTiming = 10,
  kBtConstExt = 11,
  kSetTermination = 12,
  kGetTermination = 13,
  kGetState = 14,
};
[[nodiscard]] std::string_view to_string(GsUsbRequest request) noexcept;

inline constexpr std::uint32_t kGsUsbHostFormat = 0x0000beef;  ///< gs_host_config.byte_order
inline constexpr std::uint32_t kGsUsbModeReset = 0;            ///< GS_CAN_MODE_RESET
inline constexpr std::uint32_t kGsUsbModeStart = 1;            ///< GS_CAN_MODE_START

/// gs_device_mode.flags (GS_CAN_MODE_*) and gs_device_bt_const.feature (GS_CAN_FEATURE_*) share
/// bit positions.
namespace gs_usb_flag {
inline constexpr std::uint32_t kListenOnly = 1U << 0;
inline constexpr std::uint32_t kLoopBack = 1U << 1;
inline constexpr std::uint32_t kTripleSample = 1U << 2;
inline constexpr std::uint32_t kOneShot = 1U << 3;
inline constexpr std::uint32_t kHwTimestamp = 1U << 4;
inline constexpr std::uint32_t kIdentify = 1U << 5;  ///< feature only
inline constexpr std::uint32_t kUserId = 1U << 6;    ///< feature only
inline constexpr std::uint32_t kPadPktsToMaxPktSize = 1U << 7;
inline constexpr std::uint32_t kFd = 1U << 8;
inline constexpr std::uint32_t kReqUsbQuirkLpc546xx = 1U << 9;  ///< feature only
inline constexpr std::uint32_t kBtConstExt = 1U << 10;          ///< feature only
inline constexpr std::uint32_t kTermination = 1U << 11;         ///< feature only
inline constexpr std::uint32_t kBerrReporting = 1U << 12;
inline constexpr std::uint32_t kGetState = 1U << 13;  ///< feature only
}  // namespace gs_usb_flag

/// gs_host_frame.flags (GS_CAN_FLAG_*).
namespace gs_usb_frame_flag {
inline constexpr std::uint8_t kOverflow = 1U << 0;  ///< the device lost received frames
inline constexpr std::uint8_t kFd = 1U << 1;
inline constexpr std::uint8_t kBrs = 1U << 2;
inline constexpr std::uint8_t kEsi = 1U << 3;
}  // namespace gs_usb_frame_flag

/// echo_id of a frame received from the bus (gs_usb.c: "if (hf->echo_id == -1) /* normal rx */").
inline constexpr std::uint32_t kGsUsbRxEchoId = 0xFFFFFFFF;

/// struct gs_host_frame sizes [bytes]: 12-byte header (echo_id, can_id, can_dlc, channel, flags,
/// reserved), then data[8] (classic_can) or data[64] (canfd), then an optional __le32
/// timestamp_us (classic_can_ts, canfd_ts).
inline constexpr std::size_t kGsUsbHeaderBytes = 12;
inline constexpr std::size_t kGsUsbClassicFrameBytes = 20;
inline constexpr std::size_t kGsUsbClassicTsFrameBytes = 24;
inline constexpr std::size_t kGsUsbFdFrameBytes = 76;
inline constexpr std::size_t kGsUsbFdTsFrameBytes = 80;
inline constexpr std::size_t kGsUsbMaxFrameBytes = kGsUsbFdTsFrameBytes;

// ---- Control-request payloads -------------------------------------------------------------

/// struct gs_device_config (12 bytes).
struct GsUsbDeviceConfig {
  std::uint8_t icount = 0;       ///< number of CAN channels minus one
  std::uint32_t sw_version = 0;  ///< firmware version
  std::uint32_t hw_version = 0;  ///< hardware version
  [[nodiscard]] unsigned channel_count() const noexcept { return icount + 1U; }
};

/// Bit-timing limits of one phase, in time quanta (tq) and prescaler steps (struct
/// gs_device_bt_const fields tseg1_min .. brp_inc; tseg1 = prop_seg + phase_seg1).
struct GsUsbTimingLimits {
  std::uint32_t tseg1_min = 0, tseg1_max = 0;           ///< [tq]
  std::uint32_t tseg2_min = 0, tseg2_max = 0;           ///< [tq]
  std::uint32_t sjw_max = 0;                            ///< [tq]
  std::uint32_t brp_min = 0, brp_max = 0, brp_inc = 0;  ///< prescaler range and step
};

/// struct gs_device_bt_const (40 bytes), and the data-phase part of
/// gs_device_bt_const_extended (72 bytes) when the device has GS_CAN_FEATURE_BT_CONST_EXT.
struct GsUsbBtConst {
  std::uint32_t feature = 0;      ///< gs_usb_flag bits the device supports
  std::uint32_t fclk_can_hz = 0;  ///< CAN controller clock [Hz]
  GsUsbTimingLimits nominal;      ///< arbitration phase
  GsUsbTimingLimits data;         ///< CAN FD data phase (copy of `nominal` without BT_CONST_EXT)
};

/// struct gs_device_bittiming (20 bytes): one bit is 1 (sync) + prop_seg + phase_seg1 +
/// phase_seg2 time quanta of brp / fclk_can seconds each.
struct GsUsbBitTiming {
  std::uint32_t prop_seg = 0;    ///< [tq]
  std::uint32_t phase_seg1 = 0;  ///< [tq]
  std::uint32_t phase_seg2 = 0;  ///< [tq]
  std::uint32_t sjw = 0;         ///< synchronisation jump width [tq]
  std::uint32_t brp = 0;         ///< bit-rate prescaler (tq = brp / fclk_can)
  [[nodiscard]] std::uint32_t tq_per_bit() const noexcept {
    return 1 + prop_seg + phase_seg1 + phase_seg2;
  }
  /// fclk / (brp * tq_per_bit) [bit/s].
  [[nodiscard]] double bitrate_bps(std::uint32_t fclk_can_hz) const noexcept;
  /// (1 + prop_seg + phase_seg1) / tq_per_bit, as a fraction of the bit.
  [[nodiscard]] double sample_point() const noexcept;
};

/// Largest bit-rate error compute_gs_usb_bit_timing accepts (0.5 %, well inside the oscillator
/// tolerance classic CAN allows, up to 1.58 %: Bosch CAN 2.0 / ISO 11898-1 bit timing).
inline constexpr double kGsUsbMaxBitRateError = 0.005;

/// Bit timing for `bitrate_bps` from a `fclk_can_hz` clock within `limits`, with the sample point
/// as close to `sample_point` (fraction of the bit, 0.5 .. 0.95) as the limits allow, not later
/// when two are equally close (as Linux's can_calc_bittiming). Among prescalers with the same
/// rate and sample-point error, the smallest (most tq per bit) wins. The sample point splits as
/// prop_seg = 1, phase_seg1 = tseg1 - 1 (the device only uses their sum); sjw =
/// min(sjw_max, phase_seg1, phase_seg2). Throws std::invalid_argument with one line when no
/// setting is within kGsUsbMaxBitRateError of the rate (setup).
[[nodiscard]] GsUsbBitTiming compute_gs_usb_bit_timing(std::uint32_t fclk_can_hz,
                                                       const GsUsbTimingLimits& limits,
                                                       std::uint32_t bitrate_bps,
                                                       double sample_point = 0.875);

[[nodiscard]] std::array<std::uint8_t, 4> pack_gs_usb_host_config() noexcept;
[[nodiscard]] std::array<std::uint8_t, 8> pack_gs_usb_mode(std::uint32_t mode,
                                                           std::uint32_t flags) noexcept;
[[nodiscard]] std::array<std::uint8_t, 20> pack_gs_usb_bit_timing(
    const GsUsbBitTiming& bt) noexcept;
/// Parsers of the device's replies; throw std::runtime_error ("gsusb: BT_CONST reply has 12
/// bytes, expected 40") on a short reply.
[[nodiscard]] GsUsbDeviceConfig parse_gs_usb_device_config(std::span<const std::uint8_t> bytes);
/// 40 bytes (gs_device_bt_const) or 72 (gs_device_bt_const_extended).
[[nodiscard]] GsUsbBtConst parse_gs_usb_bt_const(std::span<const std::uint8_t> bytes);

// ---- Frames ---------------------------------------------------------------------------------

/// CAN FD DLC -> payload length (ISO 11898-1:2015 table 5 / linux can_fd_dlc2len): 0..8, then
/// 12, 16, 20, 24, 32, 48, 64 for DLC 9..15. `dlc` must be <= 15.
[[nodiscard]] std::uint8_t can_fd_dlc_to_len(std::uint8_t dlc) noexcept;
/// Payload length -> smallest DLC that holds it (can_fd_len2dlc); `len` must be <= 64.
[[nodiscard]] std::uint8_t can_fd_len_to_dlc(std::uint8_t len) noexcept;

/// One struct gs_host_frame, unpacked. can_id keeps the Linux flag bits (CAN_EFF_FLAG,
/// CAN_RTR_FLAG, CAN_ERR_FLAG).
struct GsUsbHostFrame {
  std::uint32_t echo_id = kGsUsbRxEchoId;  ///< TX slot, or kGsUsbRxEchoId for a received frame
  std::uint32_t can_id = 0;                ///< identifier | CAN_*_FLAG
  std::uint8_t can_dlc = 0;                ///< DLC (FD: the code 0..15, not the length)
  std::uint8_t channel = 0;
  std::uint8_t flags = 0;  ///< gs_usb_frame_flag bits
  std::uint8_t reserved = 0;
  std::array<std::uint8_t, 64> data{};  ///< only the first 8 exist for a classic frame
  std::uint32_t timestamp_us = 0;       ///< device time [us], when the format has time stamps
};

/// What a channel exchanges: set by the MODE flags at start.
struct GsUsbFrameFormat {
  bool fd_mode = false;       ///< GS_CAN_MODE_FD: FD frames allowed, TX frames carry data[64]
  bool hw_timestamp = false;  ///< GS_CAN_MODE_HW_TIMESTAMP: RX and echo frames carry timestamp_us
  /// Bytes of every frame the host sends: 20 classic, 76 FD mode (gs_usb.c hf_size_tx).
  [[nodiscard]] std::size_t tx_bytes() const noexcept;
  /// Largest frame the device sends: 20/24/76/80 (gs_usb.c hf_size_rx).
  [[nodiscard]] std::size_t rx_max_bytes() const noexcept;
};

/// Writes `hf` in the TX layout of `format` (no time stamp; the data area zero past the
/// payload). Returns the bytes written, or 0 when `out` is too small. Real-time safe.
[[nodiscard]] std::size_t pack_gs_usb_frame(const GsUsbHostFrame& hf,
                                            const GsUsbFrameFormat& format,
                                            std::span<std::uint8_t> out) noexcept;

enum class GsUsbUnpack : std::uint8_t {
  kOk,
  kTruncated,  ///< shorter than the header, or than the frame its flags announce
  kOversized,  ///< longer than the largest frame of the format
  kNotFdMode,  ///< an FD frame on a channel not started in FD mode
};
/// Reads one frame the device sent (a bulk IN transfer holds exactly one). The frame needs
/// 12 + (FD flag ? 64 : 8) + (hw_timestamp ? 4 : 0) bytes and may be padded up to
/// format.rx_max_bytes(); anything else is rejected and nothing past `in` is read. Real-time safe.
[[nodiscard]] GsUsbUnpack unpack_gs_usb_frame(std::span<const std::uint8_t> in,
                                              const GsUsbFrameFormat& format,
                                              GsUsbHostFrame& out) noexcept;

/// CanFrame -> gs_host_frame. False when `f` cannot go out: identifier out of range, classic
/// length > 8, FD length not a CAN FD length, or an FD frame while !fd_mode. Real-time safe.
[[nodiscard]] bool to_gs_usb_frame(const CanFrame& f, std::uint32_t echo_id, std::uint8_t channel,
                                   bool fd_mode, GsUsbHostFrame& out) noexcept;

enum class GsUsbFrameKind : std::uint8_t { kData, kError, kRemote, kBadDlc };
/// gs_host_frame -> CanFrame (timestamp left as is). Classic DLC 9..15 means 8 bytes (CAN 2.0);
/// a DLC above 15 is kBadDlc. Real-time safe.
[[nodiscard]] GsUsbFrameKind from_gs_usb_frame(const GsUsbHostFrame& hf, CanFrame& out) noexcept;

/// The echo ids of frames in flight: the host tags each TX frame with a free id, the device
/// echoes the frame back with it once sent on the bus (gs_usb.c gs_alloc_tx_context and the
/// echo branch of gs_usb_receive_bulk_callback). Real-time safe; single-threaded.
class GsUsbEchoPool {
 public:
  static constexpr std::uint32_t kSlots = 64;
  /// Takes the lowest free id. False when all kSlots are in flight.
  [[nodiscard]] bool acquire(std::uint32_t& echo_id) noexcept;
  /// Frees `echo_id`. False when it was not in flight (an unknown or repeated echo).
  [[nodiscard]] bool release(std::uint32_t echo_id) noexcept;
  [[nodiscard]] std::uint32_t in_flight() const noexcept;
  void reset() noexcept { busy_ = 0; }

 private:
  std::uint64_t busy_ = 0;  ///< bit i set: id i in flight
};

// ---- Transport --------------------------------------------------------------------------------

/// Capacity of one received bulk transfer [bytes]: more than any gs_host_frame, so an oversized
/// transfer is seen as such.
inline constexpr std::size_t kGsUsbRxTransferBytes = 128;

/// One completed bulk IN transfer.
struct GsUsbRxTransfer {
  std::array<std::uint8_t, kGsUsbRxTransferBytes> bytes{};
  std::uint32_t size = 0;         ///< bytes received (<= bytes.size())
  bool overflow = false;          ///< the device sent more than the transfer could hold
  std::int64_t host_time_ns = 0;  ///< CLOCK_REALTIME when the transfer completed [ns]
};

struct GsUsbTransportStats {
  std::uint64_t rx_ring_overflows = 0;    ///< IN transfers lost: receive() not called often enough
  std::uint64_t in_transfer_errors = 0;   ///< bulk IN transfers that failed
  std::uint64_t out_transfer_errors = 0;  ///< bulk OUT transfers that failed
  bool device_gone = false;               ///< the device was unplugged
};

/// What the gs_usb protocol needs from USB. Control transfers are setup-time (blocking, may
/// throw std::runtime_error with one line); bulk_out() and poll_in() are the frame path
/// (non-blocking, noexcept, no allocation).
class GsUsbTransport {
 public:
  virtual ~GsUsbTransport() = default;
  /// bInterfaceNumber of the claimed interface (wIndex of HOST_FORMAT and DEVICE_CONFIG).
  [[nodiscard]] virtual std::uint16_t interface_number() const noexcept { return 0; }
  /// Vendor request host -> device (bmRequestType kGsUsbRequestTypeOut) with `data`.
  virtual void control_out(GsUsbRequest request, std::uint16_t value, std::uint16_t index,
                           std::span<const std::uint8_t> data) = 0;
  /// Vendor request device -> host (kGsUsbRequestTypeIn) into `data`; returns the bytes read.
  [[nodiscard]] virtual std::size_t control_in(GsUsbRequest request, std::uint16_t value,
                                               std::uint16_t index,
                                               std::span<std::uint8_t> data) = 0;
  /// Starts the asynchronous bulk IN path (transfers of `transfer_bytes`); completed transfers
  /// wait in a bounded queue for poll_in(). Setup.
  virtual void start_receiving(std::size_t transfer_bytes) = 0;
  /// Stops the IN path and flushes queued OUT transfers. Idempotent.
  virtual void stop_receiving() noexcept = 0;
  /// Queues one bulk OUT transfer of `bytes` (<= kGsUsbMaxFrameBytes), labelled `tag` (the
  /// echo id). False when the queue is full. Real-time safe.
  [[nodiscard]] virtual bool bulk_out(std::span<const std::uint8_t> bytes,
                                      std::uint32_t tag) noexcept = 0;
  /// Takes the oldest completed IN transfer. False when none is waiting. Real-time safe.
  [[nodiscard]] virtual bool poll_in(GsUsbRxTransfer& out) noexcept = 0;
  /// Takes the tag of a queued OUT transfer that never reached the device (USB error, 1 s
  /// timeout, unplugged): its echo will not come. False when there is none. Real-time safe.
  [[nodiscard]] virtual bool poll_out_failed(std::uint32_t& tag) noexcept {
    (void)tag;
    return false;
  }
  [[nodiscard]] virtual GsUsbTransportStats transport_stats() const noexcept { return {}; }
};

/// One adapter found on the USB bus (diagnostics).
struct GsUsbDeviceInfo {
  std::uint8_t bus = 0;
  std::uint8_t address = 0;
  std::uint16_t vendor_id = 0;
  std::uint16_t product_id = 0;
  std::string serial;        ///< iSerialNumber, empty when it could not be read
  std::string manufacturer;  ///< iManufacturer
  std::string product;       ///< iProduct
  std::string open_error;    ///< why the device could not be opened (e.g. "LIBUSB_ERROR_ACCESS")
};
/// Enumerates every device with an ID of kGsUsbIds (opens each briefly to read its strings).
/// Throws std::runtime_error when libusb cannot initialise. Setup.
[[nodiscard]] std::vector<GsUsbDeviceInfo> list_gs_usb_devices();

/// libusb transport: one claimed interface 0 of a gs_usb device, a libusb event thread that
/// keeps bulk IN transfers on 0x81 in flight and submits bulk OUT transfers on 0x02, and two
/// bounded SPSC rings between that thread and the frame thread. Non-copyable; on destruction
/// cancels its transfers, releases the interface and re-attaches the kernel driver it detached.
class GsUsbDevice final : public GsUsbTransport {
 public:
  /// Opens the first device of kGsUsbIds, or the one whose serial string is `serial`. Throws
  /// std::runtime_error with one line: "gsusb: no candleLight/gs_usb device (USB 1D50:606F)
  /// found", "gsusb: no gs_usb device with serial 'X' (found: A, B)", "gsusb: cannot open ...
  /// (LIBUSB_ERROR_ACCESS): ..." or "gsusb: cannot claim interface 0 (LIBUSB_ERROR_BUSY) ...".
  [[nodiscard]] static std::unique_ptr<GsUsbDevice> open(std::string_view serial = {});

  GsUsbDevice(const GsUsbDevice&) = delete;
  GsUsbDevice& operator=(const GsUsbDevice&) = delete;
  ~GsUsbDevice() override;

  [[nodiscard]] std::uint16_t interface_number() const noexcept override;
  void control_out(GsUsbRequest request, std::uint16_t value, std::uint16_t index,
                   std::span<const std::uint8_t> data) override;
  [[nodiscard]] std::size_t control_in(GsUsbRequest request, std::uint16_t value,
                                       std::uint16_t index, std::span<std::uint8_t> data) override;
  void start_receiving(std::size_t transfer_bytes) override;
  void stop_receiving() noexcept override;
  /// Real-time safe: copies into the OUT ring and wakes the event thread
  /// (libusb_interrupt_event_handler: one short internal lock and an eventfd write; no
  /// allocation). The event thread submits the transfer.
  [[nodiscard]] bool bulk_out(std::span<const std::uint8_t> bytes,
                              std::uint32_t tag) noexcept override;
  [[nodiscard]] bool poll_in(GsUsbRxTransfer& out) noexcept override;
  [[nodiscard]] bool poll_out_failed(std::uint32_t& tag) noexcept override;
  [[nodiscard]] GsUsbTransportStats transport_stats() const noexcept override;

  [[nodiscard]] const GsUsbDeviceInfo& info() const noexcept;

  struct Impl;

 private:
  explicit GsUsbDevice(std::unique_ptr<Impl> impl) noexcept;
  std::unique_ptr<Impl> impl_;
};

// ---- Endpoint ---------------------------------------------------------------------------------

struct GsUsbOptions {
  std::uint8_t channel = 0;                ///< CAN channel of the device
  std::uint32_t bitrate_bps = 500'000;     ///< nominal (arbitration) bit rate [bit/s]
  double sample_point = 0.875;             ///< nominal sample point [fraction of the bit]
  bool fd = false;                         ///< start in CAN FD mode (GS_CAN_MODE_FD)
  std::uint32_t dbitrate_bps = 2'000'000;  ///< CAN FD data-phase bit rate [bit/s], when fd
  double data_sample_point = 0.75;         ///< data-phase sample point [fraction of the bit]
  bool listen_only = false;                ///< GS_CAN_MODE_LISTEN_ONLY (never ACKs or sends)
  bool loopback = false;             ///< GS_CAN_MODE_LOOP_BACK (internal loopback, for bench tests)
  bool one_shot = false;             ///< GS_CAN_MODE_ONE_SHOT (no automatic retransmission)
  bool hw_timestamps = true;         ///< GS_CAN_MODE_HW_TIMESTAMP when the device offers it
  bool bus_error_reporting = false;  ///< GS_CAN_MODE_BERR_REPORTING when offered (may flood)
  bool receive_own = false;          ///< hand the device's echoes of our own frames to receive()
  /// Added to every time stamp [ns]. Stamps are CLOCK_REALTIME: the host's at completion of the
  /// IN transfer, or with hardware stamps the device's microsecond counter aligned to
  /// CLOCK_REALTIME once at start (no drift correction).
  std::int64_t timestamp_offset_ns = 0;
};

struct GsUsbStats {
  std::uint64_t frames_sent = 0;        ///< frames handed to the transport
  std::uint64_t frames_received = 0;    ///< data frames handed out by receive()
  std::uint64_t echoes = 0;             ///< TX confirmations matched to a frame in flight
  std::uint64_t unknown_echoes = 0;     ///< echoes whose id was not in flight
  std::uint64_t tx_pool_exhausted = 0;  ///< send() refused: all echo ids in flight
  std::uint64_t tx_queue_full = 0;      ///< send() refused: the transport queue is full
  std::uint64_t tx_failed = 0;          ///< frames queued but lost on USB (no echo will come)
  std::uint64_t tx_rejected = 0;        ///< send() refused: frame invalid for this channel
  std::uint64_t rx_truncated = 0;       ///< IN transfers shorter than their frame
  std::uint64_t rx_oversized = 0;       ///< IN transfers longer than any frame of the format
  std::uint64_t rx_malformed = 0;       ///< FD frame outside FD mode, DLC above 15
  std::uint64_t rx_wrong_channel = 0;   ///< frames of another channel
  std::uint64_t rx_rtr_dropped = 0;     ///< remote frames (CanFrame cannot carry CAN_RTR_FLAG)
};

/// A CanEndpoint on one channel of a gs_usb device. The constructor runs the device setup that
/// gs_usb.c's probe and open run (HOST_FORMAT, DEVICE_CONFIG, BT_CONST [, BT_CONST_EXT], MODE
/// reset, BITTIMING [, DATA_BITTIMING] [, TIMESTAMP], start of the IN path, MODE start); the
/// destructor resets the channel. receive() also matches echoes, so it must be called regularly
/// (every frame) or the echo pool runs dry and send() refuses.
class GsUsbEndpoint final : public CanEndpoint {
 public:
  /// Throws std::runtime_error ("gsusb: ...", one line) when the device refuses or lacks what
  /// `options` ask for, std::invalid_argument for an impossible bit rate.
  GsUsbEndpoint(std::unique_ptr<GsUsbTransport> transport, const GsUsbOptions& options = {});
  /// GsUsbDevice::open(serial) + the constructor.
  [[nodiscard]] static std::unique_ptr<GsUsbEndpoint> open(std::string_view serial,
                                                           const GsUsbOptions& options = {});
  GsUsbEndpoint(const GsUsbEndpoint&) = delete;
  GsUsbEndpoint& operator=(const GsUsbEndpoint&) = delete;
  ~GsUsbEndpoint() override;

  /// Takes an echo id, packs and queues the frame. False and counted when the frame is invalid
  /// (tx_rejected), all echo ids are in flight (tx_pool_exhausted) or the transport queue is
  /// full (tx_queue_full). Real-time safe.
  [[nodiscard]] bool send(const CanFrame& frame) noexcept override;
  /// Processes waiting IN transfers (at most 64 per call): echoes free their id, error frames go
  /// to error_counters(), malformed transfers are counted; returns at the first data frame.
  /// Also frees the ids of frames the transport reports lost (tx_failed). Real-time safe.
  [[nodiscard]] bool receive(CanFrame& out) noexcept override;

  [[nodiscard]] const GsUsbStats& stats() const noexcept { return stats_; }
  [[nodiscard]] const CanErrorCounters& error_counters() const noexcept {
    return errors_.counters();
  }
  [[nodiscard]] CanBusState bus_state() const noexcept { return errors_.state(); }
  [[nodiscard]] const GsUsbDeviceConfig& device_config() const noexcept { return device_config_; }
  [[nodiscard]] const GsUsbBtConst& bt_const() const noexcept { return bt_const_; }
  [[nodiscard]] const GsUsbBitTiming& bit_timing() const noexcept { return bit_timing_; }
  [[nodiscard]] const GsUsbBitTiming& data_bit_timing() const noexcept { return data_bit_timing_; }
  [[nodiscard]] std::uint32_t mode_flags() const noexcept { return mode_flags_; }
  [[nodiscard]] const GsUsbFrameFormat& frame_format() const noexcept { return format_; }
  [[nodiscard]] std::uint32_t echoes_in_flight() const noexcept { return pool_.in_flight(); }
  [[nodiscard]] GsUsbTransport& transport() noexcept { return *transport_; }

 private:
  std::int64_t stamp(const GsUsbHostFrame& hf, const GsUsbRxTransfer& t) noexcept;
  void reclaim_failed_out() noexcept;

  std::unique_ptr<GsUsbTransport> transport_;
  GsUsbOptions options_;
  GsUsbDeviceConfig device_config_;
  GsUsbBtConst bt_const_;
  GsUsbBitTiming bit_timing_;
  GsUsbBitTiming data_bit_timing_;
  std::uint32_t mode_flags_ = 0;
  GsUsbFrameFormat format_;
  GsUsbEchoPool pool_;
  GsUsbStats stats_;
  CanErrorTracker errors_{CanBusState::kStopped};
  // Hardware time stamps: device counter at setup, CLOCK_REALTIME then, and the unwrapped
  // microseconds since (a signed 32-bit step per frame, so the 71.6-minute wrap is followed).
  std::uint32_t hw_last_us_ = 0;
  std::int64_t hw_elapsed_us_ = 0;
  std::int64_t hw_origin_ns_ = 0;
};

}  // namespace radar_emu::io
