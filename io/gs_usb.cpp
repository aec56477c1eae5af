#include "io/gs_usb.hpp"

#include <libusb.h>
#include <linux/can.h>

#include <algorithm>
#include <atomic>
#include <bit>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <stdexcept>
#include <thread>
#include <utility>

#include "io/socketcan.hpp"  // realtime_now_ns()
#include "io/spsc_ring.hpp"

namespace radar_emu::io {

namespace {

void put_le32(std::span<std::uint8_t> out, std::size_t at, std::uint32_t v) noexcept {
  out[at + 0] = static_cast<std::uint8_t>(v);
  out[at + 1] = static_cast<std::uint8_t>(v >> 8);
  out[at + 2] = static_cast<std::uint8_t>(v >> 16);
  out[at + 3] = static_cast<std::uint8_t>(v >> 24);
}

std::uint32_t get_le32(std::span<const std::uint8_t> in, std::size_t at) noexcept {
  return static_cast<std::uint32_t>(in[at]) | (static_cast<std::uint32_t>(in[at + 1]) << 8) |
         (static_cast<std::uint32_t>(in[at + 2]) << 16) |
         (static_cast<std::uint32_t>(in[at + 3]) << 24);
}

std::string hex32(std::uint32_t v) {
  char buf[16];
  std::snprintf(buf, sizeof buf, "0x%08x", v);
  return buf;
}

struct Candidate {
  GsUsbBitTiming bt;
  double rate_error = 0.0;
  double sp_error = 0.0;
  bool valid = false;
};

}  // namespace

// ---- Names, bit timing -------------------------------------------------------------------------

std::string_view to_string(GsUsbRequest request) noexcept {
  switch (request) {
    case GsUsbRequest::kHostFormat:
      return "HOST_FORMAT";
    case GsUsbRequest::kBitTiming:
      return "BITTIMING";
    case GsUsbRequest::kMode:
      return "MODE";
    case GsUsbRequest::kBerr:
      return "BERR";
    case GsUsbRequest::kBtConst:
      return "BT_CONST";
    case GsUsbRequest::kDeviceConfig:
      return "DEVICE_CONFIG";
    case GsUsbRequest::kTimestamp:
      return "TIMESTAMP";
    case GsUsbRequest::kIdentify:
      return "IDENTIFY";
    case GsUsbRequest::kGetUserId:
      return "GET_USER_ID";
    case GsUsbRequest::kSetUserId:
      return "SET_USER_ID";
    case GsUsbRequest::kDataBitTiming:
      return "DATA_BITTIMING";
    case GsUsbRequest::kBtConstExt:
      return "BT_CONST_EXT";
    case GsUsbRequest::kSetTermination:
      return "SET_TERMINATION";
    case GsUsbRequest::kGetTermination:
      return "GET_TERMINATION";
    case GsUsbRequest::kGetState:
      return "GET_STATE";
  }
  return "?";
}

double GsUsbBitTiming::bitrate_bps(std::uint32_t fclk_can_hz) const noexcept {
  const double tq = static_cast<double>(brp) * static_cast<double>(tq_per_bit());
  return tq > 0.0 ? static_cast<double>(fclk_can_hz) / tq : 0.0;
}

double GsUsbBitTiming::sample_point() const noexcept {
  return static_cast<double>(1 + prop_seg + phase_seg1) / static_cast<double>(tq_per_bit());
}

GsUsbBitTiming compute_gs_usb_bit_timing(std::uint32_t fclk_can_hz, const GsUsbTimingLimits& lim,
                                         std::uint32_t bitrate_bps, double sample_point) {
  const std::string what = "gsusb: bit rate " + std::to_string(bitrate_bps) + " bit/s from a " +
                           std::to_string(fclk_can_hz) + " Hz clock: ";
  if (fclk_can_hz == 0 || bitrate_bps == 0)
    throw std::invalid_argument(what + "clock and bit rate must be positive");
  if (!(sample_point >= 0.5 && sample_point <= 0.95))
    throw std::invalid_argument(what + "sample point " + std::to_string(sample_point) +
                                " outside 0.5 .. 0.95");
  if (lim.tseg1_max < lim.tseg1_min || lim.tseg2_max < lim.tseg2_min || lim.brp_max < lim.brp_min ||
      lim.tseg1_max < 2 || lim.tseg2_max < 1 || lim.brp_max < 1)
    throw std::invalid_argument(what + "the device reports inconsistent timing limits");

  // Bit time = (1 + tseg1 + tseg2) tq, tq = brp / fclk (gs_device_bittiming; bit rate = fclk /
  // (brp * (1 + prop_seg + phase_seg1 + phase_seg2))). Every prescaler step is tried; for each,
  // the nearest whole number of tq per bit, then the split of the bit whose sample point is
  // nearest the target.
  const std::uint32_t tseg1_lo = std::max<std::uint32_t>(lim.tseg1_min, 2);  // prop 1 + ps1 >= 1
  const std::uint32_t tseg2_lo = std::max<std::uint32_t>(lim.tseg2_min, 1);
  const std::uint32_t n_min = 1 + tseg1_lo + tseg2_lo;
  const std::uint32_t n_max = 1 + lim.tseg1_max + lim.tseg2_max;
  const std::uint32_t step = std::max<std::uint32_t>(lim.brp_inc, 1);
  const double target = static_cast<double>(bitrate_bps);
  constexpr double kTie = 1e-12;

  Candidate best;
  for (std::uint64_t brp = std::max<std::uint32_t>(lim.brp_min, 1); brp <= lim.brp_max;
       brp += step) {
    const double exact_n = static_cast<double>(fclk_can_hz) / (static_cast<double>(brp) * target);
    const auto n = static_cast<std::uint32_t>(std::llround(exact_n));
    if (exact_n < static_cast<double>(n_min) - 0.5)
      break;  // larger prescalers give fewer tq still
    if (n < n_min || n > n_max)
      continue;
    const double rate = static_cast<double>(fclk_can_hz) / static_cast<double>(brp * n);
    const double rate_error = std::abs(rate - target) / target;
    Candidate c;
    // Every allowed split of the bit; the nearest sample point wins, the earlier one (larger
    // tseg2) on a tie.
    for (std::uint32_t tseg2 = tseg2_lo; tseg2 <= lim.tseg2_max && tseg2 + 1 + tseg1_lo <= n;
         ++tseg2) {
      const std::uint32_t tseg1 = n - 1 - tseg2;
      if (tseg1 > lim.tseg1_max)
        continue;
      const double sp = static_cast<double>(1 + tseg1) / static_cast<double>(n);
      const double sp_error = std::abs(sp - sample_point);
      if (!c.valid || sp_error <= c.sp_error + kTie) {
        c.valid = true;
        c.sp_error = sp_error;
        c.rate_error = rate_error;
        c.bt.brp = static_cast<std::uint32_t>(brp);
        c.bt.prop_seg = 1;
        c.bt.phase_seg1 = tseg1 - 1;
        c.bt.phase_seg2 = tseg2;
      }
    }
    if (!c.valid)
      continue;
    const bool better =
        !best.valid || c.rate_error < best.rate_error - kTie ||
        (c.rate_error <= best.rate_error + kTie && c.sp_error < best.sp_error - kTie);
    if (better)
      best = c;
  }
  if (!best.valid)
    throw std::invalid_argument(what + "no prescaler in " + std::to_string(lim.brp_min) + ".." +
                                std::to_string(lim.brp_max) + " gives " + std::to_string(n_min) +
                                ".." + std::to_string(n_max) + " time quanta per bit");
  if (best.rate_error > kGsUsbMaxBitRateError) {
    char buf[160];
    std::snprintf(buf, sizeof buf, "closest is %.0f bit/s, %.2f %% off (at most %.2f %% allowed)",
                  best.bt.bitrate_bps(fclk_can_hz), 100.0 * best.rate_error,
                  100.0 * kGsUsbMaxBitRateError);
    throw std::invalid_argument(what + buf);
  }
  // SJW <= min(phase_seg1, phase_seg2): a resynchronisation may lengthen phase_seg1 or shorten
  // phase_seg2 by at most SJW (Bosch CAN 2.0, "Bit Timing Requirements"; ISO 11898-1).
  best.bt.sjw =
      std::max<std::uint32_t>(1, std::min({lim.sjw_max, best.bt.phase_seg1, best.bt.phase_seg2}));
  return best.bt;
}

// ---- Control payloads ------------------------------------------------------------------------

std::array<std::uint8_t, 4> pack_gs_usb_host_config() noexcept {
  std::array<std::uint8_t, 4> out{};
  put_le32(out, 0, kGsUsbHostFormat);
  return out;
}

std::array<std::uint8_t, 8> pack_gs_usb_mode(std::uint32_t mode, std::uint32_t flags) noexcept {
  std::array<std::uint8_t, 8> out{};
  put_le32(out, 0, mode);
  put_le32(out, 4, flags);
  return out;
}

std::array<std::uint8_t, 20> pack_gs_usb_bit_timing(const GsUsbBitTiming& bt) noexcept {
  std::array<std::uint8_t, 20> out{};
  put_le32(out, 0, bt.prop_seg);
  put_le32(out, 4, bt.phase_seg1);
  put_le32(out, 8, bt.phase_seg2);
  put_le32(out, 12, bt.sjw);
  put_le32(out, 16, bt.brp);
  return out;
}

namespace {
void require_reply(std::string_view what, std::size_t got, std::size_t want) {
  if (got < want)
    throw std::runtime_error("gsusb: " + std::string(what) + " reply has " + std::to_string(got) +
                             " bytes, expected " + std::to_string(want));
}
GsUsbTimingLimits parse_limits(std::span<const std::uint8_t> b, std::size_t at) noexcept {
  GsUsbTimingLimits l;
  l.tseg1_min = get_le32(b, at + 0);
  l.tseg1_max = get_le32(b, at + 4);
  l.tseg2_min = get_le32(b, at + 8);
  l.tseg2_max = get_le32(b, at + 12);
  l.sjw_max = get_le32(b, at + 16);
  l.brp_min = get_le32(b, at + 20);
  l.brp_max = get_le32(b, at + 24);
  l.brp_inc = get_le32(b, at + 28);
  return l;
}
}  // namespace

GsUsbDeviceConfig parse_gs_usb_device_config(std::span<const std::uint8_t> bytes) {
  require_reply("DEVICE_CONFIG", bytes.size(), 12);
  GsUsbDeviceConfig c;
  c.icount = bytes[3];  // reserved1..3, icount
  c.sw_version = get_le32(bytes, 4);
  c.hw_version = get_le32(bytes, 8);
  return c;
}

GsUsbBtConst parse_gs_usb_bt_const(std::span<const std::uint8_t> bytes) {
  require_reply("BT_CONST", bytes.size(), 40);
  GsUsbBtConst c;
  c.feature = get_le32(bytes, 0);
  c.fclk_can_hz = get_le32(bytes, 4);
  c.nominal = parse_limits(bytes, 8);
  c.data = bytes.size() >= 72 ? parse_limits(bytes, 40) : c.nominal;
  return c;
}

// ---- Frames -------------------------------------------------------------------------------------

std::uint8_t can_fd_dlc_to_len(std::uint8_t dlc) noexcept {
  static constexpr std::array<std::uint8_t, 16> kLen{0, 1,  2,  3,  4,  5,  6,  7,
                                                     8, 12, 16, 20, 24, 32, 48, 64};
  return kLen[dlc & 0x0F];
}

std::uint8_t can_fd_len_to_dlc(std::uint8_t len) noexcept {
  if (len <= 8)
    return len;
  std::uint8_t dlc = 9;
  while (dlc < 15 && can_fd_dlc_to_len(dlc) < len)
    ++dlc;
  return dlc;
}

std::size_t GsUsbFrameFormat::tx_bytes() const noexcept {
  return fd_mode ? kGsUsbFdFrameBytes : kGsUsbClassicFrameBytes;
}

std::size_t GsUsbFrameFormat::rx_max_bytes() const noexcept {
  return kGsUsbHeaderBytes + (fd_mode ? 64U : 8U) + (hw_timestamp ? 4U : 0U);
}

std::size_t pack_gs_usb_frame(const GsUsbHostFrame& hf, const GsUsbFrameFormat& format,
                              std::span<std::uint8_t> out) noexcept {
  const std::size_t n = format.tx_bytes();
  if (out.size() < n)
    return 0;
  put_le32(out, 0, hf.echo_id);
  put_le32(out, 4, hf.can_id);
  out[8] = hf.can_dlc;
  out[9] = hf.channel;
  out[10] = hf.flags;
  out[11] = hf.reserved;
  std::copy_n(hf.data.begin(), n - kGsUsbHeaderBytes, out.begin() + kGsUsbHeaderBytes);
  return n;
}

GsUsbUnpack unpack_gs_usb_frame(std::span<const std::uint8_t> in, const GsUsbFrameFormat& format,
                                GsUsbHostFrame& out) noexcept {
  if (in.size() < kGsUsbHeaderBytes)
    return GsUsbUnpack::kTruncated;
  const std::uint8_t flags = in[10];
  const bool fd = (flags & gs_usb_frame_flag::kFd) != 0;
  if (fd && !format.fd_mode)
    return GsUsbUnpack::kNotFdMode;
  if (in.size() > format.rx_max_bytes())
    return GsUsbUnpack::kOversized;
  const std::size_t data_bytes = fd ? 64 : 8;
  const std::size_t need = kGsUsbHeaderBytes + data_bytes + (format.hw_timestamp ? 4 : 0);
  if (in.size() < need)
    return GsUsbUnpack::kTruncated;
  out.echo_id = get_le32(in, 0);
  out.can_id = get_le32(in, 4);
  out.can_dlc = in[8];
  out.channel = in[9];
  out.flags = flags;
  out.reserved = in[11];
  std::copy_n(in.begin() + kGsUsbHeaderBytes, data_bytes, out.data.begin());
  std::fill(out.data.begin() + static_cast<std::ptrdiff_t>(data_bytes), out.data.end(),
            std::uint8_t{0});
  out.timestamp_us = format.hw_timestamp ? get_le32(in, kGsUsbHeaderBytes + data_bytes) : 0;
  return GsUsbUnpack::kOk;
}

bool to_gs_usb_frame(const CanFrame& f, std::uint32_t echo_id, std::uint8_t channel, bool fd_mode,
                     GsUsbHostFrame& out) noexcept {
  if (f.id > (f.extended ? CAN_EFF_MASK : CAN_SFF_MASK))
    return false;
  if (f.fd ? (!fd_mode || !is_can_fd_length(f.len)) : f.len > 8)
    return false;
  out = GsUsbHostFrame{};
  out.echo_id = echo_id;
  out.can_id = f.id | (f.extended ? CAN_EFF_FLAG : 0U);
  out.channel = channel;
  if (f.fd) {
    out.can_dlc = can_fd_len_to_dlc(f.len);
    out.flags = gs_usb_frame_flag::kFd;
    if (f.fd_flags & 0x01)  // candump flag nibble: BRS = 1, ESI = 2 (can_frame.hpp)
      out.flags |= gs_usb_frame_flag::kBrs;
    if (f.fd_flags & 0x02)
      out.flags |= gs_usb_frame_flag::kEsi;
  } else {
    out.can_dlc = f.len;
  }
  std::copy_n(f.data.begin(), f.len, out.data.begin());
  return true;
}

GsUsbFrameKind from_gs_usb_frame(const GsUsbHostFrame& hf, CanFrame& out) noexcept {
  if (hf.can_dlc > 15)
    return GsUsbFrameKind::kBadDlc;
  if (hf.can_id & CAN_ERR_FLAG)
    return GsUsbFrameKind::kError;
  if (hf.can_id & CAN_RTR_FLAG)
    return GsUsbFrameKind::kRemote;
  const bool fd = (hf.flags & gs_usb_frame_flag::kFd) != 0;
  out.extended = (hf.can_id & CAN_EFF_FLAG) != 0;
  out.id = hf.can_id & (out.extended ? CAN_EFF_MASK : CAN_SFF_MASK);
  out.fd = fd;
  out.fd_flags = 0;
  if (fd) {
    out.len = can_fd_dlc_to_len(hf.can_dlc);
    if (hf.flags & gs_usb_frame_flag::kBrs)
      out.fd_flags |= 0x01;
    if (hf.flags & gs_usb_frame_flag::kEsi)
      out.fd_flags |= 0x02;
  } else {
    out.len = std::min<std::uint8_t>(hf.can_dlc, 8);  // DLC 9..15 = 8 bytes (CAN 2.0)
  }
  std::copy_n(hf.data.begin(), out.len, out.data.begin());
  std::fill(out.data.begin() + out.len, out.data.end(), std::uint8_t{0});
  return GsUsbFrameKind::kData;
}

bool GsUsbEchoPool::acquire(std::uint32_t& echo_id) noexcept {
  const int free_bit = std::countr_one(busy_);
  if (free_bit >= static_cast<int>(kSlots))
    return false;
  echo_id = static_cast<std::uint32_t>(free_bit);
  busy_ |= std::uint64_t{1} << free_bit;
  return true;
}

bool GsUsbEchoPool::release(std::uint32_t echo_id) noexcept {
  if (echo_id >= kSlots)
    return false;
  const std::uint64_t bit = std::uint64_t{1} << echo_id;
  if ((busy_ & bit) == 0)
    return false;
  busy_ &= ~bit;
  return true;
}

std::uint32_t GsUsbEchoPool::in_flight() const noexcept {
  return static_cast<std::uint32_t>(std::popcount(busy_));
}

// ---- libusb transport ------------------------------------------------------------------------

namespace {

std::string usb_error(int code) {
  return libusb_error_name(code);
}

bool is_gs_usb(const libusb_device_descriptor& d) noexcept {
  return std::any_of(kGsUsbIds.begin(), kGsUsbIds.end(), [&](const GsUsbId& id) {
    return id.vendor_id == d.idVendor && id.product_id == d.idProduct;
  });
}

std::string read_string(libusb_device_handle* h, std::uint8_t index) {
  if (index == 0)
    return {};
  unsigned char buf[256];
  const int n = libusb_get_string_descriptor_ascii(h, index, buf, sizeof buf);
  if (n <= 0)
    return {};
  return std::string(reinterpret_cast<const char*>(buf), static_cast<std::size_t>(n));
}

struct Context {
  libusb_context* ctx = nullptr;
  Context() {
    const int r = libusb_init(&ctx);
    if (r != 0)
      throw std::runtime_error("gsusb: libusb_init failed (" + usb_error(r) + ")");
  }
  ~Context() {
    if (ctx != nullptr)
      libusb_exit(ctx);
  }
  Context(const Context&) = delete;
  Context& operator=(const Context&) = delete;
  libusb_context* release() noexcept { return std::exchange(ctx, nullptr); }
};

struct DeviceList {
  libusb_device** list = nullptr;
  ssize_t count = 0;
  explicit DeviceList(libusb_context* ctx) {
    count = libusb_get_device_list(ctx, &list);
    if (count < 0)
      throw std::runtime_error("gsusb: libusb_get_device_list failed (" +
                               usb_error(static_cast<int>(count)) + ")");
  }
  ~DeviceList() {
    if (list != nullptr)
      libusb_free_device_list(list, 1);
  }
  DeviceList(const DeviceList&) = delete;
  DeviceList& operator=(const DeviceList&) = delete;
  [[nodiscard]] std::span<libusb_device*> devices() const noexcept {
    return {list, static_cast<std::size_t>(count)};
  }
};

GsUsbDeviceInfo describe(libusb_device* dev, const libusb_device_descriptor& d,
                         libusb_device_handle* h) {
  GsUsbDeviceInfo info;
  info.bus = libusb_get_bus_number(dev);
  info.address = libusb_get_device_address(dev);
  info.vendor_id = d.idVendor;
  info.product_id = d.idProduct;
  if (h != nullptr) {
    info.serial = read_string(h, d.iSerialNumber);
    info.manufacturer = read_string(h, d.iManufacturer);
    info.product = read_string(h, d.iProduct);
  }
  return info;
}

constexpr unsigned kControlTimeoutMs = 1000;
constexpr std::size_t kInTransfers = 16;   // bulk IN transfers kept in flight
constexpr std::size_t kOutTransfers = 16;  // bulk OUT transfers at most in flight
constexpr std::size_t kRxRingSlots = 1024;
constexpr std::size_t kTxRingSlots = 128;

}  // namespace

std::vector<GsUsbDeviceInfo> list_gs_usb_devices() {
  Context c;
  DeviceList list(c.ctx);
  std::vector<GsUsbDeviceInfo> out;
  for (libusb_device* dev : list.devices()) {
    libusb_device_descriptor d{};
    if (libusb_get_device_descriptor(dev, &d) != 0 || !is_gs_usb(d))
      continue;
    libusb_device_handle* h = nullptr;
    const int r = libusb_open(dev, &h);
    GsUsbDeviceInfo info = describe(dev, d, r == 0 ? h : nullptr);
    if (r != 0)
      info.open_error = usb_error(r);
    else
      libusb_close(h);
    out.push_back(std::move(info));
  }
  return out;
}

struct GsUsbDevice::Impl {
  struct TxItem {
    std::array<std::uint8_t, kGsUsbMaxFrameBytes> bytes{};
    std::uint32_t size = 0;
    std::uint32_t tag = 0;
  };
  struct OutSlot {
    Impl* self = nullptr;
    libusb_transfer* transfer = nullptr;
    std::uint32_t tag = 0;
    std::array<std::uint8_t, kGsUsbMaxFrameBytes> buffer{};
  };

  libusb_context* ctx = nullptr;
  libusb_device_handle* handle = nullptr;
  int interface = 0;
  bool claimed = false;
  bool detached = false;
  GsUsbDeviceInfo info;

  SpscRing<GsUsbRxTransfer> rx{kRxRingSlots};    // event thread -> frame thread
  SpscRing<TxItem> tx{kTxRingSlots};             // frame thread -> event thread
  SpscRing<std::uint32_t> failed{kTxRingSlots};  // event thread -> frame thread: lost OUT tags
  std::vector<libusb_transfer*> in;
  std::vector<std::vector<std::uint8_t>> in_buffers;
  std::vector<OutSlot> out;
  std::vector<std::size_t> out_free;  // event thread only, once it runs
  int active = 0;                     // transfers in flight; event thread only, once it runs
  bool receiving = false;
  std::atomic<bool> stopping{false};
  std::thread events;
  std::atomic<std::uint64_t> rx_ring_overflows{0};
  std::atomic<std::uint64_t> in_errors{0};
  std::atomic<std::uint64_t> out_errors{0};
  std::atomic<bool> device_gone{false};
  bool abandoned = false;  // transfers still in flight after the stop timeout

  Impl() = default;
  Impl(const Impl&) = delete;
  Impl& operator=(const Impl&) = delete;

  ~Impl() {
    stop();
    if (abandoned) {
      // libusb may still write into these transfers and buffers: leak them, with the handle
      // and the context, rather than free memory in use. Only after a 2 s stop timeout.
      static_cast<void>(new std::vector<OutSlot>(std::move(out)));
      static_cast<void>(new std::vector<std::vector<std::uint8_t>>(std::move(in_buffers)));
      return;
    }
    for (libusb_transfer* t : in)
      libusb_free_transfer(t);
    for (OutSlot& s : out)
      libusb_free_transfer(s.transfer);
    if (claimed)
      libusb_release_interface(handle, interface);
    if (detached)
      libusb_attach_kernel_driver(handle, interface);
    if (handle != nullptr)
      libusb_close(handle);
    if (ctx != nullptr)
      libusb_exit(ctx);
  }

  static void LIBUSB_CALL on_in(libusb_transfer* t) {
    auto* self = static_cast<Impl*>(t->user_data);
    switch (t->status) {
      case LIBUSB_TRANSFER_COMPLETED:
      case LIBUSB_TRANSFER_OVERFLOW: {
        GsUsbRxTransfer r;
        const auto n = static_cast<std::size_t>(std::max(t->actual_length, 0));
        r.size = static_cast<std::uint32_t>(std::min(n, r.bytes.size()));
        std::memcpy(r.bytes.data(), t->buffer, r.size);
        r.overflow = t->status == LIBUSB_TRANSFER_OVERFLOW || n > r.bytes.size();
        r.host_time_ns = realtime_now_ns();
        if (!self->rx.push(r))
          self->rx_ring_overflows.fetch_add(1, std::memory_order_relaxed);
        break;
      }
      case LIBUSB_TRANSFER_CANCELLED:
        --self->active;
        return;
      case LIBUSB_TRANSFER_NO_DEVICE:
        self->device_gone.store(true);
        --self->active;
        return;
      default:  // error, stall, timeout
        self->in_errors.fetch_add(1, std::memory_order_relaxed);
        break;
    }
    if (self->stopping.load() || libusb_submit_transfer(t) != 0)
      --self->active;
  }

  static void LIBUSB_CALL on_out(libusb_transfer* t) {
    auto* slot = static_cast<OutSlot*>(t->user_data);
    Impl* self = slot->self;
    if (t->status != LIBUSB_TRANSFER_COMPLETED) {
      if (t->status == LIBUSB_TRANSFER_NO_DEVICE)
        self->device_gone.store(true);
      else if (t->status != LIBUSB_TRANSFER_CANCELLED)
        self->out_errors.fetch_add(1, std::memory_order_relaxed);
      (void)self->failed.push(slot->tag);  // cannot overflow: capacity >= frames in flight
    }
    --self->active;
    self->out_free.push_back(static_cast<std::size_t>(slot - self->out.data()));
    if (!self->stopping.load())
      self->drain_tx();
  }

  void drain_tx() {
    TxItem item;
    while (!out_free.empty() && tx.pop(item)) {
      const std::size_t i = out_free.back();
      out_free.pop_back();
      OutSlot& s = out[i];
      std::memcpy(s.buffer.data(), item.bytes.data(), item.size);
      s.transfer->length = static_cast<int>(item.size);
      s.tag = item.tag;
      if (libusb_submit_transfer(s.transfer) == 0) {
        ++active;
      } else {
        out_errors.fetch_add(1, std::memory_order_relaxed);
        (void)failed.push(item.tag);
        out_free.push_back(i);
      }
    }
  }

  void run_events() {
    bool cancelled = false;
    auto cancel_start = std::chrono::steady_clock::now();
    for (;;) {
      if (stopping.load()) {
        if (!cancelled) {
          for (libusb_transfer* t : in)
            libusb_cancel_transfer(t);
          for (OutSlot& s : out)
            libusb_cancel_transfer(s.transfer);
          cancelled = true;
          cancel_start = std::chrono::steady_clock::now();
        }
        // Cancelled transfers complete through their callbacks; give up after 2 s (a device
        // that vanished mid-transfer), leaving those transfers allocated rather than freeing
        // memory libusb may still use.
        if (active <= 0 ||
            std::chrono::steady_clock::now() - cancel_start > std::chrono::seconds(2))
          break;
      } else {
        drain_tx();
      }
      timeval tv{0, 100'000};
      libusb_handle_events_timeout_completed(ctx, &tv, nullptr);
    }
    abandoned = active > 0;
  }

  void stop() noexcept {
    if (!receiving)
      return;
    stopping.store(true);
    libusb_interrupt_event_handler(ctx);
    if (events.joinable())
      events.join();
    receiving = false;
  }
};

GsUsbDevice::GsUsbDevice(std::unique_ptr<Impl> impl) noexcept : impl_(std::move(impl)) {}
GsUsbDevice::~GsUsbDevice() = default;

std::unique_ptr<GsUsbDevice> GsUsbDevice::open(std::string_view serial) {
  auto impl = std::make_unique<Impl>();
  Context c;
  DeviceList list(c.ctx);
  std::vector<std::string> seen;
  std::string open_failure;
  for (libusb_device* dev : list.devices()) {
    libusb_device_descriptor d{};
    if (libusb_get_device_descriptor(dev, &d) != 0 || !is_gs_usb(d))
      continue;
    libusb_device_handle* h = nullptr;
    const int r = libusb_open(dev, &h);
    if (r != 0) {
      const GsUsbDeviceInfo info = describe(dev, d, nullptr);
      open_failure = "cannot open the device on bus " + std::to_string(info.bus) + " address " +
                     std::to_string(info.address) + " (" + usb_error(r) + ")" +
                     (r == LIBUSB_ERROR_ACCESS
                          ? ": no permission; add a udev rule for 1d50:606f or run as root"
                          : "");
      seen.push_back("<unreadable>");
      continue;
    }
    GsUsbDeviceInfo info = describe(dev, d, h);
    if (!serial.empty() && info.serial != serial) {
      seen.push_back(info.serial.empty() ? "<no serial>" : info.serial);
      libusb_close(h);
      continue;
    }
    impl->handle = h;
    impl->info = std::move(info);
    break;
  }
  if (impl->handle == nullptr) {
    if (seen.empty())
      throw std::runtime_error("gsusb: no candleLight/gs_usb device (USB 1D50:606F) found");
    if (!open_failure.empty() && serial.empty())
      throw std::runtime_error("gsusb: " + open_failure);
    std::string found;
    for (const std::string& s : seen)
      found += (found.empty() ? "" : ", ") + s;
    throw std::runtime_error("gsusb: no gs_usb device with serial '" + std::string(serial) +
                             "' (found: " + found + ")" +
                             (open_failure.empty() ? "" : "; " + open_failure));
  }
  impl->ctx = c.release();  // impl's destructor closes handle and context from here on

  // Detach the kernel's gs_usb driver from interface 0 before claiming it (libusb API:
  // libusb_detach_kernel_driver; re-attached in ~Impl).
  const int active = libusb_kernel_driver_active(impl->handle, impl->interface);
  if (active == 1) {
    const int r = libusb_detach_kernel_driver(impl->handle, impl->interface);
    if (r != 0)
      throw std::runtime_error("gsusb: cannot detach the kernel gs_usb driver (" + usb_error(r) +
                               ")");
    impl->detached = true;
  }
  const int r = libusb_claim_interface(impl->handle, impl->interface);
  if (r != 0)
    throw std::runtime_error("gsusb: cannot claim interface 0 (" + usb_error(r) + ")" +
                             (r == LIBUSB_ERROR_BUSY ? ": another program uses the device" : ""));
  impl->claimed = true;
  return std::unique_ptr<GsUsbDevice>(new GsUsbDevice(std::move(impl)));
}

std::uint16_t GsUsbDevice::interface_number() const noexcept {
  return static_cast<std::uint16_t>(impl_->interface);
}

const GsUsbDeviceInfo& GsUsbDevice::info() const noexcept {
  return impl_->info;
}

void GsUsbDevice::control_out(GsUsbRequest request, std::uint16_t value, std::uint16_t index,
                              std::span<const std::uint8_t> data) {
  // libusb_control_transfer takes a non-const buffer for both directions; OUT only reads it.
  std::vector<std::uint8_t> buf(data.begin(), data.end());
  const int r = libusb_control_transfer(
      impl_->handle, kGsUsbRequestTypeOut, static_cast<std::uint8_t>(request), value, index,
      buf.data(), static_cast<std::uint16_t>(buf.size()), kControlTimeoutMs);
  if (r < 0)
    throw std::runtime_error("gsusb: " + std::string(to_string(request)) + " request failed (" +
                             usb_error(r) + ")");
  if (static_cast<std::size_t>(r) != buf.size())
    throw std::runtime_error("gsusb: " + std::string(to_string(request)) + " request sent " +
                             std::to_string(r) + " of " + std::to_string(buf.size()) + " bytes");
}

std::size_t GsUsbDevice::control_in(GsUsbRequest request, std::uint16_t value, std::uint16_t index,
                                    std::span<std::uint8_t> data) {
  const int r = libusb_control_transfer(
      impl_->handle, kGsUsbRequestTypeIn, static_cast<std::uint8_t>(request), value, index,
      data.data(), static_cast<std::uint16_t>(data.size()), kControlTimeoutMs);
  if (r < 0)
    throw std::runtime_error("gsusb: " + std::string(to_string(request)) + " request failed (" +
                             usb_error(r) + ")");
  return static_cast<std::size_t>(r);
}

void GsUsbDevice::start_receiving(std::size_t transfer_bytes) {
  Impl& m = *impl_;
  if (m.receiving)
    return;
  if (transfer_bytes == 0 || transfer_bytes > kGsUsbRxTransferBytes)
    throw std::invalid_argument("gsusb: IN transfer size must be 1.." +
                                std::to_string(kGsUsbRxTransferBytes) + " bytes");
  m.stopping.store(false);
  m.in_buffers.assign(kInTransfers, std::vector<std::uint8_t>(transfer_bytes));
  for (std::size_t i = 0; i < kInTransfers; ++i) {
    libusb_transfer* t = libusb_alloc_transfer(0);
    if (t == nullptr)
      throw std::runtime_error("gsusb: libusb_alloc_transfer failed");
    m.in.push_back(t);
    libusb_fill_bulk_transfer(t, m.handle, kGsUsbEndpointIn, m.in_buffers[i].data(),
                              static_cast<int>(transfer_bytes), &Impl::on_in, &m, 0);
  }
  m.out.resize(kOutTransfers);
  m.out_free.reserve(kOutTransfers);
  for (std::size_t i = 0; i < kOutTransfers; ++i) {
    Impl::OutSlot& s = m.out[i];
    s.self = &m;
    s.transfer = libusb_alloc_transfer(0);
    if (s.transfer == nullptr)
      throw std::runtime_error("gsusb: libusb_alloc_transfer failed");
    libusb_fill_bulk_transfer(s.transfer, m.handle, kGsUsbEndpointOut, s.buffer.data(), 0,
                              &Impl::on_out, &s, kControlTimeoutMs);
    m.out_free.push_back(i);
  }
  for (libusb_transfer* t : m.in) {
    const int r = libusb_submit_transfer(t);
    if (r != 0) {
      // Transfers already submitted are cancelled by the event thread that stop() runs.
      m.receiving = true;
      m.events = std::thread([&m] { m.run_events(); });
      m.stop();
      throw std::runtime_error("gsusb: cannot submit bulk IN transfers (" + usb_error(r) + ")");
    }
    ++m.active;
  }
  m.receiving = true;
  m.events = std::thread([&m] { m.run_events(); });
}

void GsUsbDevice::stop_receiving() noexcept {
  impl_->stop();
}

bool GsUsbDevice::bulk_out(std::span<const std::uint8_t> bytes, std::uint32_t tag) noexcept {
  if (bytes.size() > kGsUsbMaxFrameBytes)
    return false;
  Impl::TxItem item;
  std::copy(bytes.begin(), bytes.end(), item.bytes.begin());
  item.size = static_cast<std::uint32_t>(bytes.size());
  item.tag = tag;
  if (!impl_->tx.push(item))
    return false;
  libusb_interrupt_event_handler(impl_->ctx);
  return true;
}

bool GsUsbDevice::poll_in(GsUsbRxTransfer& out) noexcept {
  return impl_->rx.pop(out);
}

bool GsUsbDevice::poll_out_failed(std::uint32_t& tag) noexcept {
  return impl_->failed.pop(tag);
}

GsUsbTransportStats GsUsbDevice::transport_stats() const noexcept {
  GsUsbTransportStats s;
  s.rx_ring_overflows = impl_->rx_ring_overflows.load();
  s.in_transfer_errors = impl_->in_errors.load();
  s.out_transfer_errors = impl_->out_errors.load();
  s.device_gone = impl_->device_gone.load();
  return s;
}

// ---- Endpoint -------------------------------------------------------------------------------

GsUsbEndpoint::GsUsbEndpoint(std::unique_ptr<GsUsbTransport> transport, const GsUsbOptions& options)
    : transport_(std::move(transport)), options_(options) {
  if (!transport_)
    throw std::invalid_argument("gsusb: no transport");
  GsUsbTransport& t = *transport_;
  const std::uint16_t intf = t.interface_number();
  const std::uint16_t ch = options_.channel;

  // gs_usb.c gs_usb_probe: HOST_FORMAT and DEVICE_CONFIG with wValue 1, wIndex = interface.
  const auto host = pack_gs_usb_host_config();
  t.control_out(GsUsbRequest::kHostFormat, 1, intf, host);
  std::array<std::uint8_t, 12> dconf{};
  device_config_ = parse_gs_usb_device_config(
      std::span(dconf.data(), t.control_in(GsUsbRequest::kDeviceConfig, 1, intf, dconf)));
  if (ch >= device_config_.channel_count())
    throw std::runtime_error("gsusb: channel " + std::to_string(ch) +
                             " requested, the device has " +
                             std::to_string(device_config_.channel_count()) + " channel(s)");

  // gs_make_candev: BT_CONST per channel (wValue = channel, wIndex 0), BT_CONST_EXT for FD.
  std::array<std::uint8_t, 72> btc{};
  bt_const_ = parse_gs_usb_bt_const(std::span(
      btc.data(), t.control_in(GsUsbRequest::kBtConst, ch, 0, std::span(btc.data(), 40))));
  const std::uint32_t feature = bt_const_.feature;
  auto require = [&](bool wanted, std::uint32_t bit, const char* what) {
    if (wanted && (feature & bit) == 0)
      throw std::runtime_error(std::string("gsusb: the device has no ") + what +
                               " (BT_CONST feature " + hex32(feature) + ")");
  };
  require(options_.fd, gs_usb_flag::kFd, "CAN FD");
  require(options_.listen_only, gs_usb_flag::kListenOnly, "listen-only mode");
  require(options_.loopback, gs_usb_flag::kLoopBack, "loop-back mode");
  require(options_.one_shot, gs_usb_flag::kOneShot, "one-shot mode");
  if (options_.fd && (feature & gs_usb_flag::kBtConstExt)) {
    const std::size_t n = t.control_in(GsUsbRequest::kBtConstExt, ch, 0, btc);
    require_reply("BT_CONST_EXT", n, 72);
    bt_const_ = parse_gs_usb_bt_const(btc);
  }

  bit_timing_ = compute_gs_usb_bit_timing(bt_const_.fclk_can_hz, bt_const_.nominal,
                                          options_.bitrate_bps, options_.sample_point);
  if (options_.fd)
    data_bit_timing_ = compute_gs_usb_bit_timing(bt_const_.fclk_can_hz, bt_const_.data,
                                                 options_.dbitrate_bps, options_.data_sample_point);

  t.control_out(GsUsbRequest::kMode, ch, 0, pack_gs_usb_mode(kGsUsbModeReset, 0));
  t.control_out(GsUsbRequest::kBitTiming, ch, 0, pack_gs_usb_bit_timing(bit_timing_));
  if (options_.fd)
    t.control_out(GsUsbRequest::kDataBitTiming, ch, 0, pack_gs_usb_bit_timing(data_bit_timing_));

  // gs_can_open: the MODE flags.
  std::uint32_t flags = 0;
  if (options_.fd)
    flags |= gs_usb_flag::kFd;
  if (options_.loopback)
    flags |= gs_usb_flag::kLoopBack;
  else if (options_.listen_only)
    flags |= gs_usb_flag::kListenOnly;
  if (options_.one_shot)
    flags |= gs_usb_flag::kOneShot;
  if (options_.hw_timestamps && (feature & gs_usb_flag::kHwTimestamp))
    flags |= gs_usb_flag::kHwTimestamp;
  if (options_.bus_error_reporting && (feature & gs_usb_flag::kBerrReporting))
    flags |= gs_usb_flag::kBerrReporting;
  mode_flags_ = flags;
  format_.fd_mode = options_.fd;
  format_.hw_timestamp = (flags & gs_usb_flag::kHwTimestamp) != 0;

  if (format_.hw_timestamp) {  // align the device's microsecond counter with CLOCK_REALTIME
    std::array<std::uint8_t, 4> ts{};
    require_reply("TIMESTAMP", t.control_in(GsUsbRequest::kTimestamp, ch, 0, ts), 4);
    hw_last_us_ = get_le32(ts, 0);
    hw_origin_ns_ = realtime_now_ns();
    hw_elapsed_us_ = 0;
  }
  t.start_receiving(format_.rx_max_bytes());  // IN transfers before the start, as gs_can_open
  try {
    t.control_out(GsUsbRequest::kMode, ch, 0, pack_gs_usb_mode(kGsUsbModeStart, flags));
  } catch (...) {
    t.stop_receiving();
    throw;
  }
  errors_.set_state(CanBusState::kErrorActive);
}

std::unique_ptr<GsUsbEndpoint> GsUsbEndpoint::open(std::string_view serial,
                                                   const GsUsbOptions& options) {
  return std::make_unique<GsUsbEndpoint>(GsUsbDevice::open(serial), options);
}

GsUsbEndpoint::~GsUsbEndpoint() {
  try {
    transport_->control_out(GsUsbRequest::kMode, options_.channel, 0,
                            pack_gs_usb_mode(kGsUsbModeReset, 0));
  } catch (...) {  // the device may be gone; nothing more to do
  }
  transport_->stop_receiving();
}

std::int64_t GsUsbEndpoint::stamp(const GsUsbHostFrame& hf, const GsUsbRxTransfer& t) noexcept {
  if (!format_.hw_timestamp)
    return t.host_time_ns + options_.timestamp_offset_ns;
  // Signed 32-bit step: the counter wraps every 2^32 us = 71.6 min (gs_usb.c,
  // GS_USB_TIMESTAMP_WORK_DELAY_SEC comment); steps back of echo vs RX frames stay small.
  hw_elapsed_us_ += static_cast<std::int32_t>(hf.timestamp_us - hw_last_us_);
  hw_last_us_ = hf.timestamp_us;
  return hw_origin_ns_ + hw_elapsed_us_ * 1000 + options_.timestamp_offset_ns;
}

bool GsUsbEndpoint::send(const CanFrame& frame) noexcept {
  GsUsbHostFrame hf;
  if (!to_gs_usb_frame(frame, 0, options_.channel, format_.fd_mode, hf)) {
    ++stats_.tx_rejected;
    return false;
  }
  if (!pool_.acquire(hf.echo_id)) {
    reclaim_failed_out();
    if (!pool_.acquire(hf.echo_id)) {
      ++stats_.tx_pool_exhausted;
      return false;
    }
  }
  std::array<std::uint8_t, kGsUsbMaxFrameBytes> buf;
  const std::size_t n = pack_gs_usb_frame(hf, format_, buf);
  if (!transport_->bulk_out(std::span<const std::uint8_t>(buf.data(), n), hf.echo_id)) {
    (void)pool_.release(hf.echo_id);
    ++stats_.tx_queue_full;
    return false;
  }
  ++stats_.frames_sent;
  return true;
}

void GsUsbEndpoint::reclaim_failed_out() noexcept {
  std::uint32_t tag = 0;
  while (transport_->poll_out_failed(tag)) {
    if (pool_.release(tag))
      ++stats_.tx_failed;
  }
}

bool GsUsbEndpoint::receive(CanFrame& out) noexcept {
  reclaim_failed_out();
  for (int i = 0; i < 64; ++i) {
    GsUsbRxTransfer t;
    if (!transport_->poll_in(t))
      return false;
    if (t.overflow) {
      ++stats_.rx_oversized;
      continue;
    }
    GsUsbHostFrame hf;
    switch (
        unpack_gs_usb_frame(std::span<const std::uint8_t>(t.bytes.data(), t.size), format_, hf)) {
      case GsUsbUnpack::kOk:
        break;
      case GsUsbUnpack::kTruncated:
        ++stats_.rx_truncated;
        continue;
      case GsUsbUnpack::kOversized:
        ++stats_.rx_oversized;
        continue;
      case GsUsbUnpack::kNotFdMode:
        ++stats_.rx_malformed;
        continue;
    }
    if (hf.channel != options_.channel) {
      ++stats_.rx_wrong_channel;
      continue;
    }
    if (hf.flags & gs_usb_frame_flag::kOverflow)
      errors_.on_rx_overflow();
    const std::int64_t ts = stamp(hf, t);
    if (hf.echo_id != kGsUsbRxEchoId) {
      if (!pool_.release(hf.echo_id)) {
        ++stats_.unknown_echoes;
        continue;
      }
      ++stats_.echoes;
      if (!options_.receive_own)
        continue;
    }
    CanFrame f;
    switch (from_gs_usb_frame(hf, f)) {
      case GsUsbFrameKind::kData:
        break;
      case GsUsbFrameKind::kError:
        (void)errors_.on_error_frame(hf.can_id,
                                     std::span<const std::uint8_t, 8>(hf.data.data(), 8));
        continue;
      case GsUsbFrameKind::kRemote:
        ++stats_.rx_rtr_dropped;
        continue;
      case GsUsbFrameKind::kBadDlc:
        ++stats_.rx_malformed;
        continue;
    }
    f.timestamp_ns = ts;
    out = f;
    ++stats_.frames_received;
    return true;
  }
  return false;
}

}  // namespace radar_emu::io
